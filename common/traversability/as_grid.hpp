// The traversability map as the hazard checks and arc voting see it (avoidance::Grid):
// each cell's state, goodness, step, tilt, top and height sigma, with the edge cells of the
// seen region distrusted (avoidance::Grid::DistrustEdges). hazard_monitor publishes this
// grid; hazard-eval rates the vote's rules on it.
#pragma once

#include "avoidance/grid.hpp"
#include "traversability/traversability_map.hpp"

namespace rover::traversability {

avoidance::Grid AsGrid(const TraversabilityMap& map);

}  // namespace rover::traversability
