// Whether a navbench world can be crossed at all by the stack's own plan: the global
// planner (common/planner) with the executor's clearance and costs, run on a perfect map of
// the world (its exact surface, rated by the hazard map's own rules) instead of the map the
// cameras build. A goto whose world has no such way cannot succeed however well the rover
// sees; a miss in a world that has one is a navigation miss. So the benchmark can tell
// the field's density (what the rover's size and limits allow) apart from its perception
// and its choices.
#pragma once

#include "avoidance/grid.hpp"
#include "config/yaml_config.hpp"
#include "planner/global_planner.hpp"
#include "terrain/world.hpp"
#include "traversability/traversability_map.hpp"

#include <Eigen/Core>

#include <string>

namespace rover::navbench {

struct PerfectWayOptions {
  traversability::MapOptions map;   // the hazard monitor's rating (hazards.map.traversability)
  planner::PlannerOptions planner;  // the executor's plan: radii from the vote's footprint
};

// The options as a rover config gives them to hazard_monitor and sequence_executor:
// the map's rating, the footprint grown by executor.avoid_margin_m (and half a cell with
// executor.planner_vote_clearance, as the executor plans), the plan's costs. Throws
// config::ConfigError naming the key on a bad value.
PerfectWayOptions LoadPerfectWayOptions(const config::ConfigNode& rover_config);

// The world's exact surface on a grid of the map's cells covering its whole map, each cell
// rated by the map's rules (hazard_eval::FillTruth): every cell is known. Each cell at its
// highest point (what the body meets), or with at_mean at the mean of the surface in it
// (what the map's cells measure from their points, every point exact). Cells off the
// world's map are unsafe, so no way leaves it (the rover's centre keeps the plan's
// clearance off the map's edge).
avoidance::Grid PerfectMap(const terrain::World& world, const traversability::MapOptions& map,
                           bool at_mean = false);

struct PerfectWay {
  bool reachable = false;
  double length_m = 0;    // the plan's path, start to the goal disc (0 when unreachable)
  std::string why;        // the planner's reason when unreachable
};

// The plan from start to the goal disc on `grid` (PerfectMap), the whole grid its window.
PerfectWay PlanPerfectWay(const avoidance::Grid& grid, const planner::PlannerOptions& options,
                          const Eigen::Vector2d& start, const Eigen::Vector2d& goal, double goal_radius_m);

}  // namespace rover::navbench
