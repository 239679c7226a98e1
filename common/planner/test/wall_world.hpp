// The planner tests' wall world: open ground 30 x 30 m with a wall of rocks across
// x = 4..4.6, gaps of 2.4 m at the listed y, and requests to a goal beyond it at (9, 0).
#pragma once

#include "planner/global_planner.hpp"

#include <cmath>
#include <cstddef>
#include <vector>

namespace rover::planner::test {

// The wall runs out to |y| = half_length (the whole grid by default).
inline avoidance::Grid WallWithGaps(const std::vector<double>& gaps_y, double half_length = 100.0) {
  using avoidance::CellClass;
  avoidance::Grid g = avoidance::Grid::Filled(-10, -15, 0.2, 150, 150, CellClass::kSafe, 0.9f);
  for (int i = 0; i < g.rows; ++i)
    for (int j = 0; j < g.cols; ++j) {
      const double x = g.CellCentreX(i), y = g.CellCentreY(j);
      bool in_gap = false;
      for (double gy : gaps_y) in_gap = in_gap || std::abs(y - gy) < 1.2;
      if (x >= 4.0 && x <= 4.6 && !in_gap && std::abs(y) < half_length)
        g.state[static_cast<std::size_t>(i) * g.cols + j] = CellClass::kUnsafe;
    }
  return g;
}

// From (x, y) to the 0.5 m disc round (9, 0).
inline PlanRequest ToTheGoalFrom(double x, double y) {
  PlanRequest r;
  r.start_x = x, r.start_y = y;
  r.goal_x = 9.0, r.goal_y = 0.0;
  r.goal_radius_m = 0.5;
  return r;
}

}  // namespace rover::planner::test
