// The simulated cameras: what the NAVCAM pair on the mast and, optionally, the front
// HAZCAM pair on the body see at the TRUE rover pose, rendered by common/render.
//
// Both pairs are exposed at one instant (one pose), as one exposure command takes them on
// MER. A HAZCAM pair that cannot be rendered does not cost the NAVCAM pair: visual
// odometry needs it, and the map can wait for the next HAZCAM pair.
#pragma once

#include "geometry/camera_model.hpp"
#include "render/render_options.hpp"
#include "render/stereo_renderer.hpp"

#include <Eigen/Geometry>

#include <cstdint>
#include <optional>
#include <string>

namespace rover::terrain {
class World;
}

namespace rover::capture {

// Where the mast points the NAVCAM pair for one capture (capture_request_t's pan_rad,
// tilt_rad; geometry/mast_pointing.hpp): + pan toward the rover's right, + tilt further
// down, from the rig as mounted. Every ImageSource takes it; only the simulated cameras
// can honour a pointed one.
struct Pointing {
  double pan_rad = 0, tilt_rad = 0;
  // Anything but exactly (0, 0), a NaN included: a request that asks for a turn, or for
  // nonsense, is not an unpointed capture.
  bool pointed() const { return pan_rad != 0 || tilt_rad != 0; }
};

// What one exposure gives.
struct Exposure {
  render::StereoImages navcam;
  std::optional<render::StereoImages> hazcam;  // unset without HAZCAMs or when it failed
  std::string hazcam_error;                    // why a configured HAZCAM pair is missing
};

class RenderedCameras {
 public:
  // Both rigs with the ROVER frame as reference. The HAZCAM pair is rendered with
  // `hazcam_render`, but the rover's mast in its shadow stands under the NAVCAM rig that it
  // carries (render::MastUnderRig), not under the HAZCAMs. Throws std::invalid_argument
  // naming a bad render option.
  RenderedCameras(geometry::StereoRig navcam_rig, const render::RenderOptions& navcam_render);
  RenderedCameras(geometry::StereoRig navcam_rig, const render::RenderOptions& navcam_render,
                  geometry::StereoRig hazcam_rig, render::RenderOptions hazcam_render);

  bool has_hazcam() const { return hazcam_.has_value(); }

  // Both pairs at the true pose `T_site_rover`; `frame_seed` varies the sensor noise per
  // frame. A NAVCAM render failure throws; a HAZCAM one is returned in hazcam_error.
  // A pointed exposure renders the NAVCAM pair from geometry::PointedRig (its StereoImages
  // carry the pointed models) and no HAZCAM pair: the HAZCAMs are on the body, and a
  // HAZCAM frame must not go out with a frame the mast took looking elsewhere. Throws
  // std::invalid_argument on a non-finite angle.
  Exposure Expose(const terrain::World& world, const Eigen::Isometry3d& T_site_rover, std::int64_t frame_seed,
                  const Pointing& pointing = {});

 private:
  struct Pair {
    geometry::StereoRig rig;
    render::StereoRenderer renderer;
  };
  Pair navcam_;
  std::optional<Pair> hazcam_;
};

}  // namespace rover::capture
