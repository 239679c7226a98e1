// The executor's state file and what a restarted executor does with it.
#include "sequence/run_state.hpp"

#include "config/yaml_config.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <system_error>
#include <vector>

namespace fs = std::filesystem;
using namespace rover::sequence;

namespace {

// The directories TempDir made, removed when the test process exits: each ctest entry is a
// process of its own, so nothing is left behind in the temporary folder.
struct TempDirs {
  std::vector<fs::path> dirs;
  ~TempDirs() {
    std::error_code ignored;
    for (const fs::path& d : dirs) fs::remove_all(d, ignored);
  }
};

std::string TempDir(const std::string& name) {
  const fs::path dir = fs::path(testing::TempDir()) / ("run_state_" + name + "_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  static TempDirs made;
  made.dirs.push_back(dir);
  return dir.string();
}

RunState Running() {
  RunState r;
  r.submission_id = 17;
  r.sequence_name = "odd \"name\": with # and\nnewline";
  r.state = SequenceState::kRunning;
  r.command_index = 3;
  r.step_index = 2;
  return r;
}

TEST(RunState, RoundTripsThroughTheFile) {
  const std::string path = TempDir("round") + "/executor_state.yaml";
  EXPECT_FALSE(ReadRunStateFile(path));  // first start: no file
  WriteRunStateFile(path, Running());
  const auto back = ReadRunStateFile(path);
  ASSERT_TRUE(back);
  EXPECT_EQ(*back, Running());
  RunState done = Running();
  done.state = SequenceState::kCompleted;
  WriteRunStateFile(path, done);
  EXPECT_EQ(*ReadRunStateFile(path), done);
  // Replaced by rename: no temporary file is left behind.
  int files = 0;
  for (const auto& e : fs::directory_iterator(fs::path(path).parent_path())) files += e.is_regular_file();
  EXPECT_EQ(files, 1);
}

TEST(RunState, OnlyRunningOrPausedWasInterrupted) {
  RunState r = Running();
  EXPECT_TRUE(WasInterrupted(r));
  r.state = SequenceState::kPaused;
  EXPECT_TRUE(WasInterrupted(r));
  for (auto s : {SequenceState::kIdle, SequenceState::kCompleted, SequenceState::kAborted,
                 SequenceState::kRejected}) {
    r.state = s;
    EXPECT_FALSE(WasInterrupted(r));
  }
  EXPECT_EQ(InterruptedDetail(Running()),
            "sequence_executor restarted while sequence 'odd \"name\": with # and\nnewline' "
            "(submission 17) was running at command 3, step 2: not resumed; STOP commanded");
}

TEST(RunState, BadFilesAreOneLineErrors) {
  const std::string dir = TempDir("bad");
  const std::string path = dir + "/s.yaml";
  std::ofstream(path) << "submission_id: 3\nstate: driving\n";
  try {
    ReadRunStateFile(path);
    FAIL() << "accepted state: driving";
  } catch (const rover::config::ConfigError& e) {
    EXPECT_EQ(std::string(e.what()), path +
                                         ": state: expected one of: idle, running, paused, completed, "
                                         "aborted, rejected, got \"driving\"");
  }
  std::ofstream(path) << "state: running\n";
  EXPECT_THROW(ReadRunStateFile(path), rover::config::ConfigError);  // no submission id
  EXPECT_THROW(ReadRunStateFile(dir), rover::config::ConfigError);   // a directory
  const std::string fifo = dir + "/fifo";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_THROW(ReadRunStateFile(fifo), rover::config::ConfigError);  // refused, not waited on
}

TEST(RunState, UnwritablePlaceIsOneLine) {
  try {
    WriteRunStateFile("/nonexistent/dir/state.yaml", Running());
    FAIL() << "wrote into a missing directory";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("/nonexistent/dir/state.yaml: cannot write the executor state file: ", 0), 0u)
        << e.what();
  }
}

TEST(RunState, RecordedFromTheExecutorStatus) {
  SequenceStatus s;
  s.submission_id = 9;
  s.sequence_name = "a.seq";
  s.state = SequenceState::kPaused;
  s.command_index = 1;
  s.step_index = 4;
  const RunState r = RunStateOf(s);
  EXPECT_EQ(r.submission_id, 9);
  EXPECT_EQ(r.sequence_name, "a.seq");
  EXPECT_EQ(r.state, SequenceState::kPaused);
  EXPECT_EQ(r.command_index, 1);
  EXPECT_EQ(r.step_index, 4);
}

// A restarted executor: STOP once, then the old submission ABORTED "interrupted"; it stays
// the status (the periodic status repeats it) until a new sequence is submitted.
TEST(RecordInterrupted, CommandsStopOnceAndReportsTheOldSubmissionAborted) {
  SequenceExecutor ex(ExecutorOptions{}, 1000);
  ex.RecordInterrupted(17, "demo.seq", InterruptedDetail(Running()));
  const auto out = ex.TakeOutputs();
  ASSERT_EQ(out.size(), 2u);
  const auto* stop = std::get_if<MobilityCommand>(&out[0]);
  ASSERT_NE(stop, nullptr);
  EXPECT_EQ(stop->type, MobilityCommand::Type::kStop);
  const auto* status = std::get_if<SequenceStatus>(&out[1]);
  ASSERT_NE(status, nullptr);
  EXPECT_EQ(status->submission_id, 17);
  EXPECT_EQ(status->sequence_name, "demo.seq");
  EXPECT_EQ(status->state, SequenceState::kAborted);
  EXPECT_EQ(status->abort_reason, "interrupted");
  EXPECT_EQ(status->detail, InterruptedDetail(Running()));
  EXPECT_FALSE(ex.Active());
  // Time passes: only statuses, no motion, and the same verdict.
  for (int i = 1; i <= 5; ++i) ex.Tick(1'000'000 * i, 1.0 * i);
  for (const auto& o : ex.TakeOutputs()) {
    ASSERT_TRUE(std::holds_alternative<SequenceStatus>(o));
    EXPECT_EQ(std::get<SequenceStatus>(o).abort_reason, "interrupted");
  }
}

}  // namespace
