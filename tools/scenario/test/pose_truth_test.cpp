// The estimator's POSE against truth, with known answers.
#include "scenario/pose_truth.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace rover::tools {
namespace {

rover_msgs::sim_truth_t Truth(int64_t utime, double x, double y, double yaw) {
  rover_msgs::sim_truth_t t{};
  t.utime = utime;
  t.position[0] = x;
  t.position[1] = y;
  t.orientation[0] = std::cos(yaw / 2);
  t.orientation[3] = std::sin(yaw / 2);
  t.rpy[2] = yaw;
  return t;
}

rover_msgs::pose_t Pose(int64_t utime, double x, double y, double yaw, double var_x, double var_y, double var_yaw,
                        int site = 0) {
  rover_msgs::pose_t p{};
  p.utime = utime;
  p.position[0] = x;
  p.position[1] = y;
  p.orientation[0] = std::cos(yaw / 2);
  p.orientation[3] = std::sin(yaw / 2);
  p.covariance[0][0] = var_x;
  p.covariance[1][1] = var_y;
  p.covariance[5][5] = var_yaw;
  p.site_index = site;
  return p;
}

TEST(PoseTruth, NeesOfKnownErrors) {
  // Truth drives north at 1 m/s heading 0.5 rad; poses between samples are interpolated.
  const std::vector<rover_msgs::sim_truth_t> truth = {Truth(0, 0, 0, 0.5), Truth(2000000, 2, 0, 0.5)};
  const std::vector<rover_msgs::pose_t> poses = {
      // At 1 s truth is (1, 0): 0.1 m off in x with sigma 0.1 (NEES 1), heading 0.01 rad off
      // with sigma 0.01 (NEES 1).
      Pose(1000000, 1.1, 0.0, 0.51, 0.01, 0.04, 1e-4),
      // 0.4 m off in y with sigma 0.1: NEES 16, beyond; heading 4 sigma off: 16, beyond.
      Pose(1500000, 1.5, 0.4, 0.46, 0.04, 0.01, 1e-4),
      // Another site's frame, and a pose with no heading sigma, are not judged.
      Pose(1000000, 9.0, 9.0, 0.5, 0.01, 0.01, 1e-4, 1),
      Pose(1000000, 1.0, 0.0, 0.5, 0.0, 0.0, 0.0),
      // Outside truth's span: not judged.
      Pose(3000000, 3.0, 0.0, 0.5, 0.01, 0.01, 1e-4),
  };
  const auto h = JudgePoses(poses, truth);
  ASSERT_TRUE(h.has_value());
  EXPECT_EQ(h->poses, 2);
  EXPECT_EQ(h->horizontal_poses, 2);
  EXPECT_NEAR(h->heading_nees_mean, (1.0 + 16.0) / 2, 1e-6);
  EXPECT_NEAR(h->horizontal_nees_mean, (1.0 + 16.0) / 2, 1e-6);
  EXPECT_NEAR(h->heading_beyond_pct, 50.0, 1e-9);
  EXPECT_NEAR(h->horizontal_beyond_pct, 50.0, 1e-9);
  // The last judged pose (1.5 s): 3 x sqrt(0.04) claimed, 0.4 m off in truth.
  EXPECT_NEAR(h->final_horizontal_3sigma_m, 0.6, 1e-9);
  EXPECT_NEAR(h->final_horizontal_error_m, 0.4, 1e-9);
}

TEST(PoseTruth, NothingToJudgeIsEmpty) {
  EXPECT_FALSE(JudgePoses({}, {Truth(0, 0, 0, 0)}).has_value());
  EXPECT_FALSE(JudgePoses({Pose(0, 0, 0, 0, 0.01, 0.01, 1e-4)}, {}).has_value());
}

}  // namespace
}  // namespace rover::tools
