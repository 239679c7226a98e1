#include "vo_eval/rendered_drive.hpp"

#include "config/yaml_config.hpp"
#include "geometry/camera_io.hpp"
#include "geometry/pose.hpp"
#include "render/render_options.hpp"

#include <cmath>
#include <random>
#include <stdexcept>

namespace rover::vo_eval {

namespace {

constexpr double kDeg = M_PI / 180.0;

// A world file may carry a `render:` section (RenderOptions); the world loader rejects
// keys it does not know, so it gets the file without it.
terrain::WorldOptions LoadWorld(const std::string& path, render::RenderOptions* render) {
  const config::ConfigNode root = config::ConfigNode::LoadFile(path);
  if (!root.Has("render")) return terrain::WorldOptions::Load(root);
  *render = render::LoadRenderOptions(root["render"]);
  YAML::Node copy = YAML::Clone(root.yaml());
  copy.remove("render");
  return terrain::WorldOptions::Load(config::ConfigNode(copy, path, ""));
}

}  // namespace

Eigen::Isometry3d PoseOnGround(const terrain::World& world, double x, double y, double yaw) {
  // The wheels stand on the ground (rocks left out): the attitude is the plane through
  // the ground heights under the front, rear, left and right wheel pairs, a 1.2 m by
  // 1.0 m rover.
  const double half_length = 0.6, half_track = 0.5;
  const Eigen::Vector2d fwd(std::cos(yaw), std::sin(yaw)), right(-std::sin(yaw), std::cos(yaw));
  auto h = [&](double a, double b) {
    const Eigen::Vector2d p = Eigen::Vector2d(x, y) + a * fwd + b * right;
    return world.GroundElevation(p.x(), p.y());
  };
  // Positive pitch raises the nose; positive roll lowers the right side (pose.hpp).
  const double pitch = std::atan2(h(half_length, 0) - h(-half_length, 0), 2 * half_length);
  const double roll = -std::atan2(h(0, half_track) - h(0, -half_track), 2 * half_track);
  return geometry::PoseFromXyzRpy(x, y, -world.GroundElevation(x, y), roll, pitch, yaw);
}

RenderedDriveSequence::RenderedDriveSequence(const RenderedDriveOptions& options)
    : options_(options) {
  if (options.frames < 2) {
    throw std::invalid_argument("rendered drive: frames: expected at least 2, got " +
                                std::to_string(options.frames));
  }
  if (options.size < 64) {
    throw std::invalid_argument("rendered drive: size: expected at least 64 pixels, got " +
                                std::to_string(options.size));
  }
  if (!(options.step_m > 0 && options.step_m <= 2.0)) {
    throw std::invalid_argument("rendered drive: step_m: expected (0, 2] m");
  }
  if (!(options.turn_step_deg >= 0 && options.turn_step_deg <= 30)) {
    throw std::invalid_argument("rendered drive: turn_step_deg: expected [0, 30] deg");
  }
  render::RenderOptions render_options;
  world_ = std::make_unique<terrain::World>(LoadWorld(options.world_path, &render_options));
  rig_full_ = geometry::LoadStereoRigFile(options.rig_path);
  const double scale = static_cast<double>(options.size) / rig_full_.left->width();
  render_options.image_scale = scale;
  rig_.left = rig_full_.left->Scaled(scale);
  rig_.right = rig_full_.right->Scaled(scale);
  renderer_ = std::make_unique<render::StereoRenderer>(render_options);

  const terrain::StartPose& start = world_->options().start;
  double x = start.x, y = start.y, yaw = start.yaw_deg * kDeg;
  std::mt19937_64 rng(options.seed);
  std::uniform_real_distribution<double> turn(-options.turn_step_deg, options.turn_step_deg);
  for (int k = 0; k < options.frames; ++k) {
    if (k > 0) {
      yaw += turn(rng) * kDeg;
      x += options.step_m * std::cos(yaw);
      y += options.step_m * std::sin(yaw);
    }
    if (!world_->Contains(x, y)) {
      throw std::invalid_argument(options.world_path + ": the drive leaves the map at frame " +
                                  std::to_string(k) + " (fewer --frames or a shorter --step-m)");
    }
    poses_.push_back(PoseOnGround(*world_, x, y, yaw));
  }
}

RenderedDriveSequence::~RenderedDriveSequence() = default;

const std::string& RenderedDriveSequence::world_name() const { return world_->options().name; }

void RenderedDriveSequence::Render(int k, cv::Mat* left, cv::Mat* right, cv::Mat* depth_left) const {
  const render::StereoImages images = renderer_->RenderPair(
      *world_, rig_full_, SitePose(k),
      static_cast<std::int64_t>(options_.seed * 1000003ull + static_cast<std::uint64_t>(k)));
  *left = images.left;
  *right = images.right;
  if (depth_left) *depth_left = images.depth_left;
}

}  // namespace rover::vo_eval
