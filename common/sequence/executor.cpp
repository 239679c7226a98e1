#include "sequence/executor.hpp"

#include "hazards/hazard_assessor.hpp"
#include "hazards/keepout.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>

namespace rover::sequence {

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

std::string Fixed(double v, int digits = 2) {
  std::ostringstream os;
  os.setf(std::ios::fixed);
  os.precision(digits);
  os << v;
  return os.str();
}

void XyzRpy(const PoseEstimate& p, double out[6]) {
  const Eigen::Vector3d rpy = geometry::RpyFromRotation(p.orientation.normalized().toRotationMatrix());
  out[0] = p.position.x();
  out[1] = p.position.y();
  out[2] = p.position.z();
  out[3] = rpy.x();
  out[4] = rpy.y();
  out[5] = rpy.z();
}

geometry::Pose ToPose(const PoseEstimate& p) {
  geometry::Pose T = geometry::Pose::Identity();
  T.linear() = p.orientation.normalized().toRotationMatrix();
  T.translation() = p.position;
  return T;
}

std::string Join(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
  return s;
}

}  // namespace

// ---------------------------------------------------------------------------------------
// Options

void ValidateExecutorOptions(const ExecutorOptions& o) {
  auto positive = [](double v, const char* name) {
    if (!(v > 0.0) || !std::isfinite(v)) {
      throw std::invalid_argument(std::string("executor option ") + name + " must be > 0, got " +
                                  std::to_string(v));
    }
  };
  positive(o.heartbeat_timeout_s, "heartbeat_timeout_s");
  positive(o.hazard_reply_wait_s, "hazard_reply_wait_s");
  positive(o.hazard_status_wait_s, "hazard_status_wait_s");
  positive(o.vo_wait_s, "vo_wait_s");
  positive(o.pose_wait_s, "pose_wait_s");
  positive(o.mobility_wait_s, "mobility_wait_s");
  positive(o.capture_wait_s, "capture_wait_s");
  positive(o.site_wait_s, "site_wait_s");
  positive(o.mobility_timeout_factor, "mobility_timeout_factor");
  positive(o.speed_mps, "speed_mps");
  positive(o.turn_rate_rps, "turn_rate_rps");
  positive(o.default_step_m, "default_step_m");
  positive(o.default_max_turn_deg, "default_max_turn_deg");
  positive(o.goto_turn_threshold_deg, "goto_turn_threshold_deg");
  positive(o.goto_default_distance_factor, "goto_default_distance_factor");
  positive(o.path_sample_spacing_m, "path_sample_spacing_m");
  positive(o.path_sample_turn_deg, "path_sample_turn_deg");
  positive(o.status_period_s, "status_period_s");
  positive(o.blind_slope_deg, "blind_slope_deg");
  positive(o.blind_slip_pct, "blind_slip_pct");
  positive(o.lost_min_step_m, "lost_min_step_m");
  positive(o.margin_sigma_multiplier, "margin_sigma_multiplier");
  positive(o.map_wait_s, "map_wait_s");
  positive(o.avoid_lookahead_m, "avoid_lookahead_m");
  positive(o.avoid_max_curvature_per_m, "avoid_max_curvature_per_m");
  if (o.avoid_num_arcs < 1 || !(o.avoid_backup_m >= 0.0) || !(o.avoid_margin_m >= 0.0)) {
    throw std::invalid_argument("executor options avoid_num_arcs must be >= 1, avoid_backup_m and avoid_margin_m >= 0");
  }
  if (o.recent_steps < 1) {
    throw std::invalid_argument("executor option recent_steps must be >= 1, got " +
                                std::to_string(o.recent_steps));
  }
  if (!(o.step_sigma_growth_pct >= 0.0) || !std::isfinite(o.step_sigma_growth_pct)) {
    throw std::invalid_argument("executor option step_sigma_growth_pct must be >= 0, got " +
                                std::to_string(o.step_sigma_growth_pct));
  }
  if (!(o.start_wait_s >= 0.0)) {
    throw std::invalid_argument("executor option start_wait_s must be >= 0, got " +
                                std::to_string(o.start_wait_s));
  }
  for (const auto& p : o.required_processes) {
    if (p.empty()) throw std::invalid_argument("executor option required_processes holds an empty name");
  }
}

ExecutorOptions LoadExecutorOptions(const config::ConfigNode& root) {
  ExecutorOptions o;
  const config::ConfigNode n = root["executor"];
  if (n.IsNull()) return o;
  if (!n.IsMap()) n.Fail("expected a mapping of executor options");
  n.CheckKeys({"required_processes", "vo_processes", "vo_processes_required", "heartbeat_timeout_s",
               "start_wait_s", "hazard_reply_wait_s", "hazard_status_wait_s", "vo_wait_s",
               "pose_wait_s", "mobility_wait_s", "capture_wait_s", "site_wait_s",
               "mobility_timeout_factor", "mobility_timeout_margin_s", "speed_mps", "turn_rate_rps",
               "default_step_m", "default_max_turn_deg", "goto_turn_threshold_deg",
               "goto_default_distance_factor", "goto_default_distance_margin_m",
               "predictive_hazard_check", "reactive_hazard_abort", "path_sample_spacing_m",
               "path_sample_turn_deg", "slip_min_step_m", "status_period_s", "blind_slope_deg",
               "blind_slip_pct", "recent_steps", "lost_min_step_m", "step_sigma_growth_pct",
               "margin_sigma_multiplier", "state_file", "map_wait_s", "avoid_lookahead_m",
               "avoid_max_curvature_per_m", "avoid_num_arcs", "avoid_backup_m", "avoid_margin_m"});
  auto names = [&](const char* key, std::vector<std::string>& out) {
    if (!n.Has(key)) return;
    const config::ConfigNode list = n[key];
    if (!list.IsSequence()) list.Fail("expected a list of process names");
    out.clear();
    for (std::size_t i = 0; i < list.size(); ++i) {
      out.push_back(list.at(i).AsString());
      if (out.back().empty()) list.at(i).Fail("expected a process name");
    }
  };
  constexpr double kInf = std::numeric_limits<double>::infinity();
  names("required_processes", o.required_processes);
  names("vo_processes", o.vo_processes);
  n.Get("vo_processes_required", o.vo_processes_required);
  n.Get("heartbeat_timeout_s", o.heartbeat_timeout_s, 1e-3, kInf);
  n.Get("start_wait_s", o.start_wait_s, 0.0, kInf);
  n.Get("hazard_reply_wait_s", o.hazard_reply_wait_s, 1e-3, kInf);
  n.Get("hazard_status_wait_s", o.hazard_status_wait_s, 1e-3, kInf);
  n.Get("vo_wait_s", o.vo_wait_s, 1e-3, kInf);
  n.Get("pose_wait_s", o.pose_wait_s, 1e-3, kInf);
  n.Get("mobility_wait_s", o.mobility_wait_s, 1e-3, kInf);
  n.Get("capture_wait_s", o.capture_wait_s, 1e-3, kInf);
  n.Get("site_wait_s", o.site_wait_s, 1e-3, kInf);
  n.Get("mobility_timeout_factor", o.mobility_timeout_factor, 1.0, kInf);
  n.Get("mobility_timeout_margin_s", o.mobility_timeout_margin_s, 0.0, kInf);
  n.Get("speed_mps", o.speed_mps, 1e-4, 10.0);
  n.Get("turn_rate_rps", o.turn_rate_rps, 1e-4, 10.0);
  n.Get("default_step_m", o.default_step_m, 1e-3, 0.75);
  n.Get("default_max_turn_deg", o.default_max_turn_deg, 0.1, 90.0);
  n.Get("goto_turn_threshold_deg", o.goto_turn_threshold_deg, 0.1, 90.0);
  n.Get("goto_default_distance_factor", o.goto_default_distance_factor, 1.0, 100.0);
  n.Get("goto_default_distance_margin_m", o.goto_default_distance_margin_m, 0.0, kInf);
  n.Get("predictive_hazard_check", o.predictive_hazard_check);
  n.Get("reactive_hazard_abort", o.reactive_hazard_abort);
  n.Get("path_sample_spacing_m", o.path_sample_spacing_m, 1e-3, 1.0);
  n.Get("path_sample_turn_deg", o.path_sample_turn_deg, 0.01, 45.0);
  n.Get("slip_min_step_m", o.slip_min_step_m, 0.0, 0.75);
  n.Get("status_period_s", o.status_period_s, 1e-3, kInf);
  n.Get("blind_slope_deg", o.blind_slope_deg, 0.1, 45.0);
  n.Get("blind_slip_pct", o.blind_slip_pct, 0.1, 100.0);
  n.Get("recent_steps", o.recent_steps, 1, 100);
  n.Get("lost_min_step_m", o.lost_min_step_m, 0.01, 0.75);
  n.Get("step_sigma_growth_pct", o.step_sigma_growth_pct, 0.0, 100.0);
  n.Get("margin_sigma_multiplier", o.margin_sigma_multiplier, 0.1, 10.0);
  n.Get("state_file", o.state_file);
  n.Get("map_wait_s", o.map_wait_s, 1e-3, kInf);
  n.Get("avoid_lookahead_m", o.avoid_lookahead_m, 0.1, 20.0);
  n.Get("avoid_max_curvature_per_m", o.avoid_max_curvature_per_m, 0.01, 10.0);
  n.Get("avoid_num_arcs", o.avoid_num_arcs, 1, 101);
  n.Get("avoid_backup_m", o.avoid_backup_m, 0.0, 0.75);
  n.Get("avoid_margin_m", o.avoid_margin_m, 0.0, 1.0);
  return o;
}

ExecutorOptions LoadExecutorOptionsFile(const std::string& path) {
  return LoadExecutorOptions(config::ConfigNode::LoadFile(path));
}

const char* ToString(SequenceState state) {
  switch (state) {
    case SequenceState::kIdle: return "idle";
    case SequenceState::kRunning: return "running";
    case SequenceState::kPaused: return "paused";
    case SequenceState::kCompleted: return "completed";
    case SequenceState::kAborted: return "aborted";
    case SequenceState::kRejected: return "rejected";
  }
  return "?";
}

// ---------------------------------------------------------------------------------------
// Executor

SequenceExecutor::SequenceExecutor(ExecutorOptions options, int64_t first_id)
    : options_(std::move(options)), next_id_(first_id) {
  ValidateExecutorOptions(options_);
  step_m_ = options_.default_step_m;
  max_turn_rad_ = options_.default_max_turn_deg * kDeg;
  vo_wait_s_ = options_.vo_wait_s;
  blind_slope_rad_ = options_.blind_slope_deg * kDeg;
  blind_slip_pct_ = options_.blind_slip_pct;
}

bool SequenceExecutor::Active() const {
  return state_ == SequenceState::kRunning || state_ == SequenceState::kPaused;
}

std::vector<ExecutorOutput> SequenceExecutor::TakeOutputs() {
  std::vector<ExecutorOutput> out;
  out.swap(outputs_);
  return out;
}

// ---- operator ----

void SequenceExecutor::Submit(Sequence sequence, int64_t submission_id, const std::string& name) {
  if (Active()) {
    Reject(submission_id, name, abort_reason::kBusy,
           "sequence '" + sequence_.name + "' (submission " + std::to_string(submission_id_) +
               ") is " + ToString(state_) + "; abort it first");
    return;
  }
  if (sequence.commands.empty()) {
    Reject(submission_id, name, abort_reason::kInvalidSequence, "the sequence has no commands");
    return;
  }
  sequence_ = std::move(sequence);
  sequence_.name = name;
  submission_id_ = submission_id;
  state_ = SequenceState::kRunning;
  abort_reason_.clear();
  detail_ = "waiting for heartbeats and a pose";
  command_index_ = -1;
  step_index_ = 0;
  distance_m_ = 0.0;
  started_ = false;
  pause_requested_ = false;
  command_active_ = false;
  // Settings start from the defaults for every sequence.
  vo_enabled_ = false;
  step_m_ = options_.default_step_m;
  max_turn_rad_ = options_.default_max_turn_deg * kDeg;
  vo_max_failures_.reset();
  vo_past_max_ = VoFailureAction::kContinue;
  vo_wait_s_ = options_.vo_wait_s;
  vo_policy_failures_ = 0;
  vo_failures_total_ = 0;
  slip_ = SlipSetting{};
  no_progress_count_ = 0;
  tilt_ = TiltSetting{};
  limits_ = LimitSetting{};
  zones_.clear();
  vo_frame_valid_ = false;
  last_vo_frame_ = -1;
  vo_lost_ = VoLostSetting{};
  blind_slope_rad_ = options_.blind_slope_deg * kDeg;
  blind_slip_pct_ = options_.blind_slip_pct;
  vo_off_by_failures_ = false;
  recent_slip_pct_.clear();
  recent_drift_.clear();
  lost_step_scale_ = 1.0;
  sequence_uses_vo_ = false;
  for (const Command& c : sequence_.commands) {
    if (const auto* v = std::get_if<VoSetting>(&c.action); v && v->enabled) sequence_uses_vo_ = true;
  }
  EnterPhase(Phase::kWaitStart);
  EmitStatus();
  Advance();
}

void SequenceExecutor::SubmitText(std::string_view text, int64_t submission_id, const std::string& name,
                                  const LanguageLimits& limits) {
  ParseResult r = ParseSequence(text, name, limits);
  if (!r.ok()) {
    Reject(submission_id, name, abort_reason::kInvalidSequence, r.errors.front().ToString());
    return;
  }
  Submit(std::move(r.sequence), submission_id, name);
}

void SequenceExecutor::Abort(const std::string& detail) {
  if (Active()) {
    AbortWith(abort_reason::kOperator, detail.empty() ? "operator abort" : "operator abort: " + detail);
  } else {
    EmitStop();  // commanding a stop is always safe
  }
}

void SequenceExecutor::RecordInterrupted(int64_t submission_id, const std::string& name,
                                         const std::string& detail) {
  if (Active()) return;
  sequence_ = Sequence{name, {}};
  submission_id_ = submission_id;
  started_ = false;
  command_index_ = -1;
  step_index_ = 0;
  distance_m_ = 0.0;
  vo_failures_total_ = 0;
  AbortWith(abort_reason::kInterrupted, detail);
}

void SequenceExecutor::Pause() {
  if (state_ == SequenceState::kRunning) {
    pause_requested_ = true;
    Advance();
  }
}

void SequenceExecutor::Resume() {
  if (state_ == SequenceState::kRunning) {
    pause_requested_ = false;
    return;
  }
  if (state_ != SequenceState::kPaused) return;
  const auto silent = SilentProcesses(VoRequired());
  if (!silent.empty()) {
    AbortWith(abort_reason::kProcessLost, "no heartbeat from " + Join(silent) + " at resume");
    return;
  }
  state_ = SequenceState::kRunning;
  detail_ = "resumed";
  EmitStatus();
  EnterPhase(Phase::kReady);
  Advance();
}

// ---- bus inputs ----

void SequenceExecutor::OnPose(const PoseEstimate& pose) {
  pose_ = pose;
  ++pose_count_;
  now_utime_ = std::max(now_utime_, pose.utime);
  Advance();
}

void SequenceExecutor::OnMobilityStatus(const MobilityStatus& status) {
  now_utime_ = std::max(now_utime_, status.utime);
  if (phase_ != Phase::kMoving || status.command_id != mobility_id_) return;
  if (status.state == MobilityState::kDone) {
    mobility_done_ = status;
    done_pose_count_ = pose_count_;
  } else if (status.state == MobilityState::kStopped || status.state == MobilityState::kFault) {
    AbortWith(abort_reason::kMobilityFault,
              std::string("mobility ") + (status.state == MobilityState::kFault ? "fault" : "stopped") +
                  " on command " + std::to_string(status.command_id) +
                  (status.detail.empty() ? "" : ": " + status.detail));
    return;
  }
  Advance();
}

void SequenceExecutor::OnVoUpdate(const VoUpdate& update) {
  if ((phase_ == Phase::kWaitVo || phase_ == Phase::kBaseline) && update.to_frame_id == frame_id_) {
    vo_update_ = update;
    Advance();
  }
}

void SequenceExecutor::OnHazardStatus(const HazardStatus& status) {
  hazard_ = status;
  ++hazard_count_;
  // The reactive check: a violation seen while the wheels turn stops the step at once
  // rather than at its end (MER's tilt check ran during motion).
  if (state_ == SequenceState::kRunning && phase_ == Phase::kMoving && options_.reactive_hazard_abort) {
    if (status.keepout_violated) {
      AbortWith(abort_reason::kKeepout, "keep-out violated during the step: zone '" + status.zone_name +
                                            "', clearance " + Fixed(status.min_clearance_m) + " m");
      return;
    }
    const bool roll_over = tilt_.enabled && tilt_.roll_rad && std::abs(status.roll_rad) > *tilt_.roll_rad;
    const bool pitch_over = tilt_.enabled && tilt_.pitch_rad && std::abs(status.pitch_rad) > *tilt_.pitch_rad;
    if (status.tilt_violated || roll_over || pitch_over) {
      AbortWith(abort_reason::kTilt, "tilt during the step: roll " + Fixed(status.roll_rad / kDeg, 1) +
                                         " deg, pitch " + Fixed(status.pitch_rad / kDeg, 1) + " deg");
      return;
    }
  }
  Advance();
}

void SequenceExecutor::OnHazardReply(const HazardReply& reply) {
  if (phase_ == Phase::kQuery && reply.query_id == query_id_) {
    hazard_reply_ = reply;
    Advance();
  }
}

void SequenceExecutor::OnStereoFrame(int64_t frame_id) {
  if (phase_ == Phase::kImages && frame_id == frame_id_) {
    science_frame_seen_ = true;
    Advance();
  }
}

void SequenceExecutor::OnHeartbeat(const std::string& process, double wall_s) {
  heartbeats_[process] = wall_s;
  SetWall(wall_s);
  Advance();
}

void SequenceExecutor::Tick(int64_t rover_utime, double wall_s) {
  now_utime_ = std::max(now_utime_, rover_utime);
  SetWall(wall_s);
  // A needed process that goes silent during a sequence is an abort (the F Prime health
  // ping): commanding nothing is safe, driving on a dead estimator is not.
  if (state_ == SequenceState::kRunning && phase_ != Phase::kWaitStart) {
    const auto silent = SilentProcesses(VoRequired());
    if (!silent.empty()) {
      AbortWith(abort_reason::kProcessLost, "no heartbeat from " + Join(silent) + " for more than " +
                                                Fixed(options_.heartbeat_timeout_s, 1) + " s");
    }
  }
  Advance();
  if (now_wall_ - last_status_wall_ >= options_.status_period_s) EmitStatus();
}

// ---- the machine ----

void SequenceExecutor::SetWall(double wall_s) {
  if (!wall_known_) {
    // Waits entered before the first wall time start now, not at 0.
    wall_known_ = true;
    phase_start_wall_ = wall_s;
    now_wall_ = wall_s;
  }
  now_wall_ = std::max(now_wall_, wall_s);
}

void SequenceExecutor::EnterPhase(Phase phase) {
  phase_ = phase;
  phase_start_wall_ = now_wall_;
  progressed_ = true;
}

void SequenceExecutor::Advance() {
  if (in_advance_) return;
  in_advance_ = true;
  // Each pass either moves the machine on (progressed_) or waits for an input.
  for (int guard = 0; guard < 1000000; ++guard) {
    progressed_ = false;
    Poll();
    if (!progressed_) break;
  }
  in_advance_ = false;
}

void SequenceExecutor::Poll() {
  switch (phase_) {
    case Phase::kIdle:
    case Phase::kFinished:
      return;

    case Phase::kWaitStart: {
      const auto silent = SilentProcesses(options_.vo_processes_required && sequence_uses_vo_);
      if (silent.empty() && pose_) {
        start_utime_ = now_utime_;
        started_ = true;
        detail_ = "started";
        EnterPhase(Phase::kReady);
        EmitStatus();
      } else if (PhaseAge() > options_.start_wait_s) {
        const std::string why = !silent.empty() ? "no heartbeat from " + Join(silent)
                                                : std::string("no pose from the state estimator");
        Finish(SequenceState::kRejected, abort_reason::kProcessLost,
               why + " within " + Fixed(options_.start_wait_s, 1) + " s; nothing was commanded");
      }
      return;
    }

    case Phase::kReady:
      if (state_ != SequenceState::kRunning) return;
      if (pause_requested_) {
        pause_requested_ = false;
        state_ = SequenceState::kPaused;
        detail_ = "paused by the operator";
        EmitStatus();
        return;
      }
      DispatchNext();
      return;

    case Phase::kBaseline:
      if (vo_update_) {
        // Whatever VO made of the baseline pair against an older frame, the pair is the
        // reference for the next step; only an unusable pair is a failure.
        if (vo_update_->status == VoUpdate::kStatusBadInput) {
          CountVoFailure("baseline frame: " + vo_update_->reason);
        }
        EnterPhase(Phase::kReady);
      } else if (PhaseAge() > vo_wait_s_) {
        CountVoFailure("no VO answer to the baseline frame within " + Fixed(vo_wait_s_, 1) + " s");
        EnterPhase(Phase::kReady);
      }
      return;

    case Phase::kQuery:
      if (hazard_reply_) {
        const HazardReply r = *hazard_reply_;
        if (r.verdict == HazardVerdict::kSafe) {
          CommandStep();
        } else if (r.verdict == HazardVerdict::kUnsafe && r.zone_name == abort_reason::kHazardMap &&
                   AvoidRefused(r)) {
          return;
        } else if (r.verdict == HazardVerdict::kUnsafe && r.zone_name == abort_reason::kHazardMap) {
          AbortWith(abort_reason::kHazardMap, r.detail + "; not commanded");
        } else if (r.verdict == HazardVerdict::kUnknown && ImagesForMap(r)) {
          return;
        } else if (r.verdict == HazardVerdict::kUnsafe) {
          AbortWith(abort_reason::kKeepout, "the next step would enter zone '" + r.zone_name +
                                                "' (clearance " + Fixed(r.min_clearance_m) +
                                                " m); not commanded" + (r.detail.empty() ? "" : ": " + r.detail));
        } else {
          AbortWith(abort_reason::kHazardUnknown, "the hazard monitor cannot decide on the next step" +
                                                      (r.detail.empty() ? "" : ": " + r.detail));
        }
      } else if (PhaseAge() > options_.hazard_reply_wait_s) {
        AbortWith(abort_reason::kHazardUnknown, "no hazard reply within " +
                                                    Fixed(options_.hazard_reply_wait_s, 1) +
                                                    " s; the step was not commanded");
      }
      return;

    case Phase::kMoving:
      if (mobility_done_) {
        AfterMotion();
      } else if (PhaseAge() > options_.mobility_wait_s) {
        AbortWith(abort_reason::kTimeout, "mobility did not finish command " + std::to_string(mobility_id_) +
                                              " within " + Fixed(options_.mobility_wait_s, 0) + " s (wall)");
      } else if (now_utime_ > mobility_deadline_utime_) {
        AbortWith(abort_reason::kTimeout, "mobility did not finish command " + std::to_string(mobility_id_) +
                                              " in the expected rover time");
      }
      return;

    case Phase::kWaitVo:
      if (vo_update_) {
        if (vo_update_->status != VoUpdate::kStatusOk) {
          CountVoFailure("VO failed: " + (vo_update_->reason.empty() ? "status " + std::to_string(vo_update_->status)
                                                                     : vo_update_->reason));
        }
        EnterPhase(Phase::kWaitPose);
      } else if (PhaseAge() > vo_wait_s_) {
        CountVoFailure("no VO answer within " + Fixed(vo_wait_s_, 1) + " s");
        EnterPhase(Phase::kWaitPose);
      }
      return;

    case Phase::kWaitPose: {
      const bool vo_ok = vo_update_ && vo_update_->status == VoUpdate::kStatusOk;
      const bool fresh = pose_count_ > done_pose_count_;
      const bool has_update = pose_ && pose_->last_vo_to_frame >= frame_id_;
      if (fresh && (!vo_ok || has_update)) {
        hazard_mark_ = hazard_count_;
        EnterPhase(Phase::kWaitHazard);
      } else if (PhaseAge() > options_.pose_wait_s) {
        step_note_ += vo_ok ? "pose without the VO update; " : "no fresh pose; ";
        hazard_mark_ = hazard_count_;
        EnterPhase(Phase::kWaitHazard);
      }
      return;
    }

    case Phase::kWaitHazard:
      if (hazard_count_ > hazard_mark_) {
        FinishStep();
      } else if (PhaseAge() > options_.hazard_status_wait_s) {
        AbortWith(abort_reason::kHazardUnknown, "no hazard status within " +
                                                    Fixed(options_.hazard_status_wait_s, 1) + " s after the step");
      }
      return;

    case Phase::kImages:
      if (science_frame_seen_) {
        EnterPhase(Phase::kReady);
      } else if (PhaseAge() > options_.capture_wait_s) {
        detail_ = "frame " + std::to_string(frame_id_) + " not seen within " + Fixed(options_.capture_wait_s, 1) +
                  " s; going on";
        EnterPhase(Phase::kReady);
      }
      return;

    case Phase::kSite:
      if (pose_ && pose_->site_index >= wait_site_index_) {
        EnterPhase(Phase::kReady);
      } else if (PhaseAge() > options_.site_wait_s) {
        AbortWith(abort_reason::kTimeout, "no pose in site " + std::to_string(wait_site_index_) + " within " +
                                              Fixed(options_.site_wait_s, 1) + " s");
      }
      return;
  }
}

void SequenceExecutor::DispatchNext() {
  if (command_active_) {
    if (NextStepOfCommand()) return;
    command_active_ = false;
    EnterPhase(Phase::kReady);
    return;
  }
  ++command_index_;
  step_index_ = 0;
  if (command_index_ >= static_cast<int>(sequence_.commands.size())) {
    command_index_ = static_cast<int>(sequence_.commands.size()) - 1;
    Finish(SequenceState::kCompleted, "", "all " + std::to_string(sequence_.commands.size()) +
                                              " commands done");
    return;
  }
  StartCommand();
}

void SequenceExecutor::StartCommand() {
  const Command& c = sequence_.commands[command_index_];
  detail_ = "line " + std::to_string(c.line) + ": " + c.text;
  EmitStatus();
  if (!IsMotion(c)) {
    ApplySetting(c);
    return;
  }
  command_active_ = true;
  is_goto_ = false;
  steps_.clear();
  next_step_ = 0;
  no_progress_count_ = 0;
  lost_step_scale_ = 1.0;
  if (const auto* d = std::get_if<Drive>(&c.action)) {
    steps_ = SplitArc(d->distance_m, 0.0, step_m_, max_turn_rad_);
  } else if (const auto* a = std::get_if<Arc>(&c.action)) {
    steps_ = SplitArc(a->distance_m, 1.0 / a->radius_m, step_m_, max_turn_rad_);
  } else if (const auto* t = std::get_if<Turn>(&c.action)) {
    steps_ = SplitTurn(t->angle_rad, max_turn_rad_);
  } else if (const auto* h = std::get_if<TurnTo>(&c.action); h && PoseFinite()) {
    const double turn = ShortestTurn(CurrentPlanePose().yaw, h->heading_rad);
    if (std::abs(turn) > 1e-4) steps_ = SplitTurn(turn, max_turn_rad_);
  } else if (const auto* g = std::get_if<Goto>(&c.action)) {
    is_goto_ = true;
    goto_ = *g;
    goto_start_utime_ = now_utime_;
    goto_start_distance_ = distance_m_;
    const PlanePose p = CurrentPlanePose();
    const double straight = (g->target - Eigen::Vector2d(p.x, p.y)).norm();
    goto_distance_limit_ = g->distance_limit_m ? *g->distance_limit_m
                                               : options_.goto_default_distance_factor * straight +
                                                     options_.goto_default_distance_margin_m;
  }
  EnterPhase(Phase::kReady);
}

void SequenceExecutor::ApplySetting(const Command& c) {
  auto publish_zones = [&] { outputs_.push_back(KeepOutZoneSet{now_utime_, zones_}); };
  if (const auto* v = std::get_if<VoSetting>(&c.action)) {
    vo_enabled_ = v->enabled;
    if (v->step_m) step_m_ = *v->step_m;
    if (v->max_turn_rad) max_turn_rad_ = *v->max_turn_rad;
    if (v->max_failures) {
      vo_max_failures_ = v->max_failures;
      vo_past_max_ = v->past_max.value_or(VoFailureAction::kContinue);
    }
    if (v->wait_s) vo_wait_s_ = *v->wait_s;
    vo_policy_failures_ = 0;
    vo_off_by_failures_ = false;
  } else if (const auto* l = std::get_if<VoLostSetting>(&c.action)) {
    vo_lost_ = *l;
    if (l->slope_rad) blind_slope_rad_ = *l->slope_rad;
    if (l->slip_pct) blind_slip_pct_ = *l->slip_pct;
  } else if (const auto* s = std::get_if<SlipSetting>(&c.action)) {
    slip_ = *s;
    no_progress_count_ = 0;
  } else if (const auto* t = std::get_if<TiltSetting>(&c.action)) {
    tilt_ = *t;
  } else if (const auto* l = std::get_if<LimitSetting>(&c.action)) {
    if (l->time_s) limits_.time_s = l->time_s;
    if (l->distance_m) limits_.distance_m = l->distance_m;
  } else if (const auto* k = std::get_if<KeepOutAdd>(&c.action)) {
    zones_.erase(std::remove_if(zones_.begin(), zones_.end(),
                                [&](const KeepOutZone& z) { return z.name == k->zone.name; }),
                 zones_.end());
    zones_.push_back(k->zone);
    publish_zones();
  } else if (const auto* r = std::get_if<KeepOutRemove>(&c.action)) {
    zones_.erase(std::remove_if(zones_.begin(), zones_.end(),
                                [&](const KeepOutZone& z) { return z.name == r->name; }),
                 zones_.end());
    publish_zones();
  } else if (std::holds_alternative<KeepOutClear>(c.action)) {
    zones_.clear();
    publish_zones();
  } else if (std::holds_alternative<NewSite>(c.action)) {
    wait_site_index_ = (pose_ ? pose_->site_index : 0) + 1;
    outputs_.push_back(NewSiteRequest{now_utime_, wait_site_index_});
    // Zones were given in the old site frame; they mean nothing in the new one.
    if (!zones_.empty()) {
      zones_.clear();
      publish_zones();
    }
    EnterPhase(Phase::kSite);
    return;
  } else if (const auto* im = std::get_if<Images>(&c.action)) {
    if (im->purpose == ImagePurpose::kVoBaseline) {
      StartCapture("vo_baseline");
      vo_frame_valid_ = true;
      if (VoActive()) {
        EnterPhase(Phase::kBaseline);
        return;
      }
    } else {
      StartCapture("science");
    }
    science_frame_seen_ = false;
    EnterPhase(Phase::kImages);
    return;
  }
  EnterPhase(Phase::kReady);
}

bool SequenceExecutor::PoseFinite() const {
  if (!pose_) return false;
  const PlanePose p = CurrentPlanePose();
  return pose_->position.allFinite() && std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.yaw);
}

bool SequenceExecutor::NextStepOfCommand() {
  if (!PoseFinite()) {
    // No safe step can be planned or checked from a broken estimate.
    AbortWith(abort_reason::kHazardUnknown, "the pose estimate is not finite; nothing commanded");
    return true;
  }
  PlannedStep step;
  if (is_goto_ && goto_.avoid) {
    switch (AvoidStep(&step)) {
      case AvoidOutcome::kStep: break;
      case AvoidOutcome::kWait: return true;
      case AvoidOutcome::kDone: return false;
      case AvoidOutcome::kAborted: return true;
    }
  } else if (is_goto_) {
    const GotoDecision d = SteerToward(CurrentPlanePose(), goto_.target, goto_.tolerance_m, StepLength(),
                                       MaxTurn(), options_.goto_turn_threshold_deg * kDeg);
    if (d.arrived) {
      detail_ = "goto reached the disc: " + Fixed(d.remaining_m) + " m from the target";
      return false;
    }
    step = d.step;
  } else {
    if (next_step_ >= steps_.size()) return false;
    step = steps_[next_step_];
  }
  // VO switched off by `then continue` comes back on where slip is likely: there, wheel
  // odometry is no evidence of where the rover went.
  if (vo_off_by_failures_) {
    if (const std::string why = SlipLikely(*pose_, *pose_); !why.empty()) {
      vo_enabled_ = true;
      vo_off_by_failures_ = false;
      detail_ = "VO back on: slip is likely here (" + why + ")";
    }
  }
  // MER took a baseline pair before the first step so that the first step has a VO answer.
  if (VoActive() && !vo_frame_valid_) {
    StartCapture("vo_baseline");
    vo_frame_valid_ = true;
    EnterPhase(Phase::kBaseline);
    return true;
  }
  if (!is_goto_) ++next_step_;
  BeginStep(step);
  return true;
}

void SequenceExecutor::BeginStep(const PlannedStep& step) {
  step_ = step;
  pose_before_ = *pose_;
  mobility_done_.reset();
  vo_update_.reset();
  hazard_reply_.reset();
  step_vo_failed_ = false;
  step_note_.clear();
  step_vo_on_ = VoActive();
  step_ref_frame_ = vo_frame_valid_ ? last_vo_frame_ : -1;
  step_retries_ = 0;
  frame_id_ = -1;
  if (options_.predictive_hazard_check) {
    // Predictive keep-out: a step whose swept footprint would enter a zone is never commanded.
    query_id_ = NewId();
    const PlanePose p = CurrentPlanePose();
    const bool turn = step_.kind == PlannedStep::Kind::kTurn;
    std::vector<hazards::Pose2> path;
    try {
      path = hazards::SampleStepPath({p.x, p.y, p.yaw}, turn ? 0.0 : step_.distance_m,
                                     turn ? 0.0 : step_.curvature_per_m, turn ? step_.turn_rad : 0.0,
                                     options_.path_sample_spacing_m, options_.path_sample_turn_deg * kDeg);
    } catch (const std::invalid_argument& e) {
      AbortWith(abort_reason::kHazardUnknown, std::string("cannot sample the step's path: ") + e.what());
      return;
    }
    HazardQuery q{now_utime_, query_id_, {}, 0.0};
    for (const auto& s : path) q.samples.push_back({s.x, s.y, s.yaw});
    if (!turn) {
      // Opportunity stopped near Wopmay when VO showed it sliding toward the rock: the step
      // is checked where the drift VO measured over the recent steps would take it, with
      // the spread of that drift and the uncertainty the step adds as extra clearance.
      const std::vector<StepDrift> recent(recent_drift_.begin(), recent_drift_.end());
      const DriftPrediction drift = PredictDrift(recent, step_.distance_m);
      q.samples = PathWithDrift(q.samples, drift);
      const double sigma = hazards::HorizontalSigma(pose_->covariance);
      q.margin_m = drift.spread_m +
                   options_.margin_sigma_multiplier *
                       StepSigmaGrowth(sigma, step_.distance_m, options_.step_sigma_growth_pct / 100.0);
    }
    outputs_.push_back(std::move(q));
    EnterPhase(Phase::kQuery);
  } else {
    CommandStep();
  }
}

void SequenceExecutor::CommandStep() {
  MobilityCommand cmd;
  cmd.utime = now_utime_;
  cmd.command_id = mobility_id_ = NewId();
  double expected_s = 0.0;
  if (step_.kind == PlannedStep::Kind::kTurn) {
    cmd.type = MobilityCommand::Type::kTurn;
    cmd.turn_rad = step_.turn_rad;
    cmd.turn_rate_rps = options_.turn_rate_rps;
    expected_s = std::abs(step_.turn_rad) / options_.turn_rate_rps;
  } else {
    cmd.type = MobilityCommand::Type::kArc;
    cmd.distance_m = step_.distance_m;
    cmd.curvature_per_m = step_.curvature_per_m;
    cmd.speed_mps = options_.speed_mps;
    expected_s = std::abs(step_.distance_m) / options_.speed_mps;
  }
  outputs_.push_back(cmd);
  pair_here_id_ = -1;  // the rover moves: no pair is where it will stand
  map_images_taken_ = false;
  avoid_refused_ = false;
  mobility_deadline_utime_ =
      now_utime_ + static_cast<int64_t>((expected_s * options_.mobility_timeout_factor +
                                         options_.mobility_timeout_margin_s) * 1e6);
  vo_frame_valid_ = false;
  EnterPhase(Phase::kMoving);
  EmitStatus();
}

void SequenceExecutor::AfterMotion() {
  if (!VoActive()) {
    EnterPhase(Phase::kWaitPose);
    return;
  }
  if (!options_.vo_processes_required && !SilentProcesses(true).empty() &&
      SilentProcesses(false).empty()) {
    // No VO process: nothing will answer, so do not wait; the policy decides.
    CountVoFailure("no VO process");
    EnterPhase(Phase::kWaitPose);
    return;
  }
  StartCapture("vo");
  vo_frame_valid_ = true;
  EnterPhase(Phase::kWaitVo);
}

void SequenceExecutor::StartCapture(const std::string& purpose) {
  frame_id_ = NewId();
  pair_here_id_ = frame_id_;
  if (purpose != "science") last_vo_frame_ = frame_id_;
  vo_update_.reset();
  outputs_.push_back(CaptureRequest{now_utime_, frame_id_, purpose});
}

void SequenceExecutor::CountVoFailure(const std::string& why) {
  ++vo_policy_failures_;
  ++vo_failures_total_;
  step_vo_failed_ = true;
  step_note_ += why + "; ";
}

void SequenceExecutor::FinishStep() {
  const PoseEstimate after = *pose_;
  // VO lost: VO (on for the step, or switched off by `then continue`) did not measure the
  // step, where slip is likely. `retry` takes pairs again before anything else happens.
  const bool measured = StepMeasured();
  const std::string slip_likely = measured ? std::string() : SlipLikely(pose_before_, after);
  const bool vo_lost = !slip_likely.empty() && (step_vo_on_ || vo_off_by_failures_);
  if (vo_lost && vo_lost_.action == VoLostAction::kRetry && step_vo_on_ &&
      step_retries_ < vo_lost_.retries) {
    ++step_retries_;
    step_note_ += "VO lost (" + slip_likely + "), pair taken again (" + std::to_string(step_retries_) +
                  " of " + std::to_string(vo_lost_.retries) + "); ";
    detail_ = "step " + std::to_string(step_index_) + ": " + step_note_;
    done_pose_count_ = pose_count_;  // the pose must come after this pair's VO answer
    StartCapture("vo");
    vo_frame_valid_ = true;
    EnterPhase(Phase::kWaitVo);
    return;
  }
  const StepMotion m = MeasureStep(ToPose(pose_before_), ToPose(after), step_);
  distance_m_ += (after.position - pose_before_.position).norm();

  StepReport r;
  r.utime = now_utime_;
  r.submission_id = submission_id_;
  r.command_index = command_index_;
  r.step_index = step_index_;
  r.mobility_command_id = mobility_id_;
  r.commanded_distance_m = step_.kind == PlannedStep::Kind::kArc ? step_.distance_m : 0.0;
  r.commanded_turn_rad = step_.HeadingChange();
  r.estimated_distance_m = m.estimated_distance_m;
  r.estimated_turn_rad = m.estimated_turn_rad;
  r.slip_pct = m.slip_pct;
  r.vo_status = vo_update_ ? vo_update_->status : -1;
  XyzRpy(pose_before_, r.pose_before);
  XyzRpy(after, r.pose_after);
  r.utime_before = pose_before_.utime;
  r.utime_after = after.utime;
  outputs_.push_back(r);
  ++step_index_;

  const std::string step_text = "step " + std::to_string(step_index_ - 1) + ": ";
  // 1. Hazard status: keep-out or tilt. UNKNOWN cannot decide, so it stops the rover.
  const HazardStatus& h = *hazard_;
  if (h.state == HazardState::kUnknown) {
    AbortWith(abort_reason::kHazardUnknown, step_text + "hazard state unknown" + (h.detail.empty() ? "" : ": " + h.detail));
    return;
  }
  if (h.keepout_violated || (h.state == HazardState::kViolation && !h.tilt_violated)) {
    AbortWith(abort_reason::kKeepout, step_text + "keep-out zone '" + h.zone_name + "' violated (clearance " +
                                          Fixed(h.min_clearance_m) + " m)");
    return;
  }
  const double roll = r.pose_after[3], pitch = r.pose_after[4];
  if (h.tilt_violated || (tilt_.enabled && tilt_.roll_rad && std::abs(roll) > *tilt_.roll_rad) ||
      (tilt_.enabled && tilt_.pitch_rad && std::abs(pitch) > *tilt_.pitch_rad)) {
    AbortWith(abort_reason::kTilt, step_text + "tilt: roll " + Fixed(roll / kDeg, 1) + " deg, pitch " +
                                       Fixed(pitch / kDeg, 1) + " deg");
    return;
  }
  // 2. VO lost: the `vo lost` policy (abort, retries exhausted, or shorter steps).
  if (vo_lost && !OnVoLost(step_text, slip_likely)) return;
  if (measured && lost_step_scale_ < 1.0) {
    // `vo lost shorten`: each step VO measures doubles the step back toward the setting.
    lost_step_scale_ = std::min(1.0, 2.0 * lost_step_scale_);
    ResplitRemainingSteps();
  }
  //    Progress / slip, from the VO-corrected motion against the commanded (MER: a 40 %
  //    limit stopped a drive at 44.5 % slip). Where slip is likely, wheel odometry is no
  //    evidence of progress: a step VO lost is left to `vo lost`, and a step driven with VO
  //    off counts as no progress (the check cannot decide, so it stops the rover).
  RecordStep(m, measured, after);
  if (slip_.enabled && !vo_lost && step_.kind == PlannedStep::Kind::kArc &&
      std::abs(step_.distance_m) >= options_.slip_min_step_m) {
    const bool evidence = measured || slip_likely.empty();
    if (evidence && m.slip_pct > slip_.limit_pct) {
      AbortWith(abort_reason::kProgress, step_text + "slip " + Fixed(m.slip_pct, 1) + " % > limit " +
                                             Fixed(slip_.limit_pct, 1) + " % (moved " +
                                             Fixed(m.estimated_distance_m, 3) + " m of " +
                                             Fixed(step_.distance_m, 3) + " m)");
      return;
    }
    const bool no_progress = !evidence || m.progress_fraction < slip_.no_progress_fraction;
    no_progress_count_ = no_progress ? no_progress_count_ + 1 : 0;
    if (no_progress_count_ >= slip_.over_steps) {
      AbortWith(abort_reason::kProgress,
                step_text + (evidence ? "progress below " + Fixed(100.0 * slip_.no_progress_fraction, 1) + " %"
                                      : "progress unknown (VO off where slip is likely: " + slip_likely + ")") +
                    " for " + std::to_string(no_progress_count_) + " steps");
      return;
    }
  }
  // 3. VO failures. On Mars the default was to drive on with wheel odometry.
  if (vo_max_failures_ && vo_policy_failures_ > *vo_max_failures_) {
    if (vo_past_max_ == VoFailureAction::kAbort) {
      AbortWith(abort_reason::kVoFailures, step_text + std::to_string(vo_policy_failures_) +
                                               " VO failures > " + std::to_string(*vo_max_failures_) +
                                               " allowed (" + step_note_ + ")");
      return;
    }
    // `then continue` keeps its Mars meaning on ground where slip is unlikely; where it is
    // likely, VO stays on and `vo lost` decides.
    if (vo_enabled_) {
      if (const std::string why = SlipLikely(after, after); !why.empty()) {
        step_note_ += "VO stays on past " + std::to_string(*vo_max_failures_) +
                      " failures: slip is likely (" + why + "); ";
      } else {
        vo_enabled_ = false;
        vo_off_by_failures_ = true;
        detail_ = "VO off after " + std::to_string(vo_policy_failures_) +
                  " failures; continuing on wheel odometry";
      }
    }
  }
  // 4. Limits.
  const double elapsed_s = (now_utime_ - start_utime_) * 1e-6;
  if (limits_.time_s && elapsed_s > *limits_.time_s) {
    AbortWith(abort_reason::kTimeLimit, step_text + "time " + Fixed(elapsed_s, 1) + " s > limit " +
                                            Fixed(*limits_.time_s, 1) + " s");
    return;
  }
  if (limits_.distance_m && distance_m_ > *limits_.distance_m) {
    AbortWith(abort_reason::kDistanceLimit, step_text + "distance " + Fixed(distance_m_) + " m > limit " +
                                                Fixed(*limits_.distance_m) + " m");
    return;
  }
  if (is_goto_) {
    const PlanePose p = CurrentPlanePose();
    const bool arrived = (goto_.target - Eigen::Vector2d(p.x, p.y)).norm() <= goto_.tolerance_m;
    const double goto_s = (now_utime_ - goto_start_utime_) * 1e-6;
    const double goto_m = distance_m_ - goto_start_distance_;
    if (!arrived && goto_.time_limit_s && goto_s > *goto_.time_limit_s) {
      AbortWith(abort_reason::kGotoTimeLimit, step_text + "goto time " + Fixed(goto_s, 1) + " s > limit " +
                                                  Fixed(*goto_.time_limit_s, 1) + " s");
      return;
    }
    if (!arrived && goto_m > goto_distance_limit_) {
      AbortWith(abort_reason::kGotoDistanceLimit, step_text + "goto distance " + Fixed(goto_m) +
                                                      " m > limit " + Fixed(goto_distance_limit_) + " m");
      return;
    }
  }
  if (!step_note_.empty()) detail_ = step_text + step_note_;
  EnterPhase(Phase::kReady);
}

// ---- VO lost ----

bool SequenceExecutor::StepMeasured() const {
  if (!step_vo_on_ || !vo_update_ || vo_update_->status != VoUpdate::kStatusOk) return false;
  // The pose must include the update, and the update must span the step: a pair taken
  // again after a failure is measured from the failed pair when VO kept that as reference.
  return pose_ && pose_->last_vo_to_frame >= frame_id_ && vo_update_->from_frame_id <= step_ref_frame_;
}

std::string SequenceExecutor::SlipLikely(const PoseEstimate& before, const PoseEstimate& after) const {
  const double tilt = std::max(TiltAngle(before.orientation.normalized().toRotationMatrix()),
                               TiltAngle(after.orientation.normalized().toRotationMatrix()));
  if (tilt > blind_slope_rad_) {
    return "tilt " + Fixed(tilt / kDeg, 1) + " deg > " + Fixed(blind_slope_rad_ / kDeg, 1) + " deg";
  }
  for (const double pct : recent_slip_pct_) {
    if (pct > blind_slip_pct_) {
      return "VO measured " + Fixed(pct, 1) + " % slip or drift in the last " +
             std::to_string(options_.recent_steps) + " steps > " + Fixed(blind_slip_pct_, 1) + " %";
    }
  }
  return "";
}

bool SequenceExecutor::OnVoLost(const std::string& step_text, const std::string& why) {
  const std::string lost = step_text + "VO did not measure the step where slip is likely (" + why + ")";
  switch (vo_lost_.action) {
    case VoLostAction::kAbort:
      AbortWith(abort_reason::kVoLost, lost);
      return false;
    case VoLostAction::kRetry:
      AbortWith(abort_reason::kVoLost, lost + (step_vo_on_ ? ", also after " + std::to_string(step_retries_) +
                                                                  " more pairs"
                                                            : ", and VO was off"));
      return false;
    case VoLostAction::kShorten: {
      const double shortest = std::min(1.0, options_.lost_min_step_m / step_m_);
      if (lost_step_scale_ <= shortest + 1e-9) {
        AbortWith(abort_reason::kVoLost, lost + ", at the shortest step (" + Fixed(StepLength()) + " m)");
        return false;
      }
      lost_step_scale_ = std::max(0.5 * lost_step_scale_, shortest);
      ResplitRemainingSteps();
      if (vo_off_by_failures_) {
        vo_enabled_ = true;
        vo_off_by_failures_ = false;
      }
      step_note_ += "VO lost (" + why + "): steps shortened to " + Fixed(StepLength()) + " m, " +
                    Fixed(MaxTurn() / kDeg, 1) + " deg; ";
      return true;
    }
  }
  return true;
}

void SequenceExecutor::ResplitRemainingSteps() {
  if (is_goto_ || next_step_ >= steps_.size()) return;  // goto re-plans with StepLength()
  const PlannedStep kind = steps_[next_step_];
  double rest = 0.0;
  for (std::size_t i = next_step_; i < steps_.size(); ++i) {
    rest += kind.kind == PlannedStep::Kind::kTurn ? steps_[i].turn_rad : steps_[i].distance_m;
  }
  steps_ = kind.kind == PlannedStep::Kind::kTurn
               ? SplitTurn(rest, MaxTurn())
               : SplitArc(rest, kind.curvature_per_m, StepLength(), MaxTurn());
  next_step_ = 0;
}

void SequenceExecutor::RecordStep(const StepMotion& motion, bool measured, const PoseEstimate& after) {
  const bool arc = step_.kind == PlannedStep::Kind::kArc &&
                   std::abs(step_.distance_m) >= options_.slip_min_step_m;
  double slip_pct = 0.0;
  if (measured && arc) {
    const auto plane = [](const PoseEstimate& p) {
      const Eigen::Vector3d rpy = geometry::RpyFromRotation(p.orientation.normalized().toRotationMatrix());
      return PlanePose{p.position.x(), p.position.y(), rpy.z()};
    };
    const StepDrift drift = DriftOfStep(plane(pose_before_), plane(after), step_);
    slip_pct = std::max(motion.slip_pct, drift.cross_pct);
    recent_drift_.push_back(drift);
    while (static_cast<int>(recent_drift_.size()) > options_.recent_steps) recent_drift_.pop_front();
  }
  recent_slip_pct_.push_back(slip_pct);
  while (static_cast<int>(recent_slip_pct_.size()) > options_.recent_steps) recent_slip_pct_.pop_front();
}

// ---- finishing and status ----

void SequenceExecutor::Finish(SequenceState state, const std::string& reason, const std::string& detail) {
  state_ = state;
  abort_reason_ = reason;
  detail_ = detail;
  end_utime_ = now_utime_;
  command_active_ = false;
  pause_requested_ = false;
  EnterPhase(Phase::kFinished);
  EmitStatus();
}

void SequenceExecutor::AbortWith(const std::string& reason, const std::string& detail) {
  EmitStop();
  Finish(SequenceState::kAborted, reason, detail);
}

void SequenceExecutor::Reject(int64_t submission_id, const std::string& name, const std::string& reason,
                              const std::string& detail) {
  SequenceStatus s;
  s.utime = now_utime_;
  s.submission_id = submission_id;
  s.sequence_name = name;
  s.state = SequenceState::kRejected;
  s.abort_reason = reason;
  s.detail = detail;
  if (pose_) XyzRpy(*pose_, s.pose);
  if (Active()) {
    outputs_.push_back(s);  // the running sequence carries on
    return;
  }
  sequence_ = Sequence{name, {}};
  submission_id_ = submission_id;
  started_ = false;
  command_index_ = -1;
  step_index_ = 0;
  distance_m_ = 0.0;
  vo_failures_total_ = 0;
  Finish(SequenceState::kRejected, reason, detail);
}

void SequenceExecutor::EmitStop() {
  MobilityCommand stop;
  stop.utime = now_utime_;
  stop.command_id = NewId();
  stop.type = MobilityCommand::Type::kStop;
  outputs_.push_back(stop);
}

SequenceStatus SequenceExecutor::CurrentStatus() const {
  SequenceStatus s;
  s.utime = now_utime_;
  s.submission_id = submission_id_;
  s.sequence_name = sequence_.name;
  s.state = state_;
  s.num_commands = static_cast<int>(sequence_.commands.size());
  s.command_index = command_index_;
  if (command_index_ >= 0 && command_index_ < s.num_commands) {
    s.command_line = sequence_.commands[command_index_].line;
    s.command_text = sequence_.commands[command_index_].text;
  }
  s.step_index = step_index_;
  s.abort_reason = abort_reason_;
  s.detail = detail_;
  if (pose_) XyzRpy(*pose_, s.pose);
  s.distance_m = distance_m_;
  const int64_t until = phase_ == Phase::kFinished ? end_utime_ : now_utime_;  // the clock stops at the end
  s.elapsed_s = started_ ? (until - start_utime_) * 1e-6 : 0.0;
  s.vo_failures = vo_failures_total_;
  return s;
}

void SequenceExecutor::EmitStatus() {
  outputs_.push_back(CurrentStatus());
  last_status_wall_ = now_wall_;
}

// ---- helpers ----

bool SequenceExecutor::ProcessFresh(const std::string& entry) const {
  // "a|b": either process will do (the simulator or the real mobility driver).
  std::size_t start = 0;
  while (start <= entry.size()) {
    std::size_t bar = entry.find('|', start);
    if (bar == std::string::npos) bar = entry.size();
    const auto it = heartbeats_.find(entry.substr(start, bar - start));
    if (it != heartbeats_.end() && now_wall_ - it->second <= options_.heartbeat_timeout_s) return true;
    start = bar + 1;
  }
  return false;
}

std::vector<std::string> SequenceExecutor::SilentProcesses(bool include_vo) const {
  std::vector<std::string> silent;
  for (const auto& p : options_.required_processes) {
    if (!ProcessFresh(p)) silent.push_back(p);
  }
  if (include_vo) {
    for (const auto& p : options_.vo_processes) {
      if (!ProcessFresh(p)) silent.push_back(p);
    }
  }
  return silent;
}

bool SequenceExecutor::VoRequired() const { return options_.vo_processes_required && vo_enabled_; }

PlanePose SequenceExecutor::CurrentPlanePose() const {
  if (!pose_) return {};
  const Eigen::Vector3d rpy = geometry::RpyFromRotation(pose_->orientation.normalized().toRotationMatrix());
  return {pose_->position.x(), pose_->position.y(), rpy.z()};
}

}  // namespace rover::sequence
