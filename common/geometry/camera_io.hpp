// Camera models and stereo rigs from YAML (configs/cameras/*.yaml).
//
// A camera node:
//   type: pinhole | cahv | cahvor | cahvore
//   width: 1024            # pixels
//   height: 1024
//   # pinhole:
//   fx: 1236.1             # focal lengths, px
//   fy: 1236.1
//   cx: 511.5              # principal point, px; (0,0) is the centre of the top-left pixel
//   cy: 511.5
//   distortion: [k1, k2, p1, p2, k3]   # optional, OpenCV order, 4 or 5 numbers
//   position: [x, y, z]    # optional camera centre in the reference frame, m (default 0)
//   # orientation, optional, at most one of:
//   rpy_deg: [roll, pitch, yaw]   # camera BODY axes (x along the optical axis, y right,
//                                 # z down: the rover convention) in the reference frame,
//                                 # R = Rz(yaw) Ry(pitch) Rx(roll); all zero = looking along
//                                 # reference +X. A NAVCAM tilted 35 deg down has pitch -35.
//   quaternion_wxyz: [w, x, y, z] # or the OPTICAL frame (x right, y down, z forward) itself,
//                                 # R_ref_cam; normalised on load
//   # default orientation: optical frame = reference frame
//   # cahv / cahvor:
//   C: [..]  A: [..]  H: [..]  V: [..]     # as in the label, used as given
//   O: [..]  R: [r0, r1, r2]               # cahvor and cahvore
//   E: [e0, e1, e2]  linearity: L           # cahvore only; L = 1, 0 or P for T = 1, 2, 3
//
// A stereo rig node has exactly the keys `left` and `right`, each a camera node in one
// shared reference frame.
//
// Errors are rover::config::ConfigError with the one-line "file: key: expected ..." text.
#pragma once

#include "config/yaml_config.hpp"
#include "geometry/camera_model.hpp"

#include <memory>
#include <string>

namespace rover::geometry {

std::unique_ptr<CameraModel> LoadCameraModel(const config::ConfigNode& node);
StereoRig LoadStereoRig(const config::ConfigNode& node);
// LoadStereoRig on a whole file.
StereoRig LoadStereoRigFile(const std::string& path);

// R_body_optical: the optical frame (x right, y down, z forward) in body axes (x forward,
// y right, z down).
Eigen::Matrix3d BodyFromOptical();

}  // namespace rover::geometry
