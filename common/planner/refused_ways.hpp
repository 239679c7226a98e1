// Ways the local check refused. The global plan is drawn over the map's ratings; arc voting
// judges each step more closely (the swept body, ground never seen, the monitor's check).
// Where they disagree, the plan keeps leading the rover to a spot from which no step on is
// allowed: it backs up, the plan (unchanged) leads it forward to the same spot, and so on
// until a limit stops the goto (navbench k = 0.20: 300 steps round one spot). So the
// executor tells the planner where it was refused, and the planner remembers it: each
// refusal makes the ground the plan led to (the point ahead_m down its path) cost
// cost_per_m more per metre within radius_m, added up where refusals overlap, for the rest
// of the goto. After a refusal or two the way round is the cheaper one. A cost, never an
// obstacle: it shuts no way, so it cannot make a goal unreachable that is not, and it
// never makes any ground (unknown ground included) cheaper than it was. Knows nothing of LCM.
#pragma once

#include "planner/global_planner.hpp"

#include <optional>
#include <vector>

namespace rover::planner {

struct RefusalOptions {
  double cost_per_m = 10.0;  // each refusal adds this per metre (0: refusals are not remembered)
  double ahead_m = 1.0;      // the ground refused: this far down the plan's path ...
  double radius_m = 0.6;     // ... a disc this wide
  int max_refusals = 100;    // at most this many remembered in one goto

  // Throws std::invalid_argument naming the field.
  void Validate() const;
};

class RefusedWays {
 public:
  explicit RefusedWays(const RefusalOptions& options = {});
  // A new goto or a new site frame: nothing refused.
  void Reset();
  // The local check refused the way `plan` leads from its start: the disc remembered, or
  // nothing (off, no path, or max_refusals reached).
  std::optional<CostlyDisc> Refuse(const GlobalPlan& plan);
  // The refusals, as extra costs for the planner (PlanRequest::costly).
  const std::vector<CostlyDisc>& discs() const { return discs_; }

 private:
  RefusalOptions options_;
  std::vector<CostlyDisc> discs_;
};

}  // namespace rover::planner
