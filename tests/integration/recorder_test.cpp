// rover_recorder on real processes and a real bus: the log it writes of a run at the
// default sim rate has no gap in any publisher's count, and lcm-logplayer replays it whole
// (a second recorder on a second bus gets every message back, byte for byte).
#include "bus/bus.hpp"
#include "bus/channels.hpp"
#include "integration/run_support.hpp"
#include "launch/process_set.hpp"
#include "logcheck/log_check.hpp"

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>
#include <rover_msgs/heartbeat_t.hpp>
#include <rover_msgs/pose_t.hpp>

#include <chrono>
#include <cstdio>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace rover::test {
namespace {

using Clock = std::chrono::steady_clock;

// A recorder on `url`, started and heard on the bus before it returns.
class Recording {
 public:
  Recording(const std::string& url, const std::string& out_dir, const std::string& log_path)
      : bus_(url), set_(Bin(""), out_dir, false) {
    bus_.set_publisher("recorder_test");
    bus_.Subscribe<rover_msgs::heartbeat_t>(channels::kHeartbeat,
                                            [this](const rover_msgs::heartbeat_t& hb) {
                                              heard_.insert(hb.process);
                                              if (hb.process == "rover_recorder" &&
                                                  hb.detail.rfind("wrote ", 0) == 0) {
                                                wrote_.push_back(std::stoll(hb.detail.substr(6)));
                                              }
                                            });
    set_.Start({"rover_recorder", "rover_recorder", {"--lcm-url", url, log_path}});
    const auto deadline = Clock::now() + std::chrono::seconds(10);
    while (!heard_.count("rover_recorder") && Clock::now() < deadline) bus_.Handle(50);
  }
  bool ready() const { return heard_.count("rover_recorder") > 0; }
  // Waits until the recorder has caught up with what it received: two of its heartbeats in
  // a row (1 s apart) say it wrote no more than its own heartbeats in between.
  bool WaitUntilDrained(std::chrono::seconds limit) {
    const auto deadline = Clock::now() + limit;
    const std::size_t from = wrote_.size();
    while (Clock::now() < deadline) {
      bus_.Handle(50);
      if (wrote_.size() >= from + 2 && wrote_.back() - wrote_[wrote_.size() - 2] <= 3) return true;
    }
    return false;
  }
  // SIGTERM, then its exit status ("exited with code 0" when it wrote everything).
  std::string Stop() {
    set_.Signal("rover_recorder", SIGTERM);
    const auto deadline = Clock::now() + std::chrono::seconds(15);
    std::string how = "did not exit within 15 s";
    while (set_.Running("rover_recorder") && Clock::now() < deadline) {
      for (const auto& [name, status] : set_.Poll(50)) how = status;
    }
    set_.StopAll();
    return how;
  }

 private:
  bus::Bus bus_;
  launch::ProcessSet set_;
  std::set<std::string> heard_;
  std::vector<std::int64_t> wrote_;  // "wrote N messages" of each recorder heartbeat
};

// Each channel's payloads, in log order.
std::map<std::string, std::vector<std::string>> ReadLog(const std::string& path) {
  std::map<std::string, std::vector<std::string>> out;
  lcm::LogFile log(path, "r");
  EXPECT_TRUE(log.good()) << path;
  for (const lcm::LogEvent* ev = log.readNextEvent(); ev != nullptr; ev = log.readNextEvent()) {
    out[ev->channel].emplace_back(static_cast<const char*>(ev->data), ev->datalen);
  }
  return out;
}

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

TEST(Recorder, RecordsARealRunWithoutLossAndLcmLogplayerReplaysIt) {
  std::filesystem::current_path(SourceDir());  // the configs are relative to it
  const std::string out = OutDir("recorder");
  const std::string url = PrivateUrl(31);
  const std::string log_path = out + "/log.lcm";

  // 1. Record the simulator, estimator and hazard monitor at the default 50x sim rate for
  //    5 s of wall time: a few thousand messages a second (IMU alone 1,000).
  Recording recording(url, out, log_path);
  ASSERT_TRUE(recording.ready()) << "rover_recorder sent no heartbeat within 10 s: "
                                 << ReadText(out + "/rover_recorder.log");
  {
    launch::ProcessSet set(Bin(""), out, false);
    const std::vector<std::string> env = {"ROVER_LCM_URL=" + url};
    set.Start({"rover_sim", "rover_sim",
               {"--config", "configs/rover.yaml", "--world", "configs/worlds/flat_rock_course.yaml",
                "--rate", "50"}}, env);
    set.Start({"state_estimator", "state_estimator", {"--config", "configs/rover.yaml"}}, env);
    set.Start({"hazard_monitor", "hazard_monitor", {"--config", "configs/rover.yaml"}}, env);
    const auto until = Clock::now() + std::chrono::seconds(5);
    while (Clock::now() < until) {
      for (const auto& [name, how] : set.Poll(50)) ADD_FAILURE() << name << " " << how;
    }
    set.StopAll();
  }
  EXPECT_EQ(recording.Stop(), "exited with code 0");
  const std::string recorder_says = ReadText(out + "/rover_recorder.log");
  EXPECT_NE(recorder_says.find("lost upstream 0, dropped here 0"), std::string::npos)
      << recorder_says;

  // 2. The log is complete by the checker, and holds the high-rate channels.
  const auto report = logcheck::CheckLog(log_path);
  EXPECT_TRUE(report.complete) << logcheck::FormatReport(report);
  ASSERT_TRUE(report.channels.count(channels::kImu)) << logcheck::FormatReport(report);
  EXPECT_GT(report.channels.at(channels::kImu).count, 1000) << logcheck::FormatReport(report);
  EXPECT_GT(report.channels.at(channels::kPose).count, 500) << logcheck::FormatReport(report);

  // 3. lcm-logplayer (5x) replays it onto a second bus, recorded by a second recorder. The
  //    recorded heartbeats stay out: a replayed "rover_recorder" heartbeat and the second
  //    recorder's own would share one name and count.
  const std::string replay_url = PrivateUrl(32);
  const std::string replay_path = out + "/replay.lcm";
  const std::string replay_dir = out + "/replay";
  std::filesystem::create_directories(replay_dir);
  Recording replay(replay_url, replay_dir, replay_path);
  ASSERT_TRUE(replay.ready()) << ReadText(replay_dir + "/rover_recorder.log");
  {
    launch::ProcessSet player(Bin(""), replay_dir, false);
    player.Start({"lcm-logplayer", "/usr/bin/lcm-logplayer",
                  {"--lcm-url=" + replay_url, "-s", "5", "-e", "^(?!HEARTBEAT$|LCM_SELF_TEST$).*$",
                   log_path}});
    const auto deadline = Clock::now() + std::chrono::seconds(60);
    std::string how;
    while (player.Running("lcm-logplayer") && Clock::now() < deadline) {
      for (const auto& [name, status] : player.Poll(50)) how = status;
    }
    ASSERT_EQ(how, "exited with code 0") << "lcm-logplayer did not finish its replay";
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // the last messages arrive
  EXPECT_EQ(replay.Stop(), "exited with code 0");

  const auto recorded = ReadLog(log_path);
  const auto replayed = ReadLog(replay_path);
  std::size_t compared = 0;
  for (const auto& [channel, messages] : recorded) {
    if (channel == channels::kHeartbeat || channel == "LCM_SELF_TEST") continue;
    ASSERT_TRUE(replayed.count(channel)) << channel << " was not replayed";
    const auto& back = replayed.at(channel);
    ASSERT_EQ(back.size(), messages.size()) << channel;
    for (std::size_t i = 0; i < messages.size(); ++i) {
      ASSERT_EQ(back[i], messages[i]) << channel << " message " << i << " differs";
    }
    compared += messages.size();
  }
  EXPECT_GT(compared, 3000u);
}

// A flood on one channel (the hostile tester sent 1,236 copies a second of a 248 kB
// STEREO_FRAME for 20 s, and lcm-logger's successor lost 24,391 real messages and grew by
// 443 MB): the recorder's memory stays within its bound, and every message of the real
// channels is in the log or named as lost, by publisher and count, in its own report.
TEST(Recorder, AFloodOnOneChannelStaysWithinItsBoundAndTheLossesAreNamed) {
  std::filesystem::current_path(SourceDir());
  const std::string out = OutDir("recorder_flood");
  const std::string url = PrivateUrl(35);
  const std::string log_path = out + "/log.lcm";
  Recording recording(url, out, log_path);
  ASSERT_TRUE(recording.ready()) << ReadText(out + "/rover_recorder.log");
  std::int64_t flood_sent = 0;
  {
    launch::ProcessSet set(Bin(""), out, false);
    const std::vector<std::string> env = {"ROVER_LCM_URL=" + url};
    set.Start({"rover_sim", "rover_sim",
               {"--config", "configs/rover.yaml", "--world", "configs/worlds/flat_rock_course.yaml", "--rate", "50"}},
              env);
    set.Start({"state_estimator", "state_estimator", {"--config", "configs/rover.yaml"}}, env);
    lcm::LCM flood(url);
    ASSERT_TRUE(flood.good());
    const std::vector<std::uint8_t> payload(248 * 1024, 0xa5);
    const auto start = Clock::now();
    const auto until = start + std::chrono::seconds(5);
    while (Clock::now() < until) {
      // At most 1,236 a second, as the tester sent them.
      const auto due = start + std::chrono::microseconds(flood_sent * 1000000 / 1236);
      if (Clock::now() < due) {
        for (const auto& [name, how] : set.Poll(0)) ADD_FAILURE() << name << " " << how;
        std::this_thread::sleep_until(due);
        continue;
      }
      flood.publish(channels::kStereoFrame, payload.data(), static_cast<unsigned>(payload.size()));
      ++flood_sent;
    }
    set.StopAll();
  }
  EXPECT_GT(flood_sent, 1000);
  // The flood's backlog in the recorder's socket would drop what comes next.
  ASSERT_TRUE(recording.WaitUntilDrained(std::chrono::seconds(60))) << "the recorder did not catch up";
  // A known loss, after the flood: POSE from a publisher of the test's own, counts 0-59 with
  // 20-29 and 45-47 never sent. The recorder must name exactly these two gaps (by the last
  // count before each and the first after it).
  const std::string gap_publisher = "recorder_test_gaps";
  {
    lcm::LCM lcm(url);
    ASSERT_TRUE(lcm.good());
    for (std::int64_t count = 0; count < 60; ++count) {
      if ((count >= 20 && count < 30) || (count >= 45 && count < 48)) continue;
      rover_msgs::pose_t pose{};
      pose.utime = 1000000 + count * 100000;
      pose.pub_seq = (static_cast<std::int64_t>(logcheck::PublisherId(gap_publisher)) << 32) | count;
      lcm.publish(channels::kPose, &pose);
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // the last messages arrive
  EXPECT_EQ(recording.Stop(), "exited with code 0");
  const std::string says = ReadText(out + "/rover_recorder.log");

  // 1. Memory: the deepest queue stays within the recorder's bound (256 MB).
  const auto at = says.find("deepest queue ");
  ASSERT_NE(at, std::string::npos) << says;
  std::istringstream deepest(says.substr(says.find(", ", at) + 2));
  double mb = -1;
  deepest >> mb;
  EXPECT_GE(mb, 0.0) << says;
  EXPECT_LE(mb, 256.0) << says;

  // 2. The real channels: what the log lacks, the recorder's closing report names as lost
  //    (by channel, publisher and count), and their bulk is there.
  const auto report = logcheck::CheckLog(log_path);
  for (const char* channel : {channels::kImu, channels::kPose, channels::kWheelOdometry}) {
    ASSERT_TRUE(report.channels.count(channel)) << channel << "\n" << logcheck::FormatReport(report);
    const auto& c = report.channels.at(channel);
    EXPECT_GT(c.count, 100) << channel;
    for (const auto& gap : c.gaps) {
      // Under load the flood can take a process's first messages too: named as lost
      // before its first recorded message.
      const std::string named =
          gap.kind == logcheck::Gap::Kind::kAtStart
              ? ": " + std::to_string(gap.lost) + " lost before its first recorded message"
              : ": " + std::to_string(gap.lost) + " lost (count " + std::to_string(gap.count_before) + " then " +
                    std::to_string(gap.count_after) + ")";
      EXPECT_NE(says.find("gap: " + std::string(channel) + " from "), std::string::npos) << says;
      EXPECT_NE(says.find(named), std::string::npos) << "the log lacks " << gap.lost << " on " << channel
                                                     << " that the recorder did not name:\n" << says;
    }
  }

  // 3. The known loss is named exactly: publisher, counts and number.
  char hex_id[16];
  std::snprintf(hex_id, sizeof(hex_id), "0x%08x", logcheck::PublisherId(gap_publisher));
  const std::string hex(hex_id);
  for (const char* known : {": 10 lost (count 19 then 30)", ": 3 lost (count 44 then 48)"}) {
    const std::string line = "gap: " + std::string(channels::kPose) + " from " + hex + known;
    EXPECT_NE(says.find(line), std::string::npos) << "missing '" << line << "' in:\n" << says;
  }
  const auto& pose = report.channels.at(channels::kPose);
  std::int64_t known_lost = 0;
  for (const auto& gap : pose.gaps) {
    if (gap.publisher == hex) known_lost += gap.lost;
  }
  EXPECT_EQ(known_lost, 13) << logcheck::FormatReport(report);
}

}  // namespace
}  // namespace rover::test
