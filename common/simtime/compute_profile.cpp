#include "simtime/compute_profile.hpp"

#include <stdexcept>

namespace rover::simtime {

const char* ProfileNames() { return "instant, embedded, mer"; }

ComputeProfile NamedProfile(const std::string& name) {
  ComputeProfile p;
  p.name = name;
  if (name == "instant") {
    p.capture_s = p.vo_s = p.map_s = p.hazcam_map_s = p.plan_s = 0.0;
  } else if (name == "embedded") {
    p.capture_s = 0.5, p.vo_s = 1.0, p.map_s = 1.5, p.hazcam_map_s = 0.5, p.plan_s = 0.5;
  } else if (name == "mer") {
    p.capture_s = 20.0, p.vo_s = 150.0, p.map_s = 120.0, p.hazcam_map_s = 40.0, p.plan_s = 30.0;
  } else {
    throw std::invalid_argument("unknown compute profile '" + name + "' (expected one of: " +
                                ProfileNames() + ")");
  }
  return p;
}

}  // namespace rover::simtime
