// The global planner: a cost-to-go field over the site map (site_map.hpp), from the goal
// to every cell, on a configuration-space grid, and the path down it from the rover.
//
// Why this method. MER added global planning to GESTALT with Field D* (Carsten et al. 2007),
// and ENav ranks its arcs by a cost-to-go at their ends in the same way. Both use the
// planner for one thing: the cost still to go from any point, so that the local vote can
// score each arc by the progress it makes along the best way, not in a straight line.
// Field D*'s gifts are incremental repair (replanning cheaply as a few cells change) and
// interpolated, any-angle costs. Here neither pays: the hazard monitor's map changes
// everywhere in view at every step (each new pair re-rates every cell it sees), so every
// step's plan is a new plan anyway, and the map is small (a 20 m goto with 10 m margins is
// about 200 x 200 cells of 0.2 m: one Dijkstra over it, 8-connected, takes milliseconds;
// the README has a measured figure). Hybrid A* plans kinematically feasible paths for
// car-like vehicles; a rover that turns in place does not need that, and arc voting already
// makes each step drivable. So: Dijkstra from the goal over a configuration-space grid,
// recomputed at every step, the plan being the whole field.
//
// The configuration space. Obstacles: map cells rated unsafe with at least
// min_obstacle_neighbours unsafe neighbours (0, the default: every unsafe cell, as arc
// voting refuses every one, and a plan through caution between lone unsafe cells of a
// wall would lead the vote to a wall it cannot cross; more: lone cells are
// taken for stereo noise and cost as caution), the cells of
// keep-out zones grown by the position uncertainty (as the hazard monitor grows them), and
// ground the prior map calls impassable that the cameras have not rated. A cell within
// the rover's inscribed radius (half its width) of an obstacle cannot hold the rover's
// centre: it is no way through, so a gap narrower than the rover blocks the plan. Cells
// out to the circumscribed radius cost near_cost per metre (the rover fits, with its
// corners close). Costs per metre: safe 1, caution caution_cost, unknown unknown_cost times
// the prior's factor (the goal is usually beyond what was seen, so unknown ground is a way,
// at a price).
//
// The goal is unreachable when the rover's cell is not connected to the goal disc through
// cells that can hold its centre. The field is still defined, at squeeze_cost per metre,
// in the inscribed band (never across an obstacle cell), so that a rover standing in it
// (squeezing past a rock, the map having grown a rock's edge since the last step) still
// sees which way leads out. It only leads out: a cell joined to the goal through free cells
// keeps that cost, so that a squeeze through a wall's narrow gaps never undercuts the way
// round (a cul-de-sac closed by a row of rocks).
#pragma once

#include "avoidance/goal_field.hpp"
#include "avoidance/grid.hpp"
#include "hazards/keepout.hpp"
#include "planner/prior_map.hpp"
#include "planner/site_map.hpp"

#include <Eigen/Core>

#include <string>
#include <vector>

namespace rover::planner {

struct PlannerOptions {
  double inscribed_radius_m = 0.7;       // half the rover's width: its centre keeps this off obstacles
  double circumscribed_radius_m = 1.06;  // half its diagonal: closer than this costs near_cost
  double unknown_cost = 1.25;
  double caution_cost = 3.0;
  double near_cost = 3.0;
  double squeeze_cost = 10.0;
  int min_obstacle_neighbours = 0;
  double margin_m = 10.0;                // the planning window: the map, start and goal, plus this
  int max_cells = 1'000'000;             // a larger window is cut round the start and the goal

  // Throws std::invalid_argument naming the field.
  void Validate() const;
  // The radii from a rectangular footprint (plus `margin_m` all round).
  void SetRadiiFrom(const avoidance::Footprint& footprint, double margin_m);
};

// Ground the plan should rather not cross: every metre through a cell whose centre lies in
// the disc costs cost_per_m more (refused_ways.hpp: where the local check refused the way).
// A cost, never an obstacle: no way is shut by it, so it cannot make a goal unreachable.
struct CostlyDisc {
  Eigen::Vector2d center = Eigen::Vector2d::Zero();
  double radius_m = 0.5;
  double cost_per_m = 10.0;
};

struct PlanRequest {
  double start_x = 0.0, start_y = 0.0;
  double goal_x = 0.0, goal_y = 0.0;
  double goal_radius_m = 0.3;                // the goto's disc: any centre in it will do
  std::vector<hazards::KeepOutZone> zones;   // obstacles, grown by zone_grow_m
  double zone_grow_m = 0.0;                  // e.g. 3 sigma of the position
  const PriorCostMap* prior = nullptr;
  std::vector<CostlyDisc> costly;            // extra cost, added up where discs overlap
};

// The point `along_m` down a path (its last point when the path is shorter; the origin when
// it is empty).
Eigen::Vector2d PointAlongPath(const std::vector<Eigen::Vector2d>& path, double along_m);

// The plan: the cost-to-go field (the goal vote's GoalDistance) and the path down it.
class GlobalPlan final : public avoidance::GoalDistance {
 public:
  bool reachable() const { return reachable_; }
  const std::string& why_unreachable() const { return why_; }
  // From the start to the goal: cell centres down the field, then the goal itself. Empty
  // when unreachable.
  const std::vector<Eigen::Vector2d>& path() const { return path_; }
  double path_length_m() const;
  double cost_at_start() const { return DistanceAt(start_.x(), start_.y()); }
  // Cost to go from (x, y) (per-metre costs times length); +inf on an obstacle. Outside
  // the planning window: the window's border value plus the straight line to it, kept
  // monotonic so that arcs leaving the window are not rewarded.
  double DistanceAt(double x, double y) const override;
  // The site heading from the start to the point `ahead_m` along the path (NaN: no path).
  double WayHeading(double ahead_m) const;
  // Counts, for reports and tests.
  int obstacle_cells() const { return obstacle_cells_; }
  int window_cells() const { return grid_.rows * grid_.cols; }
  // Whether the centre of the cell holding (x, y) is an obstacle (false outside the window).
  bool ObstacleAt(double x, double y) const;

 private:
  friend GlobalPlan PlanOnGrid(const avoidance::Grid&, const PlanRequest&, const PlannerOptions&);
  avoidance::Grid grid_;  // the window (geometry only matters here)
  std::vector<double> field_;
  std::vector<unsigned char> obstacle_;
  Eigen::Vector2d start_ = Eigen::Vector2d::Zero(), goal_ = Eigen::Vector2d::Zero();
  bool reachable_ = false;
  std::string why_;
  std::vector<Eigen::Vector2d> path_;
  int obstacle_cells_ = 0;
};

// The cells of `grid` whose centre lies inside one of the zones grown by grow_m (1 = inside):
// what the planner takes as zone obstacles, and what the executor marks unsafe for arc voting.
std::vector<unsigned char> ZoneCells(const avoidance::Grid& grid, const std::vector<hazards::KeepOutZone>& zones,
                                     double grow_m);

// Plans on a grid already cut to the planning window (tests, and PlanOnSiteMap).
GlobalPlan PlanOnGrid(const avoidance::Grid& grid, const PlanRequest& request, const PlannerOptions& options);
// Plans over the site map's window round the map, the start and the goal (margin_m beyond).
// An empty site map plans over unknown ground (and the prior).
GlobalPlan PlanOnSiteMap(const SiteMap& map, const PlanRequest& request, const PlannerOptions& options);

}  // namespace rover::planner
