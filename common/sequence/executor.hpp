// The sequence executor: runs a checked Sequence step by step (LANGUAGE.md, "What runs
// between steps"). It knows nothing of LCM. The process shell feeds it the messages it
// reads (On*), the operator's requests (Submit, Abort, Pause, Resume) and the clocks (Tick),
// and publishes what TakeOutputs() returns. Every input struct mirrors its lcmtypes message.
//
// Time: rover time (utime, us) comes from the messages and Tick, and drives the time limits.
// Wall-clock seconds (Tick, OnHeartbeat) only guard against silent peers: heartbeats and
// the waits for hazard replies, VO updates, poses and mobility.
#pragma once

#include "avoidance/grid.hpp"
#include "avoidance/loop_breaker.hpp"
#include "avoidance/retrace_trail.hpp"
#include "config/yaml_config.hpp"
#include "planner/blocked_ways.hpp"
#include "planner/global_planner.hpp"
#include "planner/prior_map.hpp"
#include "planner/refused_ways.hpp"
#include "planner/site_map.hpp"
#include "geometry/pose.hpp"
#include "sequence/parser.hpp"
#include "sequence/sequence.hpp"
#include "sequence/stepping.hpp"

#include <Eigen/Geometry>

#include <cstdint>
#include <deque>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <variant>
#include <vector>

namespace rover::sequence {

// ---------------------------------------------------------------------------------------
// Options (YAML section `executor:`, sample in common/sequence/executor_example.yaml).
struct ExecutorOptions {
  // Heartbeats. A name "a|b" is satisfied by either process (rover_sim or a real driver).
  std::vector<std::string> required_processes = {"rover_sim|mobility_driver", "state_estimator",
                                                 "hazard_monitor"};
  // Needed while VO is on (and for `images`) when vo_processes_required; otherwise a silent
  // VO process counts as a VO failure and the sequence's VO policy decides.
  std::vector<std::string> vo_processes = {"camera_capture", "visual_odometry"};
  bool vo_processes_required = true;
  double heartbeat_timeout_s = 3.0;  // wall: older than this = silent
  double start_wait_s = 5.0;         // wall: a submission waits this long for heartbeats and a
                                     // first pose, then is rejected with process_lost

  // Wall-clock waits that guard against a silent peer.
  double hazard_reply_wait_s = 5.0;   // predictive query; no answer = abort hazard_unknown
  double hazard_status_wait_s = 5.0;  // fresh hazard status after a step; none = hazard_unknown
  double vo_wait_s = 30.0;            // VO answer; none = a VO failure (`vo ... wait` overrides)
  double pose_wait_s = 3.0;           // pose including the VO update; then the latest is used
  double mobility_wait_s = 300.0;     // mobility DONE; none = abort timeout
  double capture_wait_s = 2.0;        // science frame seen (OnStereoFrame); none = go on
  double site_wait_s = 5.0;           // pose in the new site; none = abort timeout
  // Rover time one `goto ... avoid on` decision costs the rover's computer (the arc vote):
  // the step is commanded this long after it was chosen. Not read from the `executor:`
  // section: the process sets it from the compute profile in virtual time (README,
  // "Simulated time"), and leaves it 0 on a real clock, where the work takes what it takes.
  double plan_compute_s = 0.0;

  // Rover-time guard on one step: expected duration * factor + margin, then abort timeout.
  double mobility_timeout_factor = 3.0;
  double mobility_timeout_margin_s = 30.0;

  // Motion.
  double speed_mps = 0.04;            // sent with every arc (MER: ~4 cm/s)
  double turn_rate_rps = 0.05;        // sent with every turn
  double default_step_m = 0.60;       // step length before any `vo` line
  double default_max_turn_deg = 18.0; // max turn per step before any `vo` line
  double goto_turn_threshold_deg = 10.0;  // goto turns in place above this bearing error
  // A goto with no distance limit gets factor * straight-line distance + margin.
  double goto_default_distance_factor = 1.5;
  double goto_default_distance_margin_m = 2.0;

  // Checks.
  bool predictive_hazard_check = true;  // ask before every step (hazard_query_t)
  bool reactive_hazard_abort = true;    // abort on a violation reported during a step
  double path_sample_spacing_m = 0.05;  // swept-path samples in a hazard query
  double path_sample_turn_deg = 2.0;
  double slip_min_step_m = 0.05;        // shorter steps are not slip-checked (noise)

  // Where slip is likely, a step VO could not measure is "VO lost" (`vo lost` in LANGUAGE.md):
  // the rover tilts more than blind_slope_deg (from the pose's roll and pitch), or VO measured
  // more than blind_slip_pct of slip or sideways drift in one of the last recent_steps steps.
  double blind_slope_deg = 15.0;
  double blind_slip_pct = 20.0;
  int recent_steps = 3;                 // also the drift history of the predictive check
  double lost_min_step_m = 0.15;        // `vo lost shorten` halves steps down to this
  // VO switched off by `then continue` comes back on (a baseline pair first, its failures
  // counted afresh) once the rover has driven this far without it (estimated m): the view
  // that failed (a rock filling it, a shadow) is left behind, and a goto that works round a
  // pocket for long on wheel odometry alone misplaces what it mapped (navbench seed 11
  // k0.20_r05 drove 146 steps blind, its map about 0.3 m off by then, into a rock). 0: never
  // (Mars's meaning).
  double vo_retry_after_m = 0.0;

  // Predictive keep-out margin (hazard_query_t.margin_m), on top of the monitor's k sigma:
  // the spread of the drift VO measured over the recent steps, and the position sigma the
  // step adds (the estimator's wheel-odometry error, % of the step), times this multiplier.
  double step_sigma_growth_pct = 2.0;
  double margin_sigma_multiplier = 3.0;
  double status_period_s = 1.0;         // wall: periodic status

  // `goto ... avoid on` (avoid_step.cpp, common/avoidance): arc voting on the hazard
  // monitor's traversability map. Before each step a pair is taken where the rover stands
  // (VO's pair when VO is on) and the executor waits up to map_wait_s (wall) for a map
  // that includes it, then votes on what it has.
  double map_wait_s = 5.0;
  // Thinking while driving (think_ahead.cpp), as Perseverance's ENav does: when the pair
  // taken where the rover stands is still being mapped, the step may be chosen on the map
  // in hand (an earlier pair's) and driven at once, while the new pair is mapped, provided
  // it is a forward arc whose swept ground is all known and safe on that map. Otherwise the
  // rover waits for the new map, as with this off.
  bool think_while_driving = true;
  double avoid_lookahead_m = 3.0;        // arcs are judged over this length, driven one step
  double avoid_max_curvature_per_m = 1.0;
  int avoid_num_arcs = 21;
  double avoid_backup_m = 0.3;           // 0: never back up
  // Arc voting sweeps a footprint this much larger all round than the monitor's, so that
  // the drift the monitor's check allows for (the step's path shifted by the drift VO
  // measured) does not make it refuse the step the vote chose.
  double avoid_margin_m = 0.1;
  // Squeezing through (common/avoidance/README.md, "Squeezing through"): when the plan finds
  // no way that keeps the vote's margin, the plan and that step's vote take this margin
  // instead, if a way keeps it (0: the body as the hazard monitor judges it); when the vote
  // finds no step with the margin (boxed in, after looking aside), it votes again with this
  // one. Tried only then: a goto that finds its way with the margin never narrows it, nor a
  // vote after the monitor refused a step. Negative: off.
  double avoid_squeeze_margin_m = -1.0;
  // Keep-out zones are obstacles for arc voting and the planner, grown by this many sigma
  // of the pose's horizontal position (as the hazard monitor's hazards.sigma_multiplier).
  double avoid_zone_sigma_multiplier = 3.0;
  // Unseen ground (common/avoidance/README.md). true: a step, a turn in place's corners
  // included, covers only ground the map has seen and rated or the rover has driven over
  // (no blind ring excused, and ground that could hide a rock refused at any share of the
  // step's cells). false: the vote excuses the monitor's blind ring round the rover, as the
  // monitor's own check does. Off: with the front HAZCAM pair (capture.hazcam) it
  // costs no success on navbench and removes the collisions beside the rover, without it
  // it costs success; turn both on together (common/avoidance/README.md).
  bool avoid_unseen_ground_strict = false;
  // With avoid_unseen_ground_strict: where a goto begins, the ring round the rover (the
  // monitor's blind margin) counts as known: the drive begins where the last one ended,
  // whose end-of-drive images saw it, or where the operators put the rover; and so does the
  // ground a whole turn in place of the vote's footprint sweeps there (the rover can turn
  // round where it began).
  bool avoid_start_ring_known = true;
  // The vote rates unsafe every safe or caution cell whose step reads this high or more
  // beside unknown ground the monitor's hidden_patch_m across (avoidance::Grid::
  // MarkFlanksOfHiddenGround): the flank of a rock whose top no pair saw reads far under the
  // rock (navbench k0.20_r18: 0.11 to 0.20 m round a 0.43 m rock's unseen top). 0: off.
  double avoid_hidden_flank_step_m = 0.0;
  // The vote rates unsafe every safe or caution cell whose top (the map's elevation_m) stands
  // this high or more over the ground round it, a plane fitted within
  // avoid_top_ground_radius_m (avoidance::MarkTopsOverGround): the map's step reads a rock
  // from its cells' mean heights over a plane the rock raises (navbench seed 41 k0.25_r16: a
  // 0.31 m rock read 0.20 to 0.25 m, caution, its tops 0.27 m over the ground, and the body
  // swept it). The planner's site map keeps the map's rating unless avoid_top_rise_in_plan.
  // 0: off.
  double avoid_top_rise_m = 0.0;
  double avoid_top_ground_radius_m = 1.0;
  // With avoid_top_rise_m: each map's cells the rule finds are unsafe in the planner's site
  // map too, so that the plan does not lead over ground the vote then refuses.
  bool avoid_top_rise_in_plan = false;
  // With avoid_unseen_ground_strict: ground that could hide a rock (UnknownLimits) is not
  // swept within this much beyond the vote's footprint either, wherever the step brings the
  // body nearer to it (avoidance::SweepFootprint's hidden_reach_m): a known cell beside
  // unseen ground may hold the rim of a rock that lies in it. 0: off.
  double avoid_hidden_reach_m = 0.0;
  // Looking aside (avoidance/look_aside.hpp): when the vote has no step on but backing up,
  // or none at all, or its step swings the body round, and the ground a turn in place would sweep holds at least
  // avoid_look_min_cells unknown cells on a side, the NAVCAM is pointed at that side (pan
  // this many degrees from ahead, tilted avoid_look_tilt_deg further down), the pair mapped
  // and the vote taken again; once a side per pose. With no step at all, not even backing
  // up, it looks behind (pan 180) at the ground a back-up would cross. 0: off (the cameras
  // cannot point).
  double avoid_look_pan_deg = 0.0;
  double avoid_look_tilt_deg = 15.0;
  // ... and before a step that swings the body round, a turn in place or an arc this tight.
  double avoid_look_curvature_per_m = 0.5;
  int avoid_look_min_cells = 3;
  // A rock the map once rated unsafe stays unsafe to the vote and the planner when a later
  // map reads it caution (a view from beside it sees less of it; a safe rating or driving
  // over it still replaces it): planner::SiteMap::set_keep_unsafe, common/avoidance/README.md
  // "A rock read lower from beside it". false: the newest rating alone.
  bool avoid_keep_unsafe = false;
  // A step's goodness counts up to this in the vote (avoidance::VoteOptions::good_enough):
  // at the map's caution level (1 - hazards.map.traversability.caution_fraction) safe
  // ground ranks alike and the plan's way decides. 0: the caution level each map gives
  // (TraversabilityMap::caution_goodness; a map that gives none: 1). 1: every difference
  // counts.
  double avoid_good_enough = 1.0;
  // The global planner (common/planner): a cost-to-go over the site map the executor
  // accumulates from the monitor's maps; arc voting's goal vote scores progress along it.
  // false: the vote's local field over the monitor's latest map only.
  bool planner_enabled = true;
  double planner_unknown_cost = 1.25;   // per metre of ground never seen (safe ground: 1)
  double planner_caution_cost = 3.0;    // per metre of caution
  double planner_near_cost = 3.0;       // per metre within the circumscribed radius of a rock (planner::PlannerOptions::near_cost)
  // The plan's configuration space as the vote sees the map: the vote counts a cell under
  // the body when its centre lies within half a cell of it, and grows keep-out zones by a
  // cell more than the monitor does. true: the planner keeps the rover's centre that much
  // further off obstacles and zones, so that it never leads the rover into a gap the vote
  // will not drive through (planner/README.md, "The vote's clearance").
  bool planner_vote_clearance = true;
  double planner_margin_m = 10.0;       // the plan's window: map, rover and goal, plus this
  // A goal the plan finds unreachable this many steps running aborts the goto (the map
  // changes as the rover looks again; one unlucky map is not the end).
  int planner_unreachable_plans = 3;
  // Dead ends (planner/blocked_ways.hpp): when the plan's cost to go from the rover has not
  // fallen by planner_block_min_gain_m in planner_block_after_steps steps, the way it leads
  // (planner_block_ahead_m down its path) is blocked, a disc of planner_block_radius_m the
  // planner treats as an obstacle, and the plan goes another way; when no way is left the
  // goal is unreachable (goal_unreachable). 0 steps: never.
  int planner_block_after_steps = 0;
  double planner_block_min_gain_m = 0.5;
  double planner_block_ahead_m = 1.5;
  double planner_block_radius_m = 0.4;
  // Refused ways (planner/refused_ways.hpp): where the local check refused the plan's way
  // (the vote backed up though the way lay ahead, or the rover came back where it stood a
  // few steps before: avoidance::BackWhereItWas), the point planner_refusal_ahead_m down
  // the plan's path costs planner_refusal_cost more per metre within
  // planner_refusal_radius_m, for the rest of the goto: a cost, never an obstacle.
  // 0 cost: refusals are not remembered.
  double planner_refusal_cost = 10.0;
  double planner_refusal_ahead_m = 1.0;
  double planner_refusal_radius_m = 0.6;
  // Optional prior cost map (planner/prior_map.hpp), relative to the config file. "" = none.
  std::string planner_prior_map;

  // A goto ends when its estimate is inside the disc less goto_arrival_sigmas times the
  // pose's horizontal position sigma, so that the truth is in the disc; when that leaves
  // less than goto_min_arrival_fraction of the radius, it ends inside that fraction and
  // says the disc is smaller than the estimate can promise.
  double goto_arrival_sigmas = 3.0;
  double goto_min_arrival_fraction = 0.25;

  // The running sequence's submission id, name and state, kept on disk (run_state.hpp)
  // so that a restarted executor reports it interrupted. Empty = off. Used by the shell.
  std::string state_file;
};

ExecutorOptions LoadExecutorOptions(const config::ConfigNode& root);  // reads root["executor"]
ExecutorOptions LoadExecutorOptionsFile(const std::string& path);
// Throws std::invalid_argument naming the bad value.
void ValidateExecutorOptions(const ExecutorOptions& options);
// The global planner's options as the executor plans a goto: the radii from the vote's
// footprint (the body grown by avoid_margin_m), half a cell of cell_m more with
// planner_vote_clearance, and the plan's costs and window. navbench's perfect map
// (tools/navbench/perfect_map_way.hpp) plans with the same.
planner::PlannerOptions PlanOptions(const ExecutorOptions& options, const avoidance::Footprint& vote_footprint,
                                    double cell_m);
// The planner_refusal_* options as the refused ways take them.
planner::RefusalOptions RefusalOptionsOf(const ExecutorOptions& options);

// ---------------------------------------------------------------------------------------
// Inputs (mirror lcmtypes).
struct PoseEstimate {  // pose_t
  int64_t utime = 0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  // q_site_rover
  geometry::Matrix6d covariance = geometry::Matrix6d::Zero();
  int source = 0;
  int site_index = 0;
  double odometer_m = 0.0;
  int64_t last_vo_to_frame = -1;
};

enum class MobilityState : int8_t { kIdle = 0, kMoving = 1, kDone = 2, kStopped = 3, kFault = 4 };
struct MobilityStatus {  // mobility_status_t
  int64_t utime = 0;
  int64_t command_id = -1;
  MobilityState state = MobilityState::kIdle;
  double wheel_distance_m = 0.0;
  double wheel_turn_rad = 0.0;
  std::string detail;
};

struct VoUpdate {  // vo_update_t (the delta itself reaches the executor through the pose)
  int64_t utime = 0;
  int64_t from_frame_id = -1;
  int64_t to_frame_id = -1;
  int status = 0;  // vo_update_t STATUS_*: 0 OK, 1 BASELINE, others are failures
  std::string reason;
  static constexpr int kStatusOk = 0, kStatusBaseline = 1, kStatusBadInput = 10;
};

enum class HazardState : int8_t { kSafe = 0, kViolation = 1, kUnknown = 2 };
struct HazardStatus {  // hazard_status_t
  int64_t utime = 0;
  HazardState state = HazardState::kUnknown;
  bool keepout_violated = false;
  std::string zone_name;
  double min_clearance_m = 0.0;
  bool tilt_violated = false;
  double roll_rad = 0.0;
  double pitch_rad = 0.0;
  std::string detail;
};

enum class HazardVerdict : int8_t { kSafe = 0, kUnsafe = 1, kUnknown = 2 };
struct TraversabilityMap {  // traversability_map_t (hazard_monitor)
  int64_t utime = 0;
  int64_t last_frame_id = -1;  // the newest stereo frame in the map
  avoidance::Grid grid;
  avoidance::Footprint footprint;  // what the monitor sweeps along a step
  double blind_margin_m = 0.5;
  avoidance::UnknownLimits unknown;  // how much unknown ground a step may cross
  // A step drives over no cell whose step reads this high, caution or not (0: off; the
  // monitor's hazards.map.driven_step_fraction x its map's step limit).
  double max_driven_step_m = 0.0;
  // The map's caution level: a cell of this goodness or less is caution or worse (1 - the
  // monitor's hazards.map.traversability.caution_fraction; 0: not given).
  double caution_goodness = 0.0;
  // The rover's suspension (configs/rover.yaml `clearance:`): arc voting judges paths by
  // its clearance bounds from the map's heights; unset: by the cells' ratings.
  std::optional<clearance::Suspension> suspension;
};

struct HazardReply {  // hazard_reply_t
  int64_t utime = 0;
  int64_t query_id = -1;
  HazardVerdict verdict = HazardVerdict::kUnknown;
  std::string zone_name;
  double min_clearance_m = 0.0;
  std::string detail;
};

// ---------------------------------------------------------------------------------------
// Outputs (mirror lcmtypes). TakeOutputs() returns them in the order they were made.
struct MobilityCommand {  // mobility_command_t
  enum class Type : int8_t { kArc = 0, kTurn = 1, kStop = 2 };
  int64_t utime = 0;
  int64_t command_id = 0;
  Type type = Type::kStop;
  double distance_m = 0.0;
  double curvature_per_m = 0.0;
  double turn_rad = 0.0;
  double speed_mps = 0.0;
  double turn_rate_rps = 0.0;
};
struct CaptureRequest {  // capture_request_t
  int64_t utime = 0;
  int64_t frame_id = 0;
  std::string purpose;  // "vo_baseline", "vo", "science", "look"
  double pan_rad = 0.0;   // the mast's pointing (capture_request_t): + right
  double tilt_rad = 0.0;  // + further down
};
struct HazardQuery {  // hazard_query_t
  int64_t utime = 0;
  int64_t query_id = 0;
  // Site x, y, yaw of the swept path: the commanded path, then (when VO measured drift) the
  // path shifted by the predicted drift, from its end back to the start.
  std::vector<PlanePose> samples;
  double margin_m = 0.0;           // extra clearance: drift spread and the step's sigma growth
  // Thinking while driving: the step was chosen on the map holding this frame while a newer
  // pair was being mapped, and may be judged on it at once (0: on every pair taken before).
  int64_t map_frame_id = 0;
};
struct KeepOutZoneSet {  // keepout_zones_t: the whole set in force, replacing the previous
  int64_t utime = 0;
  std::vector<KeepOutZone> zones;
};
struct NewSiteRequest {  // no message yet: the shell tells the state estimator
  int64_t utime = 0;
  int new_site_index = 0;
};
enum class SequenceState : int8_t {
  kIdle = 0, kRunning = 1, kPaused = 2, kCompleted = 3, kAborted = 4, kRejected = 5
};
struct SequenceStatus {  // sequence_status_t
  int64_t utime = 0;
  int64_t submission_id = -1;
  std::string sequence_name;
  SequenceState state = SequenceState::kIdle;
  int num_commands = 0;
  int command_index = -1;
  int command_line = 0;
  std::string command_text;
  int step_index = 0;
  std::string abort_reason;  // "" or one of the codes below
  std::string detail;
  double pose[6] = {0, 0, 0, 0, 0, 0};  // x y z roll pitch yaw
  double distance_m = 0.0;
  double elapsed_s = 0.0;
  int vo_failures = 0;
};
// How a step was chosen (step_report_t.choice): the command's own step (drive, turn, a
// plain goto), or in a `goto ... avoid on` by the arc vote, or steered straight at the
// goal because the way to it was clear (no vote). The values are the message's.
enum class StepChoice { kCommand = 0, kArcVote = 1, kSteerAtGoal = 2 };
const char* ToString(StepChoice choice);

struct StepReport {  // step_report_t
  int64_t utime = 0;
  int64_t submission_id = 0;
  int command_index = 0;
  int step_index = 0;
  int64_t mobility_command_id = 0;
  double commanded_distance_m = 0.0;
  double commanded_turn_rad = 0.0;
  double estimated_distance_m = 0.0;
  double estimated_turn_rad = 0.0;
  double slip_pct = 0.0;
  int vo_status = -1;  // vo_update_t STATUS_*, -1 = VO off / no answer
  double pose_before[6] = {0, 0, 0, 0, 0, 0};
  double pose_after[6] = {0, 0, 0, 0, 0, 0};
  int64_t utime_before = 0;
  int64_t utime_after = 0;
  int64_t utime_plan_start = 0;  // the rover time charged for choosing the step (0, 0: none)
  int64_t utime_plan_end = 0;
  StepChoice choice = StepChoice::kCommand;
  bool thought_ahead = false;  // chosen on an earlier pair's map while this pair was mapped
};

using ExecutorOutput = std::variant<MobilityCommand, CaptureRequest, HazardQuery, KeepOutZoneSet,
                                    NewSiteRequest, SequenceStatus, StepReport>;

// Abort reason codes (sequence_status_t.abort_reason).
namespace abort_reason {
inline constexpr const char* kKeepout = "keepout";
inline constexpr const char* kProgress = "progress";
inline constexpr const char* kTilt = "tilt";
inline constexpr const char* kVoFailures = "vo_failures";
inline constexpr const char* kVoLost = "vo_lost";
inline constexpr const char* kTimeLimit = "time_limit";
inline constexpr const char* kDistanceLimit = "distance_limit";
inline constexpr const char* kGotoTimeLimit = "goto_time_limit";
inline constexpr const char* kGotoDistanceLimit = "goto_distance_limit";
inline constexpr const char* kProcessLost = "process_lost";
inline constexpr const char* kHazardUnknown = "hazard_unknown";
inline constexpr const char* kHazardMap = "hazard_map";  // an unsafe cell on the traversability map
inline constexpr const char* kGoalUnreachable = "goal_unreachable";  // the global planner found no way
inline constexpr const char* kOperator = "operator";
inline constexpr const char* kMobilityFault = "mobility_fault";
inline constexpr const char* kTimeout = "timeout";
inline constexpr const char* kInvalidSequence = "invalid_sequence";  // rejections only
inline constexpr const char* kBusy = "busy";                         // rejections only
inline constexpr const char* kInterrupted = "interrupted";  // the executor restarted mid-sequence
inline constexpr const char* kTimeSourceLost = "time_source_lost";  // rover time stood still (a silent clock)
}  // namespace abort_reason

const char* ToString(SequenceState state);

// ---------------------------------------------------------------------------------------
class SequenceExecutor {
 public:
  // Ids of mobility commands, frames and hazard queries count up from `first_id`; a shell
  // that restarts should pass something new (e.g. wall time in ms) so ids never repeat.
  explicit SequenceExecutor(ExecutorOptions options = {}, int64_t first_id = 1);

  // Operator. A submission while another sequence is active is rejected (reason busy).
  // A submitted sequence is RUNNING with command_index -1 until every required process has
  // a fresh heartbeat and a first pose has arrived; if that takes longer than start_wait_s
  // it is REJECTED with process_lost, naming the silent processes, and nothing moves.
  void Submit(Sequence sequence, int64_t submission_id, const std::string& name);
  // Checks the text first; a check failure is rejected with the first error line as detail.
  void SubmitText(std::string_view text, int64_t submission_id, const std::string& name,
                  const LanguageLimits& limits = {});
  void Abort(const std::string& detail);  // reason "operator"; always commands STOP
  // The deployment's time source fell silent (bus::Process::time_source_silent): rover time
  // stands still, so nothing the executor waits for can be judged. A running or paused
  // sequence aborts with time_source_lost; the rover is stopped either way.
  void TimeSourceLost(const std::string& detail);
  // After a restart: the sequence the previous executor was running (its state file)
  // is reported ABORTED with reason "interrupted" and `detail`, and STOP is commanded
  // once. It is never resumed. Does nothing while a sequence is active.
  void RecordInterrupted(int64_t submission_id, const std::string& name, const std::string& detail);
  void Pause();   // takes effect between steps: the current step finishes first
  void Resume();

  // Bus inputs.
  void OnPose(const PoseEstimate& pose);
  void OnMobilityStatus(const MobilityStatus& status);
  void OnVoUpdate(const VoUpdate& update);
  void OnHazardStatus(const HazardStatus& status);
  void OnHazardReply(const HazardReply& reply);
  void OnTraversabilityMap(const TraversabilityMap& map);
  void OnStereoFrame(int64_t frame_id);  // optional: confirms a science capture
  void OnHeartbeat(const std::string& process, double wall_s);

  // Clocks: call often (e.g. 20 Hz). Drives every wall-clock wait and the periodic status.
  void Tick(int64_t rover_utime, double wall_s);

  // Everything to publish since the last call, in order.
  std::vector<ExecutorOutput> TakeOutputs();

  SequenceState state() const { return state_; }
  SequenceStatus CurrentStatus() const;
  bool Active() const;  // running, paused, or waiting to start

 private:
  enum class Phase {
    kIdle,           // nothing to do
    kWaitStart,      // heartbeats and a first pose before the first command
    kReady,          // between steps / commands
    kBaseline,       // VO baseline pair: wait for its VO answer
    kQuery,          // predictive hazard query: wait for the reply
    kMoving,         // wait for mobility DONE
    kWaitVo,         // wait for the VO update of the step's frame
    kWaitPose,       // wait for the pose that includes it
    kWaitHazard,     // wait for a hazard status after that pose
    kImages,         // wait for a science frame
    kSite,           // wait for the pose in the new site
    kPlanning,       // a `goto ... avoid on` step chosen: its compute time (plan_compute_s)
    kFinished,
  };

  // Operator and clocks (executor.cpp).
  void ResetSettings();  // every setting back to its default, for a new sequence
  void SetWall(double wall_s);

  // The phase machine (executor_poll.cpp): one Poll* per phase that waits for something.
  void Advance();
  void EnterPhase(Phase phase);
  void Poll();
  void PollWaitStart();
  void PollReady();
  void PollBaseline();
  void PollQuery();
  void PollMoving();
  void PollWaitVo();
  void PollWaitPose();
  void PollWaitHazard();
  void PollImages();
  void PollSite();
  void PollPlanning();
  void DispatchNext();
  double PhaseAge() const { return now_wall_ - phase_start_wall_; }

  // Commands (executor_settings.cpp).
  void StartCommand();
  void PlanMotion(const Command& command);
  void ApplySetting(const Command& command);
  void ApplyStepSetting(const Command& command);  // vo, vo lost, slip, tilt, limit
  bool ApplyKeepOut(const Command& command);      // false: not a keep-out command
  void PublishZones();
  void StartNewSite();
  void StartImages(const Images& images);

  // A step up to the end of its motion (executor_step.cpp).
  bool NextStepOfCommand();  // false: the command is done
  void BeginStep(const PlannedStep& step);
  void QueryStep();
  void CommandStep();
  void AfterMotion();
  // A pair for `purpose`; a "look" points the mast (pan + right, tilt + down) and is no VO pair.
  void StartCapture(const std::string& purpose, double pan_rad = 0.0, double tilt_rad = 0.0);
  void CountVoFailure(const std::string& why);

  // The end of a step (executor_finish.cpp). Each check returns false when it aborted.
  struct StepEnd;
  void FinishStep();
  bool RetryLostPair(const std::string& why);  // `vo lost retry`: true when a pair was taken
  void ReportStep(const StepEnd& end);
  bool CheckHazardAfterStep(const StepEnd& end);
  bool ApplyVoLostPolicy(const StepEnd& end);
  bool CheckProgress(const StepEnd& end);
  bool ApplyVoFailurePolicy(const StepEnd& end);
  bool CheckLimits(const StepEnd& end);
  // What the time limits leave, for the pause and resume lines: "sequence 1742.5 s of
  // 1800.0 s left, goto 512.0 s of 600.0 s left", or "no time limits".
  std::string TimeLeftText() const;

  // Finishing and status (executor_report.cpp).
  void Finish(SequenceState state, const std::string& reason, const std::string& detail);
  void AbortWith(const std::string& reason, const std::string& detail);
  void Reject(int64_t submission_id, const std::string& name, const std::string& reason,
              const std::string& detail);
  // The status record of a submission that does not run: rejected, or interrupted.
  void ClearRun(int64_t submission_id, const std::string& name);
  void Emit(ExecutorOutput output);
  void EmitStatus();
  void EmitStop();

  // VO lost (executor_finish.cpp): whether the step's motion was measured by VO, why slip
  // is likely here (empty: it is not), and the `vo lost` policy (false: it aborted).
  bool StepMeasured() const;
  std::string SlipLikely(const PoseEstimate& before, const PoseEstimate& after) const;
  bool OnVoLost(const std::string& step_text, const std::string& why);
  void ResplitRemainingSteps();
  void RecordStep(const StepMotion& motion, bool measured, const PoseEstimate& after);
  double StepLength() const { return step_m_ * lost_step_scale_; }
  double MaxTurn() const { return max_turn_rad_ * lost_step_scale_; }

  // `goto ... avoid on` (avoid_step.cpp). kStep fills `step`; kWait waits for a pair or the
  // map (a phase may have been entered); kDone: inside the disc; kAborted: nothing is allowed.
  // kDeclined: only while thinking ahead, the map in hand cannot choose the step alone.
  enum class AvoidOutcome { kStep, kWait, kDone, kAborted, kDeclined };
  AvoidOutcome AvoidStep(PlannedStep* step);
  AvoidOutcome VoteOnMap(const PlanePose& pose, double remaining_m, const ArrivalDisc& disc, PlannedStep* step);
  // The disc a goto ends in, judged with the estimate's uncertainty (stepping.hpp).
  ArrivalDisc GotoArrival() const;
  // The global plan for the avoid goto's next step (kAborted: no way, plans running).
  enum class PlanVerdict { kFollow, kAborted, kDeclined };
  // `footprint` and `margin_m` (the vote's, margins included): narrowed when squeezing through.
  PlanVerdict PlanAhead(const PlanePose& pose, const ArrivalDisc& disc, avoidance::Footprint* footprint,
                        double* margin_m, double zone_grow_m, bool going_round,
                        std::optional<planner::GlobalPlan>* plan);
  // The planner's options and request for a plan from `pose` with this footprint.
  std::pair<planner::PlannerOptions, planner::PlanRequest> PlanSetUp(const PlanePose& pose, const ArrivalDisc& disc,
                                                                     const avoidance::Footprint& footprint,
                                                                     double zone_grow_m) const;
  // Squeezing through: the margin to narrow the vote's `margin_m` to, or -1 for none.
  double SqueezeMargin(double margin_m) const;
  // No way keeps the vote's margin: a plan with avoid_squeeze_margin_m, if it finds one.
  std::optional<planner::GlobalPlan> SqueezeThrough(const PlanePose& pose, const ArrivalDisc& disc,
                                                    const avoidance::Footprint& footprint, double margin_m,
                                                    double zone_grow_m, avoidance::Footprint* narrower) const;
  // The local check refused the way `plan` leads (refused_ways_): remembered, and said.
  void RefuseWay(const planner::GlobalPlan& plan, const std::string& why);
  void MarkDriven();  // the ground under the rover now carried it (site map)
  avoidance::Grid PlannedGrid(avoidance::Grid grid) const;  // the map as the plan counts it (top rule)
  // An UNKNOWN map verdict on a step with no pair taken where the rover stands: take one
  // (MER: image, map, then drive) and ask again. False: the reply stands.
  bool ImagesForMap(const HazardReply& reply);
  // No step on but backing up, or none: the mast pointed at a side whose ground a turn would
  // sweep is unknown (or, with no step at all, behind, where a back-up of backup_m would
  // go), before the vote is taken again (avoidance/look_aside.hpp). True when a look began.
  bool LookAside(const avoidance::Grid& grid, const avoidance::Footprint& footprint, double backup_m,
                 const avoidance::Pose2& here, const avoidance::Choice& choice);
  // The monitor refused the step the vote chose (the drift it allows for): vote once more
  // with a wider margin. False: the refusal stands (abort).
  bool AvoidRefused(const HazardReply& reply);

  // Thinking while driving (think_ahead.cpp). ThinkAhead: the map in hand does not yet
  // hold the pair taken here; true when it chose a forward step all of whose swept ground
  // it knows safe (KnownSafeAhead), to be driven while the pair is mapped. Otherwise what
  // the vote changed is undone and the rover waits for the new map.
  bool ThinkAhead(const PlanePose& pose, double remaining_m, const ArrivalDisc& disc, PlannedStep* step);
  bool KnownSafeAhead(const avoidance::Grid& grid, const avoidance::Footprint& footprint,
                      const avoidance::Pose2& here, const PlannedStep& step) const;
  // The monitor refused a step chosen ahead: undone, and the step is chosen on the new map.
  bool AheadRefused(const HazardReply& reply);
  // A newer map came while a step chosen ahead is driven: it stops the rover (abort
  // hazard_map) when it rates ground on the step's way unsafe.
  void CheckStepChosenAhead();
  // What a vote changes besides its step and its texts (a vote writes detail_ only with a
  // step, and clears avoid_note_ first): kept to be put back when a choice made ahead is
  // not taken.
  struct AvoidState {
    planner::RefusedWays refused_ways;
    planner::BlockedWays blocked_ways;
    std::vector<avoidance::Visit> history;
    int unreachable_plans = 0;
  };
  AvoidState SaveAvoidState() const;
  void RestoreAvoidState(const AvoidState& state);

  // Processes and pose (executor.cpp).
  std::vector<std::string> SilentProcesses(bool include_vo) const;
  bool ProcessFresh(const std::string& entry) const;
  bool VoRequired() const;
  bool VoActive() const { return vo_enabled_; }
  PlanePose CurrentPlanePose() const;
  bool PoseFinite() const;
  int64_t NewId() { return next_id_++; }

  ExecutorOptions options_;
  int64_t next_id_;
  std::vector<ExecutorOutput> outputs_;

  // Clocks.
  int64_t now_utime_ = 0;
  double now_wall_ = 0.0;
  double phase_start_wall_ = 0.0;
  double last_status_wall_ = -1e300;
  bool wall_known_ = false;
  bool progressed_ = false;
  bool in_advance_ = false;

  // Inputs seen.
  std::optional<PoseEstimate> pose_;
  uint64_t pose_count_ = 0;
  std::optional<HazardStatus> hazard_;
  uint64_t hazard_count_ = 0;
  std::map<std::string, double> heartbeats_;

  // The sequence.
  Sequence sequence_;
  int64_t submission_id_ = -1;
  SequenceState state_ = SequenceState::kIdle;
  Phase phase_ = Phase::kIdle;
  bool pause_requested_ = false;
  std::string abort_reason_;
  std::string detail_;
  int command_index_ = -1;
  int step_index_ = 0;
  // Where the sequence's time limit counts from: its start, moved later by each pause, so
  // that a pause counts against no time limit (LANGUAGE.md, "Pauses and nights").
  int64_t start_utime_ = 0;
  int64_t end_utime_ = 0;  // when it finished: its elapsed time stops there
  int64_t paused_since_utime_ = 0;  // kPaused: when the pause began
  int64_t paused_total_us_ = 0;     // rover time spent paused in this sequence
  double distance_m_ = 0.0;
  bool started_ = false;
  bool sequence_uses_vo_ = false;

  // Settings in force.
  bool vo_enabled_ = false;
  double step_m_;
  double max_turn_rad_;
  std::optional<int> vo_max_failures_;
  VoFailureAction vo_past_max_ = VoFailureAction::kContinue;
  double vo_wait_s_;
  int vo_policy_failures_ = 0;
  int vo_failures_total_ = 0;
  SlipSetting slip_;
  int no_progress_count_ = 0;
  TiltSetting tilt_;
  LimitSetting limits_;
  std::vector<KeepOutZone> zones_;
  bool vo_frame_valid_ = false;  // the last VO frame was taken where the rover stands
  int64_t last_vo_frame_ = -1;   // id of the last VO pair asked for (baseline or step)
  VoLostSetting vo_lost_;        // policy; slope and slip in force below
  double blind_slope_rad_;
  double blind_slip_pct_;
  bool vo_off_by_failures_ = false;  // `then continue` switched VO off (not the operator)
  double vo_off_at_m_ = 0.0;         // distance_m_ when it did
  // The last recent_steps steps: the largest of slip and sideways drift VO measured (0 when
  // VO did not measure the step); and the drift of the last recent_steps measured arc steps.
  std::deque<double> recent_slip_pct_;
  std::deque<StepDrift> recent_drift_;

  // The command in progress.
  bool command_active_ = false;
  std::vector<PlannedStep> steps_;  // drive, arc, turn, turnto
  std::size_t next_step_ = 0;
  bool is_goto_ = false;
  Goto goto_;
  int64_t goto_start_utime_ = 0;
  std::optional<avoidance::Pose2> goto_start_pose_;  // where the goto began (avoid_start_ring_known)
  double goto_start_distance_ = 0.0;
  double goto_distance_limit_ = 0.0;
  bool baseline_done_ = false;
  double lost_step_scale_ = 1.0;  // `vo lost shorten` halves it, a measured step doubles it
                                  // back (up to 1), a new command starts at 1

  // The step in progress.
  PlannedStep step_;
  // kPlanning: the step chosen, when its choice was charged from, and whether the choice
  // in hand has been paid for (the next NextStepOfCommand commands it).
  PlannedStep planned_;
  int64_t plan_start_utime_ = 0, plan_end_utime_ = 0;
  StepChoice step_choice_ = StepChoice::kCommand;  // how the step in hand was chosen
  int64_t query_id_ = -1;
  std::optional<HazardReply> hazard_reply_;
  int64_t mobility_id_ = -1;
  int64_t mobility_deadline_utime_ = 0;
  std::optional<MobilityStatus> mobility_done_;
  uint64_t done_pose_count_ = 0;
  int64_t frame_id_ = -1;
  int64_t step_ref_frame_ = -1;  // the VO pair the step's motion is measured from
  bool step_vo_on_ = false;      // VO was on for this step
  int step_retries_ = 0;         // `vo lost retry`: pairs taken again after the step
  std::optional<VoUpdate> vo_update_;
  bool step_vo_failed_ = false;
  std::string step_note_;
  uint64_t hazard_mark_ = 0;
  PoseEstimate pose_before_;
  int wait_site_index_ = 0;
  bool science_frame_seen_ = false;

  // The traversability map and the pairs taken where the rover stands (avoid_step.cpp).
  std::optional<TraversabilityMap> map_;
  int64_t pair_here_id_ = -1;    // the last pair taken since the rover last moved, or -1
  bool map_images_taken_ = false;  // ImagesForMap took its pair for the step in hand
  int looked_here_ = 0;            // where it looked since the rover last moved: 1 left, 2 right, 4 behind
  int looks_total_ = 0;            // looks aside in this sequence
  int64_t look_frame_id_ = -1;     // the last look's frame
  bool looks_unanswered_ = false;  // a look went unanswered in this sequence: no more
  bool avoid_refused_ = false;
  double last_turn_rad_ = 0.0;    // the last commanded step's turn in place (0: not a turn)
  // The forward arcs driven one after another up to the last commanded step: the vote may
  // back up along the last, arc by arc (avoidance/retrace_trail.hpp).
  avoidance::RetraceTrail arcs_to_retrace_;
  // The site map merged from every map the monitor sends, and where the rover has been
  // (common/planner), in the site frame of map_site_; it starts again with a new site.
  planner::SiteMap site_map_;
  planner::RefusedWays refused_ways_;  // ways the local check refused (reset per goto and site)
  std::string avoid_note_;  // what planning this avoid step did besides the plan (in its detail)
  planner::BlockedWays blocked_ways_;  // ways this goto could not follow (reset per goto)
  std::vector<avoidance::Visit> avoid_history_;  // this goto's votes, where (loop_breaker.hpp)
  int map_site_ = -1;
  std::optional<planner::PriorCostMap> prior_;
  int unreachable_plans_ = 0;     // consecutive plans that found no way
  // Thinking while driving (think_ahead.cpp).
  bool thinking_ahead_ = false;   // VoteOnMap is choosing on the map of an earlier pair
  bool thought_ahead_ = false;    // the step in hand was chosen so (its query says on which map)
  bool ahead_declined_ = false;   // here, the step waits for the new map (reset when the rover moves)
  std::optional<AvoidState> ahead_saved_;  // before the step in hand was chosen ahead
  int64_t ahead_map_frame_ = 0;   // the newest pair in the map it was chosen on
  avoidance::Pose2 ahead_start_;  // where it was chosen (and begins)
  std::string ahead_note_;        // why a step chosen ahead was not driven (the next step's note)
  int steps_thought_ahead_ = 0;   // in this sequence
  std::string arrival_note_;      // how the last goto of the sequence ended (its disc and margin)
};

}  // namespace rover::sequence
