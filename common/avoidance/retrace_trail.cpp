#include "avoidance/retrace_trail.hpp"

namespace rover::avoidance {

void RetraceTrail::Driven(bool is_arc, double distance_m, double curvature_per_m) {
  if (is_arc && distance_m > 0.0) {
    if (arcs_.size() == kMaxArcs) arcs_.pop_front();
    arcs_.push_back({distance_m, curvature_per_m});
    return;
  }
  // A backup along the last arc: its curvature, no longer than what is left of it.
  constexpr double kSlack = 1e-9;
  const bool retraces = is_arc && distance_m < 0.0 && !arcs_.empty() &&
                        curvature_per_m == arcs_.back().curvature_per_m &&
                        -distance_m <= arcs_.back().length_m + kSlack;
  if (!retraces) {
    arcs_.clear();
    return;
  }
  arcs_.back().length_m += distance_m;
  if (arcs_.back().length_m <= 1e-6) arcs_.pop_back();
}

}  // namespace rover::avoidance
