// The completeness checker on logs built here with lcm::LogFile, with known gaps, restarts
// and inconsistencies, and each message encoded by the generated types.
#include "logcheck/log_check.hpp"
#include "logcheck/log_reader.hpp"

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>
#include <rover_msgs/capture_request_t.hpp>
#include <rover_msgs/hazard_status_t.hpp>
#include <rover_msgs/heartbeat_t.hpp>
#include <rover_msgs/imu_t.hpp>
#include <rover_msgs/mobility_command_t.hpp>
#include <rover_msgs/mobility_status_t.hpp>
#include <rover_msgs/pose_t.hpp>
#include <rover_msgs/step_report_t.hpp>
#include <rover_msgs/stereo_frame_t.hpp>
#include <rover_msgs/vo_update_t.hpp>

#include <unistd.h>

#include <array>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <memory>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using namespace rover::logcheck;

namespace {

std::int64_t PubSeq(const std::string& publisher, std::int64_t count) {
  return static_cast<std::int64_t>((static_cast<std::uint64_t>(PublisherId(publisher)) << 32) |
                                   static_cast<std::uint64_t>(count));
}

template <class Msg>
std::vector<std::uint8_t> Encode(const Msg& m) {
  std::vector<std::uint8_t> buf(static_cast<std::size_t>(m.getEncodedSize()));
  EXPECT_EQ(m.encode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
  return buf;
}

rover_msgs::imu_t Imu(std::int64_t utime, const std::string& publisher, std::int64_t count) {
  rover_msgs::imu_t m{};
  m.utime = utime;
  m.pub_seq = PubSeq(publisher, count);
  m.orientation[0] = 1;
  return m;
}

rover_msgs::pose_t Pose(std::int64_t utime, std::int64_t count) {
  rover_msgs::pose_t m{};
  m.utime = utime;
  m.pub_seq = PubSeq("state_estimator", count);
  return m;
}

rover_msgs::hazard_status_t HazardStatus(std::int64_t utime, std::int64_t count) {
  rover_msgs::hazard_status_t m{};
  m.utime = utime;
  m.pub_seq = PubSeq("hazard_monitor", count);
  return m;
}

rover_msgs::heartbeat_t Heartbeat(const std::string& process, std::int64_t seq) {
  rover_msgs::heartbeat_t m{};
  m.utime = seq * 1000000;
  m.process = process;
  m.seq = seq;
  return m;
}

// A log written through lcm::LogFile, in a fresh directory removed at the end.
class TestLog {
 public:
  explicit TestLog(const std::string& name) {
    dir_ = fs::temp_directory_path() / ("logcheck_test_" + std::to_string(getpid()) + "_" + name);
    fs::create_directories(dir_);
    path_ = (dir_ / "log.lcm").string();
    file_ = std::make_unique<lcm::LogFile>(path_, "w");
  }
  ~TestLog() { if (!getenv("KEEP")) fs::remove_all(dir_); }

  template <class Msg>
  void Add(const std::string& channel, const Msg& m) {
    AddRaw(channel, Encode(m));
  }
  // At a log timestamp (microseconds); later Adds go on from it.
  template <class Msg>
  void AddAt(std::int64_t timestamp_us, const std::string& channel, const Msg& m) {
    timestamp_ = timestamp_us - 1;
    Add(channel, m);
  }
  void AddRaw(const std::string& channel, std::vector<std::uint8_t> bytes) {
    lcm::LogEvent ev{};
    ev.timestamp = ++timestamp_;
    ev.channel = channel;
    ev.datalen = static_cast<std::int32_t>(bytes.size());
    ev.data = bytes.data();
    ASSERT_EQ(file_->writeEvent(&ev), 0);
  }
  // Bytes that are not an event, between events (a corrupt stretch).
  void AddGarbage(const std::string& bytes) {
    ASSERT_EQ(std::fwrite(bytes.data(), 1, bytes.size(), file_->getFilePtr()), bytes.size());
  }
  // Closes the file; returns its path.
  const std::string& Close() {
    file_.reset();
    return path_;
  }

 private:
  fs::path dir_;
  std::string path_;
  std::unique_ptr<lcm::LogFile> file_;
  std::int64_t timestamp_ = 1000;
};

}  // namespace

TEST(PublisherId, IsFnv1a32) {
  // The published FNV-1a test vectors.
  EXPECT_EQ(PublisherId(""), 0x811c9dc5u);
  EXPECT_EQ(PublisherId("a"), 0xe40c292cu);
  EXPECT_EQ(PublisherId("foobar"), 0xbf9cf968u);
}

TEST(ReadStamp, ReadsPubSeqFromTheFirstBytes) {
  const auto bytes = Encode(Imu(123456789, "rover_sim", 42));
  const auto r = ReadStamp(*FindChannel("IMU"), bytes.data(), bytes.size());
  ASSERT_TRUE(r.stamp) << r.error;
  EXPECT_EQ(r.stamp->utime, 123456789);
  EXPECT_EQ(r.stamp->publisher_id, PublisherId("rover_sim"));
  EXPECT_EQ(r.stamp->count, 42);
}

TEST(ReadStamp, ReadsAHeartbeatsProcessAndSeq) {
  const auto bytes = Encode(Heartbeat("visual_odometry", 7));
  const auto r = ReadStamp(*FindChannel("HEARTBEAT"), bytes.data(), bytes.size());
  ASSERT_TRUE(r.stamp) << r.error;
  EXPECT_EQ(r.stamp->publisher, "visual_odometry");
  EXPECT_EQ(r.stamp->count, 7);
  EXPECT_EQ(r.stamp->utime, 7000000);
}

TEST(ReadStamp, SaysWhyItCannotRead) {
  const auto imu = Encode(Imu(1, "rover_sim", 0));
  // Another type's fingerprint on the channel.
  auto r = ReadStamp(*FindChannel("POSE"), imu.data(), imu.size());
  EXPECT_FALSE(r.stamp);
  EXPECT_NE(r.error.find("fingerprint is not pose_t's"), std::string::npos) << r.error;
  // Cut short inside pub_seq.
  r = ReadStamp(*FindChannel("IMU"), imu.data(), 20);
  EXPECT_FALSE(r.stamp);
  EXPECT_NE(r.error.find("pub_seq"), std::string::npos) << r.error;
  // Not stamped at all.
  auto unstamped = Imu(1, "rover_sim", 0);
  unstamped.pub_seq = 0;
  const auto bytes = Encode(unstamped);
  r = ReadStamp(*FindChannel("IMU"), bytes.data(), bytes.size());
  EXPECT_FALSE(r.stamp);
  EXPECT_NE(r.error.find("not stamped"), std::string::npos) << r.error;
  // A heartbeat whose name length lies (0: the packet that once killed the executor).
  auto hb = Encode(Heartbeat("x", 1));
  hb[16] = hb[17] = hb[18] = hb[19] = 0;
  r = ReadStamp(*FindChannel("HEARTBEAT"), hb.data(), hb.size());
  EXPECT_FALSE(r.stamp);
  hb[16] = 0x7f;  // 2 GB
  r = ReadStamp(*FindChannel("HEARTBEAT"), hb.data(), hb.size());
  EXPECT_FALSE(r.stamp);
}

TEST(CheckLog, FindsExactlyTheGapAndTheRestart) {
  TestLog log("gap");
  // rover_sim's IMU: counts 0..9, 13..19 (10, 11, 12 lost), then a restart at 0..4.
  // state_estimator's POSE and the heartbeats run without a gap, interleaved.
  std::int64_t utime = 0, pose = 0;
  auto imu = [&](std::int64_t count) {
    utime += 50000;
    log.Add("IMU", Imu(utime, "rover_sim", count));
    log.Add("POSE", Pose(utime, pose++));
  };
  for (int c = 0; c < 10; ++c) imu(c);
  const std::int64_t before_gap = utime;
  for (int c = 13; c < 20; ++c) imu(c);
  const std::int64_t after_gap = before_gap + 50000;
  for (int c = 0; c < 5; ++c) imu(c);
  const std::int64_t restart_utime = after_gap + 7 * 50000;
  for (int s = 0; s < 3; ++s) {
    log.Add("HEARTBEAT", Heartbeat("rover_sim", s));
    log.Add("HEARTBEAT", Heartbeat("state_estimator", s));
  }
  const auto report = CheckLog(log.Close());

  EXPECT_EQ(report.messages, 22 + 22 + 6);
  EXPECT_FALSE(report.complete);
  EXPECT_EQ(report.lost, 3);
  EXPECT_EQ(report.unchecked, 0);
  const auto& imu_report = report.channels.at("IMU");
  EXPECT_EQ(imu_report.count, 22);
  ASSERT_EQ(imu_report.gaps.size(), 1u);
  const Gap& g = imu_report.gaps[0];
  EXPECT_EQ(g.kind, Gap::Kind::kSkipped);
  EXPECT_EQ(report.publisher_names.at(g.publisher), "rover_sim");
  EXPECT_EQ(g.count_before, 9);
  EXPECT_EQ(g.count_after, 13);
  EXPECT_EQ(g.lost, 3);
  EXPECT_EQ(g.utime_before, before_gap);
  EXPECT_EQ(g.utime_after, after_gap);
  ASSERT_EQ(imu_report.restarts.size(), 1u);
  EXPECT_EQ(imu_report.restarts[0].count_before, 19);
  EXPECT_EQ(imu_report.restarts[0].utime, restart_utime);
  for (const char* ch : {"POSE", "HEARTBEAT"}) {
    EXPECT_EQ(report.channels.at(ch).lost, 0) << ch;
    EXPECT_TRUE(report.channels.at(ch).gaps.empty()) << ch;
    EXPECT_TRUE(report.channels.at(ch).restarts.empty()) << ch;
  }
  EXPECT_EQ(report.channels.at("HEARTBEAT").publishers.size(), 2u);
  EXPECT_EQ(report.publisher_names.at(*report.channels.at("POSE").publishers.begin()),
            "state_estimator");

  const std::string text = FormatReport(report);
  EXPECT_NE(text.find("gap: IMU from rover_sim: 3 lost (count 9 then 13)"), std::string::npos)
      << text;
  EXPECT_NE(text.find("restart: IMU from rover_sim"), std::string::npos) << text;
  EXPECT_NE(text.find("log complete: no (3 messages lost in 1 gap)"), std::string::npos) << text;
}

TEST(CheckLog, AnUnbrokenLogIsComplete) {
  TestLog log("complete");
  for (int c = 0; c < 50; ++c) {
    log.Add("IMU", Imu(c * 1000, "rover_sim", c));
    if (c % 10 == 0) log.Add("HEARTBEAT", Heartbeat("rover_sim", c / 10));
  }
  log.AddRaw("SOMEONE_ELSES_CHANNEL", {1, 2, 3});  // counted, not checked, not a loss
  const auto report = CheckLog(log.Close());
  EXPECT_TRUE(report.complete) << report.verdict_reason;
  EXPECT_EQ(report.lost, 0);
  EXPECT_EQ(report.channels.at("SOMEONE_ELSES_CHANNEL").count, 1);
  EXPECT_NE(FormatReport(report).find("log complete: yes\n"), std::string::npos);
}

TEST(CheckLog, AFirstCountAboveZeroIsALossOnlyFromTheStart) {
  TestLog log("start");
  for (int c = 5; c < 10; ++c) log.Add("IMU", Imu(c * 1000, "rover_sim", c));
  const std::string& path = log.Close();
  const auto strict = CheckLog(path);
  EXPECT_EQ(strict.lost, 5);
  ASSERT_EQ(strict.channels.at("IMU").gaps.size(), 1u);
  EXPECT_EQ(strict.channels.at("IMU").gaps[0].kind, Gap::Kind::kAtStart);
  const auto joined = CheckLog(path, TrackerOptions{.from_start = false});
  EXPECT_EQ(joined.lost, 0);
  EXPECT_TRUE(joined.complete) << joined.verdict_reason;
}

// A recorder started after the launcher (as the README orders them): the processes heard
// in the log's first 2 s were running before it, and their earlier messages are not
// losses; a process that starts 3 s into the recording must count from 0.
TEST(CheckLog, ALateStartIsToldApartFromALossByWhenEachProcessIsFirstHeard) {
  TestLog log("late");
  log.AddAt(0, "HEARTBEAT", Heartbeat("rover_sim", 7));
  for (int c = 140; c < 150; ++c) log.AddAt(100'000 * (c - 139), "IMU", Imu(c * 1000, "rover_sim", c));
  log.AddAt(1'500'000, "HEARTBEAT", Heartbeat("state_estimator", 3));
  log.AddAt(1'600'000, "POSE", Pose(1000, 70));
  // hazard_monitor starts 3 s in, and its first 4 messages were lost.
  log.AddAt(3'000'000, "HEARTBEAT", Heartbeat("hazard_monitor", 0));
  log.AddAt(3'100'000, "HAZARD_STATUS", HazardStatus(2000, 4));
  const std::string& path = log.Close();

  TrackerOptions detect;
  detect.detect_joined = true;
  const auto report = CheckLog(path, detect);
  EXPECT_FALSE(report.complete);
  EXPECT_EQ(report.lost, 4);  // hazard_monitor's, and only those
  ASSERT_EQ(report.channels.at("HAZARD_STATUS").gaps.size(), 1u);
  EXPECT_EQ(report.channels.at("HAZARD_STATUS").gaps[0].kind, Gap::Kind::kAtStart);
  EXPECT_EQ(report.joined, (std::set<std::string>{"rover_sim", "state_estimator"}));
  EXPECT_EQ(report.before_recording, 7 + 140 + 3 + 70);
  const std::string text = FormatReport(report);
  EXPECT_NE(text.find("joined: the recording began on a running bus: rover_sim, state_estimator (heard in the "
                      "log's first 2 s) had published 220 messages before it"), std::string::npos) << text;
  EXPECT_NE(text.find("log complete: no (4 messages lost in 1 gap)"), std::string::npos) << text;
  // Strict: every first count above 0 is a loss; joined: none is.
  EXPECT_EQ(CheckLog(path).lost, 7 + 140 + 3 + 70 + 4);
  EXPECT_EQ(CheckLog(path, TrackerOptions{.from_start = false}).lost, 0);
}

// A process that starts just after the recorder (inside the joined window) and whose first
// POSEs were lost (a flood on the bus, say): its heartbeat at seq 0 is in the log, so it
// did not join a running bus, and the POSEs it skipped are losses, not "before the log".
TEST(CheckLog, AProcessFirstHeardAtCountZeroStartedDuringTheRecording) {
  TestLog log("early_start");
  log.AddAt(0, "HEARTBEAT", Heartbeat("rover_sim", 7));
  log.AddAt(200'000, "HEARTBEAT", Heartbeat("state_estimator", 0));
  log.AddAt(1'300'000, "POSE", Pose(1000, 77));
  log.AddAt(1'400'000, "POSE", Pose(1100, 78));
  TrackerOptions detect;
  detect.detect_joined = true;
  const auto report = CheckLog(log.Close(), detect);
  EXPECT_EQ(report.joined, (std::set<std::string>{"rover_sim"}));
  EXPECT_EQ(report.lost, 77);
  ASSERT_EQ(report.channels.at("POSE").gaps.size(), 1u);
  EXPECT_EQ(report.channels.at("POSE").gaps[0].kind, Gap::Kind::kAtStart);
  EXPECT_NE(FormatReport(report).find("gap: POSE from state_estimator: 77 lost before its first recorded message"),
            std::string::npos)
      << FormatReport(report);
}

TEST(CheckLog, ARestartThatMissesItsFirstMessagesIsALoss) {
  TestLog log("restart_loss");
  for (int c = 0; c < 6; ++c) log.Add("IMU", Imu(c * 1000, "rover_sim", c));
  for (int c = 2; c < 4; ++c) log.Add("IMU", Imu(10000 + c * 1000, "rover_sim", c));
  const auto report = CheckLog(log.Close());
  const auto& imu = report.channels.at("IMU");
  ASSERT_EQ(imu.restarts.size(), 1u);
  ASSERT_EQ(imu.gaps.size(), 1u);
  EXPECT_EQ(imu.gaps[0].kind, Gap::Kind::kAfterRestart);
  EXPECT_EQ(imu.gaps[0].lost, 2);
}

TEST(CheckLog, UnstampedMessagesMakeCompletenessUnknown) {
  TestLog log("unstamped");
  auto m = Imu(1000, "rover_sim", 0);
  m.pub_seq = 0;
  log.Add("IMU", m);
  log.Add("IMU", Pose(2000, 0));  // another type on the channel
  const auto report = CheckLog(log.Close());
  EXPECT_FALSE(report.complete);
  EXPECT_EQ(report.unchecked, 2);
  EXPECT_NE(report.verdict_reason.find("2 messages carry no readable count"), std::string::npos)
      << report.verdict_reason;
}

TEST(CheckLog, ATruncatedTailIsReported) {
  TestLog log("truncated");
  for (int c = 0; c < 3; ++c) log.Add("IMU", Imu(c * 1000, "rover_sim", c));
  const std::string path = log.Close();
  const auto whole = fs::file_size(path);
  // Another event's header, cut in the middle (a recorder killed mid-write).
  std::ofstream(path, std::ios::app | std::ios::binary).write("\xED\xA1\xDA\x01\x00\x00", 6);
  const auto report = CheckLog(path);
  EXPECT_EQ(report.messages, 3);
  EXPECT_FALSE(report.complete);
  EXPECT_NE(report.trailing.find("6 bytes after the last whole event at offset " +
                                 std::to_string(whole)),
            std::string::npos)
      << report.trailing;
}

TEST(CheckLog, ACorruptStretchBetweenEventsIsReported) {
  TestLog log("corrupt");
  log.Add("IMU", Imu(1000, "rover_sim", 0));
  log.AddGarbage("not an event at all");
  log.Add("IMU", Imu(2000, "rover_sim", 1));
  // LCM 1.3.1's reader stops there (and drops the event before the stretch); later versions
  // skip the stretch. Either way the checker must not call the log complete.
  const auto report = CheckLog(log.Close());
  EXPECT_LE(report.messages, 2);
  EXPECT_FALSE(report.complete);
  EXPECT_FALSE(report.trailing.empty());
  EXPECT_NE(report.verdict_reason.find("corrupt"), std::string::npos) << report.verdict_reason;
}

TEST(CheckLog, RefusesWhatIsNotAFile) {
  EXPECT_THROW(CheckLog("/nonexistent/log.lcm"), std::runtime_error);
  try {
    CheckLog(fs::temp_directory_path().string());
    FAIL() << "a directory was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("not a regular file"), std::string::npos) << e.what();
  }
}

TEST(LogReader, ReadsWhatLcmsOwnReaderReadsWithTheSameEnds) {
  TestLog log("reader");
  log.AddRaw("A", {1, 2, 3});
  log.AddRaw("LONGER_CHANNEL", std::vector<std::uint8_t>(70000, 7));
  log.AddRaw("A", {});
  log.AddRaw("B", {9});
  log.AddGarbage("half");  // a truncated tail
  const std::string path = log.Close();
  lcm::LogFile lcm_reader(path, "r");
  LogReader ours(path);
  ASSERT_TRUE(lcm_reader.good());
  ASSERT_TRUE(ours.good());
  int events = 0;
  for (;;) {
    const lcm::LogEvent* a = lcm_reader.readNextEvent();
    const lcm::LogEvent* b = ours.readNextEvent();
    ASSERT_EQ(a == nullptr, b == nullptr) << "after " << events << " events";
    if (a == nullptr) break;
    ++events;
    EXPECT_EQ(a->timestamp, b->timestamp);
    EXPECT_EQ(a->eventnum, b->eventnum);
    EXPECT_EQ(a->channel, b->channel);
    ASSERT_EQ(a->datalen, b->datalen);
    EXPECT_EQ(0, std::memcmp(a->data, b->data, static_cast<std::size_t>(a->datalen)));
    EXPECT_EQ(ftello(lcm_reader.getFilePtr()), ftello(ours.getFilePtr()));
  }
  // LCM checks that an event is followed by the next one's magic number or the end, so it
  // gives up the last event, before the tail that is not one; both readers do.
  EXPECT_EQ(events, 3);
}

TEST(LogReader, AnEmptyLogHasNoEventsAndAMissingOneIsNotGood) {
  TestLog log("reader_empty");
  const std::string path = log.Close();
  LogReader empty(path);
  EXPECT_TRUE(empty.good());
  EXPECT_EQ(empty.readNextEvent(), nullptr);
  EXPECT_FALSE(LogReader("/nonexistent/log.lcm").good());
  EXPECT_FALSE(LogReader(fs::temp_directory_path().string()).good());
}

TEST(Consistency, NamesTheCaptureFrameAndStepThatDoNotAddUp) {
  TestLog log("consistency");
  std::map<std::string, std::int64_t> counts;  // per publisher and channel, from 0
  auto next = [&](const std::string& publisher, const std::string& channel) {
    return PubSeq(publisher, counts[publisher + channel]++);
  };
  auto capture = [&](std::int64_t frame, const std::string& purpose) {
    rover_msgs::capture_request_t m{};
    m.pub_seq = next("sequence_executor", "CAPTURE_REQUEST");
    m.frame_id = frame;
    m.purpose = purpose;
    log.Add("CAPTURE_REQUEST", m);
  };
  auto frame = [&](std::int64_t id, const std::string& purpose) {
    rover_msgs::stereo_frame_t m{};
    m.pub_seq = next("camera_capture", "STEREO_FRAME");
    m.frame_id = id;
    m.purpose = purpose;
    m.left.data.assign(1000, 7);  // image bytes after the fields read
    m.left.size = 1000;
    log.Add("STEREO_FRAME", m);
  };
  auto hazcam = [&](std::int64_t id, const std::string& purpose) {
    rover_msgs::stereo_frame_t m{};
    m.pub_seq = next("camera_capture", "HAZCAM_FRAME");
    m.frame_id = id;
    m.purpose = purpose;
    m.left.data.assign(500, 9);
    m.left.size = 500;
    log.Add("HAZCAM_FRAME", m);
  };
  auto vo = [&](std::int64_t from, std::int64_t to) {
    rover_msgs::vo_update_t m{};
    m.pub_seq = next("visual_odometry", "VO_UPDATE");
    m.from_frame_id = from;
    m.to_frame_id = to;
    log.Add("VO_UPDATE", m);
  };
  auto command = [&](std::int64_t id, std::int8_t type) {
    rover_msgs::mobility_command_t m{};
    m.pub_seq = next("sequence_executor", "MOBILITY_COMMAND");
    m.command_id = id;
    m.type = type;
    log.Add("MOBILITY_COMMAND", m);
  };
  auto status = [&](std::int64_t id, std::int8_t state) {
    rover_msgs::mobility_status_t m{};
    m.pub_seq = next("rover_sim", "MOBILITY_STATUS");
    m.command_id = id;
    m.state = state;
    log.Add("MOBILITY_STATUS", m);
  };
  auto step = [&](std::int64_t command) {
    rover_msgs::step_report_t m{};
    m.pub_seq = next("sequence_executor", "STEP_REPORT");
    m.submission_id = 1;
    m.command_index = 3;
    m.step_index = 4;
    m.mobility_command_id = command;
    log.Add("STEP_REPORT", m);
  };
  using MC = rover_msgs::mobility_command_t;
  using MS = rover_msgs::mobility_status_t;
  capture(1, "vo_baseline"), hazcam(1, "vo_baseline"), frame(1, "vo_baseline"), vo(-1, 1);
  command(10, MC::TYPE_ARC), status(10, MS::STATE_MOVING), status(10, MS::STATE_DONE);
  capture(2, "vo"), hazcam(2, "vo"), frame(2, "vo");  // no VO update for frame 2
  step(10);
  command(11, MC::TYPE_TURN), status(11, MS::STATE_DONE);  // no step report for 11
  capture(3, "vo"), hazcam(3, "vo");                       // no frame 3, a HAZCAM pair alone
  capture(4, "science"), frame(4, "science");              // no VO for science: fine
  command(12, MC::TYPE_STOP), status(12, MS::STATE_DONE);  // a stop is not a motion

  const auto report = CheckLog(log.Close());
  EXPECT_TRUE(report.complete) << report.verdict_reason;  // nothing lost, yet inconsistent
  // A HAZCAM_FRAME needs no VO_UPDATE (frame 1 and 2's are not named), but one needs its
  // STEREO_FRAME; a science pair without a HAZCAM pair (frame 4) is fine.
  ASSERT_EQ(report.warnings.size(), 4u) << FormatReport(report);
  EXPECT_EQ(report.warnings[0], "1 CAPTURE_REQUEST without a STEREO_FRAME: frame 3");
  EXPECT_EQ(report.warnings[1], "1 STEREO_FRAME without a VO_UPDATE: frame 2");
  EXPECT_EQ(report.warnings[2], "1 HAZCAM_FRAME without a STEREO_FRAME: frame 3");
  EXPECT_EQ(report.channels.at("HAZCAM_FRAME").count, 3) << FormatReport(report);
  EXPECT_EQ(report.channels.at("HAZCAM_FRAME").type_name, "stereo_frame_t");
  EXPECT_EQ(report.warnings[3],
            "1 STEP_REPORT for 2 completed motion commands; completed without a step report: "
            "command 11");
}

TEST(Cli, PrintsTheVerdictAndExitsNonZeroOnALoss) {
  TestLog log("cli");
  log.Add("IMU", Imu(1000, "rover_sim", 0));
  log.Add("IMU", Imu(2000, "rover_sim", 2));
  const std::string cmd = std::string(ROVER_BINARY_DIR) + "/bin/logcheck " + log.Close();
  FILE* p = popen(cmd.c_str(), "r");
  ASSERT_NE(p, nullptr);
  std::string out;
  std::array<char, 512> buf{};
  while (fgets(buf.data(), buf.size(), p) != nullptr) out += buf.data();
  const int status = pclose(p);
  EXPECT_EQ(WEXITSTATUS(status), 1) << out;
  EXPECT_NE(out.find("gap: IMU from rover_sim: 1 lost (count 0 then 2) between utime 1000 and 2000"),
            std::string::npos)
      << out;
  EXPECT_NE(out.find("log complete: no (1 message lost in 1 gap)"), std::string::npos) << out;
}
