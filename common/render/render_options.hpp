// Options of the stereo renderer: the `render:` section of a world or camera_capture
// config. It does not depend on the `camera:` section: the rig comes separately.
// Every field is documented with its default in RENDER_OPTIONS.md.
#pragma once

#include "config/yaml_config.hpp"
#include "geometry/camera_model.hpp"

#include <array>
#include <cstdint>
#include <vector>

namespace rover::render {

// The rover's own body and mast as simple solids in the ROVER frame (X fwd, Y right,
// Z down, origin on the ground between the wheels). They cast shadows only; they are not
// drawn in the image. On Mars the rover's shadow in view fooled VO (the "rover shadow"
// episode, configs/scenarios/README.md), so it must be there in simulation.
struct RoverShadowOptions {
  bool enabled = true;
  // Axis-aligned boxes {x_min, x_max, y_min, y_max, z_min, z_max}, metres, rover frame.
  // Defaults: a MER-like deck with solar wings and the warm electronics box under it.
  std::vector<std::array<double, 6>> boxes = {
      {-0.80, 0.80, -1.10, 1.10, -0.80, -0.74},  // solar array / deck
      {-0.60, 0.60, -0.50, 0.50, -0.74, -0.38},  // warm electronics box
  };
  // When true the mast stands under the centre of the stereo rig, up to just below the
  // cameras, and a camera bar box holds both cameras: the shadow follows the rig config.
  bool mast_from_rig = true;
  // Otherwise: vertical mast cylinder with its axis at (x, y), from z_top to z_bottom
  // (z is down, so the top is the more negative value).
  double mast_x_m = 0.44;
  double mast_y_m = 0.0;
  double mast_radius_m = 0.05;
  double mast_z_top_m = -1.45;
  double mast_z_bottom_m = -0.80;
  // Six wheels as boxes, 0.25 m diameter, 0.16 m wide.
  bool wheels = true;
};

struct RenderOptions {
  // The pair is rendered with the rig's models Scaled(image_scale): 0.5 turns a
  // 1024x1024 NAVCAM into 512x512 working images.
  double image_scale = 1.0;
  // Sensor: additive Gaussian read noise in DN (8-bit), seeded by (noise_seed, frame seed).
  double noise_sigma_dn = 1.5;
  std::uint64_t noise_seed = 1;
  // DN of a surface of albedo 1 facing the sun, before the automatic exposure.
  double exposure_dn = 600.0;
  // Automatic exposure: one gain for both images so that the left image's mean is
  // target_mean_dn (the real NAVCAMs auto-exposed; a fixed exposure leaves a low-sun
  // scene nearly black). Off: exposure_dn is the exposure.
  bool auto_exposure = true;
  double target_mean_dn = 100.0;
  // Fraction of light from the dusty sky (lights shadows too; Mars: about 0.2-0.3).
  double ambient = 0.22;
  // Flat value of the sky above the horizon, and of ground beyond max_range_m.
  double sky_dn = 150.0;
  double far_ground_dn = 90.0;
  // Rays that meet nothing within this range are sky or far ground (depth 0).
  double max_range_m = 40.0;
  // Terrain and rocks farther than this toward the sun cast no shadow.
  double shadow_reach_m = 8.0;
  // Height grid: level L covers horizontal distances up to grid_near_range_m * 2^L from
  // the rig; its cell is grid_cell_pixels pixels wide at that distance.
  double grid_near_range_m = 4.0;
  double grid_cell_pixels = 3.0;
  // When set, replaces the world's sun.
  bool sun_override = false;
  double sun_azimuth_deg = 135.0;
  double sun_elevation_deg = 45.0;
  RoverShadowOptions rover_shadow;
  // 2: the left and right images are traced at once on two threads (the same images, bit
  // for bit); 1: one after the other, on the caller's thread (the benchmark's figure).
  int threads = 1;
};

// Reads the `render:` section (the node itself, not its parent). Unknown keys throw.
RenderOptions LoadRenderOptions(const config::ConfigNode& node);
// The same over `base`: the keys present replace base's values, the rest are base's (the
// HAZCAM pair's `render:` in camera_capture overrides the NAVCAM pair's key by key).
// `rover_shadow.boxes`, when present, replaces the whole list.
RenderOptions LoadRenderOptions(const config::ConfigNode& node, RenderOptions base);

// `shadow` with the mast made explicit: when mast_from_rig, the mast stands under the
// centre of `mast_rig` up to just below its cameras and a camera bar box holding both
// cameras is added to the boxes; mast_from_rig is then false. A pair rendered from another
// rig (the body-mounted HAZCAMs) so still sees the shadow of the mast that carries the
// NAVCAMs, not of a mast under itself.
RoverShadowOptions MastUnderRig(RoverShadowOptions shadow, const geometry::StereoRig& mast_rig);

}  // namespace rover::render
