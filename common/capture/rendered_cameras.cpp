#include "capture/rendered_cameras.hpp"

#include "geometry/mast_pointing.hpp"
#include "terrain/world.hpp"

#include <exception>
#include <utility>

namespace rover::capture {

RenderedCameras::RenderedCameras(geometry::StereoRig navcam_rig, const render::RenderOptions& navcam_render)
    : navcam_{std::move(navcam_rig), render::StereoRenderer(navcam_render)} {}

RenderedCameras::RenderedCameras(geometry::StereoRig navcam_rig, const render::RenderOptions& navcam_render,
                                 geometry::StereoRig hazcam_rig, render::RenderOptions hazcam_render)
    : RenderedCameras(std::move(navcam_rig), navcam_render) {
  hazcam_render.rover_shadow = render::MastUnderRig(hazcam_render.rover_shadow, navcam_.rig);
  hazcam_.emplace(Pair{std::move(hazcam_rig), render::StereoRenderer(std::move(hazcam_render))});
}

Exposure RenderedCameras::Expose(const terrain::World& world, const Eigen::Isometry3d& T_site_rover,
                                 std::int64_t frame_seed, const Pointing& pointing) {
  Exposure out;
  if (pointing.pointed()) {
    const geometry::StereoRig pointed = geometry::PointedRig(navcam_.rig, pointing.pan_rad, pointing.tilt_rad);
    out.navcam = navcam_.renderer.RenderPair(world, pointed, T_site_rover, frame_seed);
    return out;
  }
  out.navcam = navcam_.renderer.RenderPair(world, navcam_.rig, T_site_rover, frame_seed);
  if (hazcam_) {
    try {
      out.hazcam = hazcam_->renderer.RenderPair(world, hazcam_->rig, T_site_rover, frame_seed);
    } catch (const std::exception& e) {
      out.hazcam_error = e.what();
    }
  }
  return out;
}

}  // namespace rover::capture
