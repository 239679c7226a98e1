// The executor's shell-facing side: construction, the operator's requests, the bus inputs
// and the clocks. Each input is recorded, then Advance() runs the phase machine
// (executor_poll.cpp) as far as it can go.
#include "sequence/executor.hpp"
#include "sequence/executor_internal.hpp"

#include <algorithm>
#include <cmath>

namespace rover::sequence {

using internal::Fixed;
using internal::Join;
using internal::kDeg;

SequenceExecutor::SequenceExecutor(ExecutorOptions options, int64_t first_id)
    : options_(std::move(options)), next_id_(first_id) {
  ValidateExecutorOptions(options_);
  site_map_.set_keep_unsafe(options_.avoid_keep_unsafe);
  planner::BlockOptions blocks;
  blocks.stall_steps = options_.planner_block_after_steps;
  blocks.min_gain_m = options_.planner_block_min_gain_m;
  blocks.ahead_m = options_.planner_block_ahead_m;
  blocks.radius_m = options_.planner_block_radius_m;
  blocked_ways_ = planner::BlockedWays(blocks);
  refused_ways_ = planner::RefusedWays(RefusalOptionsOf(options_));
  step_m_ = options_.default_step_m;
  max_turn_rad_ = options_.default_max_turn_deg * kDeg;
  vo_wait_s_ = options_.vo_wait_s;
  blind_slope_rad_ = options_.blind_slope_deg * kDeg;
  blind_slip_pct_ = options_.blind_slip_pct;
  if (!options_.planner_prior_map.empty()) prior_ = planner::PriorCostMap::LoadFile(options_.planner_prior_map);
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
  paused_total_us_ = 0;
  command_active_ = false;
  arrival_note_.clear();
  ResetSettings();
  // The zones of an earlier sequence end with it: the hazard monitor is told too, or it
  // would go on checking (and aborting on) zones this sequence never declared.
  PublishZones();
  for (const Command& c : sequence_.commands) {
    if (const auto* v = std::get_if<VoSetting>(&c.action); v && v->enabled) sequence_uses_vo_ = true;
  }
  EnterPhase(Phase::kWaitStart);
  EmitStatus();
  Advance();
}

// Settings start from the defaults for every sequence.
void SequenceExecutor::ResetSettings() {
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

void SequenceExecutor::TimeSourceLost(const std::string& detail) {
  if (Active()) {
    AbortWith(abort_reason::kTimeSourceLost, detail);
  } else {
    EmitStop();
  }
}

void SequenceExecutor::RecordInterrupted(int64_t submission_id, const std::string& name,
                                         const std::string& detail) {
  if (Active()) return;
  ClearRun(submission_id, name);
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
  // The pause counts against no time limit: the sequence's and the goto's clocks start
  // again where they stood.
  const int64_t paused_us = std::max<int64_t>(0, now_utime_ - paused_since_utime_);
  start_utime_ += paused_us;
  if (is_goto_) goto_start_utime_ += paused_us;
  paused_total_us_ += paused_us;
  state_ = SequenceState::kRunning;
  detail_ = "resumed after " + Fixed(paused_us * 1e-6, 1) + " s paused (not counted against the time limits; " +
            TimeLeftText() + ")";
  EmitStatus();
  EnterPhase(Phase::kReady);
  Advance();
}

// ---- bus inputs ----

void SequenceExecutor::OnPose(const PoseEstimate& pose) {
  pose_ = pose;
  ++pose_count_;
  now_utime_ = std::max(now_utime_, pose.utime);
  MarkDriven();
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
                                            "', clearance " + Fixed(status.min_clearance_m) +
                                            " m (the footprint grown by the pose's uncertainty)");
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

void SequenceExecutor::SetWall(double wall_s) {
  if (!wall_known_) {
    // Waits entered before the first wall time start now, not at 0.
    wall_known_ = true;
    phase_start_wall_ = wall_s;
    now_wall_ = wall_s;
  }
  now_wall_ = std::max(now_wall_, wall_s);
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

bool SequenceExecutor::PoseFinite() const {
  if (!pose_) return false;
  const PlanePose p = CurrentPlanePose();
  return pose_->position.allFinite() && std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.yaw);
}

}  // namespace rover::sequence
