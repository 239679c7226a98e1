// The phase machine: Advance() polls the current phase until it neither moves on nor
// finishes, i.e. until it waits for an input. Each phase waits for one thing, with a
// wall-clock guard against a silent peer; Poll* says what each does on its answer and
// on its time-out.
#include "sequence/executor.hpp"
#include "sequence/executor_internal.hpp"

#include <string>

namespace rover::sequence {

using internal::Fixed;
using internal::Join;

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
    case Phase::kFinished: return;
    case Phase::kWaitStart: PollWaitStart(); return;
    case Phase::kReady: PollReady(); return;
    case Phase::kBaseline: PollBaseline(); return;
    case Phase::kQuery: PollQuery(); return;
    case Phase::kMoving: PollMoving(); return;
    case Phase::kWaitVo: PollWaitVo(); return;
    case Phase::kWaitPose: PollWaitPose(); return;
    case Phase::kWaitHazard: PollWaitHazard(); return;
    case Phase::kImages: PollImages(); return;
    case Phase::kSite: PollSite(); return;
    case Phase::kPlanning: PollPlanning(); return;
  }
}

// The rover's computer is still choosing the step (ExecutorOptions::plan_compute_s).
void SequenceExecutor::PollPlanning() {
  if (PhaseAge() < options_.plan_compute_s) return;
  plan_end_utime_ = now_utime_;
  BeginStep(planned_);
}

void SequenceExecutor::PollWaitStart() {
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
}

void SequenceExecutor::PollReady() {
  if (state_ != SequenceState::kRunning) return;
  if (pause_requested_) {
    pause_requested_ = false;
    state_ = SequenceState::kPaused;
    paused_since_utime_ = now_utime_;
    detail_ = "paused by the operator; the time limits stand still while paused (" + TimeLeftText() + ")";
    EmitStatus();
    return;
  }
  DispatchNext();
}

void SequenceExecutor::PollBaseline() {
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
}

void SequenceExecutor::PollQuery() {
  if (!hazard_reply_) {
    if (PhaseAge() > options_.hazard_reply_wait_s) {
      AbortWith(abort_reason::kHazardUnknown, "no hazard reply within " +
                                                  Fixed(options_.hazard_reply_wait_s, 1) +
                                                  " s; the step was not commanded");
    }
    return;
  }
  const HazardReply r = *hazard_reply_;
  if (r.verdict == HazardVerdict::kSafe) {
    CommandStep();
  } else if (AheadRefused(r)) {
    return;
  } else if (r.verdict == HazardVerdict::kUnsafe && r.zone_name == abort_reason::kHazardMap &&
             AvoidRefused(r)) {
    return;
  } else if (r.verdict == HazardVerdict::kUnsafe && r.zone_name == abort_reason::kHazardMap) {
    AbortWith(abort_reason::kHazardMap, r.detail + "; not commanded");
  } else if (r.verdict == HazardVerdict::kUnknown && ImagesForMap(r)) {
    return;
  } else if (r.verdict == HazardVerdict::kUnsafe) {
    AbortWith(abort_reason::kKeepout, "the next step would enter zone '" + r.zone_name + "' (clearance " +
                                          Fixed(r.min_clearance_m) + " m); not commanded" +
                                          (r.detail.empty() ? "" : ": " + r.detail));
  } else {
    AbortWith(abort_reason::kHazardUnknown, "the hazard monitor cannot decide on the next step" +
                                                (r.detail.empty() ? "" : ": " + r.detail));
  }
}

void SequenceExecutor::PollMoving() {
  if (mobility_done_) {
    AfterMotion();
  } else if (PhaseAge() > options_.mobility_wait_s) {
    AbortWith(abort_reason::kTimeout, "mobility did not finish command " + std::to_string(mobility_id_) +
                                          " within " + Fixed(options_.mobility_wait_s, 0) + " s (wall)");
  } else if (now_utime_ > mobility_deadline_utime_) {
    AbortWith(abort_reason::kTimeout, "mobility did not finish command " + std::to_string(mobility_id_) +
                                          " in the expected rover time");
  }
}

void SequenceExecutor::PollWaitVo() {
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
}

void SequenceExecutor::PollWaitPose() {
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
}

void SequenceExecutor::PollWaitHazard() {
  if (hazard_count_ > hazard_mark_) {
    FinishStep();
  } else if (PhaseAge() > options_.hazard_status_wait_s) {
    AbortWith(abort_reason::kHazardUnknown, "no hazard status within " +
                                                Fixed(options_.hazard_status_wait_s, 1) + " s after the step");
  }
}

void SequenceExecutor::PollImages() {
  if (science_frame_seen_) {
    EnterPhase(Phase::kReady);
  } else if (PhaseAge() > options_.capture_wait_s) {
    detail_ = "frame " + std::to_string(frame_id_) + " not seen within " + Fixed(options_.capture_wait_s, 1) +
              " s; going on";
    // A camera that cannot point (real cameras without a pan-tilt unit) refuses every look:
    // no more asking in this sequence.
    if (frame_id_ == look_frame_id_) {
      looks_unanswered_ = true;
      step_note_ += "the camera did not answer a look (cannot point?): no more looks in this sequence; ";
    }
    EnterPhase(Phase::kReady);
  }
}

void SequenceExecutor::PollSite() {
  if (pose_ && pose_->site_index >= wait_site_index_) {
    EnterPhase(Phase::kReady);
  } else if (PhaseAge() > options_.site_wait_s) {
    AbortWith(abort_reason::kTimeout, "no pose in site " + std::to_string(wait_site_index_) + " within " +
                                          Fixed(options_.site_wait_s, 1) + " s");
  }
}

// Between steps: the next step of the command in hand, else the next command, else done.
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
    // The last goto's arrival, with the margin it used for the estimate's uncertainty.
    Finish(SequenceState::kCompleted, "",
           "all " + std::to_string(sequence_.commands.size()) + " commands done" +
               (arrival_note_.empty() ? "" : "; " + arrival_note_) +
               (looks_total_ == 0 ? "" : "; " + std::to_string(looks_total_) + " looks aside") +
               (steps_thought_ahead_ == 0 ? "" : "; " + std::to_string(steps_thought_ahead_) + " steps chosen while driving"));
    return;
  }
  StartCommand();
}

}  // namespace rover::sequence
