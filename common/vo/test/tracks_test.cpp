// VoResult::tracks (tracked_feature.hpp): the features tracked from the previous pair,
// where they were and where they were found, and which ones the motion used.
#include "test_rig.hpp"
#include "vo/visual_odometry.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include <random>

namespace rover::vo {
namespace {

// A textured wall facing the rig at 6 m (a frontal plane: every point at the same depth),
// rendered by intersecting each pixel's ray with it.
constexpr double kDepth = 6.0, kFocal = 400.0, kTexel = 0.006;
constexpr int kTex = 2048;

cv::Mat Texture() {
  std::mt19937 rng(5);
  std::normal_distribution<float> g(0, 1);
  cv::Mat acc = cv::Mat::zeros(kTex, kTex, CV_32F);
  for (double sigma : {1.5, 4.0, 12.0}) {
    cv::Mat noise(kTex, kTex, CV_32F);
    for (int y = 0; y < kTex; ++y)
      for (int x = 0; x < kTex; ++x) noise.at<float>(y, x) = g(rng);
    cv::GaussianBlur(noise, noise, cv::Size(0, 0), sigma);
    cv::normalize(noise, noise, 0, 1, cv::NORM_MINMAX);
    acc += noise;
  }
  cv::Mat out;
  cv::normalize(acc, out, 20, 235, cv::NORM_MINMAX);
  return out;
}

cv::Mat RenderWall(const cv::Mat& texture, const geometry::CameraModel& cam, double rig_x) {
  cv::Mat mx(cam.height(), cam.width(), CV_32F), my(cam.height(), cam.width(), CV_32F);
  for (int y = 0; y < cam.height(); ++y) {
    for (int x = 0; x < cam.width(); ++x) {
      Eigen::Vector3d o, d;
      cam.BackProject(Eigen::Vector2d(x, y), &o, &d);
      const Eigen::Vector3d X = o + Eigen::Vector3d(rig_x, 0, 0) + (kDepth - o.z()) / d.z() * d;
      mx.at<float>(y, x) = static_cast<float>(kTex / 2 + X.x() / kTexel);
      my.at<float>(y, x) = static_cast<float>(kTex / 2 + X.y() / kTexel);
    }
  }
  cv::Mat out, out8;
  cv::remap(texture, out, mx, my, cv::INTER_CUBIC, cv::BORDER_REFLECT);
  out.convertTo(out8, CV_8U);
  return out8;
}

TEST(VoTracks, EachTrackedFeatureMovesAsTheKnownMotionSaysAndInliersMatchTheCount) {
  const geometry::StereoRig rig = test::MakeRig(512, 384, kFocal, 255.5, 191.5, 0.25);
  const cv::Mat texture = Texture();
  auto pair = [&](double rig_x, std::int64_t id) {
    StereoImages im;
    im.rig = rig;
    im.frame_id = id;
    im.utime = id * 100000;
    im.left = RenderWall(texture, *rig.left, rig_x);
    im.right = RenderWall(texture, *rig.right, rig_x);
    return im;
  };
  Eigen::Matrix<double, 6, 6> prior = Eigen::Matrix<double, 6, 6>::Zero();
  prior.diagonal() << 0.01, 0.01, 0.01, 1e-4, 1e-4, 1e-4;
  VisualOdometry vo(VoOptions{});
  const VoResult first = vo.Process(pair(0.0, 0), Eigen::Isometry3d::Identity(), prior);
  ASSERT_EQ(first.status, VoStatus::kBaseline);
  EXPECT_TRUE(first.tracks.empty());  // nothing to track from yet

  // The rig moves 0.1 m to its right: the wall moves 400 * 0.1 / 6 = 6.67 px left.
  Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();
  motion.translation() = Eigen::Vector3d(0.1, 0, 0);
  const VoResult r = vo.Process(pair(0.1, 1), motion, prior);
  ASSERT_EQ(r.status, VoStatus::kOk) << r.reason;
  ASSERT_EQ(static_cast<int>(r.tracks.size()), r.num_tracked);
  int inliers = 0;
  for (const auto& t : r.tracks) {
    inliers += t.inlier;
    if (!t.inlier) continue;
    const Eigen::Vector2d shift = t.curr_left - t.prev_left;
    EXPECT_NEAR(shift.x(), -kFocal * 0.1 / kDepth, 0.3);
    EXPECT_NEAR(shift.y(), 0.0, 0.3);
  }
  EXPECT_EQ(inliers, r.num_inliers);
  EXPECT_GT(inliers, 50);
}

}  // namespace
}  // namespace rover::vo
