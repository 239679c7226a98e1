// A scenario: a world, a sequence, a deployment and a start pose (README, "Scenarios"),
// run on a fresh private bus and summarised from its log.
#pragma once

#include "hazards/keepout.hpp"
#include "logcheck/log_check.hpp"
#include "scenario/rover_time.hpp"
#include "scenario/scenario_overrides.hpp"
#include "scenario/pose_truth.hpp"
#include "scenario/vo_truth.hpp"

#include <cstdint>
#include <map>
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
  // The name the sequence is submitted under (the executor, its status and so the log call
  // it by it): `sequence_name`, else the `sequence` path as written. A tool that writes
  // scenarios into an output folder of the user's choosing names them, so that the log and
  // its digest do not depend on where the folder is.
  std::string sequence_name;
  // Submitted one after another on the same running stack, each when the one before has
  // completed (summary.json reports the last).
  std::vector<std::string> then_sequences;
  std::string deployment;     // configs/deploy/*.yaml
  std::string rover_config = "configs/rover.yaml";
  double start_x = 0, start_y = 0, start_yaw_deg = 0;
  double sim_rate = 50;       // rover seconds per wall second
  double timeout_s = 300;     // the run's limit: wall seconds on a real clock; in virtual time
                              // timeout_s x sim_rate seconds of rover time from the submission
  // A day of operations (docs/OPERATING.md, "Pauses and nights"): `pause: {after_steps:
  // N, for_s: S}` pauses the first sequence once N step reports were seen and resumes it S
  // seconds of rover time after it paused; `then_idle_s` parks the rover that long (rover
  // time) after each sequence completes before the next of then_sequences is submitted.
  int pause_after_steps = 0;  // 0: no pause
  double pause_for_s = 0;
  double then_idle_s = 0;
  // Fault injection: kill `kill_process` once `kill_after_steps` step reports were seen.
  std::string kill_process;
  int kill_after_steps = 0;
  // Overrides without copying files (scenario_overrides.hpp): `seeds: {world, mobility,
  // render}` and `dragged_wheel: WHEEL` become the entries they stand for, ahead of the
  // `overrides:` (rover config) and `world_overrides:` (world file) maps of dotted keys.
  std::vector<ConfigOverride> overrides;
  std::vector<ConfigOverride> world_overrides;
  // How a campaign varies the scenario (`campaign:`): start position and heading by up to
  // +/- these, and the world's first slope by up to +/- slope_jitter_deg.
  double campaign_start_jitter_m = 0.2;
  double campaign_yaw_jitter_deg = 3.0;
  double campaign_slope_jitter_deg = 2.0;
  // What the catalogue expects (printed; asserted by tests and campaigns).
  std::string expect_outcome;
  std::string expect_abort_reason;                 // as written: "progress" or "progress|vo_lost"
  std::vector<std::string> expect_abort_reasons;   // any of these
  std::optional<double> expect_min_clearance_m;    // truth clearance to every zone >= this
  std::optional<double> expect_max_position_error_pct;
  std::optional<int> expect_max_false_updates;
  // Pose honesty (summary.json's pose_honesty): each NEES mean within [min, max], and the
  // last pose's claimed horizontal 3-sigma at most this.
  std::optional<std::pair<double, double>> expect_horizontal_nees, expect_heading_nees;
  std::optional<double> expect_max_final_3sigma_m;
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
  std::optional<VoCheck> vo;  // the step's VO update against truth (none: VO off)
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
  // The closest the true footprint came to a rock taller than the rover's step limit
  // (mobility.rock_collision.max_height_m), and that rock; empty when the world has none
  // (AddRockClearance; the runner knows the world, the log does not).
  std::optional<double> min_rock_clearance_m;
  std::string min_rock_clearance_rock;
  int rocks_over_limit = 0;
  // The true plane pose at every SIM_TRUTH (not written to summary.json).
  std::vector<hazards::Pose2> truth_track;
  // Every VO update in the log against truth: accepted = status OK; a false update is an
  // accepted one whose NEES exceeds kChi2Dof6ThreeSigma.
  int vo_updates = 0;
  int vo_updates_accepted = 0;
  int false_updates = 0;
  std::optional<double> nees_mean;
  // The state estimator's POSE against truth: is its claimed sigma honest (pose_truth.hpp)?
  std::optional<PoseHonesty> pose_honesty;
  double rover_time_s = 0;
  double wall_time_s = 0;
  // User + sys CPU seconds of each process the run started (the set, the recorder and the
  // runner itself), in start order: where a simulated hour's CPU goes.
  std::vector<std::pair<std::string, double>> cpu_s;
  std::vector<std::string> process_events;
  // At each resume after a pause and each submission after an idle: the estimate against
  // truth (the runner fills it; heading and horizontal NEES against the pose's own sigma).
  struct RestCheck {
    std::string after;          // "pause" or "idle"
    double rested_s = 0;        // rover seconds paused or parked
    double position_error_m = 0;  // horizontal
    double heading_error_deg = 0;
    double heading_sigma_deg = 0;
    double heading_nees = 0, horizontal_nees = 0;
  };
  std::vector<RestCheck> rest_checks;
  // Why a figure is absent: summary.json writes null for KEY and a KEY_reason beside it.
  std::map<std::string, std::string> missing;
  // Whether the log lost anything (tools/logcheck): counts and gaps per channel.
  logcheck::LogReport log;
  // SHA-256 of the log less its wall-time fields (logcheck/log_digest.hpp): two runs of the
  // same scenario and seeds in virtual time give the same digest.
  std::string log_digest;
  // Where the sequence's rover time went (virtual-time logs only).
  RoverTimeBreakdown rover_time;
};

// Reads an LCM log of a run and computes the summary. The footprint is used for the
// truth clearance to keep-out zones.
ScenarioSummary SummarizeLog(const std::string& log_path, const hazards::Footprint& footprint);

// A rock as the truth clearance sees it: a disc in the site plane.
struct RockDisc {
  std::string name;
  double x = 0, y = 0, radius_m = 0;
};
// Fills min_rock_clearance_m from the truth track against `rocks` (those over the limit).
void AddRockClearance(const std::vector<RockDisc>& rocks, const hazards::Footprint& footprint,
                      ScenarioSummary* summary);

std::string SummaryJson(const ScenarioSummary& summary);
// Whether the summary meets every `expect:` entry; `why` lists the ones it misses.
bool AsExpected(const ScenarioSpec& spec, const ScenarioSummary& summary, std::string* why);
std::string SummaryText(const ScenarioSummary& summary);

}  // namespace rover::tools
