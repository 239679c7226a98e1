// A rover's real day, not a fresh stack that drives at once:
//   - in virtual time, a goto paused for an hour of rover time and resumed, then a night of
//     12 h parked and the next sequence (configs/scenarios/day_pause_night.yaml, at --rate
//     max): both complete, the pause counts against no time limit, every VO update is
//     accepted, and after the night the estimate stands where the rover does, honestly;
//   - on the system clock, with rover_sim as the rover's hardware (no ROVER_CLOCK at all,
//     configs/deploy/sim_vo_system_clock.yaml), a 2 m drive with VO completes, and
//     STEREO_FRAME, POSE and VO_UPDATE carry system-clock times.
#include "bus/bus.hpp"
#include "bus/channels.hpp"
#include "integration/run_support.hpp"
#include "launch/process_set.hpp"

#include <rover_msgs/heartbeat_t.hpp>
#include <rover_msgs/pose_t.hpp>
#include <rover_msgs/stereo_frame_t.hpp>
#include <rover_msgs/vo_update_t.hpp>

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <future>
#include <iterator>
#include <set>
#include <string>

namespace rover::test {
namespace {

std::string ReadFile(const std::string& path) {
  std::ifstream in(path);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

TEST(RoverDay, AnHourPausedAndANightParkedInVirtualTime) {
  const std::string out = OutDir("day_pause_night");
  const auto result = RunCommand(Bin("scenario_runner") + " configs/scenarios/day_pause_night.yaml --out " + out +
                                 " --rate max --no-plot");
  EXPECT_EQ(result.exit_code, 0) << result.output;
  const YAML::Node s = YAML::LoadFile(out + "/summary.json");
  EXPECT_EQ(s["outcome"].as<std::string>(), "completed") << s["detail"].as<std::string>("");

  // The pause (1 h) and the night (12 h): the estimate against truth at the resume and at
  // the next submission.
  const YAML::Node checks = s["rest_checks"];
  ASSERT_EQ(checks.size(), 2u) << result.output;
  EXPECT_EQ(checks[0]["after"].as<std::string>(), "pause");
  EXPECT_NEAR(checks[0]["rested_s"].as<double>(), 3600.0, 2.5);
  const YAML::Node night = checks[1];
  EXPECT_EQ(night["after"].as<std::string>(), "idle");
  EXPECT_NEAR(night["rested_s"].as<double>(), 43200.0, 2.5);
  EXPECT_LT(std::abs(night["heading_error_deg"].as<double>()), 0.1) << result.output;
  EXPECT_LT(night["position_error_m"].as<double>(), 0.01) << result.output;
  // Honest at rest: within the 99.7 % bounds of its own sigma.
  for (const auto& c : checks) {
    EXPECT_LT(c["heading_nees"].as<double>(), 9.0) << result.output;
    EXPECT_LT(c["horizontal_nees"].as<double>(), 11.83) << result.output;
  }

  // Every VO update, after the pause and after the night too, accepted; none refused by the
  // estimator for age.
  EXPECT_GT(s["vo_updates"].as<int>(), 6);
  EXPECT_EQ(s["vo_updates_accepted"].as<int>(), s["vo_updates"].as<int>());
  EXPECT_LE(s["false_updates"].as<int>(), 1);
  const std::string estimator_log = ReadFile(out + "/state_estimator.log");
  EXPECT_EQ(estimator_log.find("refused"), std::string::npos) << estimator_log;
  // The whole day is in the log, nothing lost.
  EXPECT_TRUE(s["log_complete"].as<bool>()) << result.output;
  // Idle strides carried the clock: 13 h in far fewer instants than 0.1 s ticks.
  // 13 h at 0.1 s ticks would be 468,000 instants, each with a clock message.
  EXPECT_LT(s["log_channels"]["ROVER_CLOCK"]["count"].as<long>(), 60000L) << "the clock did not stride through the rest";
}

TEST(RoverOnTheSystemClock, ATwoMetreDriveWithVoOnRoverSimAsHardware) {
  const std::string dir = OutDir("system_clock_drive");
  const std::string url = PrivateUrl(61);
  std::filesystem::current_path(SourceDir());  // the deployment's paths are relative to the repository root
  bus::Bus bus(url);
  // A message's time is on the system clock when it is never ahead of its arrival and, as a
  // rule (the median), behind it by seconds, not years: a virtual clock, or a stamp of 0,
  // would be off by years. How far behind is the work done since the exposure, VO's above
  // all, and a busy machine makes that longer (a median of 1.08 s for VO beside two
  // burners and a build), so the bound is 5 s, not a bet on the scheduler. A VO update
  // carries its pair's exposure time, so it must name a pair that was heard.
  struct Lag {
    int count = 0;
    std::vector<double> behind_s;  // arrival - utime
    double most_ahead_s = 0;       // utime - arrival, the largest
  };
  std::map<std::string, Lag> lag;
  std::set<std::int64_t> frame_utimes;
  int vo_off_the_frames = 0;
  auto note = [&lag](const std::string& channel, std::int64_t utime) {
    Lag& l = lag[channel];
    ++l.count;
    const double behind_s = static_cast<double>(bus::RoverClock::SystemUtime() - utime) * 1e-6;
    l.behind_s.push_back(behind_s);
    l.most_ahead_s = std::max(l.most_ahead_s, -behind_s);
  };
  auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  std::set<std::string> alive;
  bus.Subscribe<rover_msgs::heartbeat_t>(channels::kHeartbeat,
                                         [&](const rover_msgs::heartbeat_t& hb) { alive.insert(hb.process); });
  bus.Subscribe<rover_msgs::stereo_frame_t>(channels::kStereoFrame,
                                            [&](const rover_msgs::stereo_frame_t& f) {
                                              note("STEREO_FRAME", f.utime);
                                              frame_utimes.insert(f.utime);
                                            }, 4);
  bus.Subscribe<rover_msgs::pose_t>(channels::kPose, [&](const rover_msgs::pose_t& p) { note("POSE", p.utime); }, 100);
  bus.Subscribe<rover_msgs::vo_update_t>(channels::kVoUpdate, [&](const rover_msgs::vo_update_t& u) {
    note("VO_UPDATE", u.utime);
    if (!frame_utimes.count(u.utime)) ++vo_off_the_frames;
    if (u.status == rover_msgs::vo_update_t::STATUS_OK) ++lag["VO_UPDATE ok"].count;
  });

  launch::ProcessSet set(std::string(ROVER_BINARY_DIR) + "/bin", dir, false);
  set.Start({"launcher", "launcher", {"configs/deploy/sim_vo_system_clock.yaml", "--lcm-url", url}}, {});
  const std::vector<std::string> expected = {"rover_sim", "camera_capture", "visual_odometry", "state_estimator",
                                             "hazard_monitor", "sequence_executor"};
  const auto start = std::chrono::steady_clock::now();
  auto all_heard = [&] {
    for (const auto& n : expected)
      if (!alive.count(n)) return false;
    return true;
  };
  while (!all_heard() && std::chrono::steady_clock::now() - start < std::chrono::seconds(60)) bus.Handle(50);
  ASSERT_TRUE(all_heard()) << "not every process sent a heartbeat within 60 s (see " << dir << ")";

  const std::string seq = dir + "/drive.seq";
  std::ofstream(seq) << "vo on step 50 cm\ndrive 2 m\n";
  auto job = std::async(std::launch::async, [&] {
    return RunCommand("timeout 300 " + Bin("rover_seq") + " submit " + seq + " --lcm-url '" + url + "'");
  });
  while (job.wait_for(std::chrono::milliseconds(0)) != std::future_status::ready) bus.Handle(20);
  const auto submitted = job.get();
  set.StopAll();
  EXPECT_EQ(submitted.exit_code, 0) << submitted.output;
  EXPECT_NE(submitted.output.find("[completed"), std::string::npos) << submitted.output;

  for (const char* channel : {"STEREO_FRAME", "POSE", "VO_UPDATE"}) {
    EXPECT_GT(lag[channel].count, 0) << "no " << channel;
    if (lag[channel].count == 0) continue;
    EXPECT_LT(lag[channel].most_ahead_s, 0.1) << channel << " times are ahead of the system clock";
    EXPECT_LT(median(lag[channel].behind_s), 5.0) << channel << " times are behind the system clock";
  }
  EXPECT_EQ(vo_off_the_frames, 0) << "VO updates whose time is no pair's exposure";
  EXPECT_GE(lag["VO_UPDATE ok"].count, 3) << "VO measured too few of the drive's steps";
  // Each process said so at start (the launcher's log holds their lines).
  const std::string launcher_log = ReadFile(dir + "/launcher.log");
  for (const std::string p : {"rover_sim", "camera_capture", "visual_odometry", "state_estimator", "sequence_executor"}) {
    EXPECT_NE(launcher_log.find(p + ": rover time: the system clock (bus.time: system)"), std::string::npos) << p;
  }
}

}  // namespace
}  // namespace rover::test
