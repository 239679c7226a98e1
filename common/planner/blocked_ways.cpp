#include "planner/blocked_ways.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace rover::planner {

void BlockOptions::Validate() const {
  auto positive = [](double v, const char* name) {
    if (!(v > 0.0) || !std::isfinite(v))
      throw std::invalid_argument(std::string("blocked ways: ") + name + " " + std::to_string(v) + " must be > 0");
  };
  if (stall_steps < 0) throw std::invalid_argument("blocked ways: stall_steps must be >= 0");
  if (max_blocks < 0) throw std::invalid_argument("blocked ways: max_blocks must be >= 0");
  positive(min_gain_m, "min_gain_m");
  positive(ahead_m, "ahead_m");
  positive(radius_m, "radius_m");
  positive(new_way_m, "new_way_m");
}

BlockedWays::BlockedWays(const BlockOptions& options) : options_(options) { options_.Validate(); }

void BlockedWays::Reset() {
  best_ = std::numeric_limits<double>::infinity();
  stalled_ = 0;
  refusals_ = 0;
  zones_.clear();
}

bool BlockedWays::Update(const GlobalPlan& plan, std::size_t refusals) {
  const bool refused = refusals > refusals_;
  refusals_ = refusals;
  if (options_.stall_steps == 0 || !plan.reachable()) return false;
  const double cost = plan.cost_at_start();
  if (!std::isfinite(cost)) return false;
  if (cost < best_ - options_.min_gain_m || (!refused && cost > best_ + options_.new_way_m)) {
    best_ = cost;
    stalled_ = 0;
    return false;
  }
  if (refused) best_ = cost;  // no progress, and no new way: counted on from the dearer plan
  if (++stalled_ < options_.stall_steps || static_cast<int>(zones_.size()) >= options_.max_blocks) return false;
  // The point ahead_m down the path (the goal itself when the path is shorter).
  const auto& path = plan.path();
  if (path.size() < 2) return false;
  const Eigen::Vector2d at = PointAlongPath(path, options_.ahead_m);
  zones_.push_back(hazards::KeepOutZone::Circle("blocked_way_" + std::to_string(zones_.size() + 1), at.x(), at.y(),
                                                options_.radius_m));
  best_ = std::numeric_limits<double>::infinity();
  stalled_ = 0;
  return true;
}

}  // namespace rover::planner
