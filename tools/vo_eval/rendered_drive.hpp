// A drive over a catalogue world (configs/worlds/*.yaml), seen through the simulator's
// own renderer (common/render: ray-traced height field and rocks, sun and shadows
// including the rover's, automatic exposure, read noise) with a NAVCAM rig file: the
// images the VO sees in the closed loop, with exact truth (VO-13 on rendered worlds).
//
// The rover starts at the world's start pose and drives straight steps whose heading
// wanders (a seeded sequence of small turns), resting on the ground at each frame: roll
// and pitch from the ground under its wheels, height from the ground under its origin. The
// rig's reference frame is the rover frame, so truth poses are T_site_rover(k).
#pragma once

#include "geometry/camera_model.hpp"
#include "render/stereo_renderer.hpp"
#include "terrain/world.hpp"

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace rover::vo_eval {

struct RenderedDriveOptions {
  std::string world_path;    // a world file (common/terrain/WORLD_FORMAT.md)
  std::string rig_path;      // a stereo rig file in the rover frame (configs/cameras/)
  int size = 512;            // rendered image width, pixels (the rig is scaled to it)
  int frames = 30;
  double step_m = 0.4;       // along the heading, per frame
  double turn_step_deg = 4.0;  // largest heading change per frame (seeded, uniform)
  std::uint64_t seed = 1;    // heading changes and sensor noise
};

class RenderedDriveSequence {
 public:
  // Throws config::ConfigError (bad world or rig file) or std::invalid_argument (bad
  // option, or a drive that leaves the world's map, naming the frame).
  explicit RenderedDriveSequence(const RenderedDriveOptions& options);
  ~RenderedDriveSequence();

  const RenderedDriveOptions& options() const { return options_; }
  const std::string& world_name() const;
  // The rig at the rendered size, reference frame = rover frame.
  const geometry::StereoRig& rig() const { return rig_; }
  int size() const { return static_cast<int>(poses_.size()); }
  // True rover pose in the site frame at frame k.
  const Eigen::Isometry3d& SitePose(int k) const { return poses_.at(static_cast<std::size_t>(k)); }

  // Renders frame k (sensor noise seeded by seed and k). Not thread-safe. `depth_left`
  // (optional): the left image's true range along each pixel's ray (m, CV_32FC1, 0 where
  // nothing is hit), for measuring against truth; the VO never sees it.
  void Render(int k, cv::Mat* left, cv::Mat* right, cv::Mat* depth_left = nullptr) const;

 private:
  RenderedDriveOptions options_;
  std::unique_ptr<terrain::World> world_;
  geometry::StereoRig rig_full_, rig_;
  std::vector<Eigen::Isometry3d> poses_;
  std::unique_ptr<render::StereoRenderer> renderer_;
};

// The rover resting on the ground (rocks left out) at (x, y) with heading `yaw`: roll and
// pitch from the ground heights under its wheel pairs, origin on the ground.
Eigen::Isometry3d PoseOnGround(const terrain::World& world, double x, double y, double yaw);

}  // namespace rover::vo_eval
