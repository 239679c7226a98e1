#include "avoidance/goal_field.hpp"

#include <cmath>
#include <functional>
#include <queue>
#include <utility>

namespace rover::avoidance {

GoalField::GoalField(const Grid& grid, double goal_x, double goal_y, double clearance_m)
    : grid_(&grid), goal_x_(goal_x), goal_y_(goal_y) {
  const int rows = grid.rows, cols = grid.cols;
  const std::size_t n = static_cast<std::size_t>(rows) * static_cast<std::size_t>(cols);
  dist_.assign(n, kUnreachable);
  if (n == 0) return;
  // What a cell's length costs: near a hazard (within the clearance of an unsafe cluster),
  // caution (or a lone unsafe cell), else its length.
  std::vector<double> factor(n, 1.0);
  for (std::size_t k = 0; k < n; ++k)
    if (grid.state[k] == CellClass::kCaution || grid.state[k] == CellClass::kUnsafe) factor[k] = kCautionCost;
  const int r = static_cast<int>(std::ceil(clearance_m / grid.cell_m));
  const double r2 = clearance_m * clearance_m + 1e-9;
  for (int i = 0; i < rows; ++i) {
    for (int j = 0; j < cols; ++j) {
      if (grid.state[static_cast<std::size_t>(i) * cols + j] != CellClass::kUnsafe) continue;
      // A lone unsafe cell is more often stereo noise than a rock: a rock over the step
      // limit is wider than a cell, so it shows as a cluster. Lone cells still veto a step
      // that crosses them (arc voting); they just do not reroute the whole drive.
      int neighbours = 0;
      for (int di = -1; di <= 1; ++di)
        for (int dj = -1; dj <= 1; ++dj) {
          const int a = i + di, b = j + dj;
          if ((di || dj) && a >= 0 && b >= 0 && a < rows && b < cols &&
              grid.state[static_cast<std::size_t>(a) * cols + b] == CellClass::kUnsafe)
            ++neighbours;
        }
      if (neighbours < 2) continue;
      for (int di = -r; di <= r; ++di) {
        for (int dj = -r; dj <= r; ++dj) {
          const int a = i + di, b = j + dj;
          if (a < 0 || b < 0 || a >= rows || b >= cols) continue;
          if ((di * di + dj * dj) * grid.cell_m * grid.cell_m > r2) continue;
          factor[static_cast<std::size_t>(a) * cols + b] = kNearHazardCost;
        }
      }
    }
  }
  using Item = std::pair<double, std::size_t>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> open;
  auto seed = [&](std::size_t k, double d) {
    if (d >= dist_[k]) return;
    dist_[k] = d;
    open.push({d, k});
  };
  const int goal_cell = grid.IndexAt(goal_x, goal_y);
  if (goal_cell >= 0) {
    seed(static_cast<std::size_t>(goal_cell), 0.0);
  } else {
    for (int i = 0; i < rows; ++i) {
      for (int j = 0; j < cols; ++j) {
        if (i != 0 && j != 0 && i != rows - 1 && j != cols - 1) continue;
        seed(static_cast<std::size_t>(i) * cols + j,
             std::hypot(goal_x - grid.CellCentreX(i), goal_y - grid.CellCentreY(j)));
      }
    }
  }
  const double diagonal = grid.cell_m * std::sqrt(2.0);
  while (!open.empty()) {
    const auto [d, k] = open.top();
    open.pop();
    if (d > dist_[k]) continue;
    const int i = static_cast<int>(k) / cols, j = static_cast<int>(k) % cols;
    for (int di = -1; di <= 1; ++di) {
      for (int dj = -1; dj <= 1; ++dj) {
        if (di == 0 && dj == 0) continue;
        const int a = i + di, b = j + dj;
        if (a < 0 || b < 0 || a >= rows || b >= cols) continue;
        // The step's cost: half its length in each cell, each at that cell's factor.
        const std::size_t next = static_cast<std::size_t>(a) * cols + b;
        const double length = di != 0 && dj != 0 ? diagonal : grid.cell_m;
        const double cost = 0.5 * length * (factor[k] + factor[next]);
        seed(next, d + cost);
      }
    }
  }
}

double GoalField::DistanceAt(double x, double y) const {
  const int k = grid_->IndexAt(x, y);
  if (k < 0) return std::hypot(goal_x_ - x, goal_y_ - y);
  return dist_[static_cast<std::size_t>(k)];
}

}  // namespace rover::avoidance
