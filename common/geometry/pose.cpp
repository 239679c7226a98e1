#include "geometry/pose.hpp"

#include <algorithm>
#include <cmath>

namespace rover::geometry {

Eigen::Matrix3d RotationFromRpy(double roll, double pitch, double yaw) {
  return (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

Eigen::Vector3d RpyFromRotation(const Eigen::Matrix3d& R) {
  const double pitch = std::asin(std::clamp(-R(2, 0), -1.0, 1.0));
  const double roll = std::atan2(R(2, 1), R(2, 2));
  const double yaw = std::atan2(R(1, 0), R(0, 0));
  return {roll, pitch, yaw};
}

Pose PoseFromXyzRpy(double x, double y, double z, double roll, double pitch, double yaw) {
  Pose T = Pose::Identity();
  T.linear() = RotationFromRpy(roll, pitch, yaw);
  T.translation() = Eigen::Vector3d(x, y, z);
  return T;
}

Vector6d XyzRpyFromPose(const Pose& T) {
  Vector6d v;
  v.head<3>() = T.translation();
  v.tail<3>() = RpyFromRotation(T.linear());
  return v;
}

double WrapAngle(double a) {
  a = std::remainder(a, 2.0 * M_PI);
  if (a <= -M_PI) a += 2.0 * M_PI;
  return a;
}

Eigen::Matrix3d Skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d S;
  S << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return S;
}

void RotationFromRpyDerivatives(const Eigen::Vector3d& rpy, Eigen::Matrix3d* R, Eigen::Matrix3d dR[3]) {
  const Eigen::Matrix3d Rx = Eigen::AngleAxisd(rpy[0], Eigen::Vector3d::UnitX()).toRotationMatrix();
  const Eigen::Matrix3d Ry = Eigen::AngleAxisd(rpy[1], Eigen::Vector3d::UnitY()).toRotationMatrix();
  const Eigen::Matrix3d Rz = Eigen::AngleAxisd(rpy[2], Eigen::Vector3d::UnitZ()).toRotationMatrix();
  if (R) *R = Rz * Ry * Rx;
  dR[0] = Rz * Ry * Rx * Skew(Eigen::Vector3d::UnitX());
  dR[1] = Rz * Ry * Skew(Eigen::Vector3d::UnitY()) * Rx;
  dR[2] = Skew(Eigen::Vector3d::UnitZ()) * Rz * Ry * Rx;
}

}  // namespace rover::geometry
