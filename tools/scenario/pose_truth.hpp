// The state estimator's POSE of a recorded run against the simulator's truth: is the sigma it
// claims honest? A goto ends inside its disc by the estimate less 3 of its sigmas, and the
// hazard monitor grows keep-out zones by them, so a sigma too small puts the rover outside
// the disc or into a zone in truth while the estimate says all is well.
#pragma once

#include <rover_msgs/pose_t.hpp>
#include <rover_msgs/sim_truth_t.hpp>

#include <optional>
#include <vector>

namespace rover::tools {

// chi-square at 99.73 % (3 sigma in 1-D) with 1 and 2 degrees of freedom.
constexpr double kChi2Dof1ThreeSigma = 9.0;
constexpr double kChi2Dof2ThreeSigma = 11.83;

struct PoseHonesty {
  int poses = 0;                    // POSE messages judged
  double heading_nees_mean = 0;     // e^2 / sigma^2 of the heading: 1 is honest
  double heading_beyond_pct = 0;    // share beyond kChi2Dof1ThreeSigma (0.27 % is honest)
  int horizontal_poses = 0;         // of them, with a horizontal covariance to judge
  double horizontal_nees_mean = 0;  // e' C^-1 e of x, y: 2 is honest
  double horizontal_beyond_pct = 0; // share beyond kChi2Dof2ThreeSigma
  // The last judged horizontal pose: its claimed 3-sigma (3 x the square root of the
  // horizontal covariance's largest eigenvalue, as a goto's disc and the keep-out zones
  // use it) and its true horizontal error.
  double final_horizontal_3sigma_m = 0;
  double final_horizontal_error_m = 0;
};

// Every POSE of site 0 (the truth's frame) with a heading variance, against the truth
// interpolated at its utime. Empty when no pose could be judged. `truth` sorted by utime.
std::optional<PoseHonesty> JudgePoses(const std::vector<rover_msgs::pose_t>& poses,
                                      const std::vector<rover_msgs::sim_truth_t>& truth);

}  // namespace rover::tools
