// A scenario: a world, a sequence, a deployment and a start pose (README, "Scenarios"),
// run on a fresh private bus and summarised from its log.
#pragma once

#include "hazards/keepout.hpp"

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace rover::tools {

struct ScenarioSpec {
  std::string source;         // the scenario file
  std::string name;
  std::string description;
  std::string world;          // configs/worlds/*.yaml
  std::string sequence;       // configs/sequences/*.seq
  std::string deployment;     // configs/deploy/*.yaml
  std::string rover_config = "configs/rover.yaml";
  double start_x = 0, start_y = 0, start_yaw_deg = 0;
  double sim_rate = 50;       // rover seconds per wall second
  double timeout_s = 300;     // wall-clock limit for the whole run
  // Fault injection: kill `kill_process` once `kill_after_steps` step reports were seen.
  std::string kill_process;
  int kill_after_steps = 0;
  // What the catalogue expects (printed; asserted by tests).
  std::string expect_outcome;
  std::string expect_abort_reason;
};

// Throws config::ConfigError naming the file and key.
ScenarioSpec LoadScenario(const std::string& path);

struct Xyzrpy {
  double v[6] = {0, 0, 0, 0, 0, 0};  // x y z roll pitch yaw
};

struct CommandOutcome {
  int index = 0;
  int line = 0;
  std::string text;
  std::string outcome;  // completed, aborted, skipped, not_run
};

struct StepSummary {
  int command_index = 0;
  int step_index = 0;
  double commanded_distance_m = 0, commanded_turn_rad = 0;
  double estimated_distance_m = 0, estimated_turn_rad = 0;
  double true_distance_m = 0, true_turn_rad = 0;
  double estimated_slip_pct = 0, true_slip_pct = 0;
  int vo_status = -1;
};

struct ScenarioSummary {
  std::string scenario;
  std::string outcome;        // completed, aborted, rejected, incomplete
  std::string abort_reason;   // empty = null
  std::string detail;
  std::vector<CommandOutcome> commands;
  std::vector<StepSummary> steps;
  std::optional<Xyzrpy> final_estimate, final_truth;
  double distance_travelled_m = 0;
  double position_error_m = 0;
  double position_error_pct = 0;
  std::optional<double> min_keepout_clearance_m;  // empty when no zone was defined
  double rover_time_s = 0;
  double wall_time_s = 0;
  std::vector<std::string> process_events;
};

// Reads an LCM log of a run and computes the summary. The footprint is used for the
// truth clearance to keep-out zones.
ScenarioSummary SummarizeLog(const std::string& log_path, const hazards::Footprint& footprint);

std::string SummaryJson(const ScenarioSummary& summary);
std::string SummaryText(const ScenarioSummary& summary);

}  // namespace rover::tools
