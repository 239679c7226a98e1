// A textured terrain stereo sequence with exact, known motion (VO-13 truth).
//
// The terrain is a gentle height field (a few seeded sinusoids, Z down in the site frame)
// carrying a seeded multi-scale value-noise texture (lattice values bilinearly
// interpolated, octaves from metres to a centimetre). Each pixel's ray, from the camera
// model's BackProject, is cast onto the height field; octaves finer than the pixel's
// ground footprint fade out, so distant ground blurs instead of aliasing, as it does
// through a real lens. The rover drives forward with a varying yaw and small roll, pitch
// and height changes, so all six motion components are exercised.
//
// The stereo rig's reference frame is the left camera frame (as in KITTI), so truth poses
// are written like KITTI poses: T_world_left(k), world = left camera frame at frame 0.
#pragma once

#include "geometry/camera_model.hpp"
#include "vo_eval/trajectory_metrics.hpp"

#include <opencv2/core.hpp>

#include <cstdint>
#include <vector>

namespace rover::vo_eval {

struct SyntheticTerrainOptions {
  int width = 1024;              // image size, pixels
  int height = 1024;
  double hfov_deg = 45.0;        // MER NAVCAM field of view
  double baseline_m = 0.20;      // MER NAVCAM stereo baseline
  double camera_height_m = 1.5;  // mast height above the ground
  double camera_pitch_deg = 35.0;  // optical axis below the horizon
  double step_m = 0.30;          // forward motion per frame
  double yaw_step_deg = 2.0;     // amplitude of the per-frame yaw change
  double relief_m = 0.15;        // height field amplitude
  double noise_dn = 1.0;         // Gaussian image noise sigma, grey levels
  std::uint64_t seed = 1;
};

class SyntheticTerrainSequence {
 public:
  // Throws std::invalid_argument naming a bad option.
  explicit SyntheticTerrainSequence(const SyntheticTerrainOptions& options);

  const SyntheticTerrainOptions& options() const { return options_; }
  const geometry::StereoRig& rig() const { return rig_; }

  // Site-frame pose of the rig reference (left camera) at frame k.
  Eigen::Isometry3d SitePose(int k) const;
  // KITTI-style truth: T_world_left(k), world = the left camera frame at frame 0.
  Eigen::Isometry3d TruthPose(int k) const;
  // The exact motion between frames k-1 and k: T_prev_curr.
  Eigen::Isometry3d TruthMotion(int k) const;
  // Gravity down and the rover's initial forward direction in the truth world frame (for
  // a top view).
  Eigen::Vector3d DownInWorld() const;
  Eigen::Vector3d ForwardInWorld() const;

  // Renders the left and right images of frame k (noise seeded by seed and k).
  void Render(int k, cv::Mat* left, cv::Mat* right) const;
  // One view through any camera model whose reference frame sits at T_site_ref.
  cv::Mat RenderView(const geometry::CameraModel& camera, const Eigen::Isometry3d& T_site_ref,
                     std::uint64_t noise_seed) const;

  // Terrain height (site Z, down positive) and texture brightness at a site (X, Y), the
  // texture low-passed for a footprint of `footprint_m`.
  double TerrainZ(double x, double y) const;
  double Brightness(double x, double y, double footprint_m) const;

 private:
  SyntheticTerrainOptions options_;
  geometry::StereoRig rig_;
  Eigen::Isometry3d T_rover_ref_;
  double relief_phase_[4];
  double relief_slope_bound_;
  // Per-octave lattice of seeded values in [-1, 1], kLattice x kLattice, wrapped. The
  // finest octave repeats every 2 m, but the sum of octaves does not repeat within
  // hundreds of metres.
  std::vector<float> lattice_;
  std::vector<double> amplitude_;
};

}  // namespace rover::vo_eval
