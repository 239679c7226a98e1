// Replay (ARCHITECTURE.md, use 2): a drive recorded with the real lcm-logger is played back
// with the real lcm-logplayer into a fresh state_estimator; its poses must equal those
// recorded, message for message.
#include "bus/channels.hpp"
#include "integration/run_support.hpp"
#include "launch/process_set.hpp"

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

namespace rover::test {
namespace {

std::vector<std::string> ReadChannel(const std::string& log_path, const std::string& channel) {
  std::vector<std::string> messages;
  lcm::LogFile log(log_path, "r");
  EXPECT_TRUE(log.good()) << log_path;
  for (const lcm::LogEvent* ev = log.readNextEvent(); ev != nullptr; ev = log.readNextEvent()) {
    if (ev->channel == channel) {
      messages.emplace_back(static_cast<const char*>(ev->data), ev->datalen);
    }
  }
  return messages;
}

// The state_estimator's arguments in the recorded run (scenario_runner writes them).
std::vector<std::string> EstimatorArgs(const std::string& commands_path) {
  std::ifstream in(commands_path);
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream ss(line);
    std::string name;
    ss >> name;
    if (name != "state_estimator") continue;
    std::vector<std::string> args;
    for (std::string a; ss >> a;) args.push_back(a);
    return args;
  }
  return {};
}

TEST(Replay, StateEstimatorReproducesRecordedPosesFromLogplayer) {
  // Record a blind drive at 10x real time (see the scenario file for why not 50x; the
  // estimator's handling of VO updates is shown deterministic in its unit tests).
  std::filesystem::current_path(SourceDir());  // the recorded arguments are relative to it
  const std::string out = OutDir("replay");
  const auto run = RunCommand(Bin("scenario_runner") +
                              " configs/scenarios/replay_drive.yaml --quiet --out " + out);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const auto recorded = ReadChannel(out + "/log.lcm", channels::kPose);
  ASSERT_GT(recorded.size(), 100u);

  // Replay into a fresh estimator on a bus of its own, recording what it publishes.
  const std::string url = PrivateUrl(11);
  const std::vector<std::string> env = {"ROVER_LCM_URL=" + url};
  const std::string replay_log = out + "/replayed_poses.lcm";
  launch::ProcessSet set(std::string(ROVER_BINARY_DIR) + "/bin", out, false);
  set.Start({"lcm-logger", "/usr/bin/lcm-logger",
             {"--lcm-url=" + url, "-q", "-f", "-c", channels::kPose, replay_log}}, env);
  auto args = EstimatorArgs(out + "/commands.txt");
  ASSERT_FALSE(args.empty()) << "no state_estimator line in commands.txt";
  set.Start({"replay_state_estimator", "state_estimator", args}, env);
  std::this_thread::sleep_for(std::chrono::milliseconds(700));  // subscribed
  set.Start({"lcm-logplayer", "/usr/bin/lcm-logplayer",
             {"--lcm-url=" + url, "-e", "^(IMU|WHEEL_ODOMETRY|VO_UPDATE|NEW_SITE|ROVER_CLOCK)$",
              out + "/log.lcm"}}, env);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (set.Running("lcm-logplayer") && std::chrono::steady_clock::now() < deadline) set.Poll(100);
  ASSERT_FALSE(set.Running("lcm-logplayer")) << "lcm-logplayer did not finish";
  std::this_thread::sleep_for(std::chrono::milliseconds(700));  // last poses reach the logger
  set.StopAll();

  const auto replayed = ReadChannel(replay_log, channels::kPose);
  // The live estimator was stopped with the run, so the replay may add a few poses at the
  // end from inputs it never processed; every recorded pose must be reproduced exactly.
  ASSERT_GE(replayed.size(), recorded.size());
  EXPECT_LE(replayed.size(), recorded.size() + 20);
  std::size_t mismatches = 0, first_mismatch = 0;
  for (std::size_t i = 0; i < recorded.size(); ++i) {
    if (recorded[i] != replayed[i] && mismatches++ == 0) first_mismatch = i;
  }
  EXPECT_EQ(mismatches, 0u) << "first differing pose: #" << first_mismatch << " of "
                            << recorded.size();
}

}  // namespace
}  // namespace rover::test
