#include "avoidance/grid.hpp"

#include <algorithm>
#include <cmath>
#include <set>
#include <stdexcept>
#include <utility>

namespace rover::avoidance {

std::string Grid::Problem() const {
  if (!(cell_m > 0.0) || !std::isfinite(cell_m)) return "cell size " + std::to_string(cell_m) + " m must be > 0";
  if (!std::isfinite(origin_x) || !std::isfinite(origin_y)) return "origin is not finite";
  if (rows < 0 || cols < 0 || rows > 4096 || cols > 4096)
    return "size " + std::to_string(rows) + "x" + std::to_string(cols) + " is out of range (expected 0 to 4096)";
  const std::size_t n = static_cast<std::size_t>(rows) * static_cast<std::size_t>(cols);
  if (state.size() != n || goodness.size() != n || step_m.size() != n)
    return "cell arrays hold " + std::to_string(state.size()) + "/" + std::to_string(goodness.size()) + "/" +
           std::to_string(step_m.size()) + " values (expected " + std::to_string(n) + ")";
  if (!tilt_deg.empty() && tilt_deg.size() != n)
    return "tilt array holds " + std::to_string(tilt_deg.size()) + " values (expected 0 or " + std::to_string(n) + ")";
  if (elevation_m.size() != sigma_m.size() || (!sigma_m.empty() && sigma_m.size() != n))
    return "height arrays hold " + std::to_string(elevation_m.size()) + "/" + std::to_string(sigma_m.size()) +
           " values (expected 0 or " + std::to_string(n) + " each)";
  for (std::size_t k = 0; k < sigma_m.size(); ++k)
    if (!std::isfinite(elevation_m[k]) || !std::isfinite(sigma_m[k]))
      return "cell " + std::to_string(k) + " has a non-finite height or sigma";
  for (std::size_t k = 0; k < tilt_deg.size(); ++k)
    if (!std::isfinite(tilt_deg[k])) return "cell " + std::to_string(k) + " has a non-finite tilt";
  for (std::size_t k = 0; k < n; ++k) {
    if (static_cast<int>(state[k]) > 3) return "cell " + std::to_string(k) + " has an unknown state";
    if (!std::isfinite(goodness[k]) || !std::isfinite(step_m[k])) return "cell " + std::to_string(k) + " is not finite";
  }
  return "";
}

clearance::HeightMap Grid::Heights() const {
  clearance::HeightMap h;
  h.origin_x = origin_x;
  h.origin_y = origin_y;
  h.cell_m = cell_m;
  h.rows = rows;
  h.cols = cols;
  h.elevation_m = elevation_m.data();
  h.sigma_m = sigma_m.data();
  return h;
}

void Grid::SetHeights(float elevation, float sigma) {
  const std::size_t n = static_cast<std::size_t>(rows) * static_cast<std::size_t>(cols);
  elevation_m.assign(n, elevation);
  sigma_m.assign(n, sigma);
}

int Grid::IndexAt(double x, double y) const {
  const double fi = std::floor((x - origin_x) / cell_m), fj = std::floor((y - origin_y) / cell_m);
  if (!(fi >= 0 && fi < rows && fj >= 0 && fj < cols)) return -1;
  return static_cast<int>(fi) * cols + static_cast<int>(fj);
}

Grid Grid::Filled(double origin_x, double origin_y, double cell_m, int rows, int cols, CellClass s, float g) {
  Grid grid;
  grid.origin_x = origin_x;
  grid.origin_y = origin_y;
  grid.cell_m = cell_m;
  grid.rows = rows;
  grid.cols = cols;
  const std::size_t n = static_cast<std::size_t>(rows) * static_cast<std::size_t>(cols);
  grid.state.assign(n, s);
  grid.goodness.assign(n, g);
  grid.step_m.assign(n, 0.0f);
  return grid;
}

int Grid::DistrustEdges() {
  std::vector<std::size_t> edge;
  auto unknown = [&](int i, int j) {
    return i < 0 || j < 0 || i >= rows || j >= cols ||
           state[static_cast<std::size_t>(i) * cols + j] == CellClass::kUnknown;
  };
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < cols; ++j) {
      const std::size_t k = static_cast<std::size_t>(i) * cols + j;
      if (state[k] != CellClass::kUnsafe && state[k] != CellClass::kCaution) continue;
      if (unknown(i - 1, j) || unknown(i + 1, j) || unknown(i, j - 1) || unknown(i, j + 1)) edge.push_back(k);
    }
  for (std::size_t k : edge) {
    state[k] = CellClass::kUnknown;
    goodness[k] = 0.0f;
  }
  return static_cast<int>(edge.size());
}

namespace {

// Every unknown cell within `reach` of (x, y) whose centre `inside(cx, cy)` holds reads safe
// (goodness 1, no step); returns how many changed. What MarkKnown and MarkTurnKnown share.
template <typename Inside>
int MarkSafeWhere(Grid* g, double x, double y, double reach, Inside inside) {
  int changed = 0;
  for (int i = std::max(0, static_cast<int>(std::floor((x - reach - g->origin_x) / g->cell_m)));
       i < g->rows && g->CellCentreX(i) <= x + reach; ++i)
    for (int j = std::max(0, static_cast<int>(std::floor((y - reach - g->origin_y) / g->cell_m)));
         j < g->cols && g->CellCentreY(j) <= y + reach; ++j) {
      const std::size_t k = static_cast<std::size_t>(i) * g->cols + j;
      if (g->state[k] != CellClass::kUnknown || !inside(g->CellCentreX(i), g->CellCentreY(j))) continue;
      g->state[k] = CellClass::kSafe;
      g->goodness[k] = 1.0f;
      g->step_m[k] = 0.0f;
      ++changed;
    }
  return changed;
}

}  // namespace

int Grid::MarkKnown(const Footprint& footprint, const Pose2& pose, double grow_m) {
  const double reach = std::hypot(0.5 * footprint.length_m + std::abs(footprint.center_forward_m),
                                  0.5 * footprint.width_m) + grow_m + cell_m;
  return MarkSafeWhere(this, pose.x, pose.y, reach,
                       [&](double cx, double cy) { return footprint.Contains(pose, cx, cy, grow_m); });
}

int Grid::MarkTurnKnown(const Footprint& footprint, const Pose2& pose) {
  const double radius = footprint.TurnRadius(0.5 * cell_m);
  return MarkSafeWhere(this, pose.x, pose.y, radius,
                       [&](double cx, double cy) { return std::hypot(cx - pose.x, cy - pose.y) <= radius; });
}

int Grid::MarkFlanksOfHiddenGround(double patch_m, double min_step_m) {
  if (patch_m <= 0.0) return 0;
  const double r = 0.5 * patch_m / cell_m;  // disc radius in cells, as HiddenGround's
  const int n = static_cast<int>(std::floor(r));
  std::vector<std::pair<int, int>> disc;
  for (int di = -n; di <= n; ++di)
    for (int dj = -n; dj <= n; ++dj)
      if (di * di + dj * dj <= r * r + 1e-9) disc.push_back({di, dj});
  auto unknown = [&](int i, int j) {
    return i >= 0 && j >= 0 && i < rows && j < cols &&
           state[static_cast<std::size_t>(i) * cols + j] == CellClass::kUnknown;
  };
  // deep: the disc centred on the cell is all unknown; hidden: some deep disc covers it.
  std::vector<char> deep(state.size(), 0), hidden(state.size(), 0);
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < cols; ++j) {
      bool all = true;
      for (const auto& [di, dj] : disc)
        if (!unknown(i + di, j + dj)) {
          all = false;
          break;
        }
      deep[static_cast<std::size_t>(i) * cols + j] = all;
    }
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < cols; ++j) {
      if (!deep[static_cast<std::size_t>(i) * cols + j]) continue;
      for (const auto& [di, dj] : disc)
        if (i + di >= 0 && j + dj >= 0 && i + di < rows && j + dj < cols)
          hidden[static_cast<std::size_t>(i + di) * cols + (j + dj)] = 1;
    }
  std::vector<std::size_t> flank;
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < cols; ++j) {
      const std::size_t k = static_cast<std::size_t>(i) * cols + j;
      if ((state[k] != CellClass::kSafe && state[k] != CellClass::kCaution) || step_m[k] < min_step_m) continue;
      bool beside = false;
      for (int di = -1; di <= 1 && !beside; ++di)
        for (int dj = -1; dj <= 1 && !beside; ++dj)
          beside = i + di >= 0 && j + dj >= 0 && i + di < rows && j + dj < cols &&
                   hidden[static_cast<std::size_t>(i + di) * cols + (j + dj)];
      if (beside) flank.push_back(k);
    }
  for (std::size_t k : flank) {
    state[k] = CellClass::kUnsafe;
    goodness[k] = 0.0f;
  }
  return static_cast<int>(flank.size());
}

void Grid::Paint(double x, double y, double radius_m, CellClass s, float g, float step) {
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < cols; ++j)
      if (std::hypot(CellCentreX(i) - x, CellCentreY(j) - y) <= radius_m) {
        const std::size_t k = static_cast<std::size_t>(i) * cols + j;
        state[k] = s;
        goodness[k] = g;
        step_m[k] = step;
        if (HasHeights()) {
          elevation_m[k] = step;
          sigma_m[k] = s == CellClass::kUnknown ? -1.0f : 0.0f;
        }
      }
}

double Footprint::TurnRadius(double grow_m) const {
  const double hx = 0.5 * length_m + grow_m, hy = 0.5 * width_m + grow_m;
  return std::max(std::hypot(center_forward_m + hx, hy), std::hypot(center_forward_m - hx, hy));
}

bool Footprint::Contains(const Pose2& p, double x, double y, double grow_m) const {
  const double c = std::cos(p.yaw), s = std::sin(p.yaw);
  const double cx = p.x + center_forward_m * c, cy = p.y + center_forward_m * s;
  const double dx = x - cx, dy = y - cy;
  const double u = c * dx + s * dy;   // forward
  const double v = -s * dx + c * dy;  // right
  return std::abs(u) <= 0.5 * length_m + grow_m && std::abs(v) <= 0.5 * width_m + grow_m;
}

double Footprint::Outside(const Pose2& p, double x, double y) const {
  const double c = std::cos(p.yaw), s = std::sin(p.yaw);
  const double dx = x - (p.x + center_forward_m * c), dy = y - (p.y + center_forward_m * s);
  return std::max(std::abs(c * dx + s * dy) - 0.5 * length_m, std::abs(-s * dx + c * dy) - 0.5 * width_m);
}

std::vector<Pose2> SamplePath(const Pose2& start, double turn_rad, double distance_m, double k,
                              double spacing_m, double angle_rad) {
  if (!std::isfinite(turn_rad) || !std::isfinite(distance_m) || !std::isfinite(k) || !(spacing_m > 0.0) ||
      !(angle_rad > 0.0)) {
    throw std::invalid_argument("SamplePath: non-finite motion or non-positive spacing");
  }
  std::vector<Pose2> out{start};
  Pose2 p = start;
  const int nt = static_cast<int>(std::ceil(std::abs(turn_rad) / angle_rad));
  for (int t = 1; t <= nt; ++t) out.push_back({p.x, p.y, start.yaw + turn_rad * t / nt});
  p.yaw = start.yaw + turn_rad;
  const int ns = std::max(static_cast<int>(std::ceil(std::abs(distance_m) / spacing_m)),
                          static_cast<int>(std::ceil(std::abs(distance_m * k) / angle_rad)));
  for (int t = 1; t <= ns; ++t) {
    const double s = distance_m * t / ns;
    double fx, fy;  // rover-frame chord
    if (std::abs(k * s) < 1e-9) {
      fx = s;
      fy = 0.5 * k * s * s;
    } else {
      fx = std::sin(k * s) / k;
      fy = (1.0 - std::cos(k * s)) / k;
    }
    const double c = std::cos(p.yaw), sn = std::sin(p.yaw);
    out.push_back({p.x + c * fx - sn * fy, p.y + sn * fx + c * fy, p.yaw + k * s});
  }
  return out;
}

namespace {

// Unknown ground as wide as a hazard (SweepFootprint's hidden_patch_m): a morphological
// opening of the unknown cells by a disc, evaluated where the sweep asks. Written by hand:
// cv::morphologyEx would do the opening, but this library knows nothing of OpenCV, and the
// sweep asks about a few dozen cells of a grid that moves with the rover.
class HiddenGround {
 public:
  HiddenGround(const Grid& grid, const Footprint& fp, const Pose2& standing, double blind_margin_m,
               double patch_m)
      : grid_(grid), fp_(fp), standing_(standing), blind_margin_m_(blind_margin_m) {
    const double r = 0.5 * patch_m / grid.cell_m;  // disc radius in cells
    const int n = static_cast<int>(std::floor(r));
    for (int di = -n; di <= n; ++di)
      for (int dj = -n; dj <= n; ++dj)
        if (di * di + dj * dj <= r * r + 1e-9) disc_.push_back({di, dj});
  }

  // Whether cell (i, j), on the grid or off it, lies in an all-unknown disc.
  bool Hidden(long i, long j) const {
    for (const auto& [di, dj] : disc_)
      if (Deep(i - di, j - dj)) return true;
    return false;
  }

 private:
  bool Unknown(long i, long j) const {
    const double x = grid_.origin_x + (i + 0.5) * grid_.cell_m, y = grid_.origin_y + (j + 0.5) * grid_.cell_m;
    if (fp_.Contains(standing_, x, y, blind_margin_m_)) return false;  // under the rover, or its ring
    if (i < 0 || j < 0 || i >= grid_.rows || j >= grid_.cols) return true;
    return grid_.state[static_cast<std::size_t>(i) * grid_.cols + j] == CellClass::kUnknown;
  }
  // The disc centred on (i, j) is all unknown.
  bool Deep(long i, long j) const {
    for (const auto& [di, dj] : disc_)
      if (!Unknown(i + di, j + dj)) return false;
    return true;
  }

  const Grid& grid_;
  const Footprint& fp_;
  Pose2 standing_;
  double blind_margin_m_;
  std::vector<std::pair<int, int>> disc_;
};

}  // namespace

UnknownVerdict JudgeUnknown(const Sweep& s, const UnknownLimits& l) {
  const double f = s.UnknownFraction();
  if (l.hidden_at_any_share && l.hidden_patch_m > 0.0 && s.hidden > 0) return UnknownVerdict::kHidden;
  if (f <= l.max_fraction) return UnknownVerdict::kAcceptable;
  if (l.hidden_patch_m <= 0.0) return UnknownVerdict::kTooMuch;
  if (s.hidden > 0) return UnknownVerdict::kHidden;
  return f > UnknownLimit(l) ? UnknownVerdict::kTooMuch : UnknownVerdict::kAcceptable;
}

double UnknownLimit(const UnknownLimits& l) {
  return l.hidden_patch_m > 0.0 ? std::max(l.max_fraction, l.max_scattered_fraction) : l.max_fraction;
}

// The hidden ground within `reach` beyond the footprint along `path` (SweepFootprint's
// hidden_reach_m), except where the rover stands: calls note(i, j, x, y) once per cell.
template <typename Note>
void NoteHiddenBeside(const Grid& grid, const Footprint& fp, const std::vector<Pose2>& path,
                      const Pose2& standing, double reach, Note note) {
  const double cell = grid.cell_m;
  const double grow = 0.5 * cell;
  const double extent = std::hypot(0.5 * fp.length_m + std::abs(fp.center_forward_m), 0.5 * fp.width_m) + cell + reach;
  std::set<std::pair<long, long>> seen;
  for (const Pose2& p : path) {
    const long i0 = static_cast<long>(std::floor((p.x - extent - grid.origin_x) / cell));
    const long i1 = static_cast<long>(std::floor((p.x + extent - grid.origin_x) / cell));
    const long j0 = static_cast<long>(std::floor((p.y - extent - grid.origin_y) / cell));
    const long j1 = static_cast<long>(std::floor((p.y + extent - grid.origin_y) / cell));
    for (long i = i0; i <= i1; ++i)
      for (long j = j0; j <= j1; ++j) {
        const double x = grid.origin_x + (i + 0.5) * cell, y = grid.origin_y + (j + 0.5) * cell;
        if (fp.Contains(p, x, y, grow) || !fp.Contains(p, x, y, grow + reach)) continue;
        if (fp.Contains(standing, x, y, grow + reach)) continue;  // as near where it stands
        if (seen.insert({i, j}).second) note(i, j, x, y);
      }
  }
}

Sweep SweepFootprint(const Grid& grid, const Footprint& fp, const std::vector<Pose2>& path,
                     const Pose2& standing, double blind_margin_m, double hidden_patch_m, double hidden_reach_m) {
  Sweep sw;
  const bool find_hidden = hidden_patch_m > 0.0;
  const HiddenGround hidden(grid, fp, standing, blind_margin_m, find_hidden ? hidden_patch_m : 0.0);
  auto note_hidden = [&](long i, long j, double x, double y) {
    if (!find_hidden || !hidden.Hidden(i, j)) return;
    if (sw.hidden++ == 0) {
      sw.hidden_x = x;
      sw.hidden_y = y;
    }
  };
  const double cell = grid.cell_m;
  const double grow = 0.5 * cell;
  const double reach = std::hypot(0.5 * fp.length_m + std::abs(fp.center_forward_m), 0.5 * fp.width_m) + cell;
  std::vector<char> seen(static_cast<std::size_t>(grid.rows) * grid.cols, 0);
  std::set<std::pair<long, long>> seen_outside;
  // Unsafe cells at the standing footprint's edge, and how far outside it each lies (the
  // header: the body may not come nearer to them).
  struct EdgeCell {
    std::size_t k;
    double x, y, outside;
  };
  std::vector<EdgeCell> edge;
  {
    const long i0 = static_cast<long>(std::floor((standing.x - reach - grid.origin_x) / cell));
    const long j0 = static_cast<long>(std::floor((standing.y - reach - grid.origin_y) / cell));
    const long i1 = static_cast<long>(std::floor((standing.x + reach - grid.origin_x) / cell));
    const long j1 = static_cast<long>(std::floor((standing.y + reach - grid.origin_y) / cell));
    for (long i = std::max(0L, i0); i <= std::min<long>(grid.rows - 1, i1); ++i)
      for (long j = std::max(0L, j0); j <= std::min<long>(grid.cols - 1, j1); ++j) {
        const std::size_t k = static_cast<std::size_t>(i) * grid.cols + j;
        if (grid.state[k] != CellClass::kUnsafe) continue;
        const double x = grid.origin_x + (i + 0.5) * cell, y = grid.origin_y + (j + 0.5) * cell;
        const double out = fp.Outside(standing, x, y);
        if (out <= grow && out > -grow) edge.push_back({k, x, y, out});
      }
  }
  constexpr double kNearer = 0.02;  // m: nearer than this counts (not rounding along a turn)
  for (std::size_t n = 0; n < path.size(); ++n) {
    const Pose2& p = path[n];
    for (EdgeCell& e : edge) {
      if (e.outside == -1e9 || fp.Outside(p, e.x, e.y) >= e.outside - kNearer) continue;
      e.outside = -1e9;  // counted once
      ++sw.unsafe;
      sw.min_goodness = 0.0;
      if (sw.first_unsafe_pose < 0) sw.first_unsafe_pose = static_cast<int>(n);
      if (sw.unsafe == 1 || grid.step_m[e.k] > sw.worst_step_m) {
        sw.worst_step_m = grid.step_m[e.k];
        sw.worst_tilt_deg = grid.tilt_deg.empty() ? -1.0 : grid.tilt_deg[e.k];
        sw.worst_x = e.x;
        sw.worst_y = e.y;
      }
    }
    const long i0 = static_cast<long>(std::floor((p.x - reach - grid.origin_x) / cell));
    const long i1 = static_cast<long>(std::floor((p.x + reach - grid.origin_x) / cell));
    const long j0 = static_cast<long>(std::floor((p.y - reach - grid.origin_y) / cell));
    const long j1 = static_cast<long>(std::floor((p.y + reach - grid.origin_y) / cell));
    for (long i = i0; i <= i1; ++i) {
      for (long j = j0; j <= j1; ++j) {
        const double x = grid.origin_x + (i + 0.5) * cell, y = grid.origin_y + (j + 0.5) * cell;
        if (!fp.Contains(p, x, y, grow)) continue;
        const bool inside = i >= 0 && i < grid.rows && j >= 0 && j < grid.cols;
        if (inside) {
          char& s = seen[static_cast<std::size_t>(i) * grid.cols + j];
          if (s) continue;
          s = 1;
        } else if (!seen_outside.insert({i, j}).second) {
          continue;
        }
        if (fp.Contains(standing, x, y, grow)) continue;  // the rover stands on it
        ++sw.cells;
        if (sw.first_unsafe_pose < 0) ++sw.clear_cells;
        const bool blind = fp.Contains(standing, x, y, blind_margin_m);
        if (!inside) {
          ++sw.outside;
          blind ? ++sw.blind_unknown : ++sw.unknown;
          if (!blind && sw.first_unsafe_pose < 0) ++sw.clear_unknown;
          if (!blind) note_hidden(i, j, x, y);
          continue;
        }
        const std::size_t k = static_cast<std::size_t>(i) * grid.cols + j;
        switch (grid.state[k]) {
          case CellClass::kUnknown:
            blind ? ++sw.blind_unknown : ++sw.unknown;
            if (!blind && sw.first_unsafe_pose < 0) ++sw.clear_unknown;
            if (!blind) note_hidden(i, j, x, y);
            break;
          case CellClass::kUnsafe:
            ++sw.unsafe;
            sw.min_goodness = 0.0;
            if (sw.first_unsafe_pose < 0) sw.first_unsafe_pose = static_cast<int>(n);
            if (sw.unsafe == 1 || grid.step_m[k] > sw.worst_step_m) {
              sw.worst_step_m = grid.step_m[k];
              sw.worst_tilt_deg = grid.tilt_deg.empty() ? -1.0 : grid.tilt_deg[k];
              sw.worst_x = x;
              sw.worst_y = y;
            }
            break;
          default:
            sw.min_goodness = std::min(sw.min_goodness, static_cast<double>(grid.goodness[k]));
            if (grid.step_m[k] > sw.max_step_m) {
              sw.max_step_m = grid.step_m[k];
              sw.max_step_x = x;
              sw.max_step_y = y;
            }
            if (sw.first_unsafe_pose < 0)
              sw.clear_min_goodness = std::min(sw.clear_min_goodness, static_cast<double>(grid.goodness[k]));
        }
      }
    }
  }
  if (find_hidden && hidden_reach_m > 0.0) {
    NoteHiddenBeside(grid, fp, path, standing, hidden_reach_m, [&](long i, long j, double x, double y) {
      const bool inside = i >= 0 && i < grid.rows && j >= 0 && j < grid.cols;
      const std::size_t k = inside ? static_cast<std::size_t>(i) * grid.cols + j : 0;
      if (inside ? seen[k] != 0 : seen_outside.count({i, j}) != 0) return;  // under the footprint: judged above
      if (inside && grid.state[k] != CellClass::kUnknown) return;
      if (fp.Contains(standing, x, y, blind_margin_m)) return;  // the blind ring is excused, as above
      note_hidden(i, j, x, y);
    });
  }
  return sw;
}

}  // namespace rover::avoidance
