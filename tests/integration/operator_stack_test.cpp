// An operator's session on one running stack, hand-launched as the README says
// (`./rover launch configs/deploy/sim.yaml`, the real launcher), driven with the real
// `rover_seq submit` and watched with `rover_console --once`:
//   - the estimate starts at the simulated rover's height (the deployment gives the
//     estimator the world), not 9 cm off it;
//   - a sequence that declares keep-out zone 'mazatzal' completes, and the console shows
//     the zone; the next sequence, which declares none, drives straight through where
//     the zone was and completes (its start cleared the zone for the hazard monitor too),
//     and the console shows no zone in force;
//   - the recorder, started after the launcher as the README orders them, makes a log that
//     `logcheck` (no --joined) calls complete, saying which processes it joined.
#include "bus/bus.hpp"
#include "bus/channels.hpp"
#include "integration/run_support.hpp"
#include "launch/process_set.hpp"

#include <rover_msgs/heartbeat_t.hpp>
#include <rover_msgs/pose_t.hpp>
#include <rover_msgs/sim_truth_t.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <future>
#include <iterator>
#include <optional>
#include <set>

namespace rover::test {
namespace {

using Clock = std::chrono::steady_clock;

double Seconds(Clock::time_point since) { return std::chrono::duration<double>(Clock::now() - since).count(); }

TEST(OperatorStack, StartHeightAndZonesOverTwoSequences) {
  const std::string dir = OutDir("operator_stack");
  const std::string url = PrivateUrl(57);
  std::filesystem::current_path(SourceDir());  // the deployment's paths are relative to the repository root
  const std::vector<std::string> expected = {"rover_sim", "state_estimator", "hazard_monitor", "sequence_executor"};

  bus::Bus bus(url);
  std::set<std::string> alive;
  std::optional<rover_msgs::pose_t> first_pose;
  std::optional<rover_msgs::sim_truth_t> first_truth;
  bus.Subscribe<rover_msgs::heartbeat_t>(channels::kHeartbeat,
                                         [&](const rover_msgs::heartbeat_t& hb) { alive.insert(hb.process); });
  bus.Subscribe<rover_msgs::pose_t>(channels::kPose, [&](const rover_msgs::pose_t& p) {
    if (!first_pose) first_pose = p;
  });
  bus.Subscribe<rover_msgs::sim_truth_t>(channels::kSimTruth, [&](const rover_msgs::sim_truth_t& t) {
    if (!first_truth) first_truth = t;
  });

  launch::ProcessSet set(std::string(ROVER_BINARY_DIR) + "/bin", dir, false);
  set.Start({"launcher", "launcher", {"configs/deploy/sim.yaml", "--lcm-url", url}}, {});
  const auto start = Clock::now();
  while ((alive.size() < expected.size() || !first_pose || !first_truth) && Seconds(start) < 60) bus.Handle(50);
  for (const auto& name : expected) ASSERT_TRUE(alive.count(name)) << name << " sent no heartbeat";
  ASSERT_TRUE(first_pose && first_truth);

  // The estimate starts where the rover stands: the world's ground under its start.
  EXPECT_NEAR(first_pose->position[2], first_truth->position[2], 0.01)
      << "estimate z " << first_pose->position[2] << " m, truth z " << first_truth->position[2] << " m";
  EXPECT_NEAR(first_pose->position[0], first_truth->position[0], 0.01);
  EXPECT_NEAR(first_pose->position[1], first_truth->position[1], 0.01);

  // The recorder, after the launcher.
  const std::string log_path = dir + "/session.lcm";
  launch::ProcessSet recorder(std::string(ROVER_BINARY_DIR) + "/bin", dir, false);
  recorder.Start({"rover_recorder", "rover_recorder", {"--lcm-url", url, log_path}}, {});
  // Nothing is sent until the recorder hears the bus. Sent while it was still starting, the
  // first sequence reached the executor unrecorded, and the executor's first message in
  // the log was its answer, KEEPOUT_ZONES count 0: logcheck took it for a process started
  // after the recording and called its earlier heartbeats and statuses lost (1 run in 10
  // beside a burner). The recorder heartbeats once it has subscribed, and this test's one
  // socket hears in order what is sent after that: once every process of the stack has
  // been heard again, the log holds a message of each sent before any sequence.
  const auto recorder_start = Clock::now();
  while (!alive.count("rover_recorder") && Seconds(recorder_start) < 10) bus.Handle(50);
  ASSERT_TRUE(alive.count("rover_recorder")) << "rover_recorder sent no heartbeat within 10 s";
  alive.clear();
  auto all_heard = [&] {
    return std::all_of(expected.begin(), expected.end(), [&](const std::string& n) { return alive.count(n) > 0; });
  };
  while (!all_heard() && Seconds(recorder_start) < 20) bus.Handle(50);
  ASSERT_TRUE(all_heard()) << "the stack went quiet after the recorder started";

  // The operator's tools, as separate processes, while this test keeps the bus drained.
  auto run = [&](const std::string& command) {
    auto job = std::async(std::launch::async, [&] { return RunCommand(command); });
    while (job.wait_for(std::chrono::milliseconds(0)) != std::future_status::ready) bus.Handle(20);
    return job.get();
  };
  auto submit = [&](const std::string& name, const std::string& text) {
    const std::string path = dir + "/" + name;
    std::ofstream(path) << text;
    return run("timeout 120 " + Bin("rover_seq") + " submit " + path + " --lcm-url '" + url + "'");
  };
  auto console = [&] { return run(Bin("rover_console") + " --once --wait 2 --lcm-url '" + url + "'"); };

  // 1. A zone 1.5 m ahead, declared by a sequence that only turns in place.
  const auto first = submit("with_zone.seq",
                            "vo off step 50 cm\nkeepout mazatzal circle 1.5 m 0 m radius 0.3 m\nturn 10 deg\n");
  ASSERT_EQ(first.exit_code, 0) << first.output;
  EXPECT_NE(first.output.find("[completed"), std::string::npos) << first.output;
  const auto during = console();
  // Started after the zone was sent: the hazard monitor's status tells it.
  EXPECT_NE(during.output.find("ZONES     the hazard monitor holds zones, nearest mazatzal"), std::string::npos)
      << during.output;

  // 2. No zones: it drives north through where 'mazatzal' was.
  const auto second = submit("no_zones.seq", "vo off step 50 cm\nturnto 0 deg\ndrive 2 m\n");
  EXPECT_EQ(second.exit_code, 0) << second.output;
  EXPECT_NE(second.output.find("[completed"), std::string::npos) << second.output;
  EXPECT_EQ(second.output.find("keep-out zone 'mazatzal'"), std::string::npos) << second.output;
  const auto after = console();
  EXPECT_NE(after.output.find("ZONES     none in force (the hazard monitor holds none)"), std::string::npos)
      << after.output;

  recorder.StopAll();
  set.StopAll();
  const auto check = RunCommand(Bin("logcheck") + " " + log_path);
  EXPECT_EQ(check.exit_code, 0) << check.output;
  EXPECT_NE(check.output.find("log complete: yes"), std::string::npos) << check.output;
  EXPECT_NE(check.output.find("joined: the recording began on a running bus: "), std::string::npos) << check.output;
  EXPECT_NE(check.output.find("sequence_executor"), std::string::npos) << check.output;
  // The recorder's own closing report says the same.
  std::ifstream recorder_log(dir + "/rover_recorder.log");
  const std::string recorder_text((std::istreambuf_iterator<char>(recorder_log)), std::istreambuf_iterator<char>());
  EXPECT_NE(recorder_text.find("log complete: yes"), std::string::npos) << recorder_text;
}

}  // namespace
}  // namespace rover::test
