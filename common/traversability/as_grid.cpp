#include "traversability/as_grid.hpp"

#include <cmath>

namespace rover::traversability {

avoidance::Grid AsGrid(const TraversabilityMap& map) {
  avoidance::Grid g;
  g.origin_x = map.origin_x();
  g.origin_y = map.origin_y();
  g.cell_m = map.cell_size();
  g.rows = map.rows();
  g.cols = map.cols();
  const auto& cells = map.cells();
  g.state.resize(cells.size());
  g.goodness.resize(cells.size());
  g.step_m.resize(cells.size());
  g.tilt_deg.resize(cells.size());
  g.elevation_m.resize(cells.size());
  g.sigma_m.resize(cells.size());
  for (std::size_t k = 0; k < cells.size(); ++k) {
    g.state[k] = static_cast<avoidance::CellClass>(cells[k].state);
    g.goodness[k] = cells[k].goodness;
    g.step_m[k] = cells[k].step_m;
    g.tilt_deg[k] = static_cast<float>(cells[k].tilt_rad * 180.0 / M_PI);
    g.elevation_m[k] = cells[k].elevation_m;
    g.sigma_m[k] = cells[k].height_sigma_m;
  }
  g.DistrustEdges();
  return g;
}

}  // namespace rover::traversability
