// The figures of a navigation benchmark run (./rover navbench, README "Navigation
// benchmark"), judged against truth: collisions of the true footprint with every rock over
// the step limit and every keep-out zone, wheels off the world's map, the path ratio, and
// the per-world rows of the results table. Nothing here reads a log or knows LCM; the
// tracks and figures come in as plain values (navbench_run.hpp reads them from a run).
#pragma once

#include "hazards/keepout.hpp"

#include <Eigen/Core>

#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace rover::navbench {

// Every contact of the true footprint with an obstacle along a track.
struct CollisionReport {
  // Times the footprint went from clear of an obstacle to overlapping it (an obstacle
  // overlapped at the first sample counts once), summed over the obstacles.
  int contacts = 0;
  std::optional<double> min_clearance_m;  // empty: no obstacle came within a footprint of the track
  std::string closest;                    // the obstacle at min_clearance_m
  std::vector<std::string> touched;       // each obstacle with a contact, once, in order of first contact
  std::vector<std::size_t> contact_samples;  // the track index at which each contact began
  // With a surface (JudgeRockCollisions): each obstacle whose disc the footprint overlapped
  // without its surface there ever rising over the clearance, once, in order (a corner over
  // a tall rock's low rim). Not contacts.
  std::vector<std::string> grazed;
};

// The footprint at every pose of `track` against every obstacle (keep-out zones as they are,
// rocks as circles), by hazards::Clearance (negative: overlap); any overlap is a contact.
// Only the obstacles within reach of a pose are measured (a grid of their bounding circles),
// so a field of thousands of rocks is judged in one pass.
CollisionReport JudgeCollisions(const std::vector<hazards::Pose2>& track, const hazards::Footprint& footprint,
                                const std::vector<hazards::KeepOutZone>& obstacles);

// How high obstacle `index`'s surface stands `gap_m` from its centre (a rock's
// terrain::RockHeightAt).
using SurfaceHeight = std::function<double(std::size_t index, double gap_m)>;

// As JudgeCollisions for circular obstacles with a surface (rocks over the collision
// height), as the simulator judges them: an overlap is a contact only while the surface
// under the footprint, at the footprint's point nearest the centre, rises over
// `clearance_m` (the belly's, mobility.rock_collision.max_height_m); the rest are grazes.
CollisionReport JudgeRockCollisions(const std::vector<hazards::Pose2>& track, const hazards::Footprint& footprint,
                                    const std::vector<hazards::KeepOutZone>& rocks, const SurfaceHeight& surface,
                                    double clearance_m);

// The world's map as an axis-aligned rectangle in the site plane.
struct MapBounds {
  double min_x = 0, max_x = 0, min_y = 0, max_y = 0;
  bool Contains(const Eigen::Vector2d& p) const {
    return p.x() >= min_x && p.x() <= max_x && p.y() >= min_y && p.y() <= max_y;
  }
};

// The six wheel contact points of a rocker-bogie (front, middle, rear on each side) in the
// rover frame (x forward, y right): axles at +wheelbase/2, 0 and -wheelbase/2, sides at
// +-track/2.
std::vector<Eigen::Vector2d> SixWheels(double wheelbase_m, double track_m);

struct OffMapReport {
  int samples = 0;                        // poses with a wheel outside the map
  std::optional<Eigen::Vector2d> first;   // the first wheel found outside
};
OffMapReport WheelsOffMap(const std::vector<hazards::Pose2>& track, const std::vector<Eigen::Vector2d>& wheels,
                          const MapBounds& map);

// The shortest way the rover could have driven: from `start` to within goal_radius_m of
// `goal`, its centre keeping `clearance_m` off every obstacle disc (navbench: the rocks over
// the map's step limit, which the stack refuses; clearance half the body's width: a lower
// bound, since the body is longer than it is wide and must turn), inside `map`. The global planner (common/planner) on the true
// world, every cell of cell_m whose centre lies in a disc an obstacle and the rest seen
// safe ground at one cost, gives the 8-connected way; it is then pulled taut (each corner
// cut where the straight line keeps the clearance from every disc, by exact geometry), so
// the length is the grid's way less its 8-connected excess (up to 8 %). What a path ratio
// can at best be, and whether a long path was forced by the rocks. Empty length: no way.
struct ShortestPath {
  std::optional<double> length_m;
  std::vector<Eigen::Vector2d> path;  // start .. goal disc, taut
};
ShortestPath ShortestSafePath(const std::vector<hazards::KeepOutZone>& obstacles, double clearance_m,
                              const Eigen::Vector2d& start, const Eigen::Vector2d& goal, double goal_radius_m,
                              const MapBounds& map, double cell_m = 0.1);

// Length of the polyline through the track's positions.
double PathLength(const std::vector<hazards::Pose2>& track);
// Driven distance over the straight line from start to goal; empty when the line is 0.
std::optional<double> PathRatio(double driven_m, const Eigen::Vector2d& start, const Eigen::Vector2d& goal);
// The median (mean of the middle two for an even count); empty for none.
std::optional<double> Median(std::vector<double> values);

// One run as the table counts it.
struct RunFigures {
  std::string group;                 // the table row: "k=0.10", "gap_wall", ...
  std::string id;                    // "k0.10_r03"
  bool ran = false;                  // a summary.json was written
  std::string outcome = "incomplete";  // completed, aborted, rejected, incomplete
  std::string abort_reason;          // empty unless aborted
  bool in_goal_disc = false;         // the TRUE final position lies inside the goal disc
  int rock_contacts = 0;             // JudgeRockCollisions against rocks over the limit
  int rock_grazes = 0;               // its grazes: tall rocks' rims under the footprint, no contact
  int zone_contacts = 0;             // and against keep-out zones
  int off_map_samples = 0;
  double goal_x = 0, goal_y = 0, goal_radius_m = 0.5;
  std::optional<Eigen::Vector2d> final_truth;  // the last true position
  double straight_m = 0;             // start to goal
  double driven_m = 0;               // the true path's length
  std::optional<double> path_ratio;  // driven / straight
  // The shortest safe way on the true world (ShortestSafePath), when one was measured.
  std::optional<double> shortest_m;
  std::optional<double> shortest_ratio() const {
    return shortest_m && straight_m > 0 ? std::optional<double>(*shortest_m / straight_m) : std::nullopt;
  }
  // The stack's own plan on a perfect map of the world (perfect_map_way.hpp), when it was
  // looked for: whether one exists, and its length. A world without one cannot be crossed
  // by this rover with its clearance, however well it sees.
  std::optional<bool> perfect_way;
  double perfect_way_m = 0;
  double rover_time_s = 0;           // span of the sequence (rover_time_breakdown.span_s)
  // Planning counts only where the stack charges it (summary.json's planning_s; 0 when null).
  double driving_s = 0, imaging_s = 0, vo_s = 0, mapping_s = 0, planning_s = 0, waiting_s = 0;
  int steps = 0, steps_thought_ahead = 0;  // step reports; chosen while driving (think_ahead.cpp)
  int vo_accepted = 0, vo_false = 0;
  // Pose honesty (summary.json's pose_honesty: POSE against truth): the horizontal poses
  // judged, their mean NEES (2 is honest) and the share beyond the 99.7 % bound.
  int horizontal_poses = 0;
  double horizontal_nees_mean = 0, horizontal_beyond_pct = 0;
  bool collided() const { return rock_contacts + zone_contacts > 0; }
  // A wheel of the true track left the world's map, with no collision: the world was too
  // small for the detour, which says nothing of the navigation. Counted apart from the
  // navigation's runs (GroupFigures::navigation_runs). A run that also collided is a collision.
  bool left_map() const { return off_map_samples > 0 && !collided(); }
  // Completed, truly inside the goal disc, no contact, no wheel off the map.
  bool success() const { return outcome == "completed" && in_goal_disc && !collided() && off_map_samples == 0; }
  // The run in one word or phrase, first that applies: "collision", "left the map",
  // "success", "missed the goal" (completed outside the goal disc by truth), "aborted
  // (REASON)", "incomplete".
  std::string Verdict() const;
};

// One row of the table: the runs of one world kind.
struct GroupFigures {
  std::string group;
  int runs = 0, successes = 0, completed = 0;
  int runs_with_collision = 0, contacts = 0;
  int runs_with_graze = 0;  // a tall rock's rim under the footprint (RunFigures::rock_grazes), collision or not
  int runs_off_map = 0;   // a wheel off the map, collision or not
  int runs_left_map = 0;  // RunFigures::left_map(): off the map, no collision (not navigation's)
  // Runs whose world was checked for the plan's way on a perfect map (RunFigures::
  // perfect_way), those with one, and the successes among the navigation runs with one.
  int runs_way_checked = 0, runs_with_way = 0, successes_with_way = 0, navigation_runs_with_way = 0;
  // Aborts without a contact or a wheel off the map, by abort reason; runs that did not end
  // (no summary, or the wall-clock limit) under "incomplete".
  std::map<std::string, int> safe_aborts;
  std::optional<double> median_path_ratio;  // over the successful runs
  // Over the same runs: the shortest safe way's ratio (what the path ratio could at best
  // be), and the driven length over that shortest way.
  std::optional<double> median_shortest_ratio, median_over_shortest;
  double driven_m = 0, rover_time_s = 0;    // sums over every run that ran
  std::optional<double> drive_rate_m_per_h; // driven_m / rover_time_s
  double driving_s = 0, imaging_s = 0, vo_s = 0, mapping_s = 0, planning_s = 0, waiting_s = 0;
  int steps = 0, steps_thought_ahead = 0;  // step reports; chosen while driving (think_ahead.cpp)
  int vo_accepted = 0, vo_false = 0;
  // Pose honesty over every pose of every run that ran (each run weighted by its poses).
  int horizontal_poses = 0;
  std::optional<double> horizontal_nees_mean, horizontal_beyond_pct;
  // The runs that judge the navigation: every run but those that left the map.
  int navigation_runs() const { return runs - runs_left_map; }
  double success_pct() const { return navigation_runs() > 0 ? 100.0 * successes / navigation_runs() : 0.0; }
};

GroupFigures Aggregate(const std::string& group, const std::vector<RunFigures>& runs);

// The results table as text (one line per group, then the rover-time breakdown) and as
// JSON (groups, then every run).
std::string TableText(const std::vector<GroupFigures>& groups);
std::string ResultsJson(const std::vector<GroupFigures>& groups, const std::vector<RunFigures>& runs,
                        const std::string& command);

}  // namespace rover::navbench
