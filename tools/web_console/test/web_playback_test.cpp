// rover_web --log: a log written here (the rover driving a curve, stamped in rover time as
// the recorder stamps a virtual-time run) played back, checked over HTTP with cpp-httplib:
//   - /api/state?at=T reports the last POSE logged at or before T (its utime, x, y), the
//     steps reported by then, heartbeat ages in log time; scrubbing back gives the earlier
//     state again (the state is rebuilt), and a POSE that fails the bus's checks is left out;
//   - every command is refused (403), and a bad ?at= gets 400;
//   - with chromium installed, the page in a headless browser shows the slider at the
//     playback's time with every command disabled (build/test-out/web_playback/screenshot.png);
//   - a missing log, or a log with an operator secret, is one clear line and exit 2.
// Run it alone: ./rover private ctest --test-dir build -R WebConsole
#include "bus/channels.hpp"
#include "integration/run_support.hpp"
#include "launch/process_set.hpp"

#include <httplib.h>
#include <lcm/lcm-cpp.hpp>

#include <rover_msgs/heartbeat_t.hpp>
#include <rover_msgs/pose_t.hpp>
#include <rover_msgs/rover_clock_t.hpp>
#include <rover_msgs/sequence_status_t.hpp>
#include <rover_msgs/sequence_submit_t.hpp>
#include <rover_msgs/step_report_t.hpp>

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <thread>
#include <vector>

namespace rover::test {
namespace {

constexpr std::int64_t kT0 = 50'000'000;  // rover time of the first message: 50 s
constexpr std::int64_t kTick = 100'000;   // 10 Hz
constexpr int kTicks = 120;               // 12 s of driving

std::string ReadText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

struct LoggedPose {
  std::int64_t stamp;
  double x, y;
};

// What the log holds, for the test's expectations.
struct WrittenLog {
  std::vector<LoggedPose> poses;        // the valid ones, in order
  std::vector<std::int64_t> steps;      // step report stamps
  std::int64_t bad_pose_stamp = 0;      // a POSE with a NaN position
  std::int64_t heartbeat_stamp = 0;     // the last state_estimator heartbeat
};

// The rover on a curve, x = 0.25 t, y = 0.02 t^2 (t seconds from the start): a clock tick,
// a POSE and a heartbeat every 0.1 s, a step report every 2 s, and one broken POSE.
WrittenLog WriteLog(const std::string& path) {
  WrittenLog w;
  lcm::LogFile file(path, "w");
  EXPECT_TRUE(file.good());
  auto write = [&](const char* channel, const auto& msg, std::int64_t stamp) {
    std::vector<std::uint8_t> buf(msg.getEncodedSize());
    msg.encode(buf.data(), 0, static_cast<int>(buf.size()));
    lcm::LogEvent ev{};
    ev.timestamp = stamp;
    ev.channel = channel;
    ev.datalen = static_cast<std::int32_t>(buf.size());
    ev.data = buf.data();
    EXPECT_EQ(file.writeEvent(&ev), 0);
  };
  rover_msgs::sequence_submit_t submit{};
  submit.submission_id = 7;
  submit.name = "curve.seq";
  submit.text = "drive 3 m\n";
  write(channels::kSequenceSubmit, submit, kT0);
  for (int i = 0; i <= kTicks; ++i) {
    const std::int64_t t = kT0 + i * kTick;
    rover_msgs::rover_clock_t clock{};
    clock.utime = t;
    clock.mode = rover_msgs::rover_clock_t::MODE_VIRTUAL;
    write(channels::kClock, clock, t);
    rover_msgs::pose_t pose{};
    pose.utime = t;
    const double s = i * kTick * 1e-6;
    pose.position[0] = 0.25 * s;
    pose.position[1] = 0.02 * s * s;
    pose.orientation[0] = 1.0;
    for (int k = 0; k < 6; ++k) pose.covariance[k][k] = 1e-4;
    if (i == 61) {  // at 56.1 s: a POSE the bus would drop
      pose.position[0] = std::numeric_limits<double>::quiet_NaN();
      w.bad_pose_stamp = t;
    } else {
      w.poses.push_back({t, pose.position[0], pose.position[1]});
    }
    write(channels::kPose, pose, t);
    if (i <= 80) {  // the estimator falls silent at 58 s
      rover_msgs::heartbeat_t hb{};
      hb.utime = t;
      hb.process = "state_estimator";
      write(channels::kHeartbeat, hb, t);
      w.heartbeat_stamp = t;
    }
    if (i > 0 && i % 20 == 0) {
      rover_msgs::step_report_t step{};
      step.utime = t;
      step.submission_id = 7;
      step.step_index = i / 20 - 1;
      step.commanded_distance_m = 0.5;
      step.vo_status = -1;
      write(channels::kStepReport, step, t);
      w.steps.push_back(t);
    }
    rover_msgs::sequence_status_t st{};
    st.utime = t;
    st.submission_id = 7;
    st.sequence_name = "curve.seq";
    st.state = i == kTicks ? rover_msgs::sequence_status_t::STATE_COMPLETED : rover_msgs::sequence_status_t::STATE_RUNNING;
    st.num_commands = 1;
    st.command_text = "drive 3 m";
    if (i % 10 == 0 || i == kTicks) write(channels::kSequenceStatus, st, t);
  }
  return w;
}

TEST(WebConsolePlayback, StateAtATimeIsTheLogsPoseThenAndCommandsAreRefused) {
  const std::string dir = OutDir("web_playback");
  const std::string log = dir + "/curve.lcm";
  const WrittenLog written = WriteLog(log);
  ASSERT_EQ(written.poses.size(), static_cast<std::size_t>(kTicks));

  launch::ProcessSet set(std::string(ROVER_BINARY_DIR) + "/bin", dir, false);
  launch::ProcessSpec web;
  web.name = "rover_web";
  web.program = "rover_web";
  web.args = {"--port", "0", "--log", log};
  set.Start(web);
  int port = 0;
  const std::string listening = "listening on http://127.0.0.1:";
  const auto start = std::chrono::steady_clock::now();
  while (port == 0 && std::chrono::steady_clock::now() - start < std::chrono::seconds(30)) {
    set.Poll(100);
    const std::string out = ReadText(dir + "/rover_web.log");
    if (const auto at = out.find(listening); at != std::string::npos) port = std::atoi(out.c_str() + at + listening.size());
  }
  ASSERT_GT(port, 0) << "rover_web did not say where it listens:\n" << ReadText(dir + "/rover_web.log");
  const std::string said = ReadText(dir + "/rover_web.log");
  EXPECT_NE(said.find("playback of " + log), std::string::npos) << said;
  EXPECT_NE(said.find("1 left out"), std::string::npos) << "the NaN POSE is not counted as left out:\n" << said;

  httplib::Client http("127.0.0.1", port);
  http.set_connection_timeout(5);
  http.set_read_timeout(10);
  auto state_at = [&](double at_s) -> YAML::Node {
    char query[64];
    std::snprintf(query, sizeof(query), "/api/state?at=%.6f", at_s);
    auto res = http.Get(query);
    EXPECT_TRUE(res) << "rover_web is not answering";
    if (!res) return YAML::Node();
    EXPECT_EQ(res->status, 200) << res->body;
    return YAML::Load(res->body);
  };
  // The last valid POSE logged at or before `stamp`.
  auto pose_logged_at = [&](std::int64_t stamp) {
    const LoggedPose* last = nullptr;
    for (const auto& p : written.poses)
      if (p.stamp <= stamp) last = &p;
    return last;
  };
  auto expect_pose_at = [&](double at_s) {
    const YAML::Node s = state_at(at_s);
    ASSERT_TRUE(s["pose"] && !s["pose"].IsNull()) << "no pose at " << at_s;
    const auto at_utime = static_cast<std::int64_t>(std::llround(at_s * 1e6));
    const LoggedPose* want = pose_logged_at(at_utime);
    ASSERT_NE(want, nullptr);
    EXPECT_EQ(s["pose"]["utime"].as<std::int64_t>(), want->stamp) << "at " << at_s;
    EXPECT_NEAR(s["pose"]["x"].as<double>(), want->x, 1e-4) << "at " << at_s;
    EXPECT_NEAR(s["pose"]["y"].as<double>(), want->y, 1e-4) << "at " << at_s;
    EXPECT_NEAR(s["playback"]["at_s"].as<double>(), at_s, 1e-6);
    EXPECT_LE(s["rover_time_s"].as<double>(), at_s + 1e-9);
    std::size_t steps = 0;
    for (auto t : written.steps) steps += t <= at_utime;
    EXPECT_EQ(s["steps"].size(), steps) << "at " << at_s;
  };

  // The page opens at the end of the log: the whole drive, completed.
  {
    auto page = http.Get("/");
    ASSERT_TRUE(page);
    EXPECT_EQ(page->status, 200);
    EXPECT_NE(page->body.find("\"playback\":{\"log\":"), std::string::npos) << "the page does not know it plays back";
    const YAML::Node s = YAML::Load(http.Get("/api/state")->body);
    EXPECT_NEAR(s["playback"]["first_s"].as<double>(), kT0 * 1e-6, 1e-6);
    EXPECT_NEAR(s["playback"]["last_s"].as<double>(), (kT0 + kTicks * kTick) * 1e-6, 1e-6);
    EXPECT_EQ(s["status"]["state"].as<std::string>(), "completed");
    EXPECT_FALSE(s["commands"]["enabled"].as<bool>());
    EXPECT_NEAR(s["pose"]["x"].as<double>(), written.poses.back().x, 1e-4);
  }
  // Times between ticks and on them, forward, then back (a new state), then forward again.
  for (const double at_s : {53.37, 57.05, 51.0, 55.0, 61.96, 53.37}) expect_pose_at(at_s);
  // The path grows with time: fewer points at 53 s than at 61 s.
  EXPECT_LT(state_at(53.0)["path"].size(), state_at(61.0)["path"].size());
  // Just after the broken POSE: the one before it stands, finite.
  {
    const double at_s = written.bad_pose_stamp * 1e-6 + 0.05;
    expect_pose_at(at_s);
    const YAML::Node s = state_at(at_s);
    EXPECT_EQ(s["pose"]["utime"].as<std::int64_t>(), written.bad_pose_stamp - kTick);
  }
  // Heartbeat ages in log time: the estimator fell silent at 58 s.
  {
    const YAML::Node s = state_at(59.5);
    ASSERT_EQ(s["processes"].size(), 1u);
    EXPECT_NEAR(s["processes"][0]["age_s"].as<double>(), 59.5 - written.heartbeat_stamp * 1e-6, 1e-6);
    EXPECT_EQ(s["processes"][0]["state"].as<std::string>(), "ok");  // 1.5 s: not yet silent (3 s)
    EXPECT_EQ(state_at(61.5)["processes"][0]["state"].as<std::string>(), "silent");
  }
  // Before the log: its first instant (the first POSE); past the end: the end.
  EXPECT_EQ(state_at(10.0)["pose"]["utime"].as<std::int64_t>(), kT0);
  EXPECT_NEAR(state_at(1e6)["playback"]["at_s"].as<double>(), (kT0 + kTicks * kTick) * 1e-6, 1e-6);

  // Commands: refused, with the secret header or without.
  for (const char* path : {"/api/pause", "/api/resume", "/api/abort", "/api/submit"}) {
    auto res = http.Post(path, {{"X-Rover-Secret", "s3cret-operator-token"}}, "drive 1 m\n", "text/plain");
    ASSERT_TRUE(res) << path;
    EXPECT_EQ(res->status, 403) << path << ": " << res->body;
    EXPECT_NE(res->body.find("playing back"), std::string::npos) << path << ": " << res->body;
  }
  auto bad = http.Get("/api/state?at=soon");
  ASSERT_TRUE(bad);
  EXPECT_EQ(bad->status, 400);
  EXPECT_NE(bad->body.find("at: \"soon\""), std::string::npos) << bad->body;
  auto no_image = http.Get("/api/image.png?at=55");
  ASSERT_TRUE(no_image);
  EXPECT_EQ(no_image->status, 404) << "the log holds no STEREO_FRAME";
  // The page in a browser (chromium is optional): the script finds the playback, shows the
  // slider at the playback's time and disables every command; a screenshot is kept.
  if (RunCommand("command -v chromium").exit_code != 0) {
    std::cout << "[  SKIPPED ] browser check: chromium is not installed (apt-get install chromium)\n";
  } else {
    state_at(56.0);  // the page opens where the playback is
    const std::string url = " http://127.0.0.1:" + std::to_string(port) + "/";
    const std::string flags = "timeout 90 chromium --headless --no-sandbox --disable-gpu --hide-scrollbars ";
    const auto dom = RunCommand(flags + "--user-data-dir=" + dir + "/chromium --dump-dom" + url + " 2>/dev/null");
    EXPECT_NE(dom.output.find("<section id=\"playbar\">"), std::string::npos) << "the playback bar is hidden:\n" << dom.output;
    EXPECT_NE(dom.output.find("<span id=\"ptime\">log time 56.0 s (6.0 of 12.0)"), std::string::npos) << dom.output;
    EXPECT_NE(dom.output.find("<button id=\"abort\" class=\"abort\" disabled"), std::string::npos) << dom.output;
    EXPECT_NE(dom.output.find("<span id=\"conn\">playback"), std::string::npos) << dom.output;
    const std::string shot = dir + "/screenshot.png";
    RunCommand(flags + "--user-data-dir=" + dir + "/chromium --window-size=1400,1000 --screenshot=" + shot + url);
    EXPECT_TRUE(std::filesystem::exists(shot)) << "chromium wrote no screenshot";
    std::cout << "screenshot: " << shot << "\n";
  }
  set.StopAll();

  // Bad input: one line, exit 2.
  const auto missing = RunCommand(Bin("rover_web") + " --port 0 --log " + dir + "/none.lcm");
  EXPECT_EQ(missing.exit_code, 2) << missing.output;
  EXPECT_NE(missing.output.find("--log: " + dir + "/none.lcm: cannot read the LCM log"), std::string::npos) << missing.output;
  const auto with_secret = RunCommand(Bin("rover_web") + " --port 0 --secret 0123456789abcdef --log " + log);
  EXPECT_EQ(with_secret.exit_code, 2) << with_secret.output;
  EXPECT_NE(with_secret.output.find("a playback sends no commands"), std::string::npos) << with_secret.output;
}

}  // namespace
}  // namespace rover::test
