// The front HAZCAM pair (configs/cameras/hazcam_front.yaml) sees the near field the mast's
// NAVCAM pair (configs/cameras/navcam_pinhole.yaml) never sees: the ground beside the front
// wheels and just ahead of the body. Known ground points are projected through both rigs'
// models, and a rock put there is found in a rendered HAZCAM pair where the model says.
#include "geometry/camera_io.hpp"
#include "geometry/pose.hpp"
#include "render/stereo_renderer.hpp"
#include "render_test_support.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace rover::render {
namespace {

using test::MarkedGround;

geometry::StereoRig LoadRig(const std::string& name) {
  return geometry::LoadStereoRigFile(std::string(ROVER_SOURCE_DIR) + "/configs/cameras/" + name);
}

// Whether the point (rover frame) projects inside the model's image.
bool InImage(const geometry::CameraModel& model, const Eigen::Vector3d& p_rover, Eigen::Vector2d* px) {
  if (!model.Project(p_rover, px)) return false;
  return px->x() >= -0.5 && px->x() <= model.width() - 0.5 && px->y() >= -0.5 && px->y() <= model.height() - 0.5;
}

// Ground points (rover frame, on flat ground z = 0) the NAVCAMs never see. The front wheels
// stand at x = 0.6 m, y = +-0.6 m (0.25 m across, 0.16 m wide: their front edge at
// x = 0.725 m, their outer side at |y| = 0.68 m); the deck ends at x = 0.8 m. (The ground
// right beside a wheel, at its axle, is 74 deg off the HAZCAM's axis, outside its 62 deg
// half-width: no front HAZCAM sees it, on MER neither.)
struct NearPoint {
  const char* what;
  Eigen::Vector3d p;
};
const NearPoint kNearField[] = {
    {"0.3 m ahead of the body", {1.1, 0.0, 0.0}},
    {"0.3 m ahead of the body, left of centre", {1.1, -0.4, 0.0}},
    {"ahead of and outside the right front wheel", {0.95, 0.75, 0.0}},
    {"ahead of and outside the left front wheel", {0.95, -0.75, 0.0}},
    {"just ahead of the right front wheel", {0.9, 0.6, 0.0}},
};

TEST(HazcamView, SeesTheNearFieldTheNavcamsNeverSee) {
  const geometry::StereoRig hazcam = LoadRig("hazcam_front.yaml");
  const geometry::StereoRig navcam = LoadRig("navcam_pinhole.yaml");
  ASSERT_EQ(hazcam.left->type(), "cahvore");
  for (const NearPoint& n : kNearField) {
    Eigen::Vector2d px;
    for (const auto* model : {hazcam.left.get(), hazcam.right.get()}) {
      EXPECT_TRUE(InImage(*model, n.p, &px)) << n.what << ": outside the HAZCAM image";
      // A ray, not a grazing one at the fish-eye's rim: at least 8 px inside.
      EXPECT_GT(std::min({px.x(), px.y(), model->width() - 1 - px.x(), model->height() - 1 - px.y()}), 8.0)
          << n.what << " at " << px.transpose();
    }
    for (const auto* model : {navcam.left.get(), navcam.right.get()}) {
      EXPECT_FALSE(InImage(*model, n.p, &px)) << n.what << ": the NAVCAM sees it at " << px.transpose();
    }
  }
  // Where the NAVCAMs do look (3 m ahead) the HAZCAMs see too: the two views overlap.
  Eigen::Vector2d px;
  EXPECT_TRUE(InImage(*navcam.left, {3.0, 0.0, 0.0}, &px));
  EXPECT_TRUE(InImage(*hazcam.left, {3.0, 0.0, 0.0}, &px));
}

// A flat-topped rock at each near-field point: the HAZCAM pair rendered at 256x256 (as
// camera_capture renders it) meets the rock's top where the model projects it, and the
// rock stands out against the same scene rendered without it.
TEST(HazcamView, ARockInTheNearFieldShowsInTheRenderedPair) {
  const geometry::StereoRig hazcam = LoadRig("hazcam_front.yaml");
  const double height = 0.08;
  MarkedGround ground;
  ground.albedo = 0.35;
  for (const NearPoint& n : kNearField) ground.bumps.push_back({n.p.x(), n.p.y(), 0.08, height, 0.04});
  MarkedGround bare = ground;
  bare.bumps.clear();

  RenderOptions options;
  options.image_scale = 0.25;
  options.noise_sigma_dn = 0;
  options.auto_exposure = false;  // the same exposure with and without the rocks
  options.rover_shadow.enabled = false;
  options.sun_override = true;
  options.sun_azimuth_deg = 60;
  options.sun_elevation_deg = 40;
  // This hand-made ground is resampled into height grids around the rig (the simulator's
  // world is traced on its own grid): cells of about 4 mm here, so that 8 cm rocks keep
  // their shape.
  options.grid_near_range_m = 1.0;
  options.grid_cell_pixels = 0.5;
  StereoRenderer renderer(options);
  const Eigen::Isometry3d T = geometry::PoseFromXyzRpy(0, 0, 0, 0, 0, 0);  // on the ground, facing north
  const StereoImages rocks = renderer.RenderPair(ground, Sun{}, hazcam, T, 3);
  const StereoImages plain = renderer.RenderPair(bare, Sun{}, hazcam, T, 3);
  ASSERT_EQ(rocks.left.cols, 256);
  ASSERT_EQ(rocks.rig.left->width(), 256);

  for (const NearPoint& n : kNearField) {
    const Eigen::Vector3d top(n.p.x(), n.p.y(), -height);  // z down
    for (int cam = 0; cam < 2; ++cam) {
      const geometry::CameraModel& model = cam == 0 ? *rocks.rig.left : *rocks.rig.right;
      Eigen::Vector2d px;
      ASSERT_TRUE(model.Project(top, &px)) << n.what;
      const int u = static_cast<int>(std::lround(px.x())), v = static_cast<int>(std::lround(px.y()));
      ASSERT_TRUE(u >= 1 && v >= 1 && u < 255 && v < 255) << n.what << " at " << px.transpose();
      // The ray of the projected pixel meets the rock's flat top, 8 cm across: its range is
      // the camera's distance to the top, within the pixel's footprint there.
      const cv::Mat& depth = cam == 0 ? rocks.depth_left : rocks.depth_right;
      const cv::Mat& depth_bare = cam == 0 ? plain.depth_left : plain.depth_right;
      const double range = (model.Center() - top).norm();
      EXPECT_NEAR(depth.at<float>(v, u), range, 0.02) << n.what << " camera " << cam;
      // Without the rock the same ray goes on to the ground behind it.
      EXPECT_GT(depth_bare.at<float>(v, u), range + 0.05) << n.what << " camera " << cam;
      // And the images differ around it: the rock is seen, not only traced. (Its flat top
      // faces up like the ground and is lit alike; its shoulder, some 25 px across here,
      // and its shadow are not.)
      const cv::Mat& img = cam == 0 ? rocks.left : rocks.right;
      const cv::Mat& img_bare = cam == 0 ? plain.left : plain.right;
      double most = 0;
      for (int dv = -8; dv <= 8; ++dv) {
        for (int du = -8; du <= 8; ++du) {
          if (u + du < 0 || v + dv < 0 || u + du > 255 || v + dv > 255) continue;
          most = std::max(most, std::abs(double(img.at<std::uint8_t>(v + dv, u + du)) -
                                         img_bare.at<std::uint8_t>(v + dv, u + du)));
        }
      }
      EXPECT_GT(most, 20.0) << n.what << " camera " << cam << ": the rock does not change the image";
    }
  }
  // Truth disparity at the left image's projection of each rock top: positive and finite
  // (both cameras see it; what the map's stereo will measure).
  const cv::Mat disparity = DisparityFromDepth(rocks.depth_left, rocks.rig);
  for (const NearPoint& n : kNearField) {
    Eigen::Vector2d px;
    ASSERT_TRUE(rocks.rig.left->Project(Eigen::Vector3d(n.p.x(), n.p.y(), -height), &px));
    const float d = disparity.at<float>(static_cast<int>(std::lround(px.y())), static_cast<int>(std::lround(px.x())));
    EXPECT_TRUE(std::isfinite(d) && d > 1.0f) << n.what << ": disparity " << d;
  }
}

// The mast in a HAZCAM render's shadow stands under the NAVCAM rig that it carries.
TEST(HazcamView, MastUnderRigPutsTheMastUnderTheNavcams) {
  const geometry::StereoRig navcam = LoadRig("navcam_pinhole.yaml");
  RoverShadowOptions shadow;
  const std::size_t boxes = shadow.boxes.size();
  const RoverShadowOptions mast = MastUnderRig(shadow, navcam);
  EXPECT_FALSE(mast.mast_from_rig);
  EXPECT_NEAR(mast.mast_x_m, 0.2, 1e-9);  // navcam_pinhole.yaml: C at x 0.2, y -+0.1, z -1.5
  EXPECT_NEAR(mast.mast_y_m, 0.0, 1e-9);
  EXPECT_NEAR(mast.mast_z_top_m, -1.44, 1e-9);
  ASSERT_EQ(mast.boxes.size(), boxes + 1);  // and the camera bar
  EXPECT_NEAR(mast.boxes.back()[2], -0.17, 1e-9);
  EXPECT_NEAR(mast.boxes.back()[3], 0.17, 1e-9);
  // An explicit mast stays where it was put.
  const RoverShadowOptions again = MastUnderRig(mast, LoadRig("hazcam_front.yaml"));
  EXPECT_EQ(again.mast_x_m, mast.mast_x_m);
  EXPECT_EQ(again.boxes.size(), mast.boxes.size());
}

// camera_capture's capture.hazcam.render: the NAVCAM's options, overridden key by key.
TEST(RenderOptions, LoadsOverABase) {
  RenderOptions base;
  base.image_scale = 0.5;
  base.threads = 2;
  base.sun_override = true;
  base.sun_azimuth_deg = 77;
  const auto node = config::ConfigNode::FromString("render:\n  image_scale: 0.25\n", "test.yaml");
  const RenderOptions o = LoadRenderOptions(node["render"], base);
  EXPECT_EQ(o.image_scale, 0.25);
  EXPECT_EQ(o.threads, 2);
  EXPECT_TRUE(o.sun_override);
  EXPECT_EQ(o.sun_azimuth_deg, 77);
  EXPECT_EQ(LoadRenderOptions(node["absent"], base).image_scale, 0.5);
  const auto bad = config::ConfigNode::FromString("render:\n  image_scal: 0.25\n", "bad.yaml");
  EXPECT_THROW(LoadRenderOptions(bad["render"], base), config::ConfigError);
}

}  // namespace
}  // namespace rover::render
