// The executor's state file (`executor.state_file`): which sequence it is running, kept
// on disk so that an executor restarted after a crash or a kill knows the sequence it was
// running was interrupted. It then reports that sequence ABORTED with reason
// "interrupted", commands STOP once, and never resumes motion by itself.
//
// The file is a small YAML mapping, replaced atomically (a temporary file in the same
// directory, fsync, rename, fsync of the directory), so a reader sees the old record or
// the new one, never half of one:
//   submission_id: 17
//   sequence_name: "configs/sequences/demo_drive.seq"
//   state: running          # idle, running, paused, completed, aborted, rejected
//   command_index: 3
//   step_index: 2
#pragma once

#include "sequence/executor.hpp"

#include <cstdint>
#include <optional>
#include <string>

namespace rover::sequence {

struct RunState {
  int64_t submission_id = -1;
  std::string sequence_name;
  SequenceState state = SequenceState::kIdle;
  int command_index = -1;
  int step_index = 0;
  bool operator==(const RunState& o) const {
    return submission_id == o.submission_id && sequence_name == o.sequence_name &&
           state == o.state && command_index == o.command_index && step_index == o.step_index;
  }
  bool operator!=(const RunState& o) const { return !(*this == o); }
};

// The record of a status (what the shell writes after every change).
RunState RunStateOf(const SequenceStatus& status);

// A sequence that was running or paused when the file was written: a restarted executor
// must report it interrupted.
bool WasInterrupted(const RunState& state);

// "sequence_executor restarted while sequence 'x' (submission 17) was running at command
// 3, step 2: not resumed; STOP commanded"
std::string InterruptedDetail(const RunState& state);

std::string FormatRunState(const RunState& state);
// Throws config::ConfigError naming `source` and the key.
RunState ParseRunState(const std::string& text, const std::string& source);

// Nothing when the file does not exist (first start). Throws config::ConfigError when it
// exists but is not a regular file of at most 64 kB or does not parse.
std::optional<RunState> ReadRunStateFile(const std::string& path);
// Atomic replace. Throws std::runtime_error "<path>: cannot write the executor state
// file: <reason>".
void WriteRunStateFile(const std::string& path, const RunState& state);

}  // namespace rover::sequence
