#include "vo/motion_prior.hpp"

#include <gtest/gtest.h>

#include <cmath>

using rover::vo::MotionPriorCovariance;
using rover::vo::MotionPriorOptions;

TEST(MotionPrior, VO6_SigmaIsAFractionOfTheMotionAboveAFloor) {
  const MotionPriorOptions o;  // 60 % / 5 cm, 30 % / 2 deg
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(0.3, 0.4, 0.0);  // 0.5 m
  T.linear() = Eigen::AngleAxisd(20.0 * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const auto cov = MotionPriorCovariance(T, o);
  EXPECT_NEAR(std::sqrt(cov(0, 0)), 0.3, 1e-12);                 // 60 % of 0.5 m
  EXPECT_NEAR(std::sqrt(cov(5, 5)), 6.0 * M_PI / 180.0, 1e-12);  // 30 % of 20 deg
  EXPECT_EQ(cov(0, 1), 0.0);
  const auto still = MotionPriorCovariance(Eigen::Isometry3d::Identity(), o);
  EXPECT_NEAR(std::sqrt(still(2, 2)), 0.05, 1e-12);               // the floors
  EXPECT_NEAR(std::sqrt(still(3, 3)), 2.0 * M_PI / 180.0, 1e-12);
}
