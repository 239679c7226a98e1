// Shared checks for the camera model tests: numerical Jacobians by central differences.
#pragma once

#include "geometry/camera_model.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace rover::geometry::test {

// d(pixel)/d(point) by central differences; step relative to the range.
inline Eigen::Matrix<double, 2, 3> NumericProjectJacobian(const CameraModel& cam,
                                                          const Eigen::Vector3d& p) {
  const double h = 1e-6 * std::max(1.0, (p - cam.Center()).norm());
  Eigen::Matrix<double, 2, 3> J;
  for (int k = 0; k < 3; ++k) {
    Eigen::Vector3d dp = Eigen::Vector3d::Zero();
    dp[k] = h;
    Eigen::Vector2d plus, minus;
    EXPECT_TRUE(cam.Project(p + dp, &plus));
    EXPECT_TRUE(cam.Project(p - dp, &minus));
    J.col(k) = (plus - minus) / (2 * h);
  }
  return J;
}

// d(direction)/d(pixel) by central differences.
inline Eigen::Matrix<double, 3, 2> NumericRayJacobian(const CameraModel& cam,
                                                      const Eigen::Vector2d& pixel) {
  const double h = 1e-3;
  Eigen::Matrix<double, 3, 2> J;
  for (int k = 0; k < 2; ++k) {
    Eigen::Vector2d dp = Eigen::Vector2d::Zero();
    dp[k] = h;
    Eigen::Vector3d o, plus, minus;
    cam.BackProject(pixel + dp, &o, &plus);
    cam.BackProject(pixel - dp, &o, &minus);
    J.col(k) = (plus - minus) / (2 * h);
  }
  return J;
}

// Relative Frobenius error of an analytic Jacobian against a numeric one.
template <typename M>
double RelativeError(const M& analytic, const M& numeric) {
  return (analytic - numeric).norm() / std::max(1e-300, numeric.norm());
}

// Angle between two directions, radians (robust near zero).
inline double AngleBetween(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

}  // namespace rover::geometry::test
