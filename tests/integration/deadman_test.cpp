// A dead commander stops the rover: the real rover_sim on a private bus, driven by
// MOBILITY_COMMAND messages from this test, which plays the sequence_executor (or plays
// dead). And a restarted sequence_executor reports the sequence it was running as
// interrupted, commands STOP once and moves nothing.
#include "bus/bus.hpp"
#include "bus/channels.hpp"
#include "integration/run_support.hpp"
#include "launch/process_set.hpp"

#include <rover_msgs/heartbeat_t.hpp>
#include <rover_msgs/mobility_command_t.hpp>
#include <rover_msgs/mobility_status_t.hpp>
#include <rover_msgs/rover_clock_t.hpp>
#include <rover_msgs/sequence_status_t.hpp>
#include <rover_msgs/sim_truth_t.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <functional>
#include <iostream>
#include <optional>
#include <sstream>

namespace rover::test {
namespace {

using Clock = std::chrono::steady_clock;
using rover_msgs::mobility_status_t;

double Since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// rover_sim alone on a private bus, on flat sand, with the estimator lockstep off (no
// estimator here) and the default dead-man (configs/rover.yaml: 1.5 s).
class DeadmanRig {
 public:
  explicit DeadmanRig(const std::string& name, int url_offset)
      : url_(PrivateUrl(url_offset)), bus_(url_), set_(std::string(ROVER_BINARY_DIR) + "/bin", OutDir(name), false) {
    // configs/rover.yaml as it is (the dead-man's default), but with no estimator here the
    // clock must not wait for poses.
    const std::string config = OutDir(name + "_config") + "/rover.yaml";
    std::ifstream in(SourceDir() + "/configs/rover.yaml");
    std::string text, line;
    while (std::getline(in, line)) {
      if (line.find("  max_lead_s:") == 0) line = "  max_lead_s: 0";
      text += line + "\n";
    }
    std::ofstream(config) << text;
    bus_.Subscribe<mobility_status_t>(channels::kMobilityStatus, [this](const mobility_status_t& s) {
      if (s.command_id != command_id_) return;
      if (s.state == mobility_status_t::STATE_MOVING) moving_seen_ = true;
      if (s.state != mobility_status_t::STATE_MOVING && s.state != mobility_status_t::STATE_IDLE && !end_) {
        end_ = s;
        end_wall_ = Clock::now();
      }
    });
    bus_.Subscribe<rover_msgs::sim_truth_t>(channels::kSimTruth, [this](const rover_msgs::sim_truth_t& t) {
      truth_ = t;
    });
    bus_.Subscribe<rover_msgs::heartbeat_t>(channels::kHeartbeat, [this](const rover_msgs::heartbeat_t& h) {
      if (h.process == "rover_sim") sim_alive_ = true;
    });
    set_.Start({"rover_sim", "rover_sim",
                {"--config", config, "--world",
                 SourceDir() + "/configs/worlds/featureless_sand.yaml", "--start", "0,0,0"}},
               {"ROVER_LCM_URL=" + url_});
  }
  ~DeadmanRig() { set_.StopAll(); }

  // Waits for the simulator's heartbeat and a truth message (its clock runs).
  bool WaitUp() {
    const auto start = Clock::now();
    while ((!sim_alive_ || !truth_) && Since(start) < 20) bus_.Handle(50);
    return sim_alive_ && truth_.has_value();
  }

  void Drive(std::int64_t id, double distance_m) {
    command_id_ = id;
    rover_msgs::mobility_command_t c{};
    c.utime = truth_->utime;
    c.command_id = id;
    c.type = rover_msgs::mobility_command_t::TYPE_ARC;
    c.distance_m = distance_m;
    bus_.Publish(channels::kMobilityCommand, c);
  }

  void Heartbeat(const std::string& process) {
    rover_msgs::heartbeat_t hb{};
    hb.utime = truth_ ? truth_->utime : 0;
    hb.process = process;
    hb.seq = heartbeat_seq_++;
    bus_.Publish(channels::kHeartbeat, hb);
  }

  // Handles messages for `seconds` of wall time, or until `until()` says so.
  void Run(double seconds, const std::function<bool()>& until = nullptr) {
    const auto start = Clock::now();
    while (Since(start) < seconds && !(until && until())) bus_.Handle(10);
  }

  bool running() const { return set_.Running("rover_sim"); }
  bool moving_seen() const { return moving_seen_; }
  const std::optional<mobility_status_t>& end() const { return end_; }
  Clock::time_point end_wall() const { return end_wall_; }
  const std::optional<rover_msgs::sim_truth_t>& truth() const { return truth_; }

 private:
  std::string url_;
  bus::Bus bus_;
  launch::ProcessSet set_;
  std::int64_t command_id_ = -1;
  std::int64_t heartbeat_seq_ = 0;
  bool moving_seen_ = false, sim_alive_ = false;
  std::optional<mobility_status_t> end_;
  Clock::time_point end_wall_;
  std::optional<rover_msgs::sim_truth_t> truth_;
};

// No executor at all: the command itself is the last word from the commander. A 10 m drive
// (250 s of rover time, 5 s of wall time at 50x) stops within 2 s of wall time.
TEST(DeadMan, SilentCommanderStopsTheRoverWithinTwoSecondsOfWallTime) {
  DeadmanRig rig("deadman_silent", 31);
  ASSERT_TRUE(rig.WaitUp()) << "rover_sim did not come up";
  const auto sent = Clock::now();
  rig.Drive(501, 10.0);
  rig.Run(4.0, [&] { return rig.end().has_value(); });
  ASSERT_TRUE(rig.end()) << "the rover did not stop within 4 s of wall time";
  const double stop_s = std::chrono::duration<double>(rig.end_wall() - sent).count();
  EXPECT_TRUE(rig.moving_seen());
  EXPECT_EQ(rig.end()->state, static_cast<int>(mobility_status_t::STATE_STOPPED)) << rig.end()->detail;
  EXPECT_NE(rig.end()->detail.find("dead-man: nothing from sequence_executor"), std::string::npos)
      << rig.end()->detail;
  std::cout << "stopped by the dead-man " << stop_s << " s of wall time after the last command\n";
  EXPECT_LE(stop_s, 2.0);
  EXPECT_GE(stop_s, 1.4);  // not before the dead-man's 1.5 s
  EXPECT_LT(rig.end()->wheel_distance_m, 5.0);
  // Stopped means stopped: the truth odometer stands still from here on.
  rig.Run(0.3);
  const double odometer = rig.truth()->odometer_m;
  rig.Run(1.0);
  EXPECT_NEAR(rig.truth()->odometer_m, odometer, 1e-6);
  EXPECT_TRUE(rig.running());
}

// The executor's heartbeat keeps a drive going past the timeout; when it stops, the rover
// stops within 2 s of the last heartbeat. Another process's heartbeat does not count.
TEST(DeadMan, ExecutorHeartbeatKeepsTheDriveGoingUntilItStops) {
  DeadmanRig rig("deadman_heartbeat", 32);
  ASSERT_TRUE(rig.WaitUp()) << "rover_sim did not come up";
  rig.Drive(502, 12.0);  // 300 s of rover time: 6 s of wall time
  Clock::time_point last_heartbeat = Clock::now();
  const auto start = Clock::now();
  while (Since(start) < 3.0 && !rig.end()) {
    if (Since(last_heartbeat) >= 0.5) {
      rig.Heartbeat("sequence_executor");
      last_heartbeat = Clock::now();
    }
    rig.Run(0.05);
  }
  ASSERT_FALSE(rig.end()) << "stopped while the executor was alive: " << rig.end()->detail;
  EXPECT_TRUE(rig.moving_seen());
  // The executor dies; the estimator carries on.
  const auto died = last_heartbeat;
  auto last_other = Clock::now();
  rig.Run(4.0, [&] {
    if (Since(last_other) >= 0.5) {
      rig.Heartbeat("state_estimator");
      last_other = Clock::now();
    }
    return rig.end().has_value();
  });
  ASSERT_TRUE(rig.end()) << "the rover did not stop after the executor's heartbeat stopped";
  EXPECT_EQ(rig.end()->state, static_cast<int>(mobility_status_t::STATE_STOPPED)) << rig.end()->detail;
  EXPECT_NE(rig.end()->detail.find("dead-man"), std::string::npos) << rig.end()->detail;
  const double stop_s = std::chrono::duration<double>(rig.end_wall() - died).count();
  std::cout << "stopped by the dead-man " << stop_s << " s of wall time after the last heartbeat\n";
  EXPECT_LE(stop_s, 2.0);
  EXPECT_LT(rig.end()->wheel_distance_m, 11.0);
}

// A restarted executor whose state file says a sequence was running: STOP once, that
// submission ABORTED "interrupted", the file updated, and no motion.
TEST(ExecutorRestart, ReportsTheInterruptedSequenceAndCommandsStopOnce) {
  const std::string dir = OutDir("executor_restart");
  const std::string state_file = dir + "/executor_state.yaml";
  std::ofstream(state_file) << "submission_id: 77\nsequence_name: \"drive_far.seq\"\nstate: running\n"
                               "command_index: 2\nstep_index: 5\n";
  const std::string url = PrivateUrl(33);
  bus::Bus bus(url);
  int stops = 0, motions = 0;
  std::optional<rover_msgs::sequence_status_t> interrupted;
  bus.Subscribe<rover_msgs::mobility_command_t>(channels::kMobilityCommand,
                                                [&](const rover_msgs::mobility_command_t& c) {
                                                  if (c.type == rover_msgs::mobility_command_t::TYPE_STOP) ++stops;
                                                  else ++motions;
                                                });
  bus.Subscribe<rover_msgs::sequence_status_t>(channels::kSequenceStatus,
                                               [&](const rover_msgs::sequence_status_t& s) {
                                                 if (s.submission_id == 77 && !interrupted) interrupted = s;
                                               });
  launch::ProcessSet set(std::string(ROVER_BINARY_DIR) + "/bin", dir, false);
  set.Start({"sequence_executor", "sequence_executor",
             {"--config", SourceDir() + "/configs/rover.yaml", "--state-file", state_file}},
            {"ROVER_LCM_URL=" + url});
  const auto start = Clock::now();
  rover_msgs::rover_clock_t clock{};
  clock.utime = 5'000'000;
  clock.rate = 50.0;
  while (Since(start) < 4.0) {  // the rover clock, as rover_sim would send it
    bus.Publish(channels::kClock, clock);
    clock.utime += 20'000;
    bus.Handle(20);
  }
  ASSERT_TRUE(interrupted) << "no status for submission 77";
  EXPECT_EQ(interrupted->state, static_cast<int>(rover_msgs::sequence_status_t::STATE_ABORTED));
  EXPECT_EQ(interrupted->abort_reason, "interrupted");
  EXPECT_EQ(interrupted->sequence_name, "drive_far.seq");
  EXPECT_NE(interrupted->detail.find("was running at command 2, step 5: not resumed"), std::string::npos)
      << interrupted->detail;
  EXPECT_EQ(stops, 1);
  EXPECT_EQ(motions, 0);
  EXPECT_TRUE(set.Running("sequence_executor"));
  set.StopAll();
  std::ifstream in(state_file);
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_NE(text.str().find("state: aborted"), std::string::npos) << text.str();

  // Restarted again: the sequence was already reported, so nothing is commanded.
  stops = 0;
  interrupted.reset();
  launch::ProcessSet again(std::string(ROVER_BINARY_DIR) + "/bin", dir, false);
  again.Start({"sequence_executor", "sequence_executor",
               {"--config", SourceDir() + "/configs/rover.yaml", "--state-file", state_file}},
              {"ROVER_LCM_URL=" + url});
  const auto start2 = Clock::now();
  while (Since(start2) < 3.0) {
    bus.Publish(channels::kClock, clock);
    clock.utime += 20'000;
    bus.Handle(20);
  }
  EXPECT_EQ(stops, 0);
  EXPECT_EQ(motions, 0);
  again.StopAll();
}

TEST(ExecutorRestart, UnwritableStateFileIsOneLineAndExitTwo) {
  const auto r = RunCommand(Bin("sequence_executor") + " --state-file /nonexistent/dir/state.yaml --lcm-url '" +
                            PrivateUrl(34) + "'");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
  EXPECT_EQ(r.output.rfind("/nonexistent/dir/state.yaml: cannot write the executor state file: ", 0), 0u)
      << r.output;
}

}  // namespace
}  // namespace rover::test
