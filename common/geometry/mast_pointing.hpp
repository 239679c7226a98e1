// Pointing a mast-mounted stereo pair (pan and tilt), as capture_request_t asks.
//
// The rig's models as mounted (its rig file) are the head at pan 0, tilt 0. The head
// turns about two axes through the pivot m, the midpoint of the two camera centres:
//   tilt about the camera bar b (the unit vector from the left centre to the right one,
//        projected on the rover's horizontal XY plane); + = further down;
//   pan  about the vertical through m; + = toward the rover's right (rover frame X
//        forward, Y right, Z down, so + turns +X toward +Y: a right-handed turn about +Z).
// The pan carries the tilt axis with it (the tilt joint sits on the pan joint), so
//   T = Translate(m) * Rz(pan) * R_b(-tilt) * Translate(-m).
// R_b(-tilt): a right-handed turn about b = +Y (a rig looking along +X) by +angle lifts
// +X toward -Z, up; down is the negative turn.
#pragma once

#include "geometry/camera_model.hpp"

namespace rover::geometry {

// The rigid motion of the rover frame that points the head (see above). Throws
// std::invalid_argument on a non-finite angle, or a bar with no horizontal extent (a
// vertical baseline has no tilt axis).
Eigen::Isometry3d MastPointingMotion(const StereoRig& rig, double pan_rad, double tilt_rad);

// The rig after pointing: both models Moved by MastPointingMotion; any other field of
// the rig as given. Pan 0 and tilt 0 return the rig itself (the same models).
StereoRig PointedRig(const StereoRig& rig, double pan_rad, double tilt_rad);

}  // namespace rover::geometry
