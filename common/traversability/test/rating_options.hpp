// The rating options hazard_monitor runs the map with (configs/rover.yaml,
// hazards.map.traversability) that the rating tests share.
#pragma once

#include "traversability/traversability_map.hpp"

namespace rover::traversability::test {

inline MapOptions MonitorRatingOptions() {
  MapOptions o;
  o.footprint_radius_m = 0.3;
  o.tilt_radius_m = 0.75;
  o.max_step_m = 0.25;
  o.max_tilt_deg = 32.0;
  o.max_roughness_m = 0.08;
  o.tilt_margin_sigmas = 1.0;
  o.dip_margin_sigmas = 2.0;
  o.roughness_margin_sigmas = 2.0;
  return o;
}

}  // namespace rover::traversability::test
