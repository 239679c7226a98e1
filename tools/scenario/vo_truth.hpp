// VO updates of a recorded run against the simulator's truth: the true motion between the
// two capture times, the error of VO's delta, and its NEES against VO's own covariance, so
// that a summary can say whether VO ever made a false (over-confident) update.
#pragma once

#include <Eigen/Geometry>
#include <rover_msgs/sim_truth_t.hpp>
#include <rover_msgs/vo_update_t.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace rover::tools {

// chi-square with 6 degrees of freedom at 99.73 % (the tail mass of 3 sigma in 1-D).
constexpr double kChi2Dof6ThreeSigma = 20.06;

using Vector6 = Eigen::Matrix<double, 6, 1>;
using Matrix6 = Eigen::Matrix<double, 6, 6>;

// The true T_site_rover at `utime`, interpolated between the two samples around it
// (position linearly, orientation by slerp). Empty outside the samples' time span.
// `truth` must be sorted by utime.
std::optional<Eigen::Isometry3d> TruthPoseAt(const std::vector<rover_msgs::sim_truth_t>& truth,
                                             std::int64_t utime);

// The error of an estimated motion against the truth in the covariance's order (x y z roll
// pitch yaw): difference of translations and of wrapped roll, pitch, yaw (the definition
// `vo_eval` uses).
Vector6 MotionError(const Eigen::Isometry3d& truth, const Eigen::Isometry3d& estimate);
// e' C^-1 e; empty when C is not positive definite.
std::optional<double> Nees(const Vector6& error, const Matrix6& covariance);

struct VoCheck {
  std::int64_t utime = 0;
  int status = -1;
  std::string reason;
  std::int64_t from_frame_id = -1, to_frame_id = -1;
  std::int64_t from_utime = 0, to_utime = 0;
  bool accepted = false;               // status OK: the delta and covariance are given
  Vector6 delta = Vector6::Zero();     // x y z roll pitch yaw of VO's T_from_to
  Matrix6 covariance = Matrix6::Zero();
  std::optional<Vector6> true_delta;   // from truth at the two capture times
  std::optional<double> nees;          // accepted, with truth and a usable covariance
  bool false_update() const { return nees && *nees > kChi2Dof6ThreeSigma; }
};

VoCheck CheckVoUpdate(const rover_msgs::vo_update_t& update,
                      const std::vector<rover_msgs::sim_truth_t>& truth);

}  // namespace rover::tools
