// VO-11, the rover's own shadow. On Sol 235 Spirit's NAVCAMs saw two small rocks on sand and
// the rover's shadow; more features were found on the shadow than on the ground, and VO
// reported the shadow's motion (none) instead of the rover's. Here the shipped NAVCAM rig
// and configs/vo.yaml look at rendered sand with the sun low behind the rover, so the shadow
// of the deck and mast fills the middle of the view, and VO must measure the ground.
#include "config/yaml_config.hpp"
#include "geometry/camera_io.hpp"
#include "geometry/pose.hpp"
#include "render/stereo_renderer.hpp"
#include "terrain/world.hpp"
#include "vo/motion_prior.hpp"
#include "vo/visual_odometry.hpp"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <string>

namespace rover::vo {
namespace {

const std::string kSource = ROVER_SOURCE_DIR;

// Textured sand (Gusev-like fines, enough texture for VO on its own) with the sun `elevation`
// degrees high, due south: the rover faces north, so its shadow lies ahead of it.
terrain::World SandWorld(double sun_elevation_deg) {
  const std::string text =
      "name: shadow_test\nseed: 77\n"
      "map: {center: [3, 0], size_m: [14, 12], resolution_m: 0.05}\n"
      "roughness: {amplitude_m: 0.005, min_wavelength_m: 0.4, max_wavelength_m: 8.0}\n"
      "ripples: {amplitude_m: 0.008, wavelength_m: 2.5, crest_azimuth_deg: 100}\n"
      "soil: {default: sand}\n"
      "rocks: {placed: [{name: A, position: [3.0, -0.6], diameter_m: 0.2, height_m: 0.1},\n"
      "                 {name: B, position: [4.2, 0.8], diameter_m: 0.25, height_m: 0.12}]}\n"
      "albedo: {sand: {contrast: 0.3, min_wavelength_m: 0.01}}\n"
      "sun: {azimuth_deg: 180, elevation_deg: " + std::to_string(sun_elevation_deg) + "}\n";
  return terrain::World(terrain::WorldOptions::Load(config::ConfigNode(YAML::Load(text), "shadow_test", "")));
}

class ShadowScene {
 public:
  explicit ShadowScene(double sun_elevation_deg)
      : world_(SandWorld(sun_elevation_deg)),
        rig_(geometry::LoadStereoRigFile(kSource + "/configs/cameras/navcam_pinhole.yaml")) {
    render::RenderOptions ro;
    ro.image_scale = 0.5;  // 512x512, as camera_capture renders (configs/rover.yaml)
    renderer_ = std::make_unique<render::StereoRenderer>(ro);
    const config::ConfigNode vo = config::ConfigNode::LoadFile(kSource + "/configs/vo.yaml");
    options_ = LoadVoOptions(vo["vo"]);
  }

  Eigen::Isometry3d PoseAt(double x) const {
    // The rover's attitude on the ground under it, from the surface normal.
    const Eigen::Vector3d n = world_.NormalUp(x, 0);  // site axes, z < 0
    const double pitch = std::atan2(-n.x(), -n.z());
    const double roll = std::atan2(n.y(), std::hypot(n.x(), n.z()));
    return geometry::PoseFromXyzRpy(x, 0, -world_.Elevation(x, 0), roll, pitch, 0);
  }

  StereoImages Render(const Eigen::Isometry3d& T, std::int64_t id) {
    const render::StereoImages r = renderer_->RenderPair(world_, rig_, T, id);
    StereoImages im;
    im.left = r.left;
    im.right = r.right;
    im.rig = r.rig;
    im.frame_id = id;
    im.utime = id * 1000000;
    return im;
  }

  const VoOptions& options() const { return options_; }

 private:
  terrain::World world_;
  geometry::StereoRig rig_;
  std::unique_ptr<render::StereoRenderer> renderer_;
  VoOptions options_;
};

// The visual_odometry process's prior for a 50 cm step: the commanded motion, with the
// spread it gives wheel odometry (vo/motion_prior.hpp defaults: 30 cm, 2 deg).
Eigen::Matrix<double, 6, 6> StepPrior() {
  return MotionPriorCovariance(geometry::PoseFromXyzRpy(0.5, 0, 0, 0, 0, 0), MotionPriorOptions{});
}

// x y z of the position and roll pitch yaw of the rotation error: the scenario runner's NEES.
double Nees(const VoResult& r, const Eigen::Isometry3d& truth) {
  Eigen::Matrix<double, 6, 1> e = geometry::XyzRpyFromPose(r.T_prev_curr) - geometry::XyzRpyFromPose(truth);
  for (int i = 3; i < 6; ++i) e(i) = geometry::WrapAngle(e(i));
  return e.dot(r.covariance.ldlt().solve(e));
}

constexpr double kNees997 = 20.06;  // chi-square, 6 dof, 99.7 %

// Drives 50 cm steps down the scene and returns the worst NEES of the accepted updates and
// how many were accepted. `slip` shortens the true step (the prior is always 50 cm).
struct DriveResult {
  int accepted = 0;
  double worst_nees = 0;
  double worst_error_m = 0;
  std::string detail;
};

DriveResult Drive(ShadowScene& scene, double slip, int steps) {
  VisualOdometry vo(scene.options());
  const Eigen::Isometry3d prior = geometry::PoseFromXyzRpy(0.5, 0, 0, 0, 0, 0);
  double x = 0;
  Eigen::Isometry3d T_prev = scene.PoseAt(x);
  vo.Process(scene.Render(T_prev, 0), Eigen::Isometry3d::Identity(), StepPrior());
  DriveResult out;
  for (int k = 1; k <= steps; ++k) {
    x += 0.5 * (1.0 - slip);
    const Eigen::Isometry3d T = scene.PoseAt(x);
    const VoResult r = vo.Process(scene.Render(T, k), prior, StepPrior());
    const Eigen::Isometry3d truth = T_prev.inverse() * T;
    out.detail += "step " + std::to_string(k) + ": " + ToString(r.status) + " " + r.reason;
    if (r.status == VoStatus::kOk) {
      ++out.accepted;
      const double nees = Nees(r, truth);
      const double err = (r.T_prev_curr.translation() - truth.translation()).norm();
      out.worst_nees = std::max(out.worst_nees, nees);
      out.worst_error_m = std::max(out.worst_error_m, err);
      out.detail += " nees " + std::to_string(nees) + " error " + std::to_string(err) + " m";
    }
    out.detail += "\n";
    T_prev = T;
  }
  std::printf("%s", out.detail.c_str());
  return out;
}

// Control: the same sand with the sun high, no shadow in view. VO measures every step, each
// within its own uncertainty.
TEST(VoShadow, WithoutTheShadowVoMeasuresTheSandHonestly) {
  ShadowScene scene(80.0);
  const DriveResult d = Drive(scene, 0.06, 6);
  EXPECT_EQ(d.accepted, 6) << d.detail;
  EXPECT_LT(d.worst_nees, kNees997) << d.detail;
}

// The shadow in view, 6 % slip: VO measures the ground, never the shadow. Sol 235's failure
// was an estimate that followed the shadow (no motion: a 47 cm error per step); here every
// step is measured, within 2 cm. (Calibration in this scene is not yet what it is without
// the shadow: the largest NEES is about 20, at the 99.7 % bound, where the control gives 7.)
TEST(VoShadow, TheRoversShadowInViewDoesNotCaptureTheEstimate) {
  ShadowScene scene(12.0);
  const DriveResult d = Drive(scene, 0.06, 6);
  EXPECT_EQ(d.accepted, 6) << d.detail;  // the ground has texture enough to measure
  EXPECT_LT(d.worst_error_m, 0.02) << d.detail;
}

// A stuck rover under its own shadow: the wheels turn (the prior says 50 cm) and nothing
// moves. Everything is fixed in the image, the ground included: VO reports no motion (the
// Sol 206 lesson: slip must be seen), or refuses; it never reports the prior.
TEST(VoShadow, AStuckRoverUnderItsShadowIsSeenNotToMove) {
  ShadowScene scene(12.0);
  const DriveResult d = Drive(scene, 1.0, 2);
  EXPECT_LT(d.worst_error_m, 0.02) << d.detail;
  EXPECT_LT(d.worst_nees, kNees997) << d.detail;
}

}  // namespace
}  // namespace rover::vo
