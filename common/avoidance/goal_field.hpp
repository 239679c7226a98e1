// The distance to the goal round the hazards the map knows: a Dijkstra field over the
// traversability grid, from the goal (or, when the goal lies beyond the grid, from every
// border cell at its straight-line distance to the goal). Arc voting's goal vote alone
// is local: in front of a wall it cannot tell the end that leads on from the end that
// does not, and a rover can wander along the wall the wrong way. MER added this kind of
// global guidance to GESTALT (Field D*, 2006); the grid here is small (60 x 60 cells), so a
// plain Dijkstra over it each step costs well under a millisecond.
//
// Cells whose centre lies within `clearance_m` of an unsafe cell's centre (the rover's half
// width: its centre should not pass there), for unsafe cells with at least two unsafe
// neighbours (a rock; a lone cell is more often stereo noise), cost kNearHazardCost times
// their length. They are dear, not forbidden: the field is then defined everywhere, so a
// rover that stands in such a cell (squeezing through a gap, the map having grown a rock's
// edge since the last step) or a goal beside a rock still has a way that leads on, rather
// than an unreachable goal leaving the vote to wander. Arc voting's veto, not the field,
// keeps the footprint off unsafe cells. Caution cells (and lone unsafe ones) cost
// kCautionCost times their length: the map often rates a rock caution from afar and
// unsafe only up close (it sees the rock's face, not its back), so a wall of caution is
// gone round where the ground is clear rather than aimed at. Unknown cells are free: the
// map only knows what the cameras saw, and the goal is usually beyond that.
#pragma once

#include "avoidance/grid.hpp"

#include <limits>
#include <vector>

namespace rover::avoidance {

// What the goal vote measures progress with: the distance (or cost) still to go from a
// point. GoalField is the local one; the global planner's cost-to-go field
// (common/planner) is the other.
class GoalDistance {
 public:
  virtual ~GoalDistance() = default;
  // +infinity where the goal cannot be reached from (x, y).
  virtual double DistanceAt(double x, double y) const = 0;
};

class GoalField final : public GoalDistance {
 public:
  GoalField(const Grid& grid, double goal_x, double goal_y, double clearance_m);
  // Path distance from (x, y) to the goal: through the grid where the point is on it,
  // the straight line where it is not.
  double DistanceAt(double x, double y) const override;
  static constexpr double kUnreachable = std::numeric_limits<double>::infinity();
  // A cell near a hazard costs this many times its length (a way round of up to that
  // many times the length through is preferred).
  static constexpr double kNearHazardCost = 5.0;
  static constexpr double kCautionCost = 3.0;

 private:
  const Grid* grid_;
  double goal_x_, goal_y_;
  std::vector<double> dist_;  // per cell
};

}  // namespace rover::avoidance
