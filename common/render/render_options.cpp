#include "render/render_options.hpp"

#include <algorithm>

namespace rover::render {

RenderOptions LoadRenderOptions(const config::ConfigNode& node) { return LoadRenderOptions(node, RenderOptions{}); }

RenderOptions LoadRenderOptions(const config::ConfigNode& node, RenderOptions base) {
  RenderOptions o = std::move(base);
  if (node.IsNull()) return o;
  node.CheckKeys({"image_scale", "noise_sigma_dn", "noise_seed", "exposure_dn", "auto_exposure",
                  "target_mean_dn", "ambient", "sky_dn",
                  "far_ground_dn", "max_range_m", "shadow_reach_m", "grid_near_range_m",
                  "grid_cell_pixels", "sun", "rover_shadow", "threads"});
  node.Get("image_scale", o.image_scale, 1e-3, 4.0);
  node.Get("noise_sigma_dn", o.noise_sigma_dn, 0.0, 100.0);
  node.Get("noise_seed", o.noise_seed);
  node.Get("exposure_dn", o.exposure_dn, 1e-3, 1e5);
  node.Get("auto_exposure", o.auto_exposure);
  node.Get("target_mean_dn", o.target_mean_dn, 1.0, 254.0);
  node.Get("ambient", o.ambient, 0.0, 1.0);
  node.Get("sky_dn", o.sky_dn, 0.0, 255.0);
  node.Get("far_ground_dn", o.far_ground_dn, 0.0, 255.0);
  node.Get("max_range_m", o.max_range_m, 0.1, 1e4);
  node.Get("shadow_reach_m", o.shadow_reach_m, 0.0, 1e3);
  node.Get("grid_near_range_m", o.grid_near_range_m, 0.1, 1e3);
  node.Get("grid_cell_pixels", o.grid_cell_pixels, 0.1, 100.0);
  node.Get("threads", o.threads, 1, 2);
  const config::ConfigNode sun = node["sun"];
  if (!sun.IsNull()) {
    sun.CheckKeys({"azimuth_deg", "elevation_deg"});
    o.sun_override = true;
    o.sun_azimuth_deg = sun.RequireDouble("azimuth_deg", -360.0, 360.0);
    o.sun_elevation_deg = sun.RequireDouble("elevation_deg", -90.0, 90.0);
  }
  const config::ConfigNode rs = node["rover_shadow"];
  if (!rs.IsNull()) {
    rs.CheckKeys({"enabled", "boxes", "wheels", "mast_from_rig", "mast_x_m", "mast_y_m", "mast_radius_m",
                  "mast_z_top_m", "mast_z_bottom_m"});
    RoverShadowOptions& r = o.rover_shadow;
    rs.Get("enabled", r.enabled);
    rs.Get("wheels", r.wheels);
    rs.Get("mast_from_rig", r.mast_from_rig);
    rs.Get("mast_x_m", r.mast_x_m);
    rs.Get("mast_y_m", r.mast_y_m);
    rs.Get("mast_radius_m", r.mast_radius_m, 0.0, 1.0);
    rs.Get("mast_z_top_m", r.mast_z_top_m);
    rs.Get("mast_z_bottom_m", r.mast_z_bottom_m);
    const config::ConfigNode boxes = rs["boxes"];
    if (!boxes.IsNull()) {
      if (!boxes.IsSequence()) boxes.Fail("expected a list of boxes [x_min, x_max, y_min, y_max, z_min, z_max]");
      r.boxes.clear();
      for (std::size_t i = 0; i < boxes.size(); ++i) {
        const config::ConfigNode b = boxes.at(i);
        const std::vector<double> v = b.AsVector(6);
        if (v[0] > v[1] || v[2] > v[3] || v[4] > v[5]) {
          b.Fail("expected [x_min, x_max, y_min, y_max, z_min, z_max] with each min <= max");
        }
        r.boxes.push_back({v[0], v[1], v[2], v[3], v[4], v[5]});
      }
    }
    if (r.mast_z_top_m > r.mast_z_bottom_m) {
      rs.Fail("mast_z_top_m must be <= mast_z_bottom_m (z is down: the top is the more negative)");
    }
  }
  return o;
}

RoverShadowOptions MastUnderRig(RoverShadowOptions shadow, const geometry::StereoRig& mast_rig) {
  if (!shadow.mast_from_rig) return shadow;
  const Eigen::Vector3d cl = mast_rig.left->Center(), cr = mast_rig.right->Center();
  const Eigen::Vector3d c = 0.5 * (cl + cr);
  shadow.mast_from_rig = false;
  shadow.mast_x_m = c.x();
  shadow.mast_y_m = c.y();
  shadow.mast_z_top_m = c.z() + 0.06;
  shadow.boxes.push_back({c.x() - 0.07, c.x() + 0.07, std::min(cl.y(), cr.y()) - 0.07,
                          std::max(cl.y(), cr.y()) + 0.07, c.z() - 0.06, c.z() + 0.06});
  return shadow;
}

}  // namespace rover::render
