// The simulated cameras: both pairs at one pose, each with its own models and size; a
// HAZCAM pair that cannot be rendered leaves the NAVCAM pair whole.
#include "capture/rendered_cameras.hpp"

#include "geometry/camera_io.hpp"
#include "geometry/mast_pointing.hpp"
#include "geometry/pose.hpp"
#include "terrain/world.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace rover::capture {
namespace {

geometry::StereoRig LoadRig(const std::string& name) {
  return geometry::LoadStereoRigFile(std::string(ROVER_SOURCE_DIR) + "/configs/cameras/" + name);
}

terrain::World SmallWorld() {
  terrain::WorldOptions wo;
  wo.seed = 3;
  wo.map_size_m = {20, 20};
  return terrain::World(wo);
}

render::RenderOptions Scaled(double scale) {
  render::RenderOptions o;
  o.image_scale = scale;
  return o;
}

TEST(RenderedCameras, BothPairsAtOnePoseEachWithItsModels) {
  const terrain::World world = SmallWorld();
  RenderedCameras cameras(LoadRig("navcam_pinhole.yaml"), Scaled(0.125), LoadRig("hazcam_front.yaml"), Scaled(0.125));
  EXPECT_TRUE(cameras.has_hazcam());
  const Eigen::Isometry3d T = geometry::PoseFromXyzRpy(1, 2, -world.Elevation(1, 2), 0, 0, 0.3);
  const Exposure e = cameras.Expose(world, T, 9);
  EXPECT_EQ(e.hazcam_error, "");
  ASSERT_TRUE(e.hazcam.has_value());
  EXPECT_EQ(e.navcam.left.cols, 128);
  EXPECT_EQ(e.navcam.rig.left->type(), "pinhole");
  EXPECT_EQ(e.hazcam->left.cols, 128);
  EXPECT_EQ(e.hazcam->rig.left->type(), "cahvore");
  EXPECT_EQ(e.hazcam->rig.right->width(), 128);
  // The HAZCAMs look from 0.52 m up at the ground 0.5 to a few metres ahead: most of their
  // image is ground within a few metres (range > 0 and short), unlike the NAVCAMs'.
  int near = 0;
  for (int v = 0; v < 128; ++v)
    for (int u = 0; u < 128; ++u) near += e.hazcam->depth_left.at<float>(v, u) > 0 && e.hazcam->depth_left.at<float>(v, u) < 1.5;
  EXPECT_GT(near, 128 * 128 / 5);
  // The same pose and seed give the same bytes: a pair is a function of the exposure.
  const Exposure again = cameras.Expose(world, T, 9);
  EXPECT_EQ(cv::countNonZero(again.hazcam->left != e.hazcam->left), 0);
  EXPECT_EQ(cv::countNonZero(again.navcam.left != e.navcam.left), 0);
}

TEST(RenderedCameras, AHazcamFailureLeavesTheNavcamPairWhole) {
  const terrain::World world = SmallWorld();
  geometry::StereoRig broken = LoadRig("hazcam_front.yaml");
  broken.right.reset();  // the renderer refuses a rig without both models
  RenderedCameras cameras(LoadRig("navcam_pinhole.yaml"), Scaled(0.125), std::move(broken), Scaled(0.125));
  const Exposure e = cameras.Expose(world, geometry::PoseFromXyzRpy(0, 0, -world.Elevation(0, 0), 0, 0, 0), 1);
  EXPECT_FALSE(e.hazcam.has_value());
  EXPECT_NE(e.hazcam_error.find("needs both a left and a right model"), std::string::npos) << e.hazcam_error;
  EXPECT_EQ(e.navcam.left.cols, 128);
  EXPECT_EQ(e.navcam.right.cols, 128);
  // Without HAZCAMs: no pair and no error.
  RenderedCameras navcam_only(LoadRig("navcam_pinhole.yaml"), Scaled(0.125));
  EXPECT_FALSE(navcam_only.has_hazcam());
  const Exposure n = navcam_only.Expose(world, geometry::PoseFromXyzRpy(0, 0, -world.Elevation(0, 0), 0, 0, 0), 1);
  EXPECT_FALSE(n.hazcam.has_value());
  EXPECT_EQ(n.hazcam_error, "");
}

TEST(RenderedCameras, APointedExposureIsTheNavcamPairFromThePointedRigAlone) {
  const terrain::World world = SmallWorld();
  const geometry::StereoRig navcam = LoadRig("navcam_pinhole.yaml");
  const Eigen::Isometry3d T = geometry::PoseFromXyzRpy(1, 2, -world.Elevation(1, 2), 0, 0, 0.3);
  const Pointing look{60 * M_PI / 180, 10 * M_PI / 180};
  ASSERT_TRUE(look.pointed());
  EXPECT_FALSE(Pointing{}.pointed());
  RenderedCameras cameras(navcam, Scaled(0.125), LoadRig("hazcam_front.yaml"), Scaled(0.125));
  const Exposure ahead = cameras.Expose(world, T, 5);
  const Exposure pointed = cameras.Expose(world, T, 5, look);
  // The same pose and noise seed, another view.
  EXPECT_GT(cv::countNonZero(pointed.navcam.left != ahead.navcam.left), 128 * 128 / 2);
  EXPECT_GT(cv::countNonZero(pointed.navcam.right != ahead.navcam.right), 128 * 128 / 2);
  // The frame carries the pointed models (rendered at image_scale, as every pair).
  const geometry::StereoRig expected = geometry::PointedRig(navcam, look.pan_rad, look.tilt_rad);
  EXPECT_EQ(pointed.navcam.rig.left->Params(), expected.left->Scaled(0.125)->Params());
  EXPECT_EQ(pointed.navcam.rig.right->Params(), expected.right->Scaled(0.125)->Params());
  EXPECT_NE(pointed.navcam.rig.left->Params(), ahead.navcam.rig.left->Params());
  // The body-fixed HAZCAMs go with unpointed pairs only, and their absence is no failure.
  ASSERT_TRUE(ahead.hazcam.has_value());
  EXPECT_FALSE(pointed.hazcam.has_value());
  EXPECT_EQ(pointed.hazcam_error, "");
  // A pointed exposure leaves nothing behind: the next unpointed one is the one a fresh
  // set of cameras takes with the same seed.
  RenderedCameras fresh(navcam, Scaled(0.125), LoadRig("hazcam_front.yaml"), Scaled(0.125));
  const Exposure after = cameras.Expose(world, T, 6);
  const Exposure reference = fresh.Expose(world, T, 6);
  EXPECT_EQ(cv::countNonZero(after.navcam.left != reference.navcam.left), 0);
  EXPECT_EQ(cv::countNonZero(after.hazcam->left != reference.hazcam->left), 0);
  // A nonsense angle is refused, not rendered.
  EXPECT_THROW(cameras.Expose(world, T, 7, Pointing{std::nan(""), 0}), std::invalid_argument);
}

}  // namespace
}  // namespace rover::capture
