// sequence_executor: runs operator sequences step by step (common/sequence). This shell
// translates messages into SequenceExecutor inputs and its outputs into messages.
//
// Restart: with a state file (executor.state_file or --state-file) it keeps the running
// sequence's submission id, name and state on disk (common/sequence/run_state.hpp). A
// restarted executor that finds a sequence running there commands STOP once, publishes
// that submission ABORTED with reason "interrupted", and never resumes motion by itself.
#include "bus/channels.hpp"
#include "bus/convert.hpp"
#include "bus/process.hpp"
#include "bus/traversability_convert.hpp"
#include "sequence/executor.hpp"
#include "sequence/run_state.hpp"

#include <rover_msgs/capture_request_t.hpp>
#include <rover_msgs/hazard_query_t.hpp>
#include <rover_msgs/hazard_reply_t.hpp>
#include <rover_msgs/hazard_status_t.hpp>
#include <rover_msgs/heartbeat_t.hpp>
#include <rover_msgs/keepout_zones_t.hpp>
#include <rover_msgs/mobility_command_t.hpp>
#include <rover_msgs/mobility_status_t.hpp>
#include <rover_msgs/new_site_t.hpp>
#include <rover_msgs/pose_t.hpp>
#include <rover_msgs/sequence_control_t.hpp>
#include <rover_msgs/sequence_status_t.hpp>
#include <rover_msgs/sequence_submit_t.hpp>
#include <rover_msgs/step_report_t.hpp>
#include <rover_msgs/stereo_frame_t.hpp>
#include <rover_msgs/vo_update_t.hpp>

#include <chrono>
#include <filesystem>
#include <iostream>
#include <optional>
#include <type_traits>

using namespace rover;
namespace seq = rover::sequence;

namespace {

// Publishes one executor output as its message.
class OutputPublisher {
 public:
  explicit OutputPublisher(bus::Process& proc) : proc_(proc) {}

  void operator()(const seq::MobilityCommand& c) {
    rover_msgs::mobility_command_t m{};
    m.utime = c.utime;
    m.command_id = c.command_id;
    m.type = static_cast<std::int8_t>(c.type);
    m.distance_m = c.distance_m;
    m.curvature_per_m = c.curvature_per_m;
    m.turn_rad = c.turn_rad;
    m.speed_mps = c.speed_mps;
    m.turn_rate_rps = c.turn_rate_rps;
    proc_.bus().Publish(channels::kMobilityCommand, m);
  }
  void operator()(const seq::CaptureRequest& c) {
    rover_msgs::capture_request_t m{};
    m.utime = c.utime;
    m.frame_id = c.frame_id;
    m.purpose = c.purpose;
    m.pan_rad = c.pan_rad;
    m.tilt_rad = c.tilt_rad;
    proc_.bus().Publish(channels::kCaptureRequest, m);
  }
  void operator()(const seq::HazardQuery& q) {
    rover_msgs::hazard_query_t m{};
    m.utime = q.utime;
    m.query_id = q.query_id;
    m.num_poses = static_cast<std::int32_t>(q.samples.size());
    for (const auto& s : q.samples) {
      m.x.push_back(s.x);
      m.y.push_back(s.y);
      m.yaw.push_back(s.yaw);
    }
    m.margin_m = q.margin_m;
    m.map_frame_id = q.map_frame_id;
    proc_.bus().Publish(channels::kHazardQuery, m);
  }
  void operator()(const seq::KeepOutZoneSet& set) {
    rover_msgs::keepout_zones_t m{};
    m.utime = set.utime;
    for (const auto& z : set.zones) {
      rover_msgs::keepout_zone_t zone{};
      zone.name = z.name;
      zone.shape = z.shape == seq::KeepOutZone::Shape::kCircle
                       ? rover_msgs::keepout_zone_t::SHAPE_CIRCLE
                       : rover_msgs::keepout_zone_t::SHAPE_POLYGON;
      zone.center[0] = z.center.x();
      zone.center[1] = z.center.y();
      zone.radius_m = z.radius_m;
      zone.num_vertices = static_cast<std::int32_t>(z.vertices.size());
      for (const auto& v : z.vertices) {
        zone.vertices_x.push_back(v.x());
        zone.vertices_y.push_back(v.y());
      }
      m.zones.push_back(zone);
    }
    m.num_zones = static_cast<std::int32_t>(m.zones.size());
    proc_.bus().Publish(channels::kKeepOutZones, m);
  }
  void operator()(const seq::NewSiteRequest& r) {
    rover_msgs::new_site_t m{};
    m.utime = r.utime;
    m.site_index = r.new_site_index;
    proc_.bus().Publish(channels::kNewSite, m);
  }
  void operator()(const seq::SequenceStatus& s) {
    rover_msgs::sequence_status_t m{};
    m.utime = s.utime;
    m.submission_id = s.submission_id;
    m.sequence_name = s.sequence_name;
    m.state = static_cast<std::int8_t>(s.state);
    m.num_commands = s.num_commands;
    m.command_index = s.command_index;
    m.command_line = s.command_line;
    m.command_text = s.command_text;
    m.step_index = s.step_index;
    m.abort_reason = s.abort_reason;
    m.detail = s.detail;
    for (int i = 0; i < 6; ++i) m.pose[i] = s.pose[i];
    m.distance_m = s.distance_m;
    m.elapsed_s = s.elapsed_s;
    m.vo_failures = s.vo_failures;
    proc_.bus().Publish(channels::kSequenceStatus, m);
    if (s.state == seq::SequenceState::kAborted || s.state == seq::SequenceState::kRejected ||
        s.state == seq::SequenceState::kCompleted) {
      if (s.submission_id != last_final_) {
        std::cout << "sequence " << s.sequence_name << ": " << seq::ToString(s.state)
                  << (s.abort_reason.empty() ? "" : " (" + s.abort_reason + ")") << ": " << s.detail
                  << "\n" << std::flush;
        last_final_ = s.submission_id;
      }
    }
  }
  void operator()(const seq::StepReport& r) {
    rover_msgs::step_report_t m{};
    m.utime = r.utime;
    m.submission_id = r.submission_id;
    m.command_index = r.command_index;
    m.step_index = r.step_index;
    m.mobility_command_id = r.mobility_command_id;
    m.commanded_distance_m = r.commanded_distance_m;
    m.commanded_turn_rad = r.commanded_turn_rad;
    m.estimated_distance_m = r.estimated_distance_m;
    m.estimated_turn_rad = r.estimated_turn_rad;
    m.slip_pct = r.slip_pct;
    m.vo_status = static_cast<std::int8_t>(r.vo_status);
    for (int i = 0; i < 6; ++i) {
      m.pose_before[i] = r.pose_before[i];
      m.pose_after[i] = r.pose_after[i];
    }
    m.utime_before = r.utime_before;
    m.utime_after = r.utime_after;
    m.utime_plan_start = r.utime_plan_start;
    m.choice = static_cast<std::int8_t>(r.choice);
    m.thought_ahead = r.thought_ahead;
    m.utime_plan_end = r.utime_plan_end;
    proc_.bus().Publish(channels::kStepReport, m);
  }

 private:
  bus::Process& proc_;
  std::int64_t last_final_ = -1;
};

// The suspension `goto ... avoid on` judges paths with (ACE clearance); without the
// `clearance:` section, or with it disabled, the map's cell ratings.
std::optional<clearance::Suspension> LoadSuspensionIfEnabled(const config::ConfigNode& config) {
  if (!config.Has("clearance")) return std::nullopt;
  auto suspension = clearance::LoadSuspension(config["clearance"]);
  if (!suspension.enabled) return std::nullopt;
  return suspension;
}

// What the previous executor left in the state file: a sequence it was running is
// reported interrupted once the rover clock is known (a STOP stamped 0 would look stale to
// its receivers).
struct Restored {
  std::optional<seq::RunState> interrupted;
  bool stop_unknown = false;  // the file could not be read: stop, whatever was running
  seq::RunState written;      // the record on disk
  bool restarted() const { return interrupted.has_value() || stop_unknown || written.submission_id >= 0; }
};

// `where` names the setting in errors (argument --state-file, or executor.state_file).
Restored RestoreRunState(const std::string& state_file, const std::string& where) {
  Restored r;
  if (state_file.empty()) return r;
  // Something other than a file there (a directory, a device) is a configuration mistake,
  // not a record this executor could not read: one line, and no start.
  std::error_code ec;
  const auto kind = std::filesystem::status(state_file, ec).type();
  if (kind != std::filesystem::file_type::not_found && kind != std::filesystem::file_type::regular &&
      kind != std::filesystem::file_type::none) {
    throw config::ConfigError(
        "sequence_executor: " + where + ": " + state_file + ": " +
        (kind == std::filesystem::file_type::directory ? "is a directory" : "is not a regular file") +
        " (expected the path of a file the executor keeps its running sequence in)");
  }
  try {
    if (auto previous = seq::ReadRunStateFile(state_file)) {
      r.written = *previous;
      if (seq::WasInterrupted(*previous)) r.interrupted = previous;
    }
  } catch (const config::ConfigError& e) {
    std::cerr << "sequence_executor: " << e.what() << "; cannot tell whether a sequence was running: commanding STOP\n";
    r.stop_unknown = true;
  }
  // A place this process cannot write is a configuration mistake: say so at start.
  try {
    seq::WriteRunStateFile(state_file, r.written);
  } catch (const std::runtime_error& e) {
    throw config::ConfigError(std::string(e.what()) + " (expected a writable path: executor.state_file or --state-file)");
  }
  return r;
}

// Ids must never repeat across restarts of this process: from the wall clock, except in
// virtual time on a fresh start, where the same run must give the same messages.
std::int64_t FirstId(bool virtual_time, const Restored& restored) {
  if (virtual_time && !restored.restarted()) return 1;
  return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// ---- Messages in, as the executor's inputs. ----
seq::PoseEstimate FromMsg(const rover_msgs::pose_t& m) {
  seq::PoseEstimate p;
  p.utime = m.utime;
  p.position = Eigen::Vector3d(m.position[0], m.position[1], m.position[2]);
  p.orientation = bus::QuaternionFromArray(m.orientation);
  p.covariance = bus::CovarianceFromArray(m.covariance);
  p.source = m.source;
  p.site_index = m.site_index;
  p.odometer_m = m.odometer_m;
  p.last_vo_to_frame = m.last_vo_to_frame;
  return p;
}

seq::MobilityStatus FromMsg(const rover_msgs::mobility_status_t& m) {
  seq::MobilityStatus s;
  s.utime = m.utime;
  s.command_id = m.command_id;
  s.state = static_cast<seq::MobilityState>(m.state);
  s.wheel_distance_m = m.wheel_distance_m;
  s.wheel_turn_rad = m.wheel_turn_rad;
  s.detail = m.detail;
  return s;
}

seq::VoUpdate FromMsg(const rover_msgs::vo_update_t& m) {
  seq::VoUpdate u;
  u.utime = m.utime;
  u.from_frame_id = m.from_frame_id;
  u.to_frame_id = m.to_frame_id;
  u.status = m.status;
  u.reason = m.reason;
  return u;
}

seq::HazardStatus FromMsg(const rover_msgs::hazard_status_t& m) {
  seq::HazardStatus h;
  h.utime = m.utime;
  h.state = static_cast<seq::HazardState>(m.state);
  h.keepout_violated = m.keepout_violated;
  h.zone_name = m.zone_name;
  h.min_clearance_m = m.min_clearance_m;
  h.tilt_violated = m.tilt_violated;
  h.roll_rad = m.roll_rad;
  h.pitch_rad = m.pitch_rad;
  h.detail = m.detail;
  return h;
}

seq::HazardReply FromMsg(const rover_msgs::hazard_reply_t& m) {
  seq::HazardReply r;
  r.utime = m.utime;
  r.query_id = m.query_id;
  r.verdict = static_cast<seq::HazardVerdict>(m.verdict);
  r.zone_name = m.zone_name;
  r.min_clearance_m = m.min_clearance_m;
  r.detail = m.detail;
  return r;
}

// The map for `goto ... avoid on`, with the rules the hazard monitor judges steps by.
seq::TraversabilityMap FromMsg(const rover_msgs::traversability_map_t& m,
                               const std::optional<clearance::Suspension>& suspension) {
  seq::TraversabilityMap t;
  bus::MapRules rules;
  t.utime = m.utime;
  t.last_frame_id = m.last_frame_id;
  t.grid = bus::GridFromMsg(m, &rules);
  t.footprint = rules.footprint;
  t.blind_margin_m = rules.blind_margin_m;
  t.unknown = rules.unknown;
  t.max_driven_step_m = rules.max_driven_step_m;
  t.caution_goodness = rules.caution_goodness;
  t.suspension = suspension;
  return t;
}

// The executor on the bus: each message into it, its outputs out (the run's state on disk
// first), and the report of a sequence a previous executor left running.
class ExecutorNode {
 public:
  ExecutorNode(bus::Process& proc, const seq::ExecutorOptions& options, std::string state_file, Restored restored,
               std::optional<clearance::Suspension> suspension)
      : proc_(proc), state_file_(std::move(state_file)), restored_(std::move(restored)),
        suspension_(std::move(suspension)), executor_(options, FirstId(proc.virtual_time(), restored_)),
        publisher_(proc) {}

  void Subscribe() {
    auto& bus = proc_.bus();
    bus.Subscribe<rover_msgs::sequence_submit_t>(channels::kSequenceSubmit, [this](const rover_msgs::sequence_submit_t& m) {
      std::cout << "received sequence " << m.name << " (" << m.text.size() << " bytes)\n" << std::flush;
      ReportInterrupted();
      executor_.SubmitText(m.text, m.submission_id, m.name);
      Flush();
    });
    bus.Subscribe<rover_msgs::sequence_control_t>(channels::kSequenceControl,
                                                  [this](const rover_msgs::sequence_control_t& m) { OnControl(m); });
    bus.Subscribe<rover_msgs::pose_t>(channels::kPose, [this](const rover_msgs::pose_t& m) {
      proc_.ObserveTime(m.utime);
      executor_.OnPose(FromMsg(m));
      Flush();
    }, 100);
    bus.Subscribe<rover_msgs::mobility_status_t>(channels::kMobilityStatus, [this](const rover_msgs::mobility_status_t& m) {
      executor_.OnMobilityStatus(FromMsg(m));
      Flush();
    }, 100);
    bus.Subscribe<rover_msgs::vo_update_t>(channels::kVoUpdate, [this](const rover_msgs::vo_update_t& m) {
      executor_.OnVoUpdate(FromMsg(m));
      Flush();
    });
    bus.Subscribe<rover_msgs::hazard_status_t>(channels::kHazardStatus, [this](const rover_msgs::hazard_status_t& m) {
      executor_.OnHazardStatus(FromMsg(m));
      Flush();
    });
    bus.Subscribe<rover_msgs::hazard_reply_t>(channels::kHazardReply, [this](const rover_msgs::hazard_reply_t& m) {
      executor_.OnHazardReply(FromMsg(m));
      Flush();
    });
    bus.Subscribe<rover_msgs::traversability_map_t>(
        channels::kTraversabilityMap, [this](const rover_msgs::traversability_map_t& m) {
          executor_.OnTraversabilityMap(FromMsg(m, suspension_));
          Flush();
        }, 4);
    bus.Subscribe<rover_msgs::stereo_frame_t>(channels::kStereoFrame, [this](const rover_msgs::stereo_frame_t& m) {
      executor_.OnStereoFrame(m.frame_id);
      Flush();
    }, 2);
    bus.Subscribe<rover_msgs::heartbeat_t>(channels::kHeartbeat, [this](const rover_msgs::heartbeat_t& m) {
      executor_.OnHeartbeat(m.process, proc_.guard_seconds());
      Flush();
    }, 100);
  }

  void Tick() {
    // The heartbeats that arrived while this process was starved count before the tick
    // judges its peers lost (at most 50 ms of them, so a flood cannot stall it; in virtual
    // time nothing is starved: they came in this tick's batch).
    proc_.HandleReceived(50);
    // A silent time source stops the rover once (its line is bus::Process's).
    if (proc_.time_source_silent() && !source_lost_handled_) {
      executor_.TimeSourceLost("the time source " + proc_.time_source() + " fell silent: rover time stands still");
      source_lost_handled_ = true;
    }
    if (!proc_.time_source_silent()) source_lost_handled_ = false;
    executor_.Tick(proc_.now(), proc_.guard_seconds());
    Flush();
    if (proc_.now() > 0 || (!proc_.virtual_time() && proc_.wall_seconds() > 2.0)) ReportInterrupted();
    // The heartbeat's detail: the state, and the commands dropped, per channel, with the
    // last reason ("idle; SEQUENCE_SUBMIT dropped 1: rejected: no authentication tag ..."),
    // so that a console whose command was dropped (unsigned, a wrong key) can say it was
    // refused and why (rover_web), whatever else the bus drops meanwhile.
    std::string detail = seq::ToString(executor_.state());
    for (const char* channel : {channels::kSequenceSubmit, channels::kSequenceControl}) {
      if (const std::int64_t n = proc_.bus().dropped_on(channel); n > 0) {
        detail += "; " + std::string(channel) + " dropped " + std::to_string(n) + ": " + proc_.bus().last_drop_on(channel);
      }
    }
    proc_.SetHealth(0, detail);
  }

  bool running() const { return executor_.state() == seq::SequenceState::kRunning; }

  // Stopping the executor while it drives stops the rover: commanding nothing is safe.
  void Shutdown() {
    if (!executor_.Active()) return;
    executor_.Abort("sequence_executor shutting down");
    Flush();
  }

 private:
  void OnControl(const rover_msgs::sequence_control_t& m) {
    ReportInterrupted();
    switch (m.action) {
      case rover_msgs::sequence_control_t::ACTION_ABORT: executor_.Abort(m.reason); break;
      case rover_msgs::sequence_control_t::ACTION_PAUSE: executor_.Pause(); break;
      case rover_msgs::sequence_control_t::ACTION_RESUME: executor_.Resume(); break;
      default:
        std::cerr << "sequence_executor: SEQUENCE_CONTROL: unknown action " << static_cast<int>(m.action)
                  << " (expected 0 abort, 1 pause, 2 resume)\n";
    }
    Flush();
  }

  void SaveState() {
    if (state_file_.empty() || restored_.interrupted) return;  // the old record stands until reported
    const seq::RunState now = seq::RunStateOf(executor_.CurrentStatus());
    if (now == restored_.written) return;
    try {
      seq::WriteRunStateFile(state_file_, now);
      restored_.written = now;
      write_failing_ = false;
    } catch (const std::runtime_error& e) {
      if (!write_failing_) std::cerr << "sequence_executor: " << e.what() << "\n";
      write_failing_ = true;
    }
  }

  void Flush() {
    auto outputs = executor_.TakeOutputs();
    SaveState();  // on disk before the commands it leads to leave
    for (const auto& out : outputs) std::visit(publisher_, out);
  }

  void ReportInterrupted() {
    if (!restored_.interrupted && !restored_.stop_unknown) return;
    executor_.Tick(proc_.now(), proc_.guard_seconds());
    if (restored_.stop_unknown) executor_.Abort("");  // nothing active: STOP only
    restored_.stop_unknown = false;
    if (restored_.interrupted) {
      const seq::RunState previous = *restored_.interrupted;
      restored_.interrupted.reset();
      executor_.RecordInterrupted(previous.submission_id, previous.sequence_name, seq::InterruptedDetail(previous));
    }
    Flush();
  }

  bus::Process& proc_;
  const std::string state_file_;
  Restored restored_;
  const std::optional<clearance::Suspension> suspension_;
  seq::SequenceExecutor executor_;
  OutputPublisher publisher_;
  bool write_failing_ = false;
  bool source_lost_handled_ = false;
};

}  // namespace

int main(int argc, char** argv) {
  return bus::RunMain("sequence_executor", [&]() -> int {
    bus::Process proc("sequence_executor",
                      "Runs operator sequences step by step: checks the whole file, commands\n"
                      "mobility, asks for captures and VO, checks hazards, progress and limits,\n"
                      "and aborts when one fails.\n"
                      "Reads SEQUENCE_SUBMIT, SEQUENCE_CONTROL, POSE, MOBILITY_STATUS, VO_UPDATE,\n"
                      "HAZARD_STATUS, HAZARD_REPLY, STEREO_FRAME, TRAVERSABILITY_MAP, HEARTBEAT; writes MOBILITY_COMMAND,\n"
                      "CAPTURE_REQUEST, HAZARD_QUERY, KEEPOUT_ZONES, NEW_SITE, SEQUENCE_STATUS, STEP_REPORT.\n"
                      "Config: the `executor:` section (see configs/rover.yaml).",
                      argc, argv,
                      {{"--state-file", "FILE",
                        "where the running sequence is kept across restarts (overrides executor.state_file)"}});
    auto options = seq::LoadExecutorOptions(proc.config());
    // Choosing a `goto ... avoid on` step costs rover time in simulation (the compute profile).
    options.plan_compute_s = proc.virtual_time() ? proc.compute().plan_s : 0.0;
    auto suspension = LoadSuspensionIfEnabled(proc.config());
    std::string state_file = options.state_file;
    if (auto f = proc.option("--state-file")) state_file = *f;
    Restored restored =
        RestoreRunState(state_file, proc.option("--state-file") ? "argument --state-file" : "executor.state_file");
    ExecutorNode node(proc, options, state_file, std::move(restored), std::move(suspension));
    node.Subscribe();
    proc.DeclarePublications({{channels::kMobilityCommand}, {channels::kCaptureRequest}, {channels::kHazardQuery},
                              {channels::kKeepOutZones}, {channels::kNewSite, "a sequence starts a new site"},
                              {channels::kSequenceStatus}, {channels::kStepReport}});
    // A sequence that is not running (none, paused, finished) leaves it nothing of its own to
    // do: quiet, so a pause or a night passes in idle strides of virtual time.
    proc.set_quiet_until([&node] { return node.running() ? 0 : bus::Process::kQuietForGood; });
    proc.Run([&] { node.Tick(); }, 25);
    node.Shutdown();
    return 0;
  });
}
