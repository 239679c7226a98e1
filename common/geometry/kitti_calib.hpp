// KITTI odometry calib.txt: rectified stereo as two pinhole models.
//
// The file has lines "P0: p00 p01 ... p23" (12 numbers, a row-major 3x4 projection
// matrix) for each camera; P0/P1 are the rectified grey left/right cameras. Other lines
// (P2, P3, Tr) are ignored. The reference frame is the left camera frame (x right, y down,
// z forward); the right camera sits at +baseline along x, baseline = -P1[3] / P1[0].
#pragma once

#include "geometry/camera_model.hpp"

#include <string>

namespace rover::geometry {

// Throws std::runtime_error "path:line: message (expected ...)" on a malformed file, a
// non-rectified P0/P1 (non-zero skew or a P0 translation), or a non-positive baseline.
StereoRig LoadKittiCalib(const std::string& calib_txt_path, int image_width, int image_height);

}  // namespace rover::geometry
