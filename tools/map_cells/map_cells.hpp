// What the hazard monitor's maps said about the ground round one site point, map by map:
// every TRAVERSABILITY_MAP in a run's LCM log, and in each the cells within a radius of the
// point (state, step, the cell's top and sigma, and that top's rise over the ground round it
// as the vote's avoid_top_rise_m reads it). The history a collision's trace needs: did the
// map ever rate the rock unsafe, and how high did its cells read?
#pragma once

#include "avoidance/tops_over_ground.hpp"

#include <cstdint>
#include <iosfwd>
#include <map>
#include <string>
#include <vector>

namespace rover::map_cells {

struct Query {
  double x = 0.0, y = 0.0;       // site frame, m
  double radius_m = 0.3;         // cells whose centre lies this near
  double ground_radius_m = 1.0;  // the ground plane round a cell (executor.avoid_top_ground_radius_m)
  double band_m = 0.25 * avoidance::kTopGroundBandFraction;  // cells this far over the plane are left out of it
};

struct CellReading {
  double x = 0.0, y = 0.0;  // the cell's centre
  int state = 0;            // traversability_map_t STATE_*
  double step_m = 0.0, goodness = 0.0;
  double elevation_m = 0.0, sigma_m = -1.0;  // sigma < 0: no height
  double top_over_ground_m = -1.0;           // < 0: no height or too little ground round it
};

struct MapReading {
  std::int64_t utime = 0;
  std::int64_t last_frame_id = -1;
  std::vector<CellReading> cells;  // empty: the point lay outside this map
};

struct History {
  std::vector<MapReading> maps;
  int undecodable = 0;  // TRAVERSABILITY_MAP events that did not decode or failed validation
};

// Reads the log; throws std::runtime_error naming the file when it cannot be opened.
History ReadHistory(const std::string& log_path, const Query& q);

// One line per map (its time, frame and each cell), then a line per state: how many maps
// rated any of the cells so.
void Print(const History& h, const Query& q, std::ostream& out);

}  // namespace rover::map_cells
