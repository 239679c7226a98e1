// The synthetic terrain renderer: the two views agree where the geometry says they must,
// the truth motions compose, and rendering is deterministic in the seed.
#include "vo_eval/synthetic_terrain.hpp"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include <cmath>
#include <random>

namespace rover::vo_eval {
namespace {

SyntheticTerrainOptions Small() {
  SyntheticTerrainOptions o;
  o.width = 320;
  o.height = 240;
  o.noise_dn = 0.0;
  return o;
}

double Bilinear(const cv::Mat& img, const Eigen::Vector2d& p) {
  const int x = static_cast<int>(std::floor(p.x())), y = static_cast<int>(std::floor(p.y()));
  const double a = p.x() - x, b = p.y() - y;
  auto at = [&](int r, int c) { return static_cast<double>(img.at<unsigned char>(r, c)); };
  return (1 - a) * (1 - b) * at(y, x) + a * (1 - b) * at(y, x + 1) + (1 - a) * b * at(y + 1, x) +
         a * b * at(y + 1, x + 1);
}

TEST(SyntheticTerrain, StereoViewsAgreeOnGroundPoints) {
  const SyntheticTerrainSequence seq(Small());
  cv::Mat left, right;
  seq.Render(3, &left, &right);
  const Eigen::Isometry3d T_ref_site = seq.SitePose(3).inverse();
  const Eigen::Isometry3d T_site_rover = seq.SitePose(3);  // only its position and heading
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  double same = 0.0, shuffled = 0.0;
  int n = 0;
  Eigen::Vector2d last_right(-1, -1);
  for (int i = 0; i < 4000 && n < 300; ++i) {
    // A point on the terrain 2.5 to 6 m ahead of the cameras, within +-2 m sideways.
    const Eigen::Vector3d ahead = T_site_rover.linear() * Eigen::Vector3d(0, 0, 1);
    const Eigen::Vector3d side = T_site_rover.linear() * Eigen::Vector3d(1, 0, 0);
    Eigen::Vector2d xy = T_site_rover.translation().head<2>() + (4.25 + 1.75 * u(rng)) * ahead.head<2>().normalized() +
                         2.0 * u(rng) * side.head<2>().normalized();
    const Eigen::Vector3d p_site(xy.x(), xy.y(), seq.TerrainZ(xy.x(), xy.y()));
    const Eigen::Vector3d p_ref = T_ref_site * p_site;
    Eigen::Vector2d pl, pr;
    if (!seq.rig().left->Project(p_ref, &pl) || !seq.rig().right->Project(p_ref, &pr)) continue;
    auto inside = [&](const Eigen::Vector2d& p) {
      return p.x() > 2 && p.y() > 2 && p.x() < left.cols - 3 && p.y() < left.rows - 3;
    };
    if (!inside(pl) || !inside(pr)) continue;
    same += std::abs(Bilinear(left, pl) - Bilinear(right, pr));
    if (last_right.x() >= 0) shuffled += std::abs(Bilinear(left, pl) - Bilinear(right, last_right));
    last_right = pr;
    ++n;
  }
  ASSERT_GE(n, 200);
  same /= n;
  shuffled /= (n - 1);
  // Ray casting onto the same surface: the views differ only by 8-bit rounding and
  // resampling; unrelated pixels differ by the texture's contrast.
  EXPECT_LT(same, 3.0) << "shuffled " << shuffled;
  EXPECT_GT(shuffled, 5.0 * same);
}

TEST(SyntheticTerrain, TextureHasContrastAndCorners) {
  SyntheticTerrainOptions o = Small();
  const SyntheticTerrainSequence seq(o);
  cv::Mat left, right;
  seq.Render(0, &left, &right);
  cv::Scalar mean, stddev;
  cv::meanStdDev(left, mean, stddev);
  EXPECT_GT(stddev[0], 15.0);
  EXPECT_GT(mean[0], 80.0);
  EXPECT_LT(mean[0], 180.0);
  std::vector<cv::Point2f> corners;
  cv::goodFeaturesToTrack(left, corners, 200, 0.01, 10);
  EXPECT_GT(corners.size(), 150u);
}

TEST(SyntheticTerrain, TruthMotionsCompose) {
  const SyntheticTerrainSequence seq(Small());
  EXPECT_TRUE(seq.TruthPose(0).isApprox(Eigen::Isometry3d::Identity(), 1e-12));
  for (int k = 1; k < 20; ++k) {
    const Eigen::Isometry3d composed = seq.TruthPose(k - 1) * seq.TruthMotion(k);
    EXPECT_TRUE(composed.isApprox(seq.TruthPose(k), 1e-9)) << k;
    // The rover drives about step_m forward each frame.
    EXPECT_NEAR(seq.TruthMotion(k).translation().norm(), seq.options().step_m, 0.05);
  }
  // Gravity is down (camera y tilted by the mast pitch) in the first camera frame.
  const double th = seq.options().camera_pitch_deg * M_PI / 180.0;
  EXPECT_TRUE(seq.DownInWorld().isApprox(Eigen::Vector3d(0, std::cos(th), std::sin(th)), 0.03))
      << seq.DownInWorld().transpose();
}

TEST(SyntheticTerrain, DeterministicInTheSeed) {
  SyntheticTerrainOptions o = Small();
  o.noise_dn = 1.0;
  cv::Mat a, b, c, d;
  SyntheticTerrainSequence(o).Render(2, &a, &b);
  SyntheticTerrainSequence(o).Render(2, &c, &d);
  EXPECT_EQ(cv::norm(a, c, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(b, d, cv::NORM_INF), 0.0);
  o.seed = 2;
  SyntheticTerrainSequence(o).Render(2, &c, &d);
  EXPECT_GT(cv::norm(a, c, cv::NORM_L1) / a.total(), 10.0);
}

TEST(SyntheticTerrain, BadOptionsNameTheValue) {
  SyntheticTerrainOptions o = Small();
  o.width = 4;
  try {
    SyntheticTerrainSequence seq(o);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("width and height"), std::string::npos);
  }
  o = Small();
  o.baseline_m = 0.0;
  EXPECT_THROW(SyntheticTerrainSequence{o}, std::invalid_argument);
}

}  // namespace
}  // namespace rover::vo_eval
