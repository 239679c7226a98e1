#include "geometry/cahv_camera.hpp"
#include "render/image_statistics.hpp"
#include "render/stereo_renderer.hpp"
#include "render/world_ground.hpp"
#include "render_test_support.hpp"
#include "terrain/world.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

namespace rover::render {
namespace {

using test::MarkedGround;
using test::Marker;
using test::NavcamRig;

RenderOptions QuietOptions() {
  RenderOptions o;
  o.noise_sigma_dn = 0;
  // A fixed exposure, so that two renders compare pixel by pixel.
  o.auto_exposure = false;
  o.rover_shadow.enabled = false;
  o.sun_override = true;
  o.sun_azimuth_deg = 0;
  o.sun_elevation_deg = 60;
  return o;
}

// Centroid of a spot around (u, v): of the darkening between a render without the markers
// and one with them, so that shading across a rock does not pull the centroid.
Eigen::Vector2d SpotCentroid(const cv::Mat& plain, const cv::Mat& marked, const Eigen::Vector2d& near,
                             int half) {
  const int u0 = static_cast<int>(std::lround(near.x())), v0 = static_cast<int>(std::lround(near.y()));
  double sw = 0, su = 0, sv = 0;
  for (int v = v0 - half; v <= v0 + half; ++v) {
    for (int u = u0 - half; u <= u0 + half; ++u) {
      const double w = std::max(0, plain.at<std::uint8_t>(v, u) - marked.at<std::uint8_t>(v, u));
      sw += w;
      su += w * u;
      sv += w * v;
    }
  }
  return {su / sw, sv / sw};
}

Eigen::Vector2d ProjectSite(const geometry::CameraModel& cam, const Eigen::Isometry3d& T_site_rover,
                            const Eigen::Vector3d& p_site) {
  Eigen::Vector2d px;
  EXPECT_TRUE(cam.Project(T_site_rover.inverse() * p_site, &px));
  return px;
}

// Ground markers and rock tops: project the known 3-D point through the camera model and
// find the spot's centroid there, to 0.05 px, in both images of `rig`.
void CheckKnownPoints(const geometry::StereoRig& rig, const std::string& label) {
  MarkedGround ground;
  ground.base = 0.3;
  ground.gx = 0.05;  // a gentle slope, so the ground is not the z = 0 plane
  ground.gy = -0.03;
  // Rock tops: flat-topped rocks (as many Gusev rocks are) with a spot on the summit;
  // a spot draped over a rounded dome would lean toward the camera.
  ground.bumps = {{3.4, 0.7, 0.25, 0.18, 0.12}, {4.5, -0.8, 0.3, 0.2, 0.14}};
  // Pose: rover at (10, 5), facing north-east, the ground under its origin.
  const double yaw = 0.6;
  const Eigen::Isometry3d T = geometry::PoseFromXyzRpy(10, 5, -ground.Elevation(10, 5), 0, 0, yaw);
  std::vector<Eigen::Vector3d> points;
  for (const Eigen::Vector2d& q_rover : {Eigen::Vector2d(2.5, 0.0), Eigen::Vector2d(3.0, -0.8),
                                         Eigen::Vector2d(3.8, 1.25), Eigen::Vector2d(4.0, 0.2),
                                         Eigen::Vector2d(3.4, 0.7), Eigen::Vector2d(4.5, -0.8)}) {
    const Eigen::Vector3d p = T * Eigen::Vector3d(q_rover.x(), q_rover.y(), 0);
    points.push_back(Eigen::Vector3d(p.x(), p.y(), -ground.Elevation(p.x(), p.y())));
  }
  // The rock bumps were given in rover coordinates above: move them to the site frame.
  for (auto& b : ground.bumps) {
    const Eigen::Vector3d p = T * Eigen::Vector3d(b.x, b.y, 0);
    b.x = p.x();
    b.y = p.y();
  }
  for (std::size_t k = 4; k < points.size(); ++k) {
    points[k].z() = -ground.Elevation(points[k].x(), points[k].y());
  }
  // Spots about 3 px wide in the image: well sampled, and small enough that perspective
  // does not move their centroid measurably.
  const Eigen::Vector3d cam_site = T * Eigen::Vector3d(0.45, 0, -1.5);
  for (std::size_t k = 0; k < points.size(); ++k) {
    ground.markers.push_back(Marker{points[k].x(), points[k].y(), 0.005 * (points[k] - cam_site).norm()});
  }

  // The sun overhead: shading across a rock top is then symmetric about the apex and does
  // not pull the spot's centroid (this test is about geometry, not photometry).
  RenderOptions opt = QuietOptions();
  opt.sun_elevation_deg = 90;
  StereoRenderer renderer(opt);
  const StereoImages images = renderer.RenderPair(ground, Sun{}, rig, T, 7);
  ground.marker_depth = 0;
  const StereoImages plain = renderer.RenderPair(ground, Sun{}, rig, T, 7);
  const int w = rig.left->width(), h = rig.left->height();
  int checked = 0;
  double worst = 0;
  for (std::size_t k = 0; k < points.size(); ++k) {
    for (int cam = 0; cam < 2; ++cam) {
      const geometry::CameraModel& model = cam == 0 ? *images.rig.left : *images.rig.right;
      const cv::Mat& img = cam == 0 ? images.left : images.right;
      const cv::Mat& img0 = cam == 0 ? plain.left : plain.right;
      const Eigen::Vector2d expected = ProjectSite(model, T, points[k]);
      ASSERT_GT(expected.x(), 14);
      ASSERT_LT(expected.x(), w - 15);
      ASSERT_GT(expected.y(), 14);
      ASSERT_LT(expected.y(), h - 15);
      if (k >= 4) {
        // A rock top is also where the range says: the ray through the projected pixel
        // meets the summit (bilinear range at the sub-pixel position).
        const cv::Mat& depth = cam == 0 ? images.depth_left : images.depth_right;
        const int u0 = static_cast<int>(expected.x()), v0 = static_cast<int>(expected.y());
        const double a = expected.x() - u0, b = expected.y() - v0;
        const double r = (1 - b) * ((1 - a) * depth.at<float>(v0, u0) + a * depth.at<float>(v0, u0 + 1)) +
                         b * ((1 - a) * depth.at<float>(v0 + 1, u0) + a * depth.at<float>(v0 + 1, u0 + 1));
        EXPECT_NEAR(r, (T * model.Center() - points[k]).norm(), 0.003) << "rock top " << k << " camera " << cam;
      }
      const Eigen::Vector2d found = SpotCentroid(img0, img, expected, 12);
      worst = std::max(worst, (found - expected).norm());
      EXPECT_LT((found - expected).norm(), 0.05)
          << label << ": point " << k << " camera " << cam << " expected " << expected.transpose() << " found "
          << found.transpose();
      ++checked;
    }
  }
  EXPECT_EQ(checked, 12);  // 4 ground markers and 2 rock tops, in both images
  std::printf("%s: worst spot centroid %.4f px from the model's projection\n", label.c_str(), worst);
}

TEST(StereoRenderer, KnownPointsAppearWhereTheModelProjectsThem) {
  CheckKnownPoints(NavcamRig(512), "pinhole");
}

// The same through CAHVOR models with a real NAVCAM's radial distortion (R of a Spirit
// NAVCAM label, cahvor_test_vectors.yaml): the renderer follows the model's own rays.
TEST(StereoRenderer, KnownPointsAppearWhereACahvorModelProjectsThem) {
  const geometry::StereoRig pin = NavcamRig(512);
  geometry::StereoRig rig;
  for (int side = 0; side < 2; ++side) {
    const auto& p = dynamic_cast<const geometry::PinholeCamera&>(side == 0 ? *pin.left : *pin.right);
    const geometry::CahvCamera cahv = geometry::CahvFromPinhole(p);
    auto model = std::make_shared<geometry::CahvorCamera>(512, 512, cahv.C(), cahv.A(), cahv.H(), cahv.V(), cahv.A(),
                                                          Eigen::Vector3d(0.019876, -0.014281, 0.020876));
    (side == 0 ? rig.left : rig.right) = model;
  }
  CheckKnownPoints(rig, "cahvor");
}

// The simulator's world is traced on its own grid: every rendered hit lies on
// World::Elevation's surface and re-projects to its own pixel centre.
TEST(StereoRenderer, DepthOfWorldHitsLiesOnTheSurfaceAndReprojects) {
  terrain::WorldOptions wo;
  wo.map_size_m = {30, 30};
  wo.roughness.amplitude_m = 0.15;
  wo.random_rocks.abundance_k = 0.1;
  wo.random_rocks.min_diameter_m = 0.1;
  wo.seed = 11;
  const terrain::World world(wo);
  const Eigen::Isometry3d T = geometry::PoseFromXyzRpy(-2, 1, -world.Elevation(-2, 1), 0.02, -0.04, 0.3);
  StereoRenderer renderer(QuietOptions());
  const StereoImages images = renderer.RenderPair(world, NavcamRig(256), T, 1);
  int hits = 0;
  double worst_px = 0, worst_mm = 0;
  for (int v = 0; v < 256; v += 3) {
    for (int u = 0; u < 256; u += 3) {
      const float r = images.depth_left.at<float>(v, u);
      if (r <= 0) continue;
      Eigen::Vector3d o, d;
      images.rig.left->BackProject(Eigen::Vector2d(u, v), &o, &d);
      const Eigen::Vector3d p_rover = o + r * d.normalized();
      const Eigen::Vector3d p_site = T * p_rover;
      Eigen::Vector2d px;
      ASSERT_TRUE(images.rig.left->Project(p_rover, &px));
      worst_px = std::max(worst_px, (px - Eigen::Vector2d(u, v)).norm());
      worst_mm = std::max(worst_mm, 1000 * std::abs(-p_site.z() - world.Elevation(p_site.x(), p_site.y())));
      ++hits;
    }
  }
  EXPECT_GT(hits, 3000);
  EXPECT_LT(worst_px, 0.01);
  EXPECT_LT(worst_mm, 0.1);  // float depth rounding only
}

// Disparity from truth agrees with range: d = f B / Z for the rectified pair, and the right
// image really holds the left image's texture at that disparity (block matching).
TEST(StereoRenderer, DisparityFromTruthAgreesWithRange) {
  terrain::WorldOptions wo;
  wo.map_size_m = {30, 30};
  wo.default_soil = terrain::Soil::kBedrock;
  wo.roughness.amplitude_m = 0.05;
  const terrain::World world(wo);
  const int size = 256;
  const geometry::StereoRig rig = NavcamRig(size);
  const auto* left = dynamic_cast<const geometry::PinholeCamera*>(rig.left.get());
  ASSERT_NE(left, nullptr);
  const double f = left->fx(), B = rig.Baseline();
  const Eigen::Isometry3d T = geometry::PoseFromXyzRpy(0, 0, -world.Elevation(0, 0), 0, 0, 0.2);
  RenderOptions opt = QuietOptions();
  StereoRenderer renderer(opt);
  const StereoImages images = renderer.RenderPair(world, rig, T, 3);
  const cv::Mat disp = DisparityFromDepth(images.depth_left, images.rig);

  std::vector<double> match_err;
  int compared = 0;
  for (int v = 20; v < size - 20; v += 6) {
    for (int u = 30; u < size - 20; u += 6) {
      const float r = images.depth_left.at<float>(v, u);
      if (r <= 0) continue;
      Eigen::Vector3d o, d;
      images.rig.left->BackProject(Eigen::Vector2d(u, v), &o, &d);
      // Depth along the optical axis of the (rectified) left camera.
      const Eigen::Vector3d p_cam = left->T_ref_cam().inverse() * (o + r * d.normalized());
      const double expected = f * B / p_cam.z();
      EXPECT_NEAR(disp.at<float>(v, u), expected, 1e-3);
      ++compared;
      // Sub-pixel block match of a 9x9 window along the same row of the right image.
      const int half = 4, c = static_cast<int>(std::lround(expected));
      if (u - c - half - 3 < 0) continue;
      double best = 1e30;
      int best_d = 0;
      std::vector<double> cost(7);
      for (int k = -3; k <= 3; ++k) {
        double sad = 0;
        for (int dv = -half; dv <= half; ++dv) {
          for (int du = -half; du <= half; ++du) {
            const double a = images.left.at<std::uint8_t>(v + dv, u + du);
            const double b = images.right.at<std::uint8_t>(v + dv, u + du - (c + k));
            sad += (a - b) * (a - b);
          }
        }
        cost[k + 3] = sad;
        if (sad < best) {
          best = sad;
          best_d = k;
        }
      }
      if (best_d == -3 || best_d == 3) continue;
      const double cm = cost[best_d + 2], c0 = cost[best_d + 3], cp = cost[best_d + 4];
      const double denom = cm - 2 * c0 + cp;
      if (denom <= 0) continue;
      const double measured = c + best_d + 0.5 * (cm - cp) / denom;
      match_err.push_back(std::abs(measured - expected));
    }
  }
  EXPECT_GT(compared, 500);
  ASSERT_GT(match_err.size(), 300u);
  std::sort(match_err.begin(), match_err.end());
  EXPECT_LT(match_err[match_err.size() / 2], 0.1);
  EXPECT_LT(match_err[match_err.size() * 9 / 10], 0.35);
}

TEST(StereoRenderer, SameSeedGivesIdenticalBytes) {
  terrain::WorldOptions wo;
  wo.map_size_m = {20, 20};
  wo.random_rocks.abundance_k = 0.08;
  const terrain::World world(wo);
  const Eigen::Isometry3d T = geometry::PoseFromXyzRpy(0, 0, -world.Elevation(0, 0), 0, 0, 0);
  RenderOptions opt;
  opt.noise_sigma_dn = 2.0;
  StereoRenderer a(opt), b(opt);
  const StereoImages i1 = a.RenderPair(world, NavcamRig(128), T, 42);
  const StereoImages i2 = b.RenderPair(world, NavcamRig(128), T, 42);
  const StereoImages i3 = a.RenderPair(world, NavcamRig(128), T, 43);
  EXPECT_EQ(cv::norm(i1.left, i2.left, cv::NORM_L1), 0);
  EXPECT_EQ(cv::norm(i1.right, i2.right, cv::NORM_L1), 0);
  EXPECT_TRUE(std::equal(i1.left.datastart, i1.left.dataend, i2.left.datastart));
  // Another frame seed: other noise.
  EXPECT_GT(cv::norm(i1.left, i3.left, cv::NORM_L1), 1000);
}

TEST(StereoRenderer, TwoThreadsGiveTheSameBytesAsOne) {
  terrain::WorldOptions wo;
  wo.map_size_m = {20, 20};
  wo.random_rocks.abundance_k = 0.1;
  const terrain::World world(wo);
  const Eigen::Isometry3d T = geometry::PoseFromXyzRpy(0.5, -0.3, -world.Elevation(0.5, -0.3), 0.02, -0.03, 0.4);
  RenderOptions opt;
  opt.noise_sigma_dn = 2.0;
  StereoRenderer one(opt);
  opt.threads = 2;
  StereoRenderer two(opt);
  const StereoImages a = one.RenderPair(world, NavcamRig(160), T, 7);
  const StereoImages b = two.RenderPair(world, NavcamRig(160), T, 7);
  ASSERT_EQ(a.left.size(), b.left.size());
  EXPECT_TRUE(std::equal(a.left.datastart, a.left.dataend, b.left.datastart));
  EXPECT_TRUE(std::equal(a.right.datastart, a.right.dataend, b.right.datastart));
  EXPECT_EQ(cv::norm(a.depth_left, b.depth_left, cv::NORM_L1), 0);
  EXPECT_EQ(cv::norm(a.depth_right, b.depth_right, cv::NORM_L1), 0);
  EXPECT_EQ(a.exposure_gain, b.exposure_gain);
  // The right image is not the left one: each thread traced its own camera.
  EXPECT_GT(cv::norm(b.left, b.right, cv::NORM_L1), 1000);
}

// The fraction of the left image darker than `fraction` of the same pixel lit without the
// rover's shadow.
double ShadowedFraction(const Ground& ground, const Eigen::Isometry3d& T, double az, double el) {
  RenderOptions opt = QuietOptions();
  opt.sun_azimuth_deg = az;
  opt.sun_elevation_deg = el;
  opt.rover_shadow.enabled = true;
  StereoRenderer with(opt);
  opt.rover_shadow.enabled = false;
  StereoRenderer without(opt);
  const geometry::StereoRig rig = NavcamRig(256);
  const cv::Mat a = with.RenderPair(ground, Sun{}, rig, T, 1).left;
  const cv::Mat b = without.RenderPair(ground, Sun{}, rig, T, 1).left;
  int dark = 0;
  for (int v = 0; v < a.rows; ++v) {
    for (int u = 0; u < a.cols; ++u) {
      if (a.at<std::uint8_t>(v, u) < 0.6 * b.at<std::uint8_t>(v, u)) ++dark;
    }
  }
  return dark / static_cast<double>(a.total());
}

TEST(StereoRenderer, RoverShadowInViewOnlyWithTheSunBehindAndLow) {
  MarkedGround sand;
  sand.albedo = 0.3;
  // Rover faces north (yaw 0) at the origin.
  const Eigen::Isometry3d T = geometry::PoseFromXyzRpy(0, 0, 0, 0, 0, 0);
  const double behind_low = ShadowedFraction(sand, T, 180, 15);
  EXPECT_GT(behind_low, 0.02) << "sun behind and low: the shadow of mast and body falls ahead";
  EXPECT_EQ(ShadowedFraction(sand, T, 0, 30), 0.0) << "sun in front: shadow behind the rover";
  EXPECT_EQ(ShadowedFraction(sand, T, 180, 85), 0.0) << "sun high: shadow under the rover";
  // Rotating the rover to face the sun moves the shadow out of view.
  const Eigen::Isometry3d T_south = geometry::PoseFromXyzRpy(0, 0, 0, 0, 0, M_PI);
  EXPECT_EQ(ShadowedFraction(sand, T_south, 180, 15), 0.0);
}

TEST(StereoRenderer, SandGivesFarFewerCornersThanBedrock) {
  RenderOptions opt;
  opt.sun_override = true;
  opt.sun_azimuth_deg = 120;
  opt.sun_elevation_deg = 40;
  StereoRenderer renderer(opt);
  // Summed over three world seeds: the count above a fixed Harris threshold depends on
  // one texture draw a lot (42 to 255 corners on bedrock for seeds 1 to 5), the soil
  // difference does not.
  int corners[2] = {0, 0};
  for (int k = 0; k < 2; ++k) {
    for (std::uint64_t seed = 1; seed <= 3; ++seed) {
      terrain::WorldOptions wo;
      wo.seed = seed;
      wo.map_size_m = {40, 40};
      wo.default_soil = k == 0 ? terrain::Soil::kSand : terrain::Soil::kBedrock;
      wo.roughness.amplitude_m = 0.03;
      const terrain::World world(wo);
      const Eigen::Isometry3d T = geometry::PoseFromXyzRpy(0, 0, -world.Elevation(0, 0), 0, 0, 0);
      const StereoImages images = renderer.RenderPair(world, NavcamRig(512), T, 5);
      corners[k] += MeasureImage(images.left).corners;
    }
  }
  EXPECT_GT(corners[1], 100) << "bedrock";
  EXPECT_LT(corners[0] * 5, corners[1]) << "sand " << corners[0] << " bedrock " << corners[1];
}

TEST(StereoRenderer, AutoExposureBringsALowSunSceneToTheTargetMean) {
  MarkedGround sand;
  sand.albedo = 0.2;
  const Eigen::Isometry3d T = geometry::PoseFromXyzRpy(0, 0, 0, 0, 0, 0);
  RenderOptions opt = QuietOptions();
  opt.sun_elevation_deg = 8;  // low sun: little direct light on flat ground
  StereoRenderer fixed(opt);
  opt.auto_exposure = true;
  opt.target_mean_dn = 110;
  StereoRenderer automatic(opt);
  const StereoImages dark = fixed.RenderPair(sand, Sun{}, NavcamRig(128), T, 1);
  const StereoImages lit = automatic.RenderPair(sand, Sun{}, NavcamRig(128), T, 1);
  const double dark_mean = cv::mean(dark.left)[0];
  EXPECT_LT(dark_mean, 60) << "fixed exposure leaves low sun dark";
  EXPECT_NEAR(cv::mean(lit.left)[0], 110, 1.0);
  EXPECT_NEAR(lit.exposure_gain, 110 / dark_mean, 0.05 * 110 / dark_mean);
  // One gain for both cameras: the right image is scaled alike, not to its own mean.
  EXPECT_NEAR(cv::mean(lit.right)[0], lit.exposure_gain * cv::mean(dark.right)[0], 0.5 * lit.exposure_gain + 0.5);
  EXPECT_EQ(dark.exposure_gain, 1.0);
}

TEST(StereoRenderer, RejectsBadOptions) {
  RenderOptions o;
  o.image_scale = 0;
  EXPECT_THROW(StereoRenderer{o}, std::invalid_argument);
  o = RenderOptions();
  o.grid_cell_pixels = -1;
  EXPECT_THROW(StereoRenderer{o}, std::invalid_argument);
}

TEST(RenderOptions, LoadsAndRejectsUnknownKeys) {
  const auto node = config::ConfigNode::FromString(
      "render:\n  noise_sigma_dn: 0.5\n  sun: {azimuth_deg: 10, elevation_deg: 20}\n"
      "  rover_shadow: {enabled: false, boxes: [[0, 1, 0, 1, -1, 0]]}\n",
      "test.yaml");
  const RenderOptions o = LoadRenderOptions(node["render"]);
  EXPECT_EQ(o.noise_sigma_dn, 0.5);
  EXPECT_TRUE(o.sun_override);
  EXPECT_EQ(o.sun_elevation_deg, 20);
  EXPECT_FALSE(o.rover_shadow.enabled);
  ASSERT_EQ(o.rover_shadow.boxes.size(), 1u);
  const auto bad = config::ConfigNode::FromString("render:\n  noise_sigmaa: 1\n", "bad.yaml");
  try {
    LoadRenderOptions(bad["render"]);
    FAIL() << "unknown key accepted";
  } catch (const config::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("noise_sigmaa"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace rover::render
