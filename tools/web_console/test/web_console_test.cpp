// rover_web on the real process set (configs/deploy/sim_vo_auth.yaml on a private bus,
// with a key made here, so the executor obeys only signed commands), checked over HTTP
// with cpp-httplib's client, as a browser would see it:
//   - /api/state reports the rover where POSE puts it (1 cm): before, paused mid-drive, after;
//   - a sequence submitted from the page runs; a bad one gets 400 and the checker's line;
//   - pause without the secret, or with a wrong one, is refused (403) and the drive goes
//     on; with it the executor pauses (so the pause was signed with the deployment key),
//     and resume finishes the sequence; abort from the page aborts a second one;
//   - the page, its script, the NAVCAM image (a PNG) and the traversability map are served;
//   - a request naming another Host (DNS rebinding) is refused;
// The page in a real browser, clicked, is web_browser_test.cpp.
// Run it alone: ./rover private ctest --test-dir build -R WebConsole
#include "web_console/test/web_test_stack.hpp"

#include <httplib.h>

#include <rover_msgs/heartbeat_t.hpp>
#include <rover_msgs/pose_t.hpp>
#include <rover_msgs/sequence_status_t.hpp>
#include <rover_msgs/step_report_t.hpp>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <thread>

#include <sys/stat.h>

namespace rover::test {
namespace {

using Clock = std::chrono::steady_clock;
using rover_msgs::sequence_status_t;
// LCM declares its constants without defining them: copies, so gtest may take references.
constexpr std::int8_t kRunning = sequence_status_t::STATE_RUNNING;
constexpr std::int8_t kPaused = sequence_status_t::STATE_PAUSED;
constexpr std::int8_t kCompleted = sequence_status_t::STATE_COMPLETED;
constexpr std::int8_t kAborted = sequence_status_t::STATE_ABORTED;

double Seconds(Clock::time_point since) { return SecondsSince(since); }

TEST(WebConsole, StateMatchesPoseAndCommandsNeedTheSecret) {
  WebStack stack("web_console", 57);
  ASSERT_GT(stack.port, 0);
  const std::string& dir = stack.dir;
  const std::string& secret = stack.secret;
  const int port = stack.port;
  Listener& heard = stack.heard;
  launch::ProcessSet& set = stack.set;
  const launch::Deployment& deployment = stack.deployment;
  httplib::Client http("127.0.0.1", port);
  http.set_connection_timeout(5);
  http.set_read_timeout(10);
  const httplib::Headers with_secret = {{"X-Rover-Secret", secret}};
  auto state = [&]() -> YAML::Node {
    auto res = http.Get("/api/state");
    if (!res || res->status != 200) return YAML::Node();
    return YAML::Load(res->body);
  };
  // The console's pose against the last POSE this test heard, while the rover stands
  // still (before the drive, paused, after it), so that both have the same one: taken
  // when no new POSE arrived during the request.
  auto expect_pose_matches = [&](const char* when) {
    rover_msgs::pose_t before, after;
    YAML::Node s;
    for (int attempt = 0; attempt < 100; ++attempt) {  // up to 10 s
      {
        std::lock_guard<std::mutex> lock(heard.mutex);
        before = heard.pose;
      }
      s = state();
      {
        std::lock_guard<std::mutex> lock(heard.mutex);
        after = heard.pose;
      }
      if (s && s["pose"] && !s["pose"].IsNull() && before.utime == after.utime && before.utime != 0) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    ASSERT_TRUE(s && s["pose"] && !s["pose"].IsNull()) << when << ": no pose in /api/state";
    const double dx = s["pose"]["x"].as<double>() - after.position[0];
    const double dy = s["pose"]["y"].as<double>() - after.position[1];
    EXPECT_LT(std::hypot(dx, dy), 0.01) << when << ": /api/state x " << s["pose"]["x"].as<double>() << " y "
                                        << s["pose"]["y"].as<double>() << ", POSE x " << after.position[0] << " y "
                                        << after.position[1];
    EXPECT_NEAR(s["pose"]["z"].as<double>(), after.position[2], 0.01) << when;
  };

  // The page and its script.
  auto page = http.Get("/");
  ASSERT_TRUE(page) << "rover_web is not answering on port " << port << ": " << httplib::to_string(page.error())
                    << "\n" << ReadText(dir + "/rover_web.log");
  EXPECT_EQ(page->status, 200);
  EXPECT_NE(page->body.find("<canvas id=\"map\""), std::string::npos);
  EXPECT_NE(page->body.find("id=\"initial-state\">{\"bus\":"), std::string::npos) << "no state in the page";
  EXPECT_EQ(page->body.find("{{STATE}}"), std::string::npos);
  EXPECT_NE(page->get_header_value("Content-Security-Policy").find("script-src 'self'"), std::string::npos);
  auto script = http.Get("/app.js");
  ASSERT_TRUE(script);
  EXPECT_EQ(script->status, 200);
  EXPECT_NE(script->body.find("EventSource"), std::string::npos);
  // Another site's name in Host (DNS rebinding): refused.
  auto rebound = http.Get("/api/state", {{"Host", "evil.example:" + std::to_string(port)}});
  ASSERT_TRUE(rebound);
  EXPECT_EQ(rebound->status, 403) << rebound->body;

  // Still: the rover has not moved.
  expect_pose_matches("before the drive");
  {
    const YAML::Node s = state();
    EXPECT_TRUE(s["commands"]["enabled"].as<bool>());
    EXPECT_TRUE(s["commands"]["signed"].as<bool>());
  }

  // Bad input: one clear 400 each, nothing sent.
  auto bad = http.Post("/api/submit?name=bad.seq", with_secret, "drive 2 deg\n", "text/plain");
  ASSERT_TRUE(bad);
  EXPECT_EQ(bad->status, 400);
  EXPECT_NE(bad->body.find("bad.seq:1:"), std::string::npos) << bad->body;
  EXPECT_NE(bad->body.find("expected"), std::string::npos) << bad->body;
  auto empty = http.Post("/api/submit", with_secret, "", "text/plain");
  ASSERT_TRUE(empty);
  EXPECT_EQ(empty->status, 400) << empty->body;
  auto bad_reason = http.Post("/api/pause", with_secret, std::string("two\x01lines"), "text/plain");
  ASSERT_TRUE(bad_reason);
  EXPECT_EQ(bad_reason->status, 400) << bad_reason->body;
  // A submit without the secret: refused, and no sequence starts.
  auto unsigned_submit = http.Post("/api/submit", "drive 1 m\n", "text/plain");
  ASSERT_TRUE(unsigned_submit);
  EXPECT_EQ(unsigned_submit->status, 403);

  // A drive of 4 steps, submitted from the page, with a keep-out zone (the demo's
  // Humphrey), then a goto (its disc is drawn).
  const std::string text =
      "vo on step 40 cm\nkeepout humphrey circle 3 m -2.8 m radius 0.7 m\ndrive 1.6 m\n"
      "goto 2.2 m 0.8 m within 0.3 m avoid on\n";
  auto submitted = http.Post("/api/submit?name=web_test.seq", with_secret, text, "text/plain");
  ASSERT_TRUE(submitted);
  ASSERT_EQ(submitted->status, 200) << submitted->body;
  const std::int64_t id = YAML::Load(submitted->body)["submission_id"].as<std::int64_t>();
  EXPECT_TRUE(YAML::Load(submitted->body)["signed"].as<bool>());

  // After the first step: pause without the secret, and with a wrong one: refused.
  const auto t0 = Clock::now();
  while (Seconds(t0) < 120) {
    {
      std::lock_guard<std::mutex> lock(heard.mutex);
      if (heard.steps >= 1) break;
    }
    set.Poll(100);
  }
  ASSERT_TRUE(heard.HasState(id, kRunning)) << "the submitted sequence did not run";
  auto no_secret = http.Post("/api/pause", "", "text/plain");
  ASSERT_TRUE(no_secret);
  EXPECT_EQ(no_secret->status, 403);
  EXPECT_NE(no_secret->body.find("X-Rover-Secret"), std::string::npos) << no_secret->body;
  auto wrong = http.Post("/api/pause", {{"X-Rover-Secret", secret + "x"}}, "", "text/plain");
  ASSERT_TRUE(wrong);
  EXPECT_EQ(wrong->status, 403);
  EXPECT_NE(wrong->body.find("wrong operator secret"), std::string::npos) << wrong->body;
  // The sequence text and its current line are on the page's state while it runs.
  {
    const YAML::Node s = state();
    EXPECT_EQ(s["sequence_text"].as<std::string>(""), text);
    EXPECT_EQ(s["status"]["submission_id"].as<std::int64_t>(), id);
  }
  // A refused pause leaves the drive going: the next step comes, and no pause.
  int steps_before_pause = 0;
  const auto t_refused = Clock::now();
  while (Seconds(t_refused) < 60) {
    {
      std::lock_guard<std::mutex> lock(heard.mutex);
      steps_before_pause = heard.steps;
    }
    if (steps_before_pause >= 2) break;
    set.Poll(100);
  }
  EXPECT_GE(steps_before_pause, 2) << "no step after the refused pauses";
  EXPECT_FALSE(heard.HasState(id, kPaused)) << "a pause without the secret was obeyed";

  // With the secret: signed, published, and the executor pauses between steps.
  auto paused = http.Post("/api/pause", with_secret, "test pause", "text/plain");
  ASSERT_TRUE(paused);
  EXPECT_EQ(paused->status, 200) << paused->body;
  const auto t1 = Clock::now();
  while (!heard.HasState(id, kPaused) && Seconds(t1) < 60) set.Poll(100);
  ASSERT_TRUE(heard.HasState(id, kPaused)) << "the executor did not pause";
  ASSERT_EQ(heard.LastState(id), kPaused);
  set.Poll(1000);
  {
    const YAML::Node s = state();
    EXPECT_EQ(s["status"]["state"].as<std::string>(), "paused");
    // Moved, and the estimate and truth are both on the page, with the path so far.
    EXPECT_GT(s["pose"]["x"].as<double>(), 0.3);
    ASSERT_TRUE(s["truth"] && !s["truth"].IsNull());
    EXPECT_LT(std::hypot(s["truth"]["x"].as<double>() - s["pose"]["x"].as<double>(),
                         s["truth"]["y"].as<double>() - s["pose"]["y"].as<double>()), 0.1);
    EXPECT_GE(s["path"].size(), 4u);
    EXPECT_GT(s["pose"]["ellipse_3sigma"]["major_m"].as<double>(), 0.0);
    EXPECT_GE(s["steps"].size(), 1u);
    EXPECT_TRUE(s["vo"] && !s["vo"].IsNull());
    EXPECT_TRUE(s["hazard"] && !s["hazard"].IsNull());
    EXPECT_GE(s["processes"].size(), 7u);
    ASSERT_EQ(s["zones"].size(), 1u);
    EXPECT_EQ(s["zones"][0]["name"].as<std::string>(), "humphrey");
    EXPECT_NEAR(s["zones"][0]["radius_m"].as<double>(), 0.7, 1e-6);
    ASSERT_TRUE(s["map"] && !s["map"].IsNull()) << "no TRAVERSABILITY_MAP on the page";
    EXPECT_EQ(s["map"]["cells"].as<std::string>().size(),
              static_cast<std::size_t>(s["map"]["rows"].as<int>() * s["map"]["cols"].as<int>()));
    EXPECT_GT(s["map"]["safe"].as<int>(), 0);
    ASSERT_TRUE(s["image"] && !s["image"].IsNull());
  }
  expect_pose_matches("paused mid-drive");

  // The NAVCAM image: a PNG of the default width.
  auto image = http.Get("/api/image.png");
  ASSERT_TRUE(image);
  ASSERT_EQ(image->status, 200) << image->body;
  EXPECT_EQ(image->get_header_value("Content-Type"), "image/png");
  const cv::Mat navcam = cv::imdecode(std::vector<unsigned char>(image->body.begin(), image->body.end()),
                                      cv::IMREAD_UNCHANGED);
  EXPECT_EQ(navcam.cols, 256);
  auto bad_width = http.Get("/api/image.png?width=9x");
  ASSERT_TRUE(bad_width);
  EXPECT_EQ(bad_width->status, 400);

  // Resume: the sequence goes on to its end (the goto inside its disc).
  bool goal_seen = false;
  auto resumed = http.Post("/api/resume", with_secret, "", "text/plain");
  ASSERT_TRUE(resumed);
  EXPECT_EQ(resumed->status, 200) << resumed->body;
  const auto t2 = Clock::now();
  while (Seconds(t2) < 240) {
    const auto last = heard.LastState(id);
    if (last == kCompleted || last == kAborted) break;
    if (!goal_seen) {
      const YAML::Node s = state();
      if (s && s["goal"] && !s["goal"].IsNull()) {
        goal_seen = true;
        EXPECT_NEAR(s["goal"]["x"].as<double>(), 2.2, 1e-6);
        EXPECT_NEAR(s["goal"]["y"].as<double>(), 0.8, 1e-6);
        EXPECT_NEAR(s["goal"]["radius_m"].as<double>(), 0.3, 1e-6);
      }
    }
    set.Poll(200);
  }
  EXPECT_EQ(heard.LastState(id), kCompleted);
  EXPECT_TRUE(goal_seen) << "the goto's disc never showed on /api/state";
  // rover_web hears the final status at its next instant of rover time (virtual time hands
  // an instant's messages over when the clock moves on): wait for it, not for the scheduler.
  std::string page_state;
  const auto t_final = Clock::now();
  while (Seconds(t_final) < 30) {
    page_state = state()["status"]["state"].as<std::string>("");
    if (page_state == "completed") break;
    set.Poll(100);
  }
  EXPECT_EQ(page_state, "completed");
  expect_pose_matches("after the drive");

  // Abort from the page: a second sequence, aborted while it runs, with the page's reason.
  auto second = http.Post("/api/submit?name=turns.seq", with_secret, "vo on\nturn 90 deg\nturn -90 deg\n", "text/plain");
  ASSERT_TRUE(second);
  ASSERT_EQ(second->status, 200) << second->body;
  const std::int64_t id2 = YAML::Load(second->body)["submission_id"].as<std::int64_t>();
  const auto t3 = Clock::now();
  while (!heard.HasState(id2, kRunning) && Seconds(t3) < 60) set.Poll(100);
  ASSERT_TRUE(heard.HasState(id2, kRunning));
  auto aborted = http.Post("/api/abort", with_secret, "web test abort", "text/plain");
  ASSERT_TRUE(aborted);
  EXPECT_EQ(aborted->status, 200) << aborted->body;
  while (heard.LastState(id2) != kAborted && Seconds(t3) < 60) set.Poll(100);
  ASSERT_EQ(heard.LastState(id2), kAborted);
  {
    // rover_web hears the final status on its own subscription: give it a moment.
    YAML::Node s = state();
    for (const auto t4 = Clock::now();
         s["status"]["abort_reason"].as<std::string>("") != "operator" && Seconds(t4) < 5;) {
      set.Poll(100);
      s = state();
    }
    EXPECT_EQ(s["status"]["abort_reason"].as<std::string>(""), "operator");
    EXPECT_NE(s["status"]["detail"].as<std::string>("").find("web test abort"), std::string::npos)
        << s["status"]["detail"].as<std::string>("");
  }

  // rover_web dropped nothing: each signed ROVER_CLOCK verified once (a second
  // subscription of its own once dropped every one as a replay).
  {
    const YAML::Node s = state();
    int found = 0;
    for (const auto& p : s["processes"]) {
      if (p["name"].as<std::string>("") != "rover_web") continue;
      ++found;
      EXPECT_EQ(p["dropped"].as<int>(-1), 0) << p["detail"].as<std::string>("");
    }
    EXPECT_EQ(found, 1) << "rover_web's own heartbeat is not on the page";
  }
  EXPECT_EQ(set.RunningNames().size(), deployment.processes.size() + 1);
  set.StopAll();
  // rover_web logged the refused guess and each command it sent, signed.
  const std::string log = ReadText(dir + "/rover_web.log");
  EXPECT_NE(log.find("wrong operator secret"), std::string::npos) << log;
  EXPECT_NE(log.find("pause sent (signed)"), std::string::npos) << log;
  EXPECT_NE(log.find("resume sent (signed)"), std::string::npos) << log;
  EXPECT_NE(log.find("abort sent (signed): web test abort"), std::string::npos) << log;
  // The executor refused nothing from rover_web (its commands were signed with the key).
  const std::string executor_log = ReadText(dir + "/sequence_executor.log");
  EXPECT_EQ(executor_log.find("SEQUENCE_CONTROL: dropped"), std::string::npos) << executor_log;
}

// Consoles the signed stack will not obey, beside the keyed one: one started without a key
// and one with another key. Each says so once on stderr and on the page's state, and a
// command from it shows as refused (403) with the executor's reason, not 200; the
// executor does not run it.
TEST(WebConsole, WithoutTheStacksKeyCommandsShowAsRefusedWithTheExecutorsReason) {
  WebStack stack("web_console_refused", 59);
  ASSERT_GT(stack.port, 0);
  const std::string other_key = stack.dir + "/other.key";
  ASSERT_EQ(RunCommand(Bin("rover_seq") + " keygen " + other_key).exit_code, 0);
  const std::string secret_file = stack.dir + "/secret";
  // Started by hand beside a running simulation: no ROVER_TIME, so they follow its clock
  // as observers, outside its barrier.
  auto start_console = [&](const std::string& name, std::vector<std::string> extra) {
    launch::ProcessSpec web;
    web.name = name;
    web.program = "rover_web";
    web.args = {"--port", "0", "--secret-file", secret_file};
    web.args.insert(web.args.end(), extra.begin(), extra.end());
    stack.set.Start(web, {"ROVER_LCM_URL=" + stack.url});
    int port = 0;
    const std::string listening = "listening on http://127.0.0.1:";
    stack.WaitFor([&] {
      const std::string log = ReadText(stack.dir + "/" + name + ".log");
      if (const auto at = log.find(listening); at != std::string::npos) port = std::atoi(log.c_str() + at + listening.size());
      return port > 0;
    }, 30);
    return port;
  };
  struct Console {
    std::string name, says, refused;
    int port;
  };
  std::vector<Console> consoles = {
      {"rover_web_nokey", "rover_web: this stack signs its messages (a signed HEARTBEAT from ",
       "refused by sequence_executor: SEQUENCE_SUBMIT: rejected: no authentication tag (a key is required on this bus)",
       start_console("rover_web_nokey", {})},
      {"rover_web_otherkey", "rover_web: rover_web's key does not verify this bus's messages (",
       "refused by sequence_executor: SEQUENCE_SUBMIT: rejected: wrong tag from \"rover_web@",
       start_console("rover_web_otherkey", {"--key", other_key})}};
  const httplib::Headers with_secret = {{"X-Rover-Secret", stack.secret}};
  for (const Console& c : consoles) {
    SCOPED_TRACE(c.name);
    ASSERT_GT(c.port, 0) << ReadText(stack.dir + "/" + c.name + ".log");
    // Said once at start, as soon as it can tell, and on the page's state.
    ASSERT_TRUE(stack.WaitFor([&] { return ReadText(stack.dir + "/" + c.name + ".log").find(c.says) != std::string::npos; },
                              60))
        << ReadText(stack.dir + "/" + c.name + ".log");
    const std::string log = ReadText(stack.dir + "/" + c.name + ".log");
    EXPECT_EQ(log.find(c.says), log.rfind(c.says)) << "said more than once:\n" << log;
    httplib::Client http("127.0.0.1", c.port);
    http.set_connection_timeout(5);
    http.set_read_timeout(20);
    auto state = http.Get("/api/state");
    ASSERT_TRUE(state);
    const std::string problem = YAML::Load(state->body)["commands"]["key_problem"].as<std::string>("");
    EXPECT_NE(problem, "");
    EXPECT_NE(c.says.find(problem.substr(0, 20)), std::string::npos) << problem;
    auto page = http.Get("/");
    ASSERT_TRUE(page);
    EXPECT_NE(page->body.find("<div id=\"banner\" role=\"alert\" hidden></div>"), std::string::npos)
        << "the page has no banner to show it in";

    // Submit: refused, with the executor's reason; the executor never ran it.
    auto submitted = http.Post("/api/submit?name=" + c.name + ".seq", with_secret, "drive 0.4 m\n", "text/plain");
    ASSERT_TRUE(submitted);
    EXPECT_EQ(submitted->status, 403) << submitted->body;
    EXPECT_EQ(submitted->body.rfind(c.refused, 0), 0u) << submitted->body;
    // Pause: refused the same way (nothing runs, so a taken pause would change nothing).
    auto paused = http.Post("/api/pause", with_secret, "", "text/plain");
    ASSERT_TRUE(paused);
    EXPECT_EQ(paused->status, 403) << paused->body;
    EXPECT_EQ(paused->body.rfind("refused by sequence_executor: SEQUENCE_CONTROL: rejected: ", 0), 0u) << paused->body;
    // Its log says so too (written just after the answer: waited for).
    EXPECT_TRUE(stack.WaitFor(
        [&] {
          return ReadText(stack.dir + "/" + c.name + ".log").find("rover_web: pause: refused by sequence_executor: ") !=
                 std::string::npos;
        },
        10))
        << ReadText(stack.dir + "/" + c.name + ".log");
  }
  {
    std::lock_guard<std::mutex> lock(stack.heard.mutex);
    for (const auto& [id, list] : stack.heard.statuses) {
      for (const auto& st : list) EXPECT_EQ(st.sequence_name.find("rover_web_"), std::string::npos) << st.sequence_name;
    }
  }
  // The keyed console beside them: its submit is answered, 200, with the executor's state.
  httplib::Client keyed("127.0.0.1", stack.port);
  keyed.set_read_timeout(20);
  auto ok = keyed.Post("/api/submit?name=keyed.seq", with_secret, "turn 10 deg\n", "text/plain");
  ASSERT_TRUE(ok);
  ASSERT_EQ(ok->status, 200) << ok->body;
  const YAML::Node answer = YAML::Load(ok->body);
  EXPECT_TRUE(answer["signed"].as<bool>());
  EXPECT_EQ(answer["executor"].as<std::string>(""), "running") << ok->body;
  EXPECT_EQ(YAML::Load(keyed.Get("/api/state")->body)["commands"]["key_problem"].as<std::string>("x"), "");
  stack.set.StopAll();
}

TEST(WebConsole, BadArgumentsGetOneLine) {
  struct Case {
    std::string args, expect;
  };
  const std::string dir = OutDir("web_console_args");
  const std::string readable = dir + "/readable_secret";
  std::ofstream(readable) << "a-long-enough-secret\n";
  chmod(readable.c_str(), 0644);
  const std::string shortf = dir + "/short_secret";
  std::ofstream(shortf) << "short\n";
  chmod(shortf.c_str(), 0600);
  for (const Case& c : std::vector<Case>{
           {"--port 70000", "expected a port number"},
           {"--listen 127.0.0.1", "expected ADDR:PORT"},
           {"--listen example.org:80", "expected an IPv4 address"},
           {"--listen unix:", "expected unix:PATH"},
           {"--listen unix:" + readable, "exists and is not a socket"},
           {"--secret-file " + readable, "other users can read it"},
           {"--secret-file " + shortf, "expected at least 12"},
           {"--secret-file " + dir + "/missing", "cannot open file"},
           {"--image-width 5", "expected 32 to 1024"},
           {"--bogus", "unknown option"}}) {
    const auto r = RunCommand("timeout 10 " + Bin("rover_web") + " --lcm-url 'udpm://239.255.76.67:7999?ttl=0' " + c.args);
    EXPECT_EQ(r.exit_code, 2) << c.args << ":\n" << r.output;
    EXPECT_NE(r.output.find(c.expect), std::string::npos) << c.args << ":\n" << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << c.args << ":\n" << r.output;
  }
}

}  // namespace
}  // namespace rover::test
