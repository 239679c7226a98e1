// The rover computer's own compute time, charged in rover time (README, "Simulated time").
//
// In simulation the work a step needs (taking a stereo pair, VO, the traversability map,
// choosing an arc) costs rover time as it would on the rover's computer, from a profile,
// never from how fast or how busy this machine is: a result is published at the rover time
// its input came plus the profile's figure. On a real rover (real clock) nothing is charged:
// the work takes the time it takes.
//
// Profiles (`compute.profile`; single figures may be overridden by key):
//   instant   0 for everything (the algorithms' answers at the instant they were asked)
//   embedded  a modern embedded computer (a few ARM cores): capture 0.5 s, VO 1 s,
//             map 1.5 s (a HAZCAM pair 0.5 s), planning 0.5 s
//   mer       MER's 20 MHz RAD6000: "each step required two to three minutes of
//             computation time" for VO (Cheng, Maimone and Matthies 2005). The map and
//             planning figures are this project's assumption of the same order:
//             capture 20 s, VO 150 s, map 120 s (a HAZCAM pair 40 s), planning 30 s
// A HAZCAM pair costs a third of a NAVCAM pair: hazard_monitor's own settings match it at
// 444x256 with 64 disparities against 512x512 with 96 (SGBM's work is pixels x disparities).
#pragma once

#include <string>

namespace rover::simtime {

struct ComputeProfile {
  std::string name = "embedded";
  double capture_s = 0.5;   // a stereo pair: expose, read out, compress
  double vo_s = 1.0;        // one VO update
  double map_s = 1.5;       // one pair into the traversability map
  double hazcam_map_s = 0.5;  // one front HAZCAM pair (256x256) into the map
  double plan_s = 0.5;      // one arc vote (goto ... avoid on)
};

// A named profile; throws std::invalid_argument naming the known ones.
ComputeProfile NamedProfile(const std::string& name);
// The names, for error lines.
const char* ProfileNames();

}  // namespace rover::simtime
