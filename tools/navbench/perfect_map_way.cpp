#include "navbench/perfect_map_way.hpp"

#include "hazard_evaluation.hpp"
#include "hazards/hazard_assessor.hpp"
#include "hazards/map_check.hpp"
#include "sequence/executor.hpp"
#include "traversability/as_grid.hpp"

#include <algorithm>
#include <cmath>

namespace rover::navbench {

PerfectWayOptions LoadPerfectWayOptions(const config::ConfigNode& rover_config) {
  PerfectWayOptions o;
  o.map = traversability::LoadMapOptions(rover_config["hazards"]["map"]["traversability"]);
  const hazards::HazardOptions hazards = hazards::LoadHazardOptions(rover_config["hazards"], {"publish_hz"});
  const sequence::ExecutorOptions executor = sequence::LoadExecutorOptions(rover_config);
  // The vote's body (SequenceExecutor::VoteOnMap: the footprint grown by its margin) and
  // the executor's plan over it.
  avoidance::Footprint body = hazards::GridFootprint(hazards.footprint);
  body.length_m += 2.0 * executor.avoid_margin_m;
  body.width_m += 2.0 * executor.avoid_margin_m;
  o.planner = sequence::PlanOptions(executor, body, o.map.cell_size_m);
  return o;
}

avoidance::Grid PerfectMap(const terrain::World& world, const traversability::MapOptions& map, bool at_mean) {
  const auto& w = world.options();
  traversability::MapOptions options = map;
  // The exact surface has every crest in it: no view to judge (as hazard-eval's truth).
  options.crest_view_range_m = 0.0;
  // The whole map and a patch round it, in one grid (the map's grid is square).
  options.extent_m = std::max(w.map_size_m.x(), w.map_size_m.y()) + 4.0 * options.cell_size_m;
  traversability::TraversabilityMap truth(options);
  truth.Recentre(w.map_center.x(), w.map_center.y());
  hazard_eval::FillTruth(world, at_mean, &truth);
  avoidance::Grid grid = traversability::AsGrid(truth);
  for (int i = 0; i < grid.rows; ++i)
    for (int j = 0; j < grid.cols; ++j) {
      if (world.Contains(grid.CellCentreX(i), grid.CellCentreY(j))) continue;
      const std::size_t k = static_cast<std::size_t>(i) * grid.cols + j;
      grid.state[k] = avoidance::CellClass::kUnsafe;
      grid.goodness[k] = 0.0f;
    }
  return grid;
}

PerfectWay PlanPerfectWay(const avoidance::Grid& grid, const planner::PlannerOptions& options,
                          const Eigen::Vector2d& start, const Eigen::Vector2d& goal, double goal_radius_m) {
  planner::PlanRequest request;
  request.start_x = start.x(), request.start_y = start.y();
  request.goal_x = goal.x(), request.goal_y = goal.y();
  request.goal_radius_m = goal_radius_m;
  planner::PlannerOptions o = options;
  o.max_cells = std::max(o.max_cells, grid.rows * grid.cols + 1);
  const planner::GlobalPlan plan = planner::PlanOnGrid(grid, request, o);
  PerfectWay way;
  way.reachable = plan.reachable();
  if (way.reachable) way.length_m = plan.path_length_m();
  else way.why = plan.why_unreachable();
  return way;
}

}  // namespace rover::navbench
