// The motion prior VO searches around (VO-6): the motion between two frames' on-board
// poses, with an uncertainty wide enough for what wheel odometry gets wrong. On loose sand
// (Sol 206) slip passes 100 %, so the spread is a fraction of the motion, with a floor.
// Shared by the visual_odometry process and the plot tool's recomputed VO steps.
#pragma once

#include "config/yaml_config.hpp"

#include <Eigen/Geometry>

namespace rover::vo {

struct MotionPriorOptions {
  double translation_sigma_fraction = 0.6;
  double min_translation_sigma_m = 0.05;
  double rotation_sigma_fraction = 0.3;
  double min_rotation_sigma_deg = 2.0;
};

// Reads the four keys above from `section` (the `visual_odometry:` config section) with
// their ranges; other keys of the section are the caller's to check.
MotionPriorOptions LoadMotionPriorOptions(const config::ConfigNode& section);

// The prior's 6x6 covariance (x y z roll pitch yaw) for the prior motion `T_prev_curr`:
// isotropic sigmas of max(floor, fraction x the motion's size).
Eigen::Matrix<double, 6, 6> MotionPriorCovariance(const Eigen::Isometry3d& T_prev_curr,
                                                  const MotionPriorOptions& options);

}  // namespace rover::vo
