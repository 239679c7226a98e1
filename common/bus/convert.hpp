// Conversions between message arrays and Eigen (quaternions are stored w, x, y, z).
#pragma once

#include "geometry/camera_model.hpp"
#include "geometry/pose.hpp"

#include <rover_msgs/camera_model_t.hpp>
#include <rover_msgs/pose_t.hpp>

namespace rover::bus {

inline Eigen::Quaterniond QuaternionFromArray(const double q[4]) {
  return Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized();
}

inline void QuaternionToArray(const Eigen::Quaterniond& q, double out[4]) {
  out[0] = q.w();
  out[1] = q.x();
  out[2] = q.y();
  out[3] = q.z();
}

inline geometry::Matrix6d CovarianceFromArray(const double c[6][6]) {
  geometry::Matrix6d m;
  for (int r = 0; r < 6; ++r)
    for (int k = 0; k < 6; ++k) m(r, k) = c[r][k];
  return m;
}

inline void CovarianceToArray(const geometry::Matrix6d& m, double out[6][6]) {
  for (int r = 0; r < 6; ++r)
    for (int k = 0; k < 6; ++k) out[r][k] = m(r, k);
}

inline geometry::Pose PoseFromMsg(const rover_msgs::pose_t& msg) {
  geometry::Pose T = geometry::Pose::Identity();
  T.linear() = QuaternionFromArray(msg.orientation).toRotationMatrix();
  T.translation() = Eigen::Vector3d(msg.position[0], msg.position[1], msg.position[2]);
  return T;
}

inline void PoseToArrays(const geometry::Pose& T, double position[3], double orientation[4]) {
  for (int i = 0; i < 3; ++i) position[i] = T.translation()[i];
  QuaternionToArray(Eigen::Quaterniond(T.linear()), orientation);
}

// A camera model as STEREO_FRAME carries it (geometry::CameraModelFromParams reads it back).
inline rover_msgs::camera_model_t CameraModelToMsg(const geometry::CameraModel& m) {
  rover_msgs::camera_model_t out{};
  out.type = m.type();
  out.width = m.width();
  out.height = m.height();
  out.params = m.Params();
  out.num_params = static_cast<std::int32_t>(out.params.size());
  return out;
}

}  // namespace rover::bus
