// Replay: the demo drive, recorded by the scenario runner's rover_recorder (standard LCM
// log format, nothing lost, checked by logcheck), is played back with the real
// lcm-logplayer, at -s 50 and at -s 250 (a virtual-time log is stamped with rover time), into a fresh state_estimator; its poses
// must equal those recorded, byte for byte, message for message. And estimator_replay, the
// same estimator offline over the same inputs, gives the same poses again.
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

// Plays the recorded inputs in `log` into a fresh state_estimator on a bus of its own, at
// lcm-logplayer speed `speed`, and returns the poses it published (recorded by
// rover_recorder, which loses nothing).
std::vector<std::string> ReplayPoses(const std::string& out, const std::string& log, const std::string& speed,
                                     int port_offset) {
  const std::string url = PrivateUrl(port_offset);
  const std::vector<std::string> env = {"ROVER_LCM_URL=" + url};
  const std::string replay_log = out + "/replayed_x" + speed + ".lcm";
  std::filesystem::remove(replay_log);
  launch::ProcessSet set(std::string(ROVER_BINARY_DIR) + "/bin", out, false);
  set.Start({"replay_recorder_x" + speed, "rover_recorder", {"--lcm-url", url, replay_log}}, env);
  auto args = EstimatorArgs(out + "/commands.txt");
  EXPECT_FALSE(args.empty()) << "no state_estimator line in commands.txt";
  if (args.empty()) return {};
  set.Start({"replay_state_estimator_x" + speed, "state_estimator", args}, env);
  // Subscribed before the first input is played: wait for the estimator's heartbeat.
  {
    lcm::LCM probe(url);
    bool heard = false;
    struct Listener {
      bool* heard;
      void On(const lcm::ReceiveBuffer*, const std::string&) { *heard = true; }
    } listener{&heard};
    probe.subscribe(channels::kHeartbeat, &Listener::On, &listener);
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    while (!heard && std::chrono::steady_clock::now() < until) probe.handleTimeout(100);
    EXPECT_TRUE(heard) << "the replay's state_estimator sent no heartbeat";
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
  }
  set.Start({"lcm-logplayer_x" + speed, "/usr/bin/lcm-logplayer",
             {"--lcm-url=" + url, "-s", speed, "-e", "^(IMU|WHEEL_ODOMETRY|VO_UPDATE|NEW_SITE|ROVER_CLOCK)$", log}},
            env);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(180);
  while (set.Running("lcm-logplayer_x" + speed) && std::chrono::steady_clock::now() < deadline) set.Poll(100);
  EXPECT_FALSE(set.Running("lcm-logplayer_x" + speed)) << "lcm-logplayer did not finish";
  std::this_thread::sleep_for(std::chrono::milliseconds(1000));  // last poses reach the recorder
  set.StopAll();
  return ReadChannel(replay_log, channels::kPose);
}

// Every recorded pose must be reproduced exactly, message for message; the live estimator
// was stopped with the run, so a replay may add a few poses at the end from inputs it
// never processed.
void ExpectSamePoses(const std::vector<std::string>& recorded, const std::vector<std::string>& replayed,
                     const std::string& what) {
  ASSERT_GE(replayed.size(), recorded.size()) << what;
  EXPECT_LE(replayed.size(), recorded.size() + 20) << what;
  std::size_t mismatches = 0, first_mismatch = 0;
  for (std::size_t i = 0; i < recorded.size(); ++i) {
    if (recorded[i] != replayed[i] && mismatches++ == 0) first_mismatch = i;
  }
  EXPECT_EQ(mismatches, 0u) << what << ": " << mismatches << " differing poses, the first #" << first_mismatch
                            << " of " << recorded.size();
}

TEST(Replay, DemoLogReplaysIntoAFreshEstimatorWithEveryPoseByteIdentical) {
  // The demo (VO in the loop, the default 50x), recorded by the scenario runner.
  std::filesystem::current_path(SourceDir());  // the recorded arguments are relative to it
  const std::string out = OutDir("replay");
  const auto run = RunCommand(Bin("scenario_runner") + " configs/scenarios/demo.yaml --quiet --out " + out);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const auto check = RunCommand(Bin("logcheck") + " " + out + "/log.lcm");
  ASSERT_EQ(check.exit_code, 0) << "the demo's log lost messages:\n" << check.output;
  const auto recorded = ReadChannel(out + "/log.lcm", channels::kPose);
  ASSERT_GT(recorded.size(), 1000u);

  ExpectSamePoses(recorded, ReplayPoses(out, out + "/log.lcm", "50", 11), "lcm-logplayer -s 50");
  ExpectSamePoses(recorded, ReplayPoses(out, out + "/log.lcm", "250", 12), "lcm-logplayer -s 250");
}

// estimator_replay (tools/estimator_replay): the estimator again, offline, over the demo's
// logged inputs. With the run's own settings every replayed pose is the logged one (the
// tool prints the largest position difference: 0 m) and the pose honesty is the logged
// one (to 1 %); a changed setting changes what it claims (without the slip memory the demo's
// horizontal NEES is larger: the wheels' sigma falls back to the 2 % prior); a misspelt
// key is refused in one line that names it, and a file that holds no run, too.
TEST(EstimatorReplay, TheDemosInputsGiveTheLoggedPosesAgainAndASettingChangesThem) {
  std::filesystem::current_path(SourceDir());
  const std::string out = OutDir("estimator_replay");
  const auto run = RunCommand(Bin("scenario_runner") + " configs/scenarios/demo.yaml --rate max --quiet --no-plot --out " + out);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const std::string log = out + "/log.lcm";

  const auto same = RunCommand(Bin("estimator_replay") + " " + log);
  ASSERT_EQ(same.exit_code, 0) << same.output;
  EXPECT_NE(same.output.find("largest position difference from the log over the first"), std::string::npos)
      << same.output;
  EXPECT_NE(same.output.find(": 0 m\n"), std::string::npos) << "replayed poses differ from the logged:\n" << same.output;
  // "logged  : N poses, heading NEES mean H (...), horizontal NEES mean X (...)" and the same
  // for "replayed": the horizontal means as printed.
  auto horizontal_nees = [](const std::string& text, const std::string& who) {
    const auto line = text.find(who + ": ");
    const auto at = text.find("horizontal NEES mean ", line);
    if (line == std::string::npos || at == std::string::npos) return -1.0;
    return std::stod(text.substr(at + 21));
  };
  const double logged = horizontal_nees(same.output, "logged  ");
  ASSERT_GT(logged, 0.0) << same.output;
  // (The replay may judge one pose more than the log holds: the last, after the recorder stopped.)
  EXPECT_NEAR(horizontal_nees(same.output, "replayed"), logged, 0.01 * logged) << same.output;

  const auto changed = RunCommand(Bin("estimator_replay") + " " + log + " --set estimator.slip_memory_updates=0");
  ASSERT_EQ(changed.exit_code, 0) << changed.output;
  EXPECT_EQ(horizontal_nees(changed.output, "logged  "), logged) << changed.output;
  EXPECT_GT(horizontal_nees(changed.output, "replayed"), 1.5 * logged) << changed.output;

  const auto misspelt = RunCommand(Bin("estimator_replay") + " " + log + " --set estimator.slip_memory=0");
  EXPECT_EQ(misspelt.exit_code, 2) << misspelt.output;
  EXPECT_NE(misspelt.output.find("estimator.slip_memory: unknown key"), std::string::npos) << misspelt.output;
  const auto no_run = RunCommand(Bin("estimator_replay") + " " + out + "/summary.json");
  EXPECT_EQ(no_run.exit_code, 2) << no_run.output;
  EXPECT_NE(no_run.output.find("no POSE or no SIM_TRUTH in the log"), std::string::npos) << no_run.output;
}

}  // namespace
}  // namespace rover::test
