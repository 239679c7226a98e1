#include "scenario/pose_truth.hpp"

#include "geometry/pose.hpp"
#include "scenario/vo_truth.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>

namespace rover::tools {

std::optional<PoseHonesty> JudgePoses(const std::vector<rover_msgs::pose_t>& poses,
                                      const std::vector<rover_msgs::sim_truth_t>& truth) {
  PoseHonesty h;
  double heading_sum = 0, horizontal_sum = 0;
  int heading_beyond = 0, horizontal_beyond = 0;
  for (const auto& p : poses) {
    if (p.site_index != 0) continue;
    const double yaw_var = p.covariance[5][5];
    if (!(yaw_var > 0) || !std::isfinite(yaw_var)) continue;
    const std::optional<Eigen::Isometry3d> t = TruthPoseAt(truth, p.utime);
    if (!t) continue;
    const Eigen::Quaterniond q(p.orientation[0], p.orientation[1], p.orientation[2], p.orientation[3]);
    const double yaw_est = geometry::RpyFromRotation(q.normalized().toRotationMatrix()).z();
    const double yaw_true = geometry::RpyFromRotation(t->linear()).z();
    const double e_yaw = geometry::WrapAngle(yaw_est - yaw_true);
    const double n_yaw = e_yaw * e_yaw / yaw_var;
    ++h.poses;
    heading_sum += n_yaw;
    heading_beyond += n_yaw > kChi2Dof1ThreeSigma;

    Eigen::Matrix2d C;
    C << p.covariance[0][0], p.covariance[0][1], p.covariance[1][0], p.covariance[1][1];
    const Eigen::Vector2d e(p.position[0] - t->translation().x(), p.position[1] - t->translation().y());
    Eigen::LLT<Eigen::Matrix2d> llt(0.5 * (C + C.transpose()));
    if (llt.info() != Eigen::Success || !(C.determinant() > 1e-18)) continue;
    const double n_xy = e.dot(llt.solve(e));
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(0.5 * (C + C.transpose()));
    h.final_horizontal_3sigma_m = 3.0 * std::sqrt(std::max(0.0, es.eigenvalues().maxCoeff()));
    h.final_horizontal_error_m = e.norm();
    ++h.horizontal_poses;
    horizontal_sum += n_xy;
    horizontal_beyond += n_xy > kChi2Dof2ThreeSigma;
  }
  if (h.poses == 0) return std::nullopt;
  h.heading_nees_mean = heading_sum / h.poses;
  h.heading_beyond_pct = 100.0 * heading_beyond / h.poses;
  if (h.horizontal_poses > 0) {
    h.horizontal_nees_mean = horizontal_sum / h.horizontal_poses;
    h.horizontal_beyond_pct = 100.0 * horizontal_beyond / h.horizontal_poses;
  }
  return h;
}

}  // namespace rover::tools
