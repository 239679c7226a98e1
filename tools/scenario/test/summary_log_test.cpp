// summary.json from logs built here: the log's completeness per channel, and a reason beside
// every figure the log could not give (never a bare null).
#include "bus/bus.hpp"
#include "scenario/scenario.hpp"

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>
#include <rover_msgs/keepout_zones_t.hpp>
#include <rover_msgs/pose_t.hpp>
#include <rover_msgs/sequence_status_t.hpp>
#include <rover_msgs/sequence_submit_t.hpp>
#include <rover_msgs/sim_truth_t.hpp>
#include <yaml-cpp/yaml.h>

#include <unistd.h>

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using namespace rover;

namespace {

std::int64_t PubSeq(const std::string& publisher, std::int64_t count) {
  return static_cast<std::int64_t>((static_cast<std::uint64_t>(bus::PublisherId(publisher)) << 32) |
                                   static_cast<std::uint64_t>(count));
}

class TestLog {
 public:
  explicit TestLog(const std::string& name) {
    dir_ = fs::temp_directory_path() / ("summary_log_test_" + std::to_string(getpid()) + name);
    fs::create_directories(dir_);
    path_ = (dir_ / "log.lcm").string();
    file_ = std::make_unique<lcm::LogFile>(path_, "w");
  }
  ~TestLog() { fs::remove_all(dir_); }
  template <class Msg>
  void Add(const std::string& channel, const Msg& m) {
    std::vector<std::uint8_t> buf(static_cast<std::size_t>(m.getEncodedSize()));
    ASSERT_GT(m.encode(buf.data(), 0, static_cast<int>(buf.size())), 0);
    lcm::LogEvent ev{};
    ev.timestamp = ++timestamp_;
    ev.channel = channel;
    ev.datalen = static_cast<std::int32_t>(buf.size());
    ev.data = buf.data();
    ASSERT_EQ(file_->writeEvent(&ev), 0);
  }
  const std::string& Close() {
    file_.reset();
    return path_;
  }

 private:
  fs::path dir_;
  std::string path_;
  std::unique_ptr<lcm::LogFile> file_;
  std::int64_t timestamp_ = 0;
};

rover_msgs::sequence_status_t Completed() {
  rover_msgs::sequence_status_t m{};
  m.utime = 5000000;
  m.pub_seq = PubSeq("sequence_executor", 0);
  m.submission_id = 1;
  m.state = rover_msgs::sequence_status_t::STATE_COMPLETED;
  m.num_commands = 0;
  return m;
}

rover_msgs::sim_truth_t Truth(std::int64_t count) {
  rover_msgs::sim_truth_t m{};
  m.utime = 100000 * count;
  m.pub_seq = PubSeq("rover_sim", count);
  m.orientation[0] = 1;
  m.odometer_m = 0.01 * static_cast<double>(count);
  return m;
}

hazards::Footprint SmallFootprint() {
  hazards::Footprint f;
  f.length_m = 1.0;
  f.width_m = 1.0;
  return f;
}

YAML::Node Json(const tools::ScenarioSummary& s) { return YAML::Load(tools::SummaryJson(s)); }

}  // namespace

TEST(SummaryLog, EveryFigureTheLogCannotGiveSaysWhy) {
  TestLog log("no_truth");
  rover_msgs::keepout_zones_t zones{};
  zones.pub_seq = PubSeq("sequence_executor", 0);
  rover_msgs::keepout_zone_t rock{};
  rock.name = "rock";
  rock.shape = rover_msgs::keepout_zone_t::SHAPE_CIRCLE;
  rock.center[0] = 3;
  rock.radius_m = 0.5;
  zones.zones.push_back(rock);
  zones.num_zones = 1;
  log.Add("KEEPOUT_ZONES", zones);
  log.Add("SEQUENCE_STATUS", Completed());
  const auto s = tools::SummarizeLog(log.Close(), SmallFootprint());
  const YAML::Node j = Json(s);

  EXPECT_TRUE(j["log_complete"].as<bool>());
  EXPECT_EQ(j["log_channels"]["KEEPOUT_ZONES"]["count"].as<int>(), 1);
  EXPECT_EQ(j["log_channels"]["SEQUENCE_STATUS"]["lost"].as<int>(), 0);
  EXPECT_TRUE(j["final_estimate"].IsNull());
  EXPECT_EQ(j["final_estimate_reason"].as<std::string>(), "no POSE in the log");
  for (const char* key : {"final_truth", "distance_travelled_m", "rover_time_s",
                          "position_error_m", "position_error_pct", "min_keepout_clearance_m"}) {
    EXPECT_TRUE(j[key].IsNull()) << key;
    ASSERT_TRUE(j[std::string(key) + "_reason"]) << key << " is a bare null";
    const auto why = j[std::string(key) + "_reason"].as<std::string>();
    EXPECT_NE(why.find("no SIM_TRUTH in the log"), std::string::npos) << key << ": " << why;
  }
  EXPECT_EQ(j["min_keepout_clearance_m_reason"].as<std::string>().rfind("no SIM_TRUTH in the log", 0),
            0u);
  // Every null at the top level has its reason (abort_reason is null when nothing aborted).
  for (const auto& kv : j) {
    const auto key = kv.first.as<std::string>();
    if (kv.second.IsNull() && key != "abort_reason") {
      EXPECT_TRUE(j[key + "_reason"]) << key << " is null without a reason";
    }
  }
}

TEST(SummaryLog, ALossShowsPerChannelAndInTheReasons) {
  TestLog log("gap");
  for (const int c : {0, 1, 2, 6, 7}) log.Add("SIM_TRUTH", Truth(c));  // 3, 4, 5 lost
  rover_msgs::pose_t pose{};
  pose.utime = 700000;
  pose.pub_seq = PubSeq("state_estimator", 0);
  pose.orientation[0] = 1;
  log.Add("POSE", pose);
  log.Add("SEQUENCE_STATUS", Completed());
  const auto s = tools::SummarizeLog(log.Close(), SmallFootprint());
  const YAML::Node j = Json(s);

  EXPECT_FALSE(j["log_complete"].as<bool>());
  EXPECT_EQ(j["log_complete_reason"].as<std::string>(), "3 messages lost in 1 gap");
  EXPECT_EQ(j["log_lost"].as<int>(), 3);
  const YAML::Node gaps = j["log_channels"]["SIM_TRUTH"]["gaps"];
  ASSERT_EQ(gaps.size(), 1u);
  EXPECT_EQ(gaps[0]["publisher"].as<std::string>(), "rover_sim");
  EXPECT_EQ(gaps[0]["lost"].as<int>(), 3);
  EXPECT_EQ(gaps[0]["utime_before"].as<long long>(), 200000);
  EXPECT_EQ(gaps[0]["utime_after"].as<long long>(), 600000);
  // Truth and estimate are there, so the figures are; no zone, so no clearance, and why.
  EXPECT_FALSE(j["final_truth"].IsNull());
  EXPECT_FALSE(j["position_error_m"].IsNull());
  EXPECT_TRUE(j["min_keepout_clearance_m"].IsNull());
  EXPECT_EQ(j["min_keepout_clearance_m_reason"].as<std::string>(), "no keep-out zone was defined");
  EXPECT_NE(tools::SummaryText(s).find("log: 7 messages, 3 lost; complete: no"), std::string::npos)
      << tools::SummaryText(s);
}

// Two sequences on one running stack (scenario then_sequences): the summary judges the
// last one submitted; while it has not ended, the run is incomplete, whatever the first did.
TEST(SummaryLog, TheLastSequenceSubmittedIsJudged) {
  auto submit = [](std::int64_t id, const std::string& text) {
    rover_msgs::sequence_submit_t m{};
    m.submission_id = id;
    m.name = "s" + std::to_string(id) + ".seq";
    m.text = text;
    return m;
  };
  rover_msgs::sequence_status_t second = Completed();
  second.submission_id = 2;
  second.state = rover_msgs::sequence_status_t::STATE_ABORTED;
  second.abort_reason = "goal_unreachable";
  second.pub_seq = PubSeq("sequence_executor", 1);
  {
    TestLog log("two_unfinished");
    log.Add(channels::kSequenceSubmit, submit(1, "drive 1 m\n"));
    log.Add(channels::kSequenceStatus, Completed());
    log.Add(channels::kSequenceSubmit, submit(2, "goto 0 m 0 m within 0.5 m avoid on\n"));
    const auto s = tools::SummarizeLog(log.Close(), SmallFootprint());
    EXPECT_EQ(s.outcome, "incomplete");
  }
  {
    TestLog log("two_ended");
    log.Add(channels::kSequenceSubmit, submit(1, "drive 1 m\n"));
    log.Add(channels::kSequenceStatus, Completed());
    log.Add(channels::kSequenceSubmit, submit(2, "goto 0 m 0 m within 0.5 m avoid on\n"));
    log.Add(channels::kSequenceStatus, second);
    const auto s = tools::SummarizeLog(log.Close(), SmallFootprint());
    EXPECT_EQ(s.outcome, "aborted");
    EXPECT_EQ(s.abort_reason, "goal_unreachable");
  }
}
