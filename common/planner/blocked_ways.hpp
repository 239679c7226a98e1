// Ways the rover could not follow. The global plan is drawn over the map's ratings; arc
// voting, which must drive it, judges every step more closely (the swept body, ground it
// has not seen, the monitor's check). Where the two disagree (a gap the plan fits through
// and no step will cross, a pocket's mouth rated passable and a wall behind it) the rover
// votes step after step toward a way it never takes: back and forth, round in circles,
// until a limit stops it. So the executor watches the plan's cost to go from the rover:
// when it has not fallen by min_gain_m in stall_steps steps, the way the plan leads (the
// point ahead_m down its path) is marked blocked, a disc of radius_m that the planner
// treats as an obstacle, like a keep-out zone, and the next plan goes another way. When
// every way is blocked the plan says the goal is unreachable, and the goto ends so
// (goal_unreachable), rather than on a time or distance limit. Knows nothing of LCM.
#pragma once

#include "hazards/keepout.hpp"
#include "planner/global_planner.hpp"

#include <cstddef>
#include <limits>
#include <vector>

namespace rover::planner {

struct BlockOptions {
  int stall_steps = 20;      // steps without progress before the way is blocked (0: never)
  double min_gain_m = 0.5;   // progress: the cost to go falling by this much
  double ahead_m = 1.5;      // the way blocked: this far down the plan's path
  double radius_m = 0.4;     // the disc blocked (the planner keeps the rover's centre off it)
  // A plan whose cost to go jumps by this much over the best so far is a new way (the map
  // found the old one longer): progress is counted afresh.
  double new_way_m = 3.0;
  int max_blocks = 10;       // at most this many ways blocked in one goto

  // Throws std::invalid_argument naming the field.
  void Validate() const;
};

class BlockedWays {
 public:
  explicit BlockedWays(const BlockOptions& options = {});
  // A new goto: nothing blocked.
  void Reset();
  // After each plan from the rover's position: its cost to go there (plan.cost_at_start()),
  // and how many refused ways (refused_ways.hpp) the goto has so far. A refusal makes the
  // way it refused dearer, and that rise is neither progress nor a new way: the count goes
  // on, measured from the dearer plan. Counted as a new way, each refusal restarted it
  // (keepout_avoid's variants: the cost crept from 9.9 to 42 over 60 steps of dithering,
  // and 10 steps never passed without such a rise). Returns true when the way was blocked
  // now (zones() has a new disc: plan again).
  bool Update(const GlobalPlan& plan, std::size_t refusals = 0);
  // The blocked ways, as obstacles for the planner (PlanRequest::zones).
  const std::vector<hazards::KeepOutZone>& zones() const { return zones_; }
  int stalled_steps() const { return stalled_; }

 private:
  BlockOptions options_;
  double best_ = std::numeric_limits<double>::infinity();
  int stalled_ = 0;
  std::size_t refusals_ = 0;
  std::vector<hazards::KeepOutZone> zones_;
};

}  // namespace rover::planner
