// The stereo NAVCAM renderer: what a camera pair at the TRUE rover pose would see.
//
// For each pixel centre the camera model's own ray (BackProject) is carried into the site
// frame with the true pose and traced against the height field (rocks included) to its
// first hit; so a 3-D point on the ground appears exactly where the model projects it
// (render_test proves it to 0.05 px). The hit is shaded Lambertian with the ground's
// albedo and the sun, shadowed by terrain, rocks and the rover's own body and mast; rays
// that hit nothing see a flat sky. Seeded sensor noise, then 8-bit output.
//
// Render rule: the pose, world and sun are truth; nothing else from truth goes into the
// images, and nothing but the images and the camera models leaves the renderer (depth is
// for tests and for looking at the world).
#pragma once

#include "geometry/camera_model.hpp"
#include "render/ground.hpp"
#include "render/render_options.hpp"

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace rover::terrain {
class World;
}

namespace rover::render {

struct StereoImages {
  cv::Mat left, right;              // CV_8UC1
  cv::Mat depth_left, depth_right;  // CV_32FC1: range along the pixel's ray, metres;
                                    // 0 where nothing is hit within max_range_m
  geometry::StereoRig rig;          // the models the images were rendered with (scaled)
  double exposure_gain = 1.0;       // the automatic exposure's gain on exposure_dn (1 if off)
};

// Where the time went in the last RenderPair.
struct RenderTiming {
  double grid_seconds = 0;   // sampling the ground into height grids (or adopting it)
  double trace_seconds = 0;  // both images
  std::size_t grid_nodes = 0;
};

class StereoRenderer {
 public:
  // Throws std::invalid_argument naming the value when an option is out of range.
  explicit StereoRenderer(RenderOptions options = {});

  // `rig_in_rover_frame`: both models with the ROVER frame as reference.
  // `T_site_rover`: the true pose. `frame_seed` varies the sensor noise per frame.
  StereoImages RenderPair(const Ground& ground, const Sun& sun,
                          const geometry::StereoRig& rig_in_rover_frame,
                          const Eigen::Isometry3d& T_site_rover, std::int64_t frame_seed);
  // The simulator's world, with its own sun unless options.sun_override.
  StereoImages RenderPair(const terrain::World& world,
                          const geometry::StereoRig& rig_in_rover_frame,
                          const Eigen::Isometry3d& T_site_rover, std::int64_t frame_seed);

  const RenderOptions& options() const { return options_; }
  const RenderTiming& last_timing() const { return timing_; }

 private:
  struct RayTable;
  const RayTable& RaysFor(const geometry::CameraModel& model);

  RenderOptions options_;
  RenderTiming timing_;
  std::map<std::string, std::shared_ptr<RayTable>> ray_cache_;
  // The last adopted native grid, reused while the ground's grid is the same.
  struct GridCache;
  std::shared_ptr<GridCache> grid_cache_;
};

// Disparity from the true depth of the left image: the left pixel minus the column where
// the same 3-D point projects in the right model (for a rectified pinhole pair this is
// f B / Z). NaN where the depth is 0 or the point is behind the right camera.
cv::Mat DisparityFromDepth(const cv::Mat& depth_left, const geometry::StereoRig& rig);

// A colour picture of a disparity image (near = warm), black where NaN.
cv::Mat ColourDisparity(const cv::Mat& disparity);

}  // namespace rover::render
