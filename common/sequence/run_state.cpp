#include "sequence/run_state.hpp"

#include "config/file_read.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <yaml-cpp/yaml.h>

#include <cerrno>
#include <climits>
#include <cstring>
#include <filesystem>
#include <stdexcept>

namespace rover::sequence {

namespace {

constexpr std::size_t kMaxStateFileBytes = 64 * 1024;

const SequenceState kStates[] = {SequenceState::kIdle,      SequenceState::kRunning,
                                 SequenceState::kPaused,    SequenceState::kCompleted,
                                 SequenceState::kAborted,   SequenceState::kRejected};

[[noreturn]] void WriteFailed(const std::string& path, const std::string& step) {
  throw std::runtime_error(path + ": cannot write the executor state file: " + step + ": " +
                           std::strerror(errno));
}

void WriteAll(int fd, const std::string& text, const std::string& path) {
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) WriteFailed(path, "write");
    done += static_cast<std::size_t>(n);
  }
}

}  // namespace

RunState RunStateOf(const SequenceStatus& status) {
  RunState r;
  r.submission_id = status.submission_id;
  r.sequence_name = status.sequence_name;
  r.state = status.state;
  r.command_index = status.command_index;
  r.step_index = status.step_index;
  return r;
}

bool WasInterrupted(const RunState& state) {
  return state.state == SequenceState::kRunning || state.state == SequenceState::kPaused;
}

std::string InterruptedDetail(const RunState& state) {
  std::string where;
  if (state.command_index >= 0) {
    where = " at command " + std::to_string(state.command_index) + ", step " +
            std::to_string(state.step_index);
  }
  return "sequence_executor restarted while sequence '" + state.sequence_name + "' (submission " +
         std::to_string(state.submission_id) + ") was " + ToString(state.state) + where +
         ": not resumed; STOP commanded";
}

std::string FormatRunState(const RunState& state) {
  YAML::Emitter out;
  out << YAML::Comment("sequence_executor state (executor.state_file): replaced on every change");
  out << YAML::BeginMap;
  out << YAML::Key << "submission_id" << YAML::Value << state.submission_id;
  out << YAML::Key << "sequence_name" << YAML::Value << YAML::DoubleQuoted << state.sequence_name;
  out << YAML::Key << "state" << YAML::Value << ToString(state.state);
  out << YAML::Key << "command_index" << YAML::Value << state.command_index;
  out << YAML::Key << "step_index" << YAML::Value << state.step_index;
  out << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

RunState ParseRunState(const std::string& text, const std::string& source) {
  const auto root = config::ConfigNode::FromString(text, source);
  root.CheckKeys({"submission_id", "sequence_name", "state", "command_index", "step_index"});
  RunState r;
  if (!root.Has("submission_id")) root.Fail("missing key \"submission_id\" (expected an integer)");
  root.Get("submission_id", r.submission_id);
  if (root.Has("sequence_name")) r.sequence_name = root["sequence_name"].AsString();
  std::string state = root.RequireString("state");
  root.GetEnum("state", state, {"idle", "running", "paused", "completed", "aborted", "rejected"});
  for (SequenceState s : kStates) {
    if (state == ToString(s)) r.state = s;
  }
  root.Get("command_index", r.command_index, -1, INT_MAX);
  root.Get("step_index", r.step_index, 0, INT_MAX);
  return r;
}

std::optional<RunState> ReadRunStateFile(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::exists(std::filesystem::symlink_status(path, ec))) return std::nullopt;
  return ParseRunState(
      config::ReadBoundedRegularFile(path, kMaxStateFileBytes, "executor state file (YAML)"), path);
}

void WriteRunStateFile(const std::string& path, const RunState& state) {
  const std::string text = FormatRunState(state);
  const std::filesystem::path target(path);
  const std::string dir = target.has_parent_path() ? target.parent_path().string() : ".";
  const std::string temp = path + ".tmp" + std::to_string(getpid());
  const int fd = open(temp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) WriteFailed(path, "create " + temp);
  try {
    WriteAll(fd, text, path);
    if (fsync(fd) != 0) WriteFailed(path, "fsync");
  } catch (...) {
    close(fd);
    unlink(temp.c_str());
    throw;
  }
  close(fd);
  if (rename(temp.c_str(), path.c_str()) != 0) {
    const int saved = errno;
    unlink(temp.c_str());
    errno = saved;
    WriteFailed(path, "rename");
  }
  // The rename itself reaches the disk with the directory.
  const int dir_fd = open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir_fd >= 0) {
    fsync(dir_fd);
    close(dir_fd);
  }
}

}  // namespace rover::sequence
