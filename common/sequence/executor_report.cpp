// The end of a sequence and what the executor reports: finishing, aborting (always with a
// STOP first), rejecting, and the sequence status.
#include "sequence/executor.hpp"
#include "sequence/executor_internal.hpp"

namespace rover::sequence {

using internal::XyzRpy;

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

const char* ToString(StepChoice choice) {
  switch (choice) {
    case StepChoice::kCommand: return "command";
    case StepChoice::kArcVote: return "arc_vote";
    case StepChoice::kSteerAtGoal: return "steer_at_goal";
  }
  return "?";
}

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
    Emit(s);  // the running sequence carries on
    return;
  }
  ClearRun(submission_id, name);
  Finish(SequenceState::kRejected, reason, detail);
}

void SequenceExecutor::ClearRun(int64_t submission_id, const std::string& name) {
  sequence_ = Sequence{name, {}};
  submission_id_ = submission_id;
  started_ = false;
  command_index_ = -1;
  step_index_ = 0;
  distance_m_ = 0.0;
  vo_failures_total_ = 0;
  looks_total_ = 0;
  steps_thought_ahead_ = 0;
  ahead_note_.clear();
  looks_unanswered_ = false;
}

// Every output goes out through here, in the order it was made.
void SequenceExecutor::Emit(ExecutorOutput output) { outputs_.push_back(std::move(output)); }

void SequenceExecutor::EmitStop() {
  MobilityCommand stop;
  stop.utime = now_utime_;
  stop.command_id = NewId();
  stop.type = MobilityCommand::Type::kStop;
  Emit(stop);
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
  Emit(CurrentStatus());
  last_status_wall_ = now_wall_;
}

}  // namespace rover::sequence
