// keepout_zones_t <-> hazards::KeepOutZone, shared by hazard_monitor and the scenario
// summary. Header-only so that rover_bus itself does not depend on rover_hazards.
#pragma once

#include "hazards/keepout.hpp"

#include <rover_msgs/keepout_zones_t.hpp>

#include <vector>

namespace rover::bus {

// Throws std::invalid_argument (from hazards::KeepOutZone) on an invalid zone.
inline std::vector<hazards::KeepOutZone> ZonesFromMsg(const rover_msgs::keepout_zones_t& msg) {
  std::vector<hazards::KeepOutZone> zones;
  for (const auto& z : msg.zones) {
    if (z.shape == rover_msgs::keepout_zone_t::SHAPE_CIRCLE) {
      zones.push_back(hazards::KeepOutZone::Circle(z.name, z.center[0], z.center[1], z.radius_m));
    } else {
      std::vector<Eigen::Vector2d> vertices;
      for (int i = 0; i < z.num_vertices; ++i) vertices.emplace_back(z.vertices_x[i], z.vertices_y[i]);
      zones.push_back(hazards::KeepOutZone::Polygon(z.name, vertices));
    }
  }
  return zones;
}

}  // namespace rover::bus
