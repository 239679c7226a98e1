// A step's life up to the end of its motion: plan it (NextStepOfCommand), ask the hazard
// monitor about its swept path (BeginStep, QueryStep), command it (CommandStep), then take
// the VO pair that measures it (AfterMotion). FinishStep (executor_finish.cpp) judges it.
#include "sequence/executor.hpp"
#include "sequence/executor_internal.hpp"

#include "hazards/hazard_assessor.hpp"
#include "hazards/keepout.hpp"

#include <cmath>
#include <stdexcept>

namespace rover::sequence {

using internal::Fixed;
using internal::kDeg;

bool SequenceExecutor::NextStepOfCommand() {
  if (!PoseFinite()) {
    // No safe step can be planned or checked from a broken estimate.
    AbortWith(abort_reason::kHazardUnknown, "the pose estimate is not finite; nothing commanded");
    return true;
  }
  PlannedStep step;
  step_choice_ = StepChoice::kCommand;  // AvoidStep says otherwise
  thought_ahead_ = false;               // and whether it chose on an earlier pair's map
  if (is_goto_ && goto_.avoid) {
    switch (AvoidStep(&step)) {
      case AvoidOutcome::kStep: break;
      case AvoidOutcome::kWait:
      case AvoidOutcome::kDeclined: return true;
      case AvoidOutcome::kDone: return false;
      case AvoidOutcome::kAborted: return true;
    }
  } else if (is_goto_) {
    const ArrivalDisc disc = GotoArrival();
    const GotoDecision d = SteerToward(CurrentPlanePose(), goto_.target, disc.radius_m, StepLength(), MaxTurn(),
                                       options_.goto_turn_threshold_deg * kDeg);
    if (d.arrived) {
      detail_ = arrival_note_ = "goto reached the disc: " + Fixed(d.remaining_m) +
                                " m from the target by the estimate, " + disc.Describe();
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
    } else if (options_.vo_retry_after_m > 0.0 && distance_m_ - vo_off_at_m_ >= options_.vo_retry_after_m) {
      // Tried again away from the view that failed, with its failures counted afresh.
      vo_enabled_ = true;
      vo_off_by_failures_ = false;
      vo_policy_failures_ = 0;
      detail_ = "VO back on after " + Fixed(distance_m_ - vo_off_at_m_) + " m on wheel odometry";
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
  plan_start_utime_ = plan_end_utime_ = 0;
  if (is_goto_ && goto_.avoid && options_.plan_compute_s > 0) {
    // The choice costs the rover's computer rover time before the step can be commanded.
    planned_ = step;
    plan_start_utime_ = now_utime_;
    EnterPhase(Phase::kPlanning);
    return true;
  }
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
  step_note_ = std::move(ahead_note_);  // a step chosen ahead and refused before this one, if any
  ahead_note_.clear();
  step_vo_on_ = VoActive();
  step_ref_frame_ = vo_frame_valid_ ? last_vo_frame_ : -1;
  step_retries_ = 0;
  frame_id_ = -1;
  if (options_.predictive_hazard_check) {
    QueryStep();
  } else {
    CommandStep();
  }
}

// Predictive keep-out: a step whose swept footprint would enter a zone is never commanded.
void SequenceExecutor::QueryStep() {
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
  HazardQuery q{now_utime_, query_id_, {}, 0.0, thought_ahead_ ? ahead_map_frame_ : 0};
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
  Emit(std::move(q));
  EnterPhase(Phase::kQuery);
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
  Emit(cmd);
  pair_here_id_ = -1;  // the rover moves: no pair is where it will stand
  map_images_taken_ = false;
  looked_here_ = 0;
  ahead_declined_ = false;
  ahead_saved_.reset();
  if (thought_ahead_) ++steps_thought_ahead_;
  avoid_refused_ = false;
  last_turn_rad_ = step_.kind == PlannedStep::Kind::kTurn ? step_.turn_rad : 0.0;
  arcs_to_retrace_.Driven(step_.kind == PlannedStep::Kind::kArc, step_.distance_m, step_.curvature_per_m);
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

void SequenceExecutor::StartCapture(const std::string& purpose, double pan_rad, double tilt_rad) {
  frame_id_ = NewId();
  pair_here_id_ = frame_id_;
  if (purpose != "science" && purpose != "look") last_vo_frame_ = frame_id_;
  vo_update_.reset();
  Emit(CaptureRequest{now_utime_, frame_id_, purpose, pan_rad, tilt_rad});
}

void SequenceExecutor::CountVoFailure(const std::string& why) {
  ++vo_policy_failures_;
  ++vo_failures_total_;
  step_vo_failed_ = true;
  step_note_ += why + "; ";
}

}  // namespace rover::sequence
