#include "geometry/pose.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace rover::geometry;

TEST(Frames, YawNinetyFacesEast) {
  // Rover X (forward) at yaw +90 deg points along site +Y (east).
  const Eigen::Vector3d fwd = RotationFromRpy(0, 0, M_PI / 2) * Eigen::Vector3d::UnitX();
  EXPECT_NEAR(fwd.y(), 1.0, 1e-12);
  EXPECT_NEAR(fwd.x(), 0.0, 1e-12);
}

TEST(Frames, PositivePitchRaisesTheNose) {
  // Z is down, so a raised nose has a negative site Z component.
  const Eigen::Vector3d fwd = RotationFromRpy(0, 0.2, 0) * Eigen::Vector3d::UnitX();
  EXPECT_LT(fwd.z(), 0.0);
}

TEST(Frames, PositiveRollDropsTheRightSide) {
  // Rover Y (right) under positive roll gets a positive site Z (down) component.
  const Eigen::Vector3d right = RotationFromRpy(0.2, 0, 0) * Eigen::Vector3d::UnitY();
  EXPECT_GT(right.z(), 0.0);
}

TEST(Frames, RpyRoundTrip) {
  for (double r : {-0.5, 0.0, 0.4})
    for (double p : {-1.2, 0.1, 1.0})
      for (double y : {-3.0, 0.0, 2.5}) {
        const Eigen::Vector3d rpy = RpyFromRotation(RotationFromRpy(r, p, y));
        EXPECT_NEAR(rpy.x(), r, 1e-12);
        EXPECT_NEAR(rpy.y(), p, 1e-12);
        EXPECT_NEAR(rpy.z(), y, 1e-12);
      }
}

TEST(Frames, WrapAngle) {
  EXPECT_NEAR(WrapAngle(3 * M_PI / 2), -M_PI / 2, 1e-12);
  EXPECT_NEAR(WrapAngle(-M_PI), M_PI, 1e-12);
  EXPECT_NEAR(WrapAngle(0.3), 0.3, 1e-12);
}

TEST(Frames, RotationDerivativesMatchFiniteDifferences) {
  const Eigen::Vector3d rpy(0.3, -0.7, 2.1);
  Eigen::Matrix3d R, dR[3];
  RotationFromRpyDerivatives(rpy, &R, dR);
  EXPECT_LT((R - RotationFromRpy(rpy[0], rpy[1], rpy[2])).norm(), 1e-12);
  const double h = 1e-6;
  for (int k = 0; k < 3; ++k) {
    Eigen::Vector3d a = rpy, b = rpy;
    a[k] += h;
    b[k] -= h;
    const Eigen::Matrix3d numeric = (RotationFromRpy(a[0], a[1], a[2]) - RotationFromRpy(b[0], b[1], b[2])) / (2 * h);
    EXPECT_LT((dR[k] - numeric).norm(), 1e-8) << "angle " << k;
  }
}
