#include "planner/global_planner.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <queue>
#include <stdexcept>
#include <utility>

namespace rover::planner {

using avoidance::CellClass;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

std::string Num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f", v);
  return buf;
}

// What each cell is to the planner: an obstacle, a squeeze (its centre within the inscribed
// radius of one), and what a metre through it costs otherwise.
struct CostGrid {
  std::vector<unsigned char> obstacle, squeeze;
  std::vector<double> factor;
  std::vector<double> extra;  // costly discs' cost per metre, added to the factor (squeeze too)
  int obstacles = 0;
};

}  // namespace

std::vector<unsigned char> ZoneCells(const avoidance::Grid& g, const std::vector<hazards::KeepOutZone>& zones,
                                     double grow_m) {
  std::vector<unsigned char> cells(static_cast<std::size_t>(g.rows) * g.cols, 0);
  hazards::Footprint point;  // a point: the distance from a cell centre to the zone
  point.length_m = point.width_m = 1e-4;
  for (const hazards::KeepOutZone& z : zones) {
    double x0, x1, y0, y1;
    if (z.shape == hazards::KeepOutZone::Shape::kCircle) {
      x0 = z.center.x() - z.radius_m, x1 = z.center.x() + z.radius_m;
      y0 = z.center.y() - z.radius_m, y1 = z.center.y() + z.radius_m;
    } else {
      x0 = y0 = kInf, x1 = y1 = -kInf;
      for (const Eigen::Vector2d& v : z.vertices) {
        x0 = std::min(x0, v.x()), x1 = std::max(x1, v.x());
        y0 = std::min(y0, v.y()), y1 = std::max(y1, v.y());
      }
    }
    const int i0 = std::max(0, static_cast<int>(std::floor((x0 - grow_m - g.origin_x) / g.cell_m)));
    const int i1 = std::min(g.rows - 1, static_cast<int>(std::floor((x1 + grow_m - g.origin_x) / g.cell_m)));
    const int j0 = std::max(0, static_cast<int>(std::floor((y0 - grow_m - g.origin_y) / g.cell_m)));
    const int j1 = std::min(g.cols - 1, static_cast<int>(std::floor((y1 + grow_m - g.origin_y) / g.cell_m)));
    for (int i = i0; i <= i1; ++i)
      for (int j = j0; j <= j1; ++j)
        if (hazards::Clearance(z, point, g.CellCentreX(i), g.CellCentreY(j), 0.0) < grow_m)
          cells[static_cast<std::size_t>(i) * g.cols + j] = 1;
  }
  return cells;
}

namespace {

void AddCostlyDiscs(const avoidance::Grid& g, const std::vector<CostlyDisc>& discs, std::vector<double>* extra) {
  for (const CostlyDisc& d : discs) {
    const int i0 = std::max(0, static_cast<int>(std::floor((d.center.x() - d.radius_m - g.origin_x) / g.cell_m)));
    const int i1 = std::min(g.rows - 1, static_cast<int>(std::floor((d.center.x() + d.radius_m - g.origin_x) / g.cell_m)));
    const int j0 = std::max(0, static_cast<int>(std::floor((d.center.y() - d.radius_m - g.origin_y) / g.cell_m)));
    const int j1 = std::min(g.cols - 1, static_cast<int>(std::floor((d.center.y() + d.radius_m - g.origin_y) / g.cell_m)));
    for (int i = i0; i <= i1; ++i)
      for (int j = j0; j <= j1; ++j)
        if (std::hypot(g.CellCentreX(i) - d.center.x(), g.CellCentreY(j) - d.center.y()) <= d.radius_m)
          (*extra)[static_cast<std::size_t>(i) * g.cols + j] += d.cost_per_m;
  }
}

CostGrid BuildCosts(const avoidance::Grid& g, const PlanRequest& r, const PlannerOptions& o) {
  const std::size_t n = static_cast<std::size_t>(g.rows) * g.cols;
  CostGrid c;
  c.obstacle.assign(n, 0);
  c.squeeze.assign(n, 0);
  c.factor.assign(n, 1.0);
  c.extra.assign(n, 0.0);
  AddCostlyDiscs(g, r.costly, &c.extra);
  auto unsafe = [&](int i, int j) {
    return i >= 0 && j >= 0 && i < g.rows && j < g.cols &&
           g.state[static_cast<std::size_t>(i) * g.cols + j] == CellClass::kUnsafe;
  };
  for (int i = 0; i < g.rows; ++i) {
    for (int j = 0; j < g.cols; ++j) {
      const std::size_t k = static_cast<std::size_t>(i) * g.cols + j;
      switch (g.state[k]) {
        case CellClass::kSafe: break;
        case CellClass::kCaution: c.factor[k] = o.caution_cost; break;
        case CellClass::kUnsafe: {
          int neighbours = 0;
          for (int di = -1; di <= 1; ++di)
            for (int dj = -1; dj <= 1; ++dj) neighbours += (di || dj) && unsafe(i + di, j + dj);
          if (neighbours >= o.min_obstacle_neighbours) c.obstacle[k] = 1;
          c.factor[k] = o.caution_cost;
          break;
        }
        case CellClass::kUnknown: {
          const double prior = r.prior ? r.prior->CostAt(g.CellCentreX(i), g.CellCentreY(j)) : 1.0;
          if (std::isinf(prior)) c.obstacle[k] = 1;
          c.factor[k] = o.unknown_cost * (std::isinf(prior) ? 1.0 : prior);
          break;
        }
      }
    }
  }
  const std::vector<unsigned char> zone = ZoneCells(g, r.zones, r.zone_grow_m);
  for (std::size_t k = 0; k < n; ++k) c.obstacle[k] |= zone[k];
  c.obstacles = static_cast<int>(std::count(c.obstacle.begin(), c.obstacle.end(), 1));
  if (c.obstacles == 0) return c;
  // The distance from each cell centre to the nearest obstacle cell centre: OpenCV's exact
  // Euclidean distance transform (to the nearest zero pixel).
  cv::Mat free_mask(g.rows, g.cols, CV_8U);
  for (int i = 0; i < g.rows; ++i)
    for (int j = 0; j < g.cols; ++j) free_mask.at<unsigned char>(i, j) = c.obstacle[static_cast<std::size_t>(i) * g.cols + j] ? 0 : 255;
  cv::Mat dist;
  cv::distanceTransform(free_mask, dist, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  for (int i = 0; i < g.rows; ++i) {
    for (int j = 0; j < g.cols; ++j) {
      const std::size_t k = static_cast<std::size_t>(i) * g.cols + j;
      if (c.obstacle[k]) continue;
      const double d = dist.at<float>(i, j) * g.cell_m;
      if (d < o.inscribed_radius_m) {
        c.squeeze[k] = 1;
      } else if (d < o.circumscribed_radius_m) {
        c.factor[k] = std::max(c.factor[k], o.near_cost);
      }
    }
  }
  return c;
}

// Whether a frozen cell has a neighbour that is not: only such a cell can lower another
// cell's value, so only they need be sources (a frozen cell is never lowered itself). The
// field comes out the same, since Dijkstra's result does not depend on its sources' order.
bool BesideUnfrozen(const avoidance::Grid& g, const std::vector<unsigned char>& frozen, std::size_t k) {
  const int i = static_cast<int>(k / static_cast<std::size_t>(g.cols));
  const int j = static_cast<int>(k % static_cast<std::size_t>(g.cols));
  for (int ni = std::max(0, i - 1); ni <= std::min(g.rows - 1, i + 1); ++ni)
    for (int nj = std::max(0, j - 1); nj <= std::min(g.cols - 1, j + 1); ++nj)
      if (!frozen[static_cast<std::size_t>(ni) * g.cols + nj]) return true;
  return false;
}

// Dijkstra over the 8-connected grid from the cells already finite in *field, through cells
// that are not obstacles (nor squeezes, unless allow_squeeze). A metre of a step costs half
// its length at each end cell's factor (squeeze cells: squeeze_cost). A diagonal step needs
// both cells beside it passable, so that the way never slips between two obstacle cells
// that touch at a corner. Cells marked in `frozen` keep their value (they are only sources).
void Spread(const avoidance::Grid& g, const CostGrid& c, const PlannerOptions& o, bool allow_squeeze,
            std::vector<double>* field, const std::vector<unsigned char>* frozen = nullptr) {
  using Item = std::pair<double, std::size_t>;
  std::vector<Item> sources;
  for (std::size_t k = 0; k < field->size(); ++k)
    if (std::isfinite((*field)[k]) && (!frozen || !(*frozen)[k] || BesideUnfrozen(g, *frozen, k)))
      sources.push_back({(*field)[k], k});
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> open(std::greater<Item>(), std::move(sources));
  // Whether each cell is passable, with a ring of impassable cells round the grid so that a
  // neighbour needs no bounds check, and each cell's factor: looked up once, not per visit
  // (the same values in the same order as asking each time, so the same field).
  const int w = g.cols + 2;
  std::vector<unsigned char> pass(static_cast<std::size_t>(g.rows + 2) * w, 0);
  std::vector<double> factor(field->size());
  for (int i = 0; i < g.rows; ++i) {
    for (int j = 0; j < g.cols; ++j) {
      const std::size_t k = static_cast<std::size_t>(i) * g.cols + j;
      pass[static_cast<std::size_t>(i + 1) * w + (j + 1)] = !c.obstacle[k] && (allow_squeeze || !c.squeeze[k]);
      factor[k] = (c.squeeze[k] ? o.squeeze_cost : c.factor[k]) + c.extra[k];
    }
  }
  const double diagonal = g.cell_m * std::sqrt(2.0);
  while (!open.empty()) {
    const auto [d, k] = open.top();
    open.pop();
    if (d > (*field)[k]) continue;
    const int i = static_cast<int>(k / static_cast<std::size_t>(g.cols));
    const int j = static_cast<int>(k % static_cast<std::size_t>(g.cols));
    const unsigned char* here = &pass[static_cast<std::size_t>(i + 1) * w + (j + 1)];
    for (int di = -1; di <= 1; ++di) {
      for (int dj = -1; dj <= 1; ++dj) {
        if ((di == 0 && dj == 0) || !here[di * w + dj]) continue;
        if (di != 0 && dj != 0 && (!here[di * w] || !here[dj])) continue;
        const std::size_t next = static_cast<std::size_t>(i + di) * g.cols + (j + dj);
        if (frozen && (*frozen)[next]) continue;
        const double step = (di != 0 && dj != 0 ? diagonal : g.cell_m) * 0.5 * (factor[k] + factor[next]);
        if (d + step < (*field)[next]) {
          (*field)[next] = d + step;
          open.push({d + step, next});
        }
      }
    }
  }
}

int IndexOf(const avoidance::Grid& g, double x, double y) { return g.IndexAt(x, y); }

}  // namespace

void PlannerOptions::Validate() const {
  auto check = [](bool ok, const char* name, double v) {
    if (!ok) throw std::invalid_argument(std::string("planner: ") + name + " " + std::to_string(v) + " is out of range");
  };
  check(inscribed_radius_m >= 0.0 && std::isfinite(inscribed_radius_m), "inscribed_radius_m (>= 0)", inscribed_radius_m);
  check(circumscribed_radius_m >= inscribed_radius_m && std::isfinite(circumscribed_radius_m),
        "circumscribed_radius_m (>= inscribed_radius_m)", circumscribed_radius_m);
  check(unknown_cost >= 1.0 && std::isfinite(unknown_cost), "unknown_cost (>= 1)", unknown_cost);
  check(caution_cost >= 1.0 && std::isfinite(caution_cost), "caution_cost (>= 1)", caution_cost);
  check(near_cost >= 1.0 && std::isfinite(near_cost), "near_cost (>= 1)", near_cost);
  check(squeeze_cost >= 1.0 && std::isfinite(squeeze_cost), "squeeze_cost (>= 1)", squeeze_cost);
  check(min_obstacle_neighbours >= 0 && min_obstacle_neighbours <= 8, "min_obstacle_neighbours (0 to 8)",
        min_obstacle_neighbours);
  check(margin_m >= 0.0 && std::isfinite(margin_m), "margin_m (>= 0)", margin_m);
  check(max_cells >= 100, "max_cells (>= 100)", max_cells);
}

void PlannerOptions::SetRadiiFrom(const avoidance::Footprint& footprint, double margin_m) {
  inscribed_radius_m = 0.5 * footprint.width_m + margin_m;
  circumscribed_radius_m = 0.5 * std::hypot(footprint.length_m, footprint.width_m) + std::abs(footprint.center_forward_m) + margin_m;
}

GlobalPlan PlanOnGrid(const avoidance::Grid& grid, const PlanRequest& r, const PlannerOptions& o) {
  o.Validate();
  if (const std::string p = grid.Problem(); !p.empty()) throw std::invalid_argument("planner: grid: " + p);
  for (double v : {r.start_x, r.start_y, r.goal_x, r.goal_y, r.goal_radius_m, r.zone_grow_m})
    if (!std::isfinite(v)) throw std::invalid_argument("planner: start, goal, goal radius and zone growth must be finite");
  if (r.goal_radius_m < 0.0 || r.zone_grow_m < 0.0) throw std::invalid_argument("planner: goal radius and zone growth must be >= 0");
  for (const CostlyDisc& d : r.costly)
    if (!d.center.allFinite() || !(d.radius_m > 0.0) || !std::isfinite(d.radius_m) || !(d.cost_per_m >= 0.0) ||
        !std::isfinite(d.cost_per_m))
      throw std::invalid_argument("planner: a costly disc needs a finite centre, radius > 0 and cost_per_m >= 0");
  GlobalPlan plan;
  plan.grid_ = grid;
  plan.start_ = {r.start_x, r.start_y};
  plan.goal_ = {r.goal_x, r.goal_y};
  const int start = IndexOf(grid, r.start_x, r.start_y);
  if (start < 0 || IndexOf(grid, r.goal_x, r.goal_y) < 0)
    throw std::invalid_argument("planner: the start and the goal must lie in the planning window");
  const CostGrid costs = BuildCosts(grid, r, o);
  plan.obstacle_ = costs.obstacle;
  plan.obstacle_cells_ = costs.obstacles;
  const std::size_t n = costs.factor.size();

  // The goal disc: every cell whose centre lies in it and can hold the rover's centre (its
  // distance to the goal to go), else the goal's own cell if it is not an obstacle.
  std::vector<double> field(n, kInf);
  const int reach = static_cast<int>(std::ceil(r.goal_radius_m / grid.cell_m)) + 1;
  const int gi = IndexOf(grid, r.goal_x, r.goal_y) / grid.cols, gj = IndexOf(grid, r.goal_x, r.goal_y) % grid.cols;
  bool seeded = false;
  for (int i = std::max(0, gi - reach); i <= std::min(grid.rows - 1, gi + reach); ++i) {
    for (int j = std::max(0, gj - reach); j <= std::min(grid.cols - 1, gj + reach); ++j) {
      const std::size_t k = static_cast<std::size_t>(i) * grid.cols + j;
      const double d = std::hypot(grid.CellCentreX(i) - r.goal_x, grid.CellCentreY(j) - r.goal_y);
      if ((d <= r.goal_radius_m || (i == gi && j == gj)) && !costs.obstacle[k] && !costs.squeeze[k]) {
        field[k] = d;
        seeded = true;
      }
    }
  }
  Spread(grid, costs, o, false, &field);
  const std::vector<double> through_free = field;
  if (!seeded) {
    // The field is still wanted (the vote leans toward the goal); seed what is not an obstacle.
    const std::size_t g = static_cast<std::size_t>(IndexOf(grid, r.goal_x, r.goal_y));
    if (!costs.obstacle[g]) field[g] = 0.0;
  }
  // The squeeze band only leads out, to the way through free cells: a cell joined to the
  // goal through free cells keeps that cost, so that no squeeze through a gap narrower than
  // the rover (a closed wall of rocks seen as a row of obstacle cells with gaps between
  // them) can undercut the way round, however long that is.
  std::vector<unsigned char> frozen(n, 0);
  for (std::size_t k = 0; k < n; ++k) frozen[k] = std::isfinite(through_free[k]);
  Spread(grid, costs, o, true, &field, &frozen);
  plan.field_ = std::move(field);

  // Reachable: the rover's cell is connected to the disc through cells that hold its centre,
  // or it stands in the squeeze band beside such a cell (it can step out of it).
  const std::size_t s = static_cast<std::size_t>(start);
  plan.reachable_ = std::isfinite(through_free[s]);
  if (!plan.reachable_ && costs.squeeze[s]) {
    const int si = start / grid.cols, sj = start % grid.cols;
    const int esc = static_cast<int>(std::ceil(o.inscribed_radius_m / grid.cell_m)) + 1;
    for (int i = std::max(0, si - esc); i <= std::min(grid.rows - 1, si + esc) && !plan.reachable_; ++i)
      for (int j = std::max(0, sj - esc); j <= std::min(grid.cols - 1, sj + esc); ++j)
        if (std::isfinite(through_free[static_cast<std::size_t>(i) * grid.cols + j])) {
          plan.reachable_ = true;
          break;
        }
  }
  if (!plan.reachable_) {
    plan.why_ = !seeded ? "the goal disc (" + Num(r.goal_radius_m) + " m round " + Num(r.goal_x) + "," + Num(r.goal_y) +
                              ") lies within " + Num(o.inscribed_radius_m) + " m of an obstacle"
                        : "no way from " + Num(r.start_x) + "," + Num(r.start_y) + " to within " + Num(r.goal_radius_m) +
                              " m of " + Num(r.goal_x) + "," + Num(r.goal_y) + " keeps the rover's centre " +
                              Num(o.inscribed_radius_m) + " m from every obstacle (" + std::to_string(costs.obstacles) +
                              " obstacle cells: rocks, keep-out zones, impassable prior)";
    return plan;
  }
  // The path: down the field, one neighbour at a time, to a cell of the disc.
  std::size_t k = s;
  plan.path_.push_back(plan.start_);
  for (std::size_t guard = 0; guard < n; ++guard) {
    const int i = static_cast<int>(k / static_cast<std::size_t>(grid.cols));
    const int j = static_cast<int>(k % static_cast<std::size_t>(grid.cols));
    std::size_t best = k;
    for (int di = -1; di <= 1; ++di)
      for (int dj = -1; dj <= 1; ++dj) {
        const int a = i + di, b = j + dj;
        if (a < 0 || b < 0 || a >= grid.rows || b >= grid.cols) continue;
        const std::size_t m = static_cast<std::size_t>(a) * grid.cols + b;
        if (plan.field_[m] < plan.field_[best]) best = m;
      }
    if (best == k) break;
    k = best;
    plan.path_.emplace_back(grid.CellCentreX(static_cast<int>(k) / grid.cols), grid.CellCentreY(static_cast<int>(k) % grid.cols));
  }
  plan.path_.push_back(plan.goal_);
  return plan;
}

GlobalPlan PlanOnSiteMap(const SiteMap& map, const PlanRequest& r, const PlannerOptions& o) {
  o.Validate();
  double x0 = std::min(r.start_x, r.goal_x), x1 = std::max(r.start_x, r.goal_x);
  double y0 = std::min(r.start_y, r.goal_y), y1 = std::max(r.start_y, r.goal_y);
  const double cell = map.Empty() ? 0.2 : map.cell_m();
  const auto cells = [&](double a0, double b0, double a1, double b1) {
    return ((a1 - a0) / cell + 1.0) * ((b1 - b0) / cell + 1.0);
  };
  double mx0, my0, mx1, my1;
  if (map.Bounds(&mx0, &my0, &mx1, &my1) &&
      cells(std::min(x0, mx0) - o.margin_m, std::min(y0, my0) - o.margin_m, std::max(x1, mx1) + o.margin_m,
            std::max(y1, my1) + o.margin_m) <= o.max_cells) {
    x0 = std::min(x0, mx0), y0 = std::min(y0, my0), x1 = std::max(x1, mx1), y1 = std::max(y1, my1);
  }
  x0 -= o.margin_m, y0 -= o.margin_m, x1 += o.margin_m, y1 += o.margin_m;
  if (cells(x0, y0, x1, y1) > o.max_cells)
    throw std::invalid_argument("planner: the goal is too far for the planning window (" + Num(x1 - x0) + " x " +
                                Num(y1 - y0) + " m at " + Num(cell) + " m cells is over max_cells " +
                                std::to_string(o.max_cells) + ")");
  if (map.Empty()) {
    const int i0 = static_cast<int>(std::floor(x0 / cell)), j0 = static_cast<int>(std::floor(y0 / cell));
    const int rows = static_cast<int>(std::floor(x1 / cell)) - i0 + 1, cols = static_cast<int>(std::floor(y1 / cell)) - j0 + 1;
    return PlanOnGrid(avoidance::Grid::Filled(i0 * cell, j0 * cell, cell, rows, cols, CellClass::kUnknown, 0.0f), r, o);
  }
  return PlanOnGrid(map.Window(x0, y0, x1, y1), r, o);
}

double GlobalPlan::path_length_m() const {
  double l = 0.0;
  for (std::size_t i = 1; i < path_.size(); ++i) l += (path_[i] - path_[i - 1]).norm();
  return l;
}

double GlobalPlan::DistanceAt(double x, double y) const {
  if (grid_.rows == 0) return std::hypot(goal_.x() - x, goal_.y() - y);
  const int k = grid_.IndexAt(x, y);
  if (k >= 0) return field_[static_cast<std::size_t>(k)];
  // Outside: the nearest border cell's value plus the way to it.
  const double cx = std::clamp(x, grid_.origin_x, grid_.origin_x + grid_.rows * grid_.cell_m - 1e-9);
  const double cy = std::clamp(y, grid_.origin_y, grid_.origin_y + grid_.cols * grid_.cell_m - 1e-9);
  return field_[static_cast<std::size_t>(grid_.IndexAt(cx, cy))] + std::hypot(x - cx, y - cy);
}

Eigen::Vector2d PointAlongPath(const std::vector<Eigen::Vector2d>& path, double along_m) {
  if (path.empty()) return Eigen::Vector2d::Zero();
  double along = 0.0;
  for (std::size_t i = 1; i < path.size(); ++i) {
    along += (path[i] - path[i - 1]).norm();
    if (along >= along_m) return path[i];
  }
  return path.back();
}

double GlobalPlan::WayHeading(double ahead_m) const {
  if (path_.size() < 2) return std::numeric_limits<double>::quiet_NaN();
  const Eigen::Vector2d d = PointAlongPath(path_, ahead_m) - start_;
  if (d.norm() < 1e-9) return std::numeric_limits<double>::quiet_NaN();
  return std::atan2(d.y(), d.x());
}

bool GlobalPlan::ObstacleAt(double x, double y) const {
  const int k = grid_.IndexAt(x, y);
  return k >= 0 && obstacle_[static_cast<std::size_t>(k)];
}

}  // namespace rover::planner
