// An optional prior cost map for ground the rover has not seen: what orbital imagery says
// about the site (HiRISE at about 0.25 m a pixel shows dune fields, rock clusters and
// scarps), as a cost per metre relative to open ground, or impassable. The rover's own map
// overrides it wherever the cameras have rated a cell. Knows nothing of LCM.
//
// File format (YAML; sample: configs/planner/prior_example.yaml), drawn like an image with
// north at the top and west at the left:
//   prior_cost_map:
//     south_west: [-2.0, -6.0]   # site x (north), y (east) of the map's south-west corner, m
//     cell_m: 1.0                # side of one character's square, m
//     legend: {".": 1, "s": 2.5, "#": impassable}
//     rows:                       # the first row is the northern edge
//       - "....##...."
//       - "....##...."
#pragma once

#include <limits>
#include <string>
#include <vector>

namespace rover::planner {

struct PriorCostMap {
  double origin_x = 0.0, origin_y = 0.0;  // south-west corner
  double cell_m = 1.0;
  int rows = 0, cols = 0;                 // row i covers x in [origin_x + i*cell, +cell)
  std::vector<double> cost;               // rows*cols, >= 1, or kImpassable
  static constexpr double kImpassable = std::numeric_limits<double>::infinity();

  // The cost factor at (x, y): 1 outside the map.
  double CostAt(double x, double y) const;

  // Throws config::ConfigError with one line naming the file, the key and what was expected.
  static PriorCostMap LoadFile(const std::string& path);
  static PriorCostMap FromYaml(const std::string& text, const std::string& source_name);
};

}  // namespace rover::planner
