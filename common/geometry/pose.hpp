// Frames and rotations, written down once (MER frames: README.md, "Layout").
//
//   site frame:  X north, Y east,  Z down   (right-handed)
//   rover frame: X forward, Y right, Z down
//   T_site_rover maps rover-frame points into the site frame: p_site = T_site_rover * p_rover.
//   Euler angles are roll (about X), pitch (about Y), yaw (about Z), applied as
//   R_site_rover = Rz(yaw) * Ry(pitch) * Rx(roll). Yaw 0 faces north, +pi/2 faces east.
//   Positive pitch raises the nose (Z is down, so the nose goes to -Z).
//   Quaternions are stored w, x, y, z in messages.
//   A 6x6 pose covariance is ordered x, y, z, roll, pitch, yaw (metres, radians).
#pragma once

#include <Eigen/Geometry>

namespace rover::geometry {

using Pose = Eigen::Isometry3d;
using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;

// R = Rz(yaw) * Ry(pitch) * Rx(roll).
Eigen::Matrix3d RotationFromRpy(double roll, double pitch, double yaw);
// Inverse of RotationFromRpy; pitch in [-pi/2, pi/2].
Eigen::Vector3d RpyFromRotation(const Eigen::Matrix3d& R);

Pose PoseFromXyzRpy(double x, double y, double z, double roll, double pitch, double yaw);
// x, y, z, roll, pitch, yaw.
Vector6d XyzRpyFromPose(const Pose& T);

// Wraps an angle to (-pi, pi].
double WrapAngle(double a);

// Skew-symmetric matrix of v: Skew(v) * w == v.cross(w).
Eigen::Matrix3d Skew(const Eigen::Vector3d& v);

// R = RotationFromRpy(rpy) (R may be null) and its derivatives dR/d(roll), dR/d(pitch),
// dR/d(yaw): the Jacobians of the motion estimate and of VO tracking.
void RotationFromRpyDerivatives(const Eigen::Vector3d& rpy, Eigen::Matrix3d* R, Eigen::Matrix3d dR[3]);

}  // namespace rover::geometry
