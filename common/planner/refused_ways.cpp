#include "planner/refused_ways.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace rover::planner {

void RefusalOptions::Validate() const {
  auto check = [](bool ok, const char* what, double v) {
    if (!ok) throw std::invalid_argument(std::string("refused ways: ") + what + ", got " + std::to_string(v));
  };
  check(cost_per_m >= 0.0 && std::isfinite(cost_per_m), "cost_per_m must be >= 0", cost_per_m);
  check(ahead_m > 0.0 && std::isfinite(ahead_m), "ahead_m must be > 0", ahead_m);
  check(radius_m > 0.0 && std::isfinite(radius_m), "radius_m must be > 0", radius_m);
  check(max_refusals >= 0, "max_refusals must be >= 0", max_refusals);
}

RefusedWays::RefusedWays(const RefusalOptions& options) : options_(options) { options_.Validate(); }

void RefusedWays::Reset() { discs_.clear(); }

std::optional<CostlyDisc> RefusedWays::Refuse(const GlobalPlan& plan) {
  if (options_.cost_per_m <= 0.0 || !plan.reachable() || plan.path().size() < 2 ||
      static_cast<int>(discs_.size()) >= options_.max_refusals)
    return std::nullopt;
  CostlyDisc d;
  d.center = PointAlongPath(plan.path(), options_.ahead_m);
  d.radius_m = options_.radius_m;
  d.cost_per_m = options_.cost_per_m;
  discs_.push_back(d);
  return d;
}

}  // namespace rover::planner
