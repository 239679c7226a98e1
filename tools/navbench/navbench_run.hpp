// The runs of a navigation benchmark (./rover navbench): each drawn from the benchmark's
// seed, written as a world, a sequence and a scenario into its own folder (the scenario
// campaign runs them: scenario_campaign --each), and read back from its summary.json and log
// as the figures navbench_metrics.hpp tables.
#pragma once

#include "navbench/navbench_metrics.hpp"
#include "navbench/perfect_map_way.hpp"
#include "scenario/scenario_overrides.hpp"

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace rover::navbench {

struct BenchOptions {
  int runs = 20;  // per world kind
  std::vector<double> densities = {0.05, 0.10, 0.15, 0.20};  // Golombek k of the rock fields
  std::vector<std::string> worlds = {"gap_wall", "cul_de_sac"};  // fixed layouts (FixedWorlds)
  std::uint64_t seed = 1;
  double min_goal_m = 20, max_goal_m = 50;  // goto length on the rock fields
  std::string out_dir = "out/navbench";
  // Rover-config settings tried on every run (--set KEY=VALUE), after the map's own
  // (hazards.map.enabled: true), in each run's scenario `overrides:`.
  std::vector<tools::ConfigOverride> overrides;
};

// "KEY=VALUE" as a rover-config override: the dotted key and the value as YAML (a number,
// true, a list [1, 2]). Throws config::ConfigError "navbench: --set ...: expected ..." on a
// missing '=', an empty key or key component, or a value that is not YAML.
tools::ConfigOverride ParseSetting(const std::string& text);

// A world with a fixed layout: its file, and the goal its runs drive to from (0, 0).
struct FixedWorld {
  std::string name, world_file;
  double goal_x = 0, goal_y = 0;
};
const std::vector<FixedWorld>& FixedWorlds();

struct RunPlan {
  std::string group;  // the table row: "k=0.10", or a fixed world's name
  std::string id;     // "k0.10_r03", "gap_wall_r01"
  std::string dir;    // absolute: this run's folder
  int index = 0;      // 1-based within the group
  std::optional<double> abundance_k;  // rock fields
  std::string world_file;             // a fixed world's file (empty: a generated rock field)
  std::uint64_t world_seed = 0, mobility_seed = 0, render_seed = 0;
  double goal_x = 0, goal_y = 0, goal_radius_m = 0.5;
  double start_yaw_deg = 0;
  double sun_azimuth_deg = 120, sun_elevation_deg = 55;
  double straight_m() const;
  std::string scenario_path() const { return dir + "/scenario.yaml"; }
};

// Every run of the benchmark, in table order. A run depends only on (seed, its world kind,
// its index), so `--densities 0.15` alone draws the same k = 0.15 runs as the full set.
std::vector<RunPlan> PlanRuns(const BenchOptions& options);

// The rock-field world of a run (WORLD_FORMAT.md): Golombek rocks of 0.1 to 1.5 m at its k
// over a map round the start and the goal, none within a footprint of either.
std::string RockFieldYaml(const RunPlan& plan);
// The run's sequence: VO on, the limits, one `goto ... avoid on`.
std::string SequenceText(const RunPlan& plan);
// Writes the world (rock fields), the sequence and the scenario into plan.dir.
void WriteRun(const RunPlan& plan, const std::vector<tools::ConfigOverride>& overrides = {});

// What a plot of the run needs besides its figures.
struct RunTrack {
  std::vector<hazards::Pose2> truth;
  std::vector<hazards::KeepOutZone> rocks_over_limit, zones;
  std::vector<hazards::KeepOutZone> small_rocks;  // under the limit (drawn, not judged)
  MapBounds map;
  hazards::Footprint footprint;
  std::vector<hazards::Pose2> contact_poses;  // where each collision began
  std::vector<Eigen::Vector2d> shortest;       // the shortest safe way (ShortestSafePath)
};

// Reads a finished run: its summary.json, the truth track and keep-out zones in its log,
// and the world and rover config it ran with (the runner's copies in its folder when the
// scenario overrode them). A run with no summary.json gives ran = false.
RunFigures ReadRun(const RunPlan& plan, RunTrack* track);

// The stack's plan on a perfect map of a written run's world (perfect_map_way.hpp), with the
// rover config and world its scenario runs with (its overrides applied to copies in
// DIR/perfect_way). The run need not have been driven (navbench --ways). at_mean: each cell
// at the mean of the surface in it (PerfectMap).
PerfectWay RunPerfectWay(const RunPlan& plan, bool at_mean = false);

}  // namespace rover::navbench
