#include "scenario/vo_truth.hpp"

#include "geometry/pose.hpp"

#include <algorithm>

namespace rover::tools {

namespace {

Eigen::Isometry3d TruthPose(const rover_msgs::sim_truth_t& t) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Quaterniond(t.orientation[0], t.orientation[1], t.orientation[2], t.orientation[3])
                   .normalized()
                   .toRotationMatrix();
  T.translation() = Eigen::Vector3d(t.position[0], t.position[1], t.position[2]);
  return T;
}

}  // namespace

std::optional<Eigen::Isometry3d> TruthPoseAt(const std::vector<rover_msgs::sim_truth_t>& truth,
                                             std::int64_t utime) {
  if (truth.empty() || utime < truth.front().utime || utime > truth.back().utime) return std::nullopt;
  auto after = std::lower_bound(truth.begin(), truth.end(), utime,
                                [](const rover_msgs::sim_truth_t& t, std::int64_t u) { return t.utime < u; });
  if (after->utime == utime || after == truth.begin()) return TruthPose(*after);
  const auto& b = *after;
  const auto& a = *(after - 1);
  const double f = static_cast<double>(utime - a.utime) / static_cast<double>(b.utime - a.utime);
  const Eigen::Isometry3d Ta = TruthPose(a), Tb = TruthPose(b);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Quaterniond(Ta.linear()).slerp(f, Eigen::Quaterniond(Tb.linear())).toRotationMatrix();
  T.translation() = (1.0 - f) * Ta.translation() + f * Tb.translation();
  return T;
}

Vector6 MotionError(const Eigen::Isometry3d& truth, const Eigen::Isometry3d& estimate) {
  Vector6 e = geometry::XyzRpyFromPose(estimate) - geometry::XyzRpyFromPose(truth);
  for (int i = 3; i < 6; ++i) e(i) = geometry::WrapAngle(e(i));
  return e;
}

std::optional<double> Nees(const Vector6& error, const Matrix6& covariance) {
  if (!covariance.allFinite()) return std::nullopt;
  const Eigen::LDLT<Matrix6> ldlt(covariance);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive() || (ldlt.vectorD().array() <= 0.0).any()) {
    return std::nullopt;
  }
  return error.dot(ldlt.solve(error));
}

VoCheck CheckVoUpdate(const rover_msgs::vo_update_t& u, const std::vector<rover_msgs::sim_truth_t>& truth) {
  VoCheck c;
  c.utime = u.utime;
  c.status = u.status;
  c.reason = u.reason;
  c.from_frame_id = u.from_frame_id;
  c.to_frame_id = u.to_frame_id;
  c.from_utime = u.from_utime;
  c.to_utime = u.to_utime;
  c.accepted = u.status == rover_msgs::vo_update_t::STATUS_OK;
  if (!c.accepted) return c;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Quaterniond(u.delta_orientation[0], u.delta_orientation[1], u.delta_orientation[2],
                                  u.delta_orientation[3])
                   .normalized()
                   .toRotationMatrix();
  T.translation() = Eigen::Vector3d(u.delta_position[0], u.delta_position[1], u.delta_position[2]);
  c.delta = geometry::XyzRpyFromPose(T);
  for (int r = 0; r < 6; ++r) {
    for (int k = 0; k < 6; ++k) c.covariance(r, k) = u.covariance[r][k];
  }
  const auto from = TruthPoseAt(truth, u.from_utime);
  const auto to = TruthPoseAt(truth, u.to_utime);
  if (!from || !to) return c;
  const Eigen::Isometry3d true_T = from->inverse() * *to;
  c.true_delta = geometry::XyzRpyFromPose(true_T);
  c.nees = Nees(MotionError(true_T, T), c.covariance);
  return c;
}

}  // namespace rover::tools
