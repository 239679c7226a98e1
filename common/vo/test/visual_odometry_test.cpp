// The whole pipeline on rendered stereo pairs (VO-1..VO-10), features (VO-2) and options.
#include "geometry/pose.hpp"
#include "test_rig.hpp"
#include "vo/features.hpp"
#include "vo/simd.hpp"
#include "vo/visual_odometry.hpp"

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include <random>
#include <tuple>

namespace rover::vo {
namespace {

// A textured plane seen by a stereo rig, rendered by intersecting every pixel's ray with
// the plane (a homography) and sampling a multi-scale random texture.
class PlaneScene {
 public:
  PlaneScene() : rig_(test::MakeRig(512, 384, 400, 255.5, 191.5, 0.25)) {
    std::mt19937 rng(17);
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
    cv::normalize(acc, texture_, 20, 235, cv::NORM_MINMAX);
    normal_ = Eigen::Vector3d(0, 0.45, -1).normalized();
    origin_ = Eigen::Vector3d(0, 0, 6);
    e1_ = Eigen::Vector3d::UnitX();
    e2_ = normal_.cross(e1_).normalized();
  }

  const geometry::StereoRig& rig() const { return rig_; }

  // T_world_ref: pose of the rig's reference frame (the left camera) in the world.
  StereoImages Render(const Eigen::Isometry3d& T_world_ref, std::int64_t id) const {
    StereoImages im;
    im.rig = rig_;
    im.frame_id = id;
    im.utime = id * 100000;
    im.left = RenderOne(*rig_.left, T_world_ref);
    im.right = RenderOne(*rig_.right, T_world_ref);
    return im;
  }

 private:
  cv::Mat RenderOne(const geometry::CameraModel& cam, const Eigen::Isometry3d& T) const {
    cv::Mat mx(cam.height(), cam.width(), CV_32F), my(cam.height(), cam.width(), CV_32F);
    for (int y = 0; y < cam.height(); ++y) {
      for (int x = 0; x < cam.width(); ++x) {
        Eigen::Vector3d o, d;
        cam.BackProject(Eigen::Vector2d(x, y), &o, &d);
        o = T * o;
        d = T.linear() * d;
        const double lambda = (normal_.dot(origin_) - normal_.dot(o)) / normal_.dot(d);
        const Eigen::Vector3d X = o + lambda * d - origin_;
        mx.at<float>(y, x) = static_cast<float>(kTex / 2 + X.dot(e1_) / kTexel);
        my.at<float>(y, x) = static_cast<float>(kTex / 2 + X.dot(e2_) / kTexel);
      }
    }
    cv::Mat out, out8;
    cv::remap(texture_, out, mx, my, cv::INTER_CUBIC, cv::BORDER_REFLECT);
    out.convertTo(out8, CV_8U);
    return out8;
  }

  static constexpr int kTex = 2048;
  static constexpr double kTexel = 0.006;  // metres per texel
  geometry::StereoRig rig_;
  cv::Mat texture_;
  Eigen::Vector3d normal_, origin_, e1_, e2_;
};

Eigen::Matrix<double, 6, 6> WidePrior() {
  Eigen::Matrix<double, 6, 6> c = Eigen::Matrix<double, 6, 6>::Zero();
  c.diagonal() << 0.09, 0.09, 0.09, 0.0025, 0.0025, 0.0025;  // 0.3 m, 2.9 deg
  return c;
}

TEST(VisualOdometry, VO1_VO10_RecoversKnownMotionFromRenderedStereoPairs) {
  const PlaneScene scene;
  const Eigen::Isometry3d motion = geometry::PoseFromXyzRpy(0.06, -0.02, 0.35, 0.01, 0.03, -0.015);
  VisualOdometry vo(VoOptions{});
  const VoResult first = vo.Process(scene.Render(Eigen::Isometry3d::Identity(), 0),
                                    Eigen::Isometry3d::Identity(), WidePrior());
  EXPECT_EQ(first.status, VoStatus::kBaseline);
  EXPECT_GT(first.num_matched, 100);
  // The prior (as from wheel odometry) is off by 10 cm and 1 deg.
  const Eigen::Isometry3d prior = geometry::PoseFromXyzRpy(0.0, 0.0, 0.25, 0.0, 0.015, 0.0);
  const VoResult r = vo.Process(scene.Render(motion, 1), prior, WidePrior());
  ASSERT_EQ(r.status, VoStatus::kOk) << r.reason;
  EXPECT_GT(r.num_inliers, 50);
  const Eigen::Vector3d dt = r.T_prev_curr.translation() - motion.translation();
  const double dr = Eigen::AngleAxisd(r.T_prev_curr.linear().transpose() * motion.linear()).angle();
  std::printf("translation error %.2f mm, rotation error %.4f deg, sigma_t %.2f mm, %d inliers, "
              "%.1f ms\n", 1e3 * dt.norm(), dr * 180 / M_PI,
              1e3 * std::sqrt(r.covariance.topLeftCorner<3, 3>().trace()), r.num_inliers,
              r.times.total_ms);
  EXPECT_LT(dt.norm(), 0.005);
  EXPECT_LT(dr, 0.05 * M_PI / 180);
  // The reported covariance is positive definite and the error lies within it.
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eig(r.covariance);
  EXPECT_GT(eig.eigenvalues().minCoeff(), 0);
  for (int i = 0; i < 3; ++i) EXPECT_LT(std::abs(dt[i]), 5 * std::sqrt(r.covariance(i, i)) + 5e-4);
  EXPECT_GE(r.times.total_ms, r.times.track_ms);
}

// The portable loops (vo/simd.hpp, what a CPU without AVX2 takes) and the CPU's best give
// the same motion, covariance and counts to the bit over a pair of rendered pairs.
TEST(VisualOdometry, VO1_ThePortableLoopsGiveTheSameMotionBitForBit) {
  const PlaneScene scene;
  const Eigen::Isometry3d motion = geometry::PoseFromXyzRpy(0.06, -0.02, 0.35, 0.01, 0.03, -0.015);
  const Eigen::Isometry3d prior = geometry::PoseFromXyzRpy(0.0, 0.0, 0.25, 0.0, 0.015, 0.0);
  const auto first_pair = scene.Render(Eigen::Isometry3d::Identity(), 0);
  const auto second_pair = scene.Render(motion, 1);
  VoResult results[2];
  for (const bool portable : {false, true}) {
    const PathForScope path(portable);
    VisualOdometry vo(VoOptions{});
    vo.Process(first_pair, Eigen::Isometry3d::Identity(), WidePrior());
    results[portable ? 1 : 0] = vo.Process(second_pair, prior, WidePrior());
  }
  const VoResult& best = results[0];
  const VoResult& portable = results[1];
  ASSERT_EQ(best.status, VoStatus::kOk) << best.reason;
  ASSERT_EQ(portable.status, best.status) << portable.reason;
  EXPECT_EQ(portable.num_matched, best.num_matched);
  EXPECT_EQ(portable.num_inliers, best.num_inliers);
  EXPECT_EQ(portable.T_prev_curr.matrix(), best.T_prev_curr.matrix());
  EXPECT_EQ(portable.covariance, best.covariance);
}

TEST(VisualOdometry, VO10_MotionTooLargeReinitialisesTracking) {
  const PlaneScene scene;
  VisualOdometry vo(VoOptions{});
  vo.Process(scene.Render(Eigen::Isometry3d::Identity(), 0), Eigen::Isometry3d::Identity(), WidePrior());
  const Eigen::Isometry3d turn = geometry::PoseFromXyzRpy(0, 0, 0, 0, 0.6, 0);  // 34 deg
  const VoResult big = vo.Process(scene.Render(Eigen::Isometry3d::Identity(), 1), turn, WidePrior());
  EXPECT_EQ(big.status, VoStatus::kMotionTooLarge);
  EXPECT_FALSE(big.reason.empty());
  EXPECT_TRUE(big.T_prev_curr.isApprox(Eigen::Isometry3d::Identity()));
  // Tracking restarted on the last pair: the next small step converges.
  const Eigen::Isometry3d step = geometry::PoseFromXyzRpy(0, 0, 0.2, 0, 0, 0);
  const VoResult next = vo.Process(scene.Render(step, 2), step, WidePrior());
  ASSERT_EQ(next.status, VoStatus::kOk) << next.reason;
  EXPECT_LT((next.T_prev_curr.translation() - step.translation()).norm(), 0.005);
}

TEST(VisualOdometry, VO10_TurnAtTheExecutorsLimitPlusSlipIsMeasured) {
  // The executor turns at most 18 deg per step; with slip the prior reads a little more.
  // VO must measure such a turn, not refuse it for its size (its limit is 27 deg).
  const PlaneScene scene;
  VisualOdometry vo(VoOptions{});
  vo.Process(scene.Render(Eigen::Isometry3d::Identity(), 0), Eigen::Isometry3d::Identity(), WidePrior());
  const Eigen::Isometry3d turn = geometry::PoseFromXyzRpy(0, 0, 0.05, 0, 20.0 * M_PI / 180, 0);
  const Eigen::Isometry3d prior = geometry::PoseFromXyzRpy(0, 0, 0.05, 0, 19.0 * M_PI / 180, 0);
  const VoResult r = vo.Process(scene.Render(turn, 1), prior, WidePrior());
  ASSERT_EQ(r.status, VoStatus::kOk) << r.reason;
  const double dr = Eigen::AngleAxisd(r.T_prev_curr.linear().transpose() * turn.linear()).angle();
  EXPECT_LT(dr, 0.05 * M_PI / 180);
  EXPECT_LT((r.T_prev_curr.translation() - turn.translation()).norm(), 0.005);
}

TEST(VisualOdometry, VO10_TexturelessPairGivesNoUpdate) {
  const geometry::StereoRig rig = test::MakeRig(512, 384, 400, 255.5, 191.5, 0.25);
  std::mt19937 rng(2);
  std::normal_distribution<double> noise(0, 1.0);
  auto flat = [&] {
    cv::Mat m(384, 512, CV_8U);
    for (int y = 0; y < m.rows; ++y)
      for (int x = 0; x < m.cols; ++x) m.at<uchar>(y, x) = cv::saturate_cast<uchar>(110 + noise(rng));
    return m;
  };
  VisualOdometry vo(VoOptions{});
  for (int k = 0; k < 3; ++k) {
    StereoImages im;
    im.rig = rig;
    im.left = flat();
    im.right = flat();
    const VoResult r = vo.Process(im, Eigen::Isometry3d::Identity(), WidePrior());
    if (k == 0) {
      EXPECT_EQ(r.status, VoStatus::kBaseline);
      continue;
    }
    EXPECT_NE(r.status, VoStatus::kOk);
    EXPECT_TRUE(r.status == VoStatus::kTooFewFeatures || r.status == VoStatus::kTooFewMatches)
        << ToString(r.status);
    EXPECT_FALSE(r.reason.empty());
    EXPECT_TRUE(r.T_prev_curr.isApprox(Eigen::Isometry3d::Identity()));
  }
}

TEST(VisualOdometry, VO1_BadInputIsRefusedWithAReason) {
  VisualOdometry vo(VoOptions{});
  StereoImages im;
  im.rig = test::MakeRig(512, 384, 400, 255.5, 191.5, 0.25);
  im.left = cv::Mat(384, 512, CV_8U, cv::Scalar(0));
  im.right = cv::Mat(300, 512, CV_8U, cv::Scalar(0));
  const VoResult r = vo.Process(im, Eigen::Isometry3d::Identity(), WidePrior());
  EXPECT_EQ(r.status, VoStatus::kBadInput);
  EXPECT_NE(r.reason.find("size"), std::string::npos) << r.reason;
}

TEST(Features, VO2_FixedCountSpreadAtMinimumDistance) {
  cv::Mat img(300, 400, CV_32F);
  cv::randu(img, 0, 1);
  cv::GaussianBlur(img, img, cv::Size(0, 0), 1.5);
  CornerOptions o;
  o.count = 100;
  o.min_distance_px = 20;
  o.grid_cell_px = 8;
  o.min_response = 0;
  const std::vector<Corner> c = DetectCorners(img, o);
  ASSERT_EQ(static_cast<int>(c.size()), 100);
  for (size_t i = 0; i < c.size(); ++i) {
    if (i > 0) {
      EXPECT_LE(c[i].response, c[i - 1].response);
    }
    for (size_t j = 0; j < i; ++j) {
      EXPECT_GE(std::hypot(c[i].x - c[j].x, c[i].y - c[j].y), 20.0);
    }
  }
  // Features span the image: every quarter of it holds some.
  int quarter[4] = {0, 0, 0, 0};
  for (const Corner& k : c) ++quarter[(k.x >= 200) + 2 * (k.y >= 150)];
  for (int q : quarter) EXPECT_GT(q, 10);
}

// Known answer, exactly: the grid pass (made row by row with the response, vectorised)
// finds in every cell the pixel a plain scan of the response image finds: the strongest
// 3x3 local maximum above the floor, the first in raster order on ties. With a spacing of
// 1 px every cell's peak is kept, so the corners are the cells' peaks; cells of 8 (the
// default) and of 5, with the image's width not a whole number of cells.
TEST(Features, VO2_GridPeaksAreThePlainScansOfTheResponse) {
  cv::Mat img(123, 211, CV_32F);
  cv::randu(img, 0, 1);
  cv::GaussianBlur(img, img, cv::Size(0, 0), 1.2);
  // On each path (vo/simd.hpp): the CPU's best (AVX2 here) and the portable loops.
  for (const auto& [portable, cell] : std::vector<std::pair<bool, int>>{{false, 8}, {false, 5}, {true, 8}, {true, 5}}) {
    SCOPED_TRACE(portable ? "the portable loops" : "the CPU's best loops");
    const PathForScope path(portable);
    CornerOptions o;
    o.count = 1 << 20;
    o.min_distance_px = 1;
    o.grid_cell_px = cell;
    o.border_px = 7;
    cv::Mat response;
    std::vector<Corner> got = DetectCorners(img, o, &response);
    const int x_begin = o.border_px, x_end = img.cols - o.border_px;
    const int y_begin = o.border_px, y_end = img.rows - o.border_px;
    const int gx = (x_end - x_begin + cell - 1) / cell, gy = (y_end - y_begin + cell - 1) / cell;
    std::vector<Corner> best(static_cast<std::size_t>(gx * gy));
    const float floor = static_cast<float>(o.min_response);
    for (int y = y_begin; y < y_end; ++y) {
      for (int x = x_begin; x < x_end; ++x) {
        const float v = response.at<float>(y, x);
        bool peak = v > floor;
        for (int dy = -1; dy <= 1 && peak; ++dy) {
          for (int dx = -1; dx <= 1; ++dx) peak = peak && v >= response.at<float>(y + dy, x + dx);
        }
        Corner& b = best[static_cast<std::size_t>((y - y_begin) / cell * gx + (x - x_begin) / cell)];
        if (peak && v > b.response) b = Corner{x, y, v};
      }
    }
    std::vector<Corner> expected;
    for (const Corner& c : best) {
      if (c.response > 0) expected.push_back(c);
    }
    auto order = [](const Corner& a, const Corner& b) {
      return std::make_tuple(a.response, a.y, a.x) > std::make_tuple(b.response, b.y, b.x);
    };
    std::sort(got.begin(), got.end(), order);
    std::sort(expected.begin(), expected.end(), order);
    ASSERT_EQ(got.size(), expected.size()) << "cell " << cell;
    ASSERT_GT(expected.size(), 100u);
    for (std::size_t i = 0; i < got.size(); ++i) {
      EXPECT_EQ(got[i].x, expected[i].x) << "cell " << cell << ", corner " << i;
      EXPECT_EQ(got[i].y, expected[i].y) << "cell " << cell << ", corner " << i;
      EXPECT_EQ(got[i].response, expected[i].response) << "cell " << cell << ", corner " << i;
    }
  }
}

TEST(VoOptions, LoadsTheProjectConfigAndRejectsUnknownKeys) {
  const auto node = config::ConfigNode::LoadFile(std::string(ROVER_SOURCE_DIR) + "/configs/vo.yaml");
  const VoOptions o = LoadVoOptions(node["vo"]);
  EXPECT_GT(o.feature_count, 0);
  EXPECT_NO_THROW(VisualOdometry{o});
  const auto bad = config::ConfigNode::FromString("vo:\n  feature_cont: 3\n", "test.yaml");
  try {
    LoadVoOptions(bad["vo"]);
    FAIL() << "unknown key accepted";
  } catch (const config::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("feature_cont"), std::string::npos) << e.what();
  }
  const auto even = config::ConfigNode::FromString("vo:\n  match_template_px: 10\n", "test.yaml");
  EXPECT_THROW(LoadVoOptions(even["vo"]), config::ConfigError);
  // The covariance's carries: both -1 (the weights') or both in [0, 1].
  for (const char* text : {"vo:\n  window_covariance_track_carry: 1.5\n",
                           "vo:\n  window_covariance_track_carry: -0.5\n  window_covariance_stereo_carry: -0.5\n",
                           "vo:\n  window_covariance_track_carry: -1\n  window_covariance_stereo_carry: 0.5\n"}) {
    EXPECT_THROW(LoadVoOptions(config::ConfigNode::FromString(text, "test.yaml")["vo"]), config::ConfigError) << text;
  }
  const auto weights = config::ConfigNode::FromString(
      "vo:\n  window_stereo_carry: 1\n  window_covariance_track_carry: -1\n  window_covariance_stereo_carry: -1\n",
      "test.yaml");
  const VoOptions w = LoadVoOptions(weights["vo"]);
  EXPECT_EQ(CovarianceTrackCarry(w), 0.0);
  EXPECT_EQ(CovarianceStereoCarry(w), 1.0);
  // The published factor's floor: read, 0 (none) in the project config, and not negative.
  EXPECT_EQ(o.window_covariance_min_variance_factor, 0.0);
  const auto floor = config::ConfigNode::FromString("vo:\n  window_covariance_min_variance_factor: 0.9\n", "t.yaml");
  EXPECT_DOUBLE_EQ(LoadVoOptions(floor["vo"]).window_covariance_min_variance_factor, 0.9);
  EXPECT_THROW(LoadVoOptions(config::ConfigNode::FromString("vo:\n  window_covariance_min_variance_factor: -0.1\n",
                                                             "t.yaml")["vo"]),
               config::ConfigError);
  // The s0^2 bound's alpha: read, 1e-4 in the project config, in [0, 0.5].
  EXPECT_DOUBLE_EQ(o.window_covariance_factor_alpha, 1e-4);
  EXPECT_DOUBLE_EQ(LoadVoOptions(config::ConfigNode::FromString("vo:\n  window_covariance_factor_alpha: 0.05\n",
                                                                "t.yaml")["vo"])
                       .window_covariance_factor_alpha,
                   0.05);
  EXPECT_THROW(LoadVoOptions(config::ConfigNode::FromString("vo:\n  window_covariance_factor_alpha: 0.6\n",
                                                             "t.yaml")["vo"]),
               config::ConfigError);
}

// The window's carries are fractions in [0, 1]; the random-walk switch they replaced is
// gone, and a config that still has it is told so by name.
TEST(VoOptions, WindowCarriesAreFractionsAndTheOldSwitchIsNamed) {
  const auto both = config::ConfigNode::FromString("vo:\n  window_track_carry: 0.6\n  window_stereo_carry: 1\n", "t.yaml");
  const VoOptions o = LoadVoOptions(both["vo"]);
  EXPECT_DOUBLE_EQ(o.window_track_carry, 0.6);
  EXPECT_DOUBLE_EQ(o.window_stereo_carry, 1.0);
  for (const char* text : {"vo:\n  window_track_carry: 1.5\n", "vo:\n  window_stereo_carry: -0.1\n",
                           "vo:\n  window_chained_tracks: true\n"}) {
    const auto bad = config::ConfigNode::FromString(text, "t.yaml");
    try {
      LoadVoOptions(bad["vo"]);
      ADD_FAILURE() << "accepted: " << text;
    } catch (const config::ConfigError& e) {
      const std::string key = std::string(text).substr(6, std::string(text).find(':', 6) - 6);
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
    }
  }
}

TEST(VoStatus, NumbersMatchTheMessage) {
  // lcmtypes/vo_update_t.lcm STATUS_*.
  EXPECT_EQ(static_cast<int>(VoStatus::kOk), 0);
  EXPECT_EQ(static_cast<int>(VoStatus::kMotionTooLarge), 7);
  EXPECT_EQ(static_cast<int>(VoStatus::kBadInput), 10);
  EXPECT_STREQ(ToString(VoStatus::kShadowAmbiguous), "shadow_ambiguous");
}

}  // namespace
}  // namespace rover::vo
