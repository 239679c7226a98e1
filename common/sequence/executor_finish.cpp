// The end of a step: once the pose after it and a hazard status have come, FinishStep
// reports the step and runs the checks between steps (LANGUAGE.md, "What runs between
// steps") in order; the first that aborts ends the sequence, else the machine is ready for
// the next step.
#include "sequence/executor.hpp"
#include "sequence/executor_internal.hpp"

#include <algorithm>
#include <cmath>

namespace rover::sequence {

using internal::Fixed;
using internal::kDeg;
using internal::XyzRpy;

namespace {

geometry::Pose ToPose(const PoseEstimate& p) {
  geometry::Pose T = geometry::Pose::Identity();
  T.linear() = p.orientation.normalized().toRotationMatrix();
  T.translation() = p.position;
  return T;
}

}  // namespace

void SequenceExecutor::FinishStep() {
  StepEnd end;
  end.after = *pose_;
  // VO lost: VO (on for the step, or switched off by `then continue`) did not measure the
  // step, where slip is likely. `retry` takes pairs again before anything else happens.
  end.measured = StepMeasured();
  end.slip_likely = end.measured ? std::string() : SlipLikely(pose_before_, end.after);
  end.vo_lost = !end.slip_likely.empty() && (step_vo_on_ || vo_off_by_failures_);
  if (end.vo_lost && RetryLostPair(end.slip_likely)) return;
  end.motion = MeasureStep(ToPose(pose_before_), ToPose(end.after), step_);
  distance_m_ += (end.after.position - pose_before_.position).norm();
  ReportStep(end);
  ++step_index_;
  end.text = "step " + std::to_string(step_index_ - 1) + ": ";

  if (!CheckHazardAfterStep(end)) return;
  if (!ApplyVoLostPolicy(end)) return;
  RecordStep(end.motion, end.measured, end.after);
  if (!CheckProgress(end)) return;
  if (!ApplyVoFailurePolicy(end)) return;
  if (!CheckLimits(end)) return;
  if (!step_note_.empty()) detail_ = end.text + step_note_;
  EnterPhase(Phase::kReady);
}

bool SequenceExecutor::RetryLostPair(const std::string& why) {
  if (vo_lost_.action != VoLostAction::kRetry || !step_vo_on_ || step_retries_ >= vo_lost_.retries) {
    return false;
  }
  ++step_retries_;
  step_note_ += "VO lost (" + why + "), pair taken again (" + std::to_string(step_retries_) + " of " +
                std::to_string(vo_lost_.retries) + "); ";
  detail_ = "step " + std::to_string(step_index_) + ": " + step_note_;
  done_pose_count_ = pose_count_;  // the pose must come after this pair's VO answer
  StartCapture("vo");
  vo_frame_valid_ = true;
  EnterPhase(Phase::kWaitVo);
  return true;
}

void SequenceExecutor::ReportStep(const StepEnd& end) {
  const StepMotion& m = end.motion;
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
  XyzRpy(end.after, r.pose_after);
  r.utime_before = pose_before_.utime;
  r.utime_after = end.after.utime;
  r.utime_plan_start = plan_start_utime_;
  r.utime_plan_end = plan_end_utime_;
  r.choice = step_choice_;
  r.thought_ahead = thought_ahead_;
  Emit(r);
}

// 1. Hazard status: keep-out or tilt. UNKNOWN cannot decide, so it stops the rover.
bool SequenceExecutor::CheckHazardAfterStep(const StepEnd& end) {
  const std::string& step_text = end.text;
  const HazardStatus& h = *hazard_;
  if (h.state == HazardState::kUnknown) {
    AbortWith(abort_reason::kHazardUnknown, step_text + "hazard state unknown" + (h.detail.empty() ? "" : ": " + h.detail));
    return false;
  }
  if (h.keepout_violated || (h.state == HazardState::kViolation && !h.tilt_violated)) {
    AbortWith(abort_reason::kKeepout, step_text + "keep-out zone '" + h.zone_name + "' violated (clearance " +
                                          Fixed(h.min_clearance_m) + " m)");
    return false;
  }
  double pose_after[6];
  XyzRpy(end.after, pose_after);
  const double roll = pose_after[3], pitch = pose_after[4];
  if (h.tilt_violated || (tilt_.enabled && tilt_.roll_rad && std::abs(roll) > *tilt_.roll_rad) ||
      (tilt_.enabled && tilt_.pitch_rad && std::abs(pitch) > *tilt_.pitch_rad)) {
    AbortWith(abort_reason::kTilt, step_text + "tilt: roll " + Fixed(roll / kDeg, 1) + " deg, pitch " +
                                       Fixed(pitch / kDeg, 1) + " deg");
    return false;
  }
  return true;
}

// 2. VO lost: the `vo lost` policy (abort, retries exhausted, or shorter steps).
bool SequenceExecutor::ApplyVoLostPolicy(const StepEnd& end) {
  if (end.vo_lost && !OnVoLost(end.text, end.slip_likely)) return false;
  if (end.measured && lost_step_scale_ < 1.0) {
    // `vo lost shorten`: each step VO measures doubles the step back toward the setting.
    lost_step_scale_ = std::min(1.0, 2.0 * lost_step_scale_);
    ResplitRemainingSteps();
  }
  return true;
}

// Progress / slip, from the VO-corrected motion against the commanded (MER: a 40 % limit
// stopped a drive at 44.5 % slip). Where slip is likely, wheel odometry is no evidence of
// progress: a step VO lost is left to `vo lost`, and a step driven with VO off counts as no
// progress (the check cannot decide, so it stops the rover).
bool SequenceExecutor::CheckProgress(const StepEnd& end) {
  if (!(slip_.enabled && !end.vo_lost && step_.kind == PlannedStep::Kind::kArc &&
        std::abs(step_.distance_m) >= options_.slip_min_step_m)) {
    return true;
  }
  const StepMotion& m = end.motion;
  const std::string& step_text = end.text;
  const bool evidence = end.measured || end.slip_likely.empty();
  if (evidence && m.slip_pct > slip_.limit_pct) {
    AbortWith(abort_reason::kProgress, step_text + "slip " + Fixed(m.slip_pct, 1) + " % > limit " +
                                           Fixed(slip_.limit_pct, 1) + " % (moved " +
                                           Fixed(m.estimated_distance_m, 3) + " m of " +
                                           Fixed(step_.distance_m, 3) + " m)");
    return false;
  }
  const bool no_progress = !evidence || m.progress_fraction < slip_.no_progress_fraction;
  no_progress_count_ = no_progress ? no_progress_count_ + 1 : 0;
  if (no_progress_count_ >= slip_.over_steps) {
    AbortWith(abort_reason::kProgress,
              step_text + (evidence ? "progress below " + Fixed(100.0 * slip_.no_progress_fraction, 1) + " %"
                                    : "progress unknown (VO off where slip is likely: " + end.slip_likely + ")") +
                  " for " + std::to_string(no_progress_count_) + " steps");
    return false;
  }
  return true;
}

// 3. VO failures. On Mars the default was to drive on with wheel odometry.
bool SequenceExecutor::ApplyVoFailurePolicy(const StepEnd& end) {
  if (!vo_max_failures_ || vo_policy_failures_ <= *vo_max_failures_) return true;
  if (vo_past_max_ == VoFailureAction::kAbort) {
    AbortWith(abort_reason::kVoFailures, end.text + std::to_string(vo_policy_failures_) + " VO failures > " +
                                             std::to_string(*vo_max_failures_) + " allowed (" + step_note_ + ")");
    return false;
  }
  // `then continue` keeps its Mars meaning on ground where slip is unlikely; where it is
  // likely, VO stays on and `vo lost` decides.
  if (vo_enabled_) {
    if (const std::string why = SlipLikely(end.after, end.after); !why.empty()) {
      step_note_ += "VO stays on past " + std::to_string(*vo_max_failures_) + " failures: slip is likely (" +
                    why + "); ";
    } else {
      vo_enabled_ = false;
      vo_off_by_failures_ = true;
      vo_off_at_m_ = distance_m_;
      detail_ = "VO off after " + std::to_string(vo_policy_failures_) + " failures; continuing on wheel odometry" +
                (options_.vo_retry_after_m > 0.0 ? " (VO tried again after " + Fixed(options_.vo_retry_after_m) + " m)"
                                                 : std::string());
    }
  }
  return true;
}

std::string SequenceExecutor::TimeLeftText() const {
  const int64_t now = state_ == SequenceState::kPaused ? paused_since_utime_ : now_utime_;
  std::string text;
  auto left = [&](const char* what, int64_t since, double limit_s) {
    const double used_s = started_ ? std::max(0.0, (now - since) * 1e-6) : 0.0;
    text += (text.empty() ? "" : ", ") + std::string(what) + " " + Fixed(std::max(0.0, limit_s - used_s), 1) +
            " s of " + Fixed(limit_s, 1) + " s left";
  };
  if (limits_.time_s) left("sequence", start_utime_, *limits_.time_s);
  if (is_goto_ && goto_.time_limit_s) left("goto", goto_start_utime_, *goto_.time_limit_s);
  return text.empty() ? "no time limits" : text;
}

// 4. Limits: the sequence's time and distance, then the goto's unless it arrived.
bool SequenceExecutor::CheckLimits(const StepEnd& end) {
  const std::string& step_text = end.text;
  const double elapsed_s = (now_utime_ - start_utime_) * 1e-6;
  if (limits_.time_s && elapsed_s > *limits_.time_s) {
    AbortWith(abort_reason::kTimeLimit, step_text + "time " + Fixed(elapsed_s, 1) + " s > limit " +
                                            Fixed(*limits_.time_s, 1) + " s");
    return false;
  }
  if (limits_.distance_m && distance_m_ > *limits_.distance_m) {
    AbortWith(abort_reason::kDistanceLimit, step_text + "distance " + Fixed(distance_m_) + " m > limit " +
                                                Fixed(*limits_.distance_m) + " m");
    return false;
  }
  if (!is_goto_) return true;
  const PlanePose p = CurrentPlanePose();
  const bool arrived = (goto_.target - Eigen::Vector2d(p.x, p.y)).norm() <= goto_.tolerance_m;
  const double goto_s = (now_utime_ - goto_start_utime_) * 1e-6;
  const double goto_m = distance_m_ - goto_start_distance_;
  if (!arrived && goto_.time_limit_s && goto_s > *goto_.time_limit_s) {
    AbortWith(abort_reason::kGotoTimeLimit, step_text + "goto time " + Fixed(goto_s, 1) + " s > limit " +
                                                Fixed(*goto_.time_limit_s, 1) + " s");
    return false;
  }
  if (!arrived && goto_m > goto_distance_limit_) {
    AbortWith(abort_reason::kGotoDistanceLimit, step_text + "goto distance " + Fixed(goto_m) + " m > limit " +
                                                    Fixed(goto_distance_limit_) + " m");
    return false;
  }
  return true;
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

}  // namespace rover::sequence
