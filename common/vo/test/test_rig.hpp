// Stereo rigs for the VO tests, built from the project's pinhole model
// (geometry/pinhole_camera.hpp): reference frame = left camera (x right, y down,
// z forward), right camera at +baseline along x.
#pragma once

#include "geometry/pinhole_camera.hpp"

#include <memory>

namespace rover::vo::test {

inline geometry::StereoRig MakeRig(int w, int h, double f, double cx, double cy, double baseline) {
  geometry::StereoRig rig;
  rig.left = std::make_shared<geometry::PinholeCamera>(w, h, f, f, cx, cy);
  Eigen::Isometry3d T_ref_right = Eigen::Isometry3d::Identity();
  T_ref_right.translation() = Eigen::Vector3d(baseline, 0, 0);
  rig.right = std::make_shared<geometry::PinholeCamera>(w, h, f, f, cx, cy, std::vector<double>{},
                                                        T_ref_right);
  return rig;
}

}  // namespace rover::vo::test
