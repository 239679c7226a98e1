#include "avoidance/tops_over_ground.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <vector>

namespace rover::avoidance {
namespace {

constexpr int kMinGroundCells = 6;
constexpr int kMaxFits = 5;

struct Neighbour {
  double dx, dy, z;
};

// The known heights within radius_m of cell (i, j), as offsets from its centre.
std::vector<Neighbour> HeightsAround(const Grid& g, int i, int j, double radius_m) {
  const int n = static_cast<int>(std::floor(radius_m / g.cell_m));
  std::vector<Neighbour> out;
  for (int di = -n; di <= n; ++di)
    for (int dj = -n; dj <= n; ++dj) {
      const int a = i + di, b = j + dj;
      if (a < 0 || b < 0 || a >= g.rows || b >= g.cols) continue;
      const double dx = di * g.cell_m, dy = dj * g.cell_m;
      if (dx * dx + dy * dy > radius_m * radius_m + 1e-9) continue;
      const std::size_t k = static_cast<std::size_t>(a) * g.cols + b;
      if (g.sigma_m[k] < 0.0f) continue;
      out.push_back({dx, dy, g.elevation_m[k]});
    }
  return out;
}

// The plane z = c0 + c1 dx + c2 dy through the ground among `cells`: fitted to all, then
// again to those not more than band_m above the last fit. Its height at the centre (c0),
// or NaN when too few cells are left to fit.
double GroundAtCentre(const std::vector<Neighbour>& cells, double band_m) {
  std::vector<char> use(cells.size(), 1);
  double ground = std::nan("");
  for (int fit = 0; fit < kMaxFits; ++fit) {
    Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
    Eigen::Vector3d atb = Eigen::Vector3d::Zero();
    int used = 0;
    for (std::size_t k = 0; k < cells.size(); ++k) {
      if (!use[k]) continue;
      const Eigen::Vector3d a(1.0, cells[k].dx, cells[k].dy);
      ata += a * a.transpose();
      atb += a * cells[k].z;
      ++used;
    }
    if (used < kMinGroundCells) return std::nan("");
    const Eigen::Vector3d c = ata.ldlt().solve(atb);
    ground = c(0);
    bool changed = false;
    for (std::size_t k = 0; k < cells.size(); ++k) {
      const char keep = cells[k].z - (c(0) + c(1) * cells[k].dx + c(2) * cells[k].dy) <= band_m;
      changed |= keep != use[k];
      use[k] = keep;
    }
    if (!changed) break;
  }
  return ground;
}

}  // namespace

double TopOverGround(const Grid& grid, int k, double radius_m, double band_m) {
  if (!grid.HasHeights() || k < 0 || grid.sigma_m[k] < 0.0f) return -1.0;
  const double ground = GroundAtCentre(HeightsAround(grid, k / grid.cols, k % grid.cols, radius_m), band_m);
  if (!std::isfinite(ground)) return -1.0;
  return std::max(0.0, grid.elevation_m[k] - ground);
}

int MarkTopsOverGround(Grid* grid, double radius_m, double min_rise_m) {
  if (!grid->HasHeights() || radius_m <= 0.0 || min_rise_m <= 0.0) return 0;
  // Judged on the heights as they came: marking changes ratings, never heights.
  std::vector<std::pair<std::size_t, float>> marked;
  for (int k = 0; k < grid->rows * grid->cols; ++k) {
    const CellClass s = grid->state[k];
    if (s != CellClass::kSafe && s != CellClass::kCaution) continue;
    const double rise = TopOverGround(*grid, k, radius_m, kTopGroundBandFraction * min_rise_m);
    if (rise >= min_rise_m) marked.push_back({static_cast<std::size_t>(k), static_cast<float>(rise)});
  }
  for (const auto& [k, rise] : marked) {
    grid->state[k] = CellClass::kUnsafe;
    grid->goodness[k] = 0.0f;
    grid->step_m[k] = std::max(grid->step_m[k], rise);
  }
  return static_cast<int>(marked.size());
}

}  // namespace rover::avoidance
