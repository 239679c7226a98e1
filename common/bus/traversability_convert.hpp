// traversability_map_t <-> avoidance::Grid (and the footprint and rules the monitor judges
// steps with). Header-only so that rover_bus itself does not depend on rover_avoidance.
#pragma once

#include "avoidance/grid.hpp"

#include <rover_msgs/traversability_map_t.hpp>

#include <string>

namespace rover::bus {

struct MapRules {
  avoidance::Footprint footprint;
  double blind_margin_m = 0.5;
  avoidance::UnknownLimits unknown;
  double max_driven_step_m = 0.0;  // hazards.map.driven_step_fraction x the map's step limit (0: off)
  double caution_goodness = 0.0;   // 1 - the map's caution_fraction: caution at this goodness or less (0: not given)
};

inline rover_msgs::traversability_map_t MapToMsg(const avoidance::Grid& g, const MapRules& rules,
                                                 int64_t utime, int64_t last_frame_id) {
  rover_msgs::traversability_map_t m{};
  m.utime = utime;
  m.last_frame_id = last_frame_id;
  m.origin_x = g.origin_x;
  m.origin_y = g.origin_y;
  m.cell_m = g.cell_m;
  m.rows = g.rows;
  m.cols = g.cols;
  m.num_cells = g.rows * g.cols;
  m.state.resize(m.num_cells);
  for (int k = 0; k < m.num_cells; ++k) m.state[k] = static_cast<int8_t>(g.state[k]);
  m.goodness = g.goodness;
  m.step_m = g.step_m;
  if (g.HasHeights()) {
    m.elevation_m = g.elevation_m;
    m.sigma_m = g.sigma_m;
  } else {
    m.elevation_m.assign(m.num_cells, 0.0f);
    m.sigma_m.assign(m.num_cells, -1.0f);
  }
  m.footprint_length_m = rules.footprint.length_m;
  m.footprint_width_m = rules.footprint.width_m;
  m.footprint_center_forward_m = rules.footprint.center_forward_m;
  m.blind_margin_m = rules.blind_margin_m;
  m.max_unknown_fraction = rules.unknown.max_fraction;
  m.hidden_patch_m = rules.unknown.hidden_patch_m;
  m.max_scattered_unknown_fraction = rules.unknown.max_scattered_fraction;
  m.max_driven_step_m = rules.max_driven_step_m;
  m.caution_goodness = rules.caution_goodness;
  return m;
}

// The message has passed Problem() (common/bus/validate.cpp) on the bus.
inline avoidance::Grid GridFromMsg(const rover_msgs::traversability_map_t& m, MapRules* rules = nullptr) {
  avoidance::Grid g;
  g.origin_x = m.origin_x;
  g.origin_y = m.origin_y;
  g.cell_m = m.cell_m;
  g.rows = m.rows;
  g.cols = m.cols;
  g.state.resize(m.state.size());
  for (std::size_t k = 0; k < m.state.size(); ++k) g.state[k] = static_cast<avoidance::CellClass>(m.state[k]);
  g.goodness = m.goodness;
  g.step_m = m.step_m;
  g.elevation_m = m.elevation_m;
  g.sigma_m = m.sigma_m;
  if (rules) {
    rules->footprint.length_m = m.footprint_length_m;
    rules->footprint.width_m = m.footprint_width_m;
    rules->footprint.center_forward_m = m.footprint_center_forward_m;
    rules->blind_margin_m = m.blind_margin_m;
    rules->unknown = {m.max_unknown_fraction, m.hidden_patch_m, m.max_scattered_unknown_fraction};
    rules->max_driven_step_m = m.max_driven_step_m;
    rules->caution_goodness = m.caution_goodness;
  }
  return g;
}

}  // namespace rover::bus
