// rover_console --once on a private bus: the test publishes a drive's messages while the
// console listens, then checks the frame it printed. Run inside a private network
// namespace (./rover test does), on a bus of its own (PrivateUrl).
#include "integration/run_support.hpp"

#include "bus/bus.hpp"
#include "bus/channels.hpp"

#include <gtest/gtest.h>
#include <rover_msgs/heartbeat_t.hpp>
#include <rover_msgs/pose_t.hpp>
#include <rover_msgs/sequence_status_t.hpp>
#include <rover_msgs/step_report_t.hpp>
#include <rover_msgs/vo_update_t.hpp>

#include <array>
#include <chrono>
#include <cstdio>
#include <thread>

namespace {

TEST(ConsoleOnTheBus, OnceShowsWhatWasPublished) {
  const std::string url = rover::test::PrivateUrl(31);
  FILE* console = popen((rover::test::Bin("rover_console") + " --once --wait 3 --lcm-url '" + url + "' 2>&1").c_str(), "r");
  ASSERT_NE(console, nullptr);
  rover::bus::Bus bus(url);
  bus.set_publisher("console_test");
  const auto start = std::chrono::steady_clock::now();
  for (int i = 0; std::chrono::steady_clock::now() - start < std::chrono::milliseconds(2500); ++i) {
    const std::int64_t utime = 50'000'000 + i * 100'000;
    rover_msgs::heartbeat_t hb{};
    hb.utime = utime;
    hb.process = "sequence_executor";
    hb.seq = i;
    hb.dropped = 4;
    bus.Publish(rover::channels::kHeartbeat, hb);
    rover_msgs::sequence_status_t st{};
    st.utime = utime;
    st.submission_id = 42;
    st.sequence_name = "approach.seq";
    st.state = rover_msgs::sequence_status_t::STATE_RUNNING;
    st.num_commands = 3;
    st.command_index = 1;
    st.command_line = 5;
    st.command_text = "drive 2 m";
    st.step_index = 2;
    bus.Publish(rover::channels::kSequenceStatus, st);
    rover_msgs::pose_t pose{};
    pose.utime = utime;
    pose.position[0] = 1.25;
    pose.orientation[0] = 1;
    pose.covariance[0][0] = pose.covariance[1][1] = 0.02 * 0.02;
    bus.Publish(rover::channels::kPose, pose);
    if (i == 3) {
      rover_msgs::step_report_t r{};
      r.utime = utime;
      r.submission_id = 42;
      r.command_index = 1;
      r.step_index = 1;
      r.commanded_distance_m = 0.5;
      r.estimated_distance_m = 0.4;
      r.slip_pct = 20.0;
      r.vo_status = 0;
      bus.Publish(rover::channels::kStepReport, r);
      rover_msgs::vo_update_t u{};
      u.utime = utime;
      u.status = rover_msgs::vo_update_t::STATUS_TOO_FEW_INLIERS;
      u.reason = "7 RANSAC inliers (need 10)";
      u.num_tracked = 30;
      u.num_inliers = 7;
      u.delta_orientation[0] = 1;
      bus.Publish(rover::channels::kVoUpdate, u);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  std::string out;
  std::array<char, 4096> buf;
  while (fgets(buf.data(), buf.size(), console) != nullptr) out += buf.data();
  const int status = pclose(console);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0) << out;
  EXPECT_NE(out.find("approach.seq (#42)  RUNNING"), std::string::npos) << out;
  EXPECT_NE(out.find("2/3, line 5: drive 2 m   step 3"), std::string::npos) << out;
  EXPECT_NE(out.find("2.2       0.500 m 0.0 deg    0.400 m 0.0 deg    20.0 %   VO"), std::string::npos) << out;
  EXPECT_NE(out.find("too_few_inliers"), std::string::npos) << out;
  EXPECT_NE(out.find("7 RANSAC inliers (need 10)"), std::string::npos) << out;
  EXPECT_NE(out.find("x 1.250  y 0.000"), std::string::npos) << out;
  EXPECT_NE(out.find("1-sigma: position 0.020 m"), std::string::npos) << out;
  EXPECT_NE(out.find("sequence_executor   ok"), std::string::npos) << out;
  EXPECT_EQ(out.find("\x1b["), std::string::npos) << "--once prints no escapes";
}

TEST(ConsoleOnTheBus, NothingHeardExits3WithOneLine) {
  const auto r = rover::test::RunCommand(rover::test::Bin("rover_console") + " --once --wait 0.5 --lcm-url '" +
                                         rover::test::PrivateUrl(32) + "'");
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("rover_console: nothing heard on"), std::string::npos) << r.output;
}

}  // namespace
