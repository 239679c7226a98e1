// Where to point the mast before a goto's next step: the ground beside the rover that a turn
// in place would sweep and no view from here has framed. The mast cameras look ahead and the
// body-fixed HAZCAM sees nothing behind the body's front face, so a rock wholly beside the
// view stays unknown (or, worse, is rated from the ground round it) until the body turns
// onto it. MER's NAVCAM sat on a pan-tilt mast and imaged whatever the drive needed; here,
// when the vote has no step on but backing up, the executor points the NAVCAM at the side
// whose ground is unknown, maps it and votes again (common/sequence/avoid_step.cpp).
// Knows nothing of LCM.
#pragma once

#include "avoidance/grid.hpp"

namespace rover::avoidance {

// Unknown cells round the rover, by where the mast would have to look to see them:
//   - left, right: within the disc a whole turn in place of `footprint` at `pose` sweeps
//     (the same disc as Grid::MarkTurnKnown), bearing from the heading between
//     min_bearing_rad and pi - min_bearing_rad;
//   - behind: bearing beyond pi - min_bearing_rad, out to that disc plus `behind_reach_m`
//     (the ground a back-up would cross).
// The ground ahead is the mast's own view.
struct UnknownBeside {
  int left = 0, right = 0, behind = 0;
};
UnknownBeside CountUnknownBeside(const Grid& grid, const Footprint& footprint, const Pose2& pose,
                                 double behind_reach_m = 0.0, double min_bearing_rad = 0.5);

}  // namespace rover::avoidance
