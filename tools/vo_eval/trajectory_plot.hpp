// The estimated and true trajectories seen from above, drawn by gnuplot (Debian
// gnuplot-nox, as for ./rover plot) and returned as an image.
#pragma once

#include "vo_eval/trajectory_metrics.hpp"

#include <opencv2/core.hpp>

#include <string>

namespace rover::vo_eval {

struct TopViewOptions {
  // Gravity and the initial heading in the poses' world frame. The defaults fit KITTI
  // (camera frame: y down, z forward). The view's horizontal axis is down x forward
  // (to the right), its vertical axis is forward.
  Eigen::Vector3d down = Eigen::Vector3d::UnitY();
  Eigen::Vector3d forward = Eigen::Vector3d::UnitZ();
  int size_px = 800;
  std::string title;
};

// Truth may be empty. Equal scale on both axes, a grid with labels, a legend below.
// Throws std::invalid_argument if down and forward are parallel, std::runtime_error when
// gnuplot cannot be run or fails.
cv::Mat DrawTopView(const PoseList& truth, const PoseList& estimate,
                    const TopViewOptions& options = {});

// A "nice" grid spacing (1, 2 or 5 x 10^n) giving about `target_lines` lines over `range`.
double GridSpacing(double range, int target_lines = 6);

}  // namespace rover::vo_eval
