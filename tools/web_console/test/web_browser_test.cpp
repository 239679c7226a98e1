// The web console in a real browser: Debian's Chromium, headless, driven by playwright-core
// (tools/web_console/browser_test/page_agent.mjs) on the page rover_web serves, while the
// signed simulated stack drives on a private bus. The test hears the bus itself and
// compares the page with it:
//   - the sequence is typed into the page and sent with its Submit button (secret typed in);
//   - while it drives, the position the page shows is a POSE the bus carried (same utime)
//     and close to the bus's newest;
//   - the page's Pause button pauses the executor, and the rover stays put while rover time
//     goes on (no step, the same POSE); the page then shows the bus's position (1 cm), the
//     bus's step count, the keep-out zone the bus carries and the goto's goal, and its map
//     canvas has the estimate's colour at the bus's POSE and the zone's and the goal's
//     outlines where they lie;
//   - the page's Resume button goes on, and the sequence completes; the page agrees.
// Screenshots: build/test-out/web_browser/paused.png and completed.png.
// It skips, saying why in one line, without node, chromium or playwright-core (./rover test
// installs it into build/web_browser_test with npm ci).
// Run it alone: ./rover test -R WebBrowser, or
//   ROVER_BUILD_DIR=$PWD/build ./rover private ctest --test-dir build -R WebBrowser
#include "web_console/test/web_test_stack.hpp"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <csignal>
#include <filesystem>
#include <string>

#include <fcntl.h>
#include <poll.h>
#include <sys/wait.h>
#include <unistd.h>

namespace rover::test {
namespace {

namespace fs = std::filesystem;
using rover_msgs::sequence_status_t;
constexpr std::int8_t kPaused = sequence_status_t::STATE_PAUSED;
constexpr std::int8_t kCompleted = sequence_status_t::STATE_COMPLETED;
constexpr std::int8_t kAborted = sequence_status_t::STATE_ABORTED;

std::string Quote(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (c == '\n') {
      out += "\\n";
    } else {
      out += c;
    }
  }
  return out + "\"";
}

// page_agent.mjs as a child: one JSON request a line on its stdin, one answer a line on
// its stdout; its stderr goes to a log.
class PageAgent {
 public:
  PageAgent(const std::string& modules, const std::string& chromium, const std::string& log) {
    std::signal(SIGPIPE, SIG_IGN);  // a dead agent is a failed Ask, not a dead test
    int in[2], out[2];
    if (pipe2(in, O_CLOEXEC) != 0 || pipe2(out, O_CLOEXEC) != 0) return;
    const std::string script = SourceDir() + "/tools/web_console/browser_test/page_agent.mjs";
    pid_ = fork();
    if (pid_ == 0) {
      dup2(in[0], 0);
      dup2(out[1], 1);
      const int err = open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      if (err >= 0) dup2(err, 2);
      execlp("node", "node", script.c_str(), modules.c_str(), chromium.c_str(), static_cast<char*>(nullptr));
      _exit(127);
    }
    close(in[0]);
    close(out[1]);
    to_ = in[1];
    from_ = out[0];
  }
  ~PageAgent() {
    if (pid_ <= 0) return;
    Ask("{\"op\":\"quit\"}", 5);
    close(to_);
    close(from_);
    for (int i = 0; i < 100; ++i) {
      if (waitpid(pid_, nullptr, WNOHANG) == pid_) return;
      usleep(50000);
    }
    kill(pid_, SIGKILL);
    waitpid(pid_, nullptr, 0);
  }

  // The next answer line (the first one says the browser is up), or a null node with
  // `error` set.
  YAML::Node Next(double timeout_s) {
    const auto start = WebClock::now();
    while (true) {
      if (const auto nl = buffer_.find('\n'); nl != std::string::npos) {
        const std::string line = buffer_.substr(0, nl);
        buffer_.erase(0, nl + 1);
        YAML::Node answer;
        try {
          answer = YAML::Load(line);
        } catch (const std::exception& e) {
          error = "page_agent answered a line that is not JSON: " + line;
          return YAML::Node();
        }
        if (!answer["ok"].as<bool>(false)) {
          error = "page_agent: " + answer["error"].as<std::string>("(no error text)");
          return YAML::Node();
        }
        if (answer["page_errors"] && answer["page_errors"].size() > 0) {
          error = "the page's script threw: " + answer["page_errors"][0].as<std::string>();
          return YAML::Node();
        }
        return answer;
      }
      const double left = timeout_s - SecondsSince(start);
      pollfd p{from_, POLLIN, 0};
      if (left <= 0 || poll(&p, 1, static_cast<int>(left * 1000) + 1) <= 0) {
        error = "page_agent did not answer within " + std::to_string(timeout_s) + " s";
        return YAML::Node();
      }
      char chunk[65536];
      const ssize_t n = read(from_, chunk, sizeof(chunk));
      if (n <= 0) {
        error = "page_agent ended (see its log)";
        return YAML::Node();
      }
      buffer_.append(chunk, static_cast<std::size_t>(n));
    }
  }

  YAML::Node Ask(const std::string& request, double timeout_s = 30) {
    const std::string line = request + "\n";
    if (pid_ <= 0 || write(to_, line.data(), line.size()) != static_cast<ssize_t>(line.size())) {
      error = "cannot write to page_agent";
      return YAML::Node();
    }
    return Next(timeout_s);
  }

  std::string error;

 private:
  pid_t pid_ = -1;
  int to_ = -1, from_ = -1;
  std::string buffer_;
};

// Why the browser test cannot run here, or "".
std::string MissingTool(const std::string& modules, std::string* chromium) {
  if (RunCommand("command -v node").exit_code != 0) return "node is not installed (apt-get install nodejs; ./rover test installs it)";
  if (const auto v = RunCommand("node -e 'process.exit(parseInt(process.versions.node) >= 20 ? 0 : 1)'"); v.exit_code != 0) {
    std::string version = RunCommand("node --version").output;
    version = version.substr(0, version.find('\n'));
    return "node " + version + " is older than 20 (playwright-core needs 20 or newer)";
  }
  const char* env = std::getenv("ROVER_CHROMIUM");
  *chromium = env != nullptr ? env : "/usr/bin/chromium";
  if (access(chromium->c_str(), X_OK) != 0) return *chromium + " is not installed (apt-get install chromium; ./rover test installs it)";
  if (!fs::exists(modules + "/node_modules/playwright-core/package.json")) {
    return "playwright-core is not installed in " + modules +
           " (./rover test installs it with npm ci; it failed or was not run, see its output)";
  }
  return "";
}

// The canvas colour near #rrggbb (a drawn outline or the rover's fill).
bool Near(const YAML::Node& rgba, int r, int g, int b, int tolerance) {
  if (!rgba || !rgba.IsSequence() || rgba.size() != 4) return false;
  return std::abs(rgba[0].as<int>() - r) <= tolerance && std::abs(rgba[1].as<int>() - g) <= tolerance &&
         std::abs(rgba[2].as<int>() - b) <= tolerance;
}

// Points around a circle, as a JSON list of site [x, y].
std::string Ring(double x, double y, double radius, int n) {
  std::string out;
  for (int i = 0; i < n; ++i) {
    const double a = 2 * M_PI * i / n;
    out += (out.empty() ? "" : ",") + std::string("[") + std::to_string(x + radius * std::cos(a)) + "," +
           std::to_string(y + radius * std::sin(a)) + "]";
  }
  return out;
}

// The sequence: a keep-out zone, a drive, then a goto whose disc the page draws. The
// pause comes once the goto has started.
constexpr double kZoneX = 3.0, kZoneY = -2.8, kZoneR = 0.7;
constexpr double kGoalX = 2.6, kGoalY = 1.0, kGoalR = 0.3;
const char* const kSequence =
    "vo on step 40 cm\n"
    "keepout humphrey circle 3 m -2.8 m radius 0.7 m\n"
    "drive 0.8 m\n"
    "goto 2.6 m 1 m within 0.3 m avoid on\n";

TEST(WebBrowser, PageShowsTheBusAndItsButtonsPauseAndResume) {
  const std::string modules = std::string(ROVER_BINARY_DIR) + "/web_browser_test";
  std::string chromium;
  if (const std::string missing = MissingTool(modules, &chromium); !missing.empty()) {
    GTEST_SKIP() << "browser test: " << missing;
  }
  // rate 5: rover time at most 5x the wall clock, so that a step takes seconds of wall time
  // and the browser's clicks land between the steps meant (virtual time still decides what
  // the rover does; a slower machine only slows it further).
  WebStack stack("web_browser", 71, {"--rate", "5"});
  ASSERT_GT(stack.port, 0);
  Listener& bus = stack.heard;
  const std::string dir = stack.dir;

  PageAgent agent(modules, chromium, dir + "/page_agent.log");
  const YAML::Node up = agent.Next(120);
  ASSERT_TRUE(up) << agent.error << "\n" << ReadText(dir + "/page_agent.log");
  std::cout << "browser: Chromium " << up["browser"].as<std::string>("?") << "\n";
  auto ask = [&](const std::string& request, double timeout_s = 30) {
    YAML::Node a = agent.Ask(request, timeout_s);
    EXPECT_TRUE(a) << request.substr(0, 80) << ": " << agent.error;
    return a;
  };
  auto read_page = [&](const std::string& points = "") {
    const YAML::Node a = ask("{\"op\":\"read\",\"points\":[" + points + "]}");
    return a ? a["page"] : YAML::Node();
  };

  ASSERT_TRUE(ask("{\"op\":\"open\",\"url\":\"http://127.0.0.1:" + std::to_string(stack.port) + "/\"}", 60));
  ASSERT_TRUE(ask("{\"op\":\"fill\",\"id\":\"secret\",\"text\":" + Quote(stack.secret) + "}"));
  ASSERT_TRUE(ask("{\"op\":\"fill\",\"id\":\"text\",\"text\":" + Quote(kSequence) + "}"));
  const YAML::Node submitted = ask("{\"op\":\"click\",\"id\":\"submit\"}");
  ASSERT_TRUE(submitted);
  const std::string submit_result = submitted["result"].as<std::string>();
  ASSERT_EQ(submit_result.rfind("200: ", 0), 0u) << submit_result;
  const std::int64_t id = YAML::Load(submit_result.substr(5))["submission_id"].as<std::int64_t>();

  // Driving: what the page shows is a POSE the bus carried, and not far behind the newest.
  auto running_goto = [&] {
    const auto st = bus.LastStatus(id);
    return st && st->command_text.rfind("goto", 0) == 0;
  };
  ASSERT_TRUE(stack.WaitFor([&] { return bus.StepsOf(id) >= 1; }, 120)) << "no step of the page's sequence";
  {
    const YAML::Node page = read_page();
    const rover_msgs::pose_t newest = bus.LastPose();
    ASSERT_TRUE(page && page["pose"] && !page["pose"].IsNull()) << "the page shows no position";
    const std::int64_t shown = page["pose"]["utime"].as<std::int64_t>();
    auto same = bus.PoseAt(shown);
    if (!same) {  // the test's own listener may be a moment behind rover_web
      stack.set.Poll(500);
      same = bus.PoseAt(shown);
    }
    ASSERT_TRUE(same) << "the page shows a POSE (utime " << page["pose"]["utime"].as<std::string>()
                      << ") the bus never carried";
    EXPECT_LT(std::hypot(page["pose"]["x"].as<double>() - same->position[0],
                         page["pose"]["y"].as<double>() - same->position[1]), 0.001);
    EXPECT_LT(std::hypot(page["pose"]["x"].as<double>() - newest.position[0],
                         page["pose"]["y"].as<double>() - newest.position[1]), 0.5)
        << "the page lags the bus by more than half a metre while driving";
  }

  // Pause from the page once the goto has started.
  ASSERT_TRUE(stack.WaitFor(running_goto, 120)) << "the goto did not start";
  const YAML::Node paused = ask("{\"op\":\"click\",\"id\":\"pause\"}");
  ASSERT_TRUE(paused);
  EXPECT_EQ(paused["result"].as<std::string>().rfind("200: ", 0), 0u) << paused["result"].as<std::string>();
  ASSERT_TRUE(stack.WaitFor([&] { return bus.HasState(id, kPaused); }, 60)) << "the executor did not pause";
  ASSERT_NE(bus.LastState(id), kCompleted) << "the sequence ended before the pause took effect";

  // Paused: rover time goes on (10 s of it), the rover does not move and takes no step.
  const int steps_paused = bus.StepsOf(id);
  const rover_msgs::pose_t at_pause = bus.LastPose();
  const std::int64_t t_pause = bus.RoverUtime();
  ASSERT_TRUE(stack.WaitFor([&] { return bus.RoverUtime() >= t_pause + 10000000; }, 90))
      << "rover time did not go on while paused";
  EXPECT_EQ(bus.LastState(id), kPaused);
  EXPECT_EQ(bus.StepsOf(id), steps_paused) << "a step while paused";
  const rover_msgs::pose_t still = bus.LastPose();
  EXPECT_GT(still.utime, at_pause.utime) << "no POSE while paused";
  EXPECT_LT(std::hypot(still.position[0] - at_pause.position[0], still.position[1] - at_pause.position[1]), 0.001)
      << "the rover moved while paused";

  // The page while paused, against the bus. The canvas is sampled at the bus's POSE, on the
  // zone's circle and on the goal's.
  {
    const rover_msgs::pose_t pose = bus.LastPose();
    const std::string points = "[" + std::to_string(pose.position[0]) + "," + std::to_string(pose.position[1]) + "]," +
                               Ring(kZoneX, kZoneY, kZoneR, 8) + "," + Ring(kGoalX, kGoalY, kGoalR, 8);
    YAML::Node page;
    // The page hears the pause at its next event (twice a second).
    for (int i = 0; i < 20; ++i) {
      page = read_page(points);
      if (page && page["state"].as<std::string>("") == "paused") break;
      stack.set.Poll(250);
    }
    ASSERT_TRUE(page);
    EXPECT_EQ(page["state"].as<std::string>(""), "paused");
    EXPECT_EQ(page["submission_id"].as<std::int64_t>(0), id);
    EXPECT_EQ(page["banner"].as<std::string>("(none read)"), "") << "a key problem shown on the keyed console";
    ASSERT_TRUE(page["pose"] && !page["pose"].IsNull());
    EXPECT_LT(std::hypot(page["pose"]["x"].as<double>() - pose.position[0], page["pose"]["y"].as<double>() - pose.position[1]),
              0.01)
        << "page x " << page["pose"]["x"].as<double>() << " y " << page["pose"]["y"].as<double>() << ", bus POSE x "
        << pose.position[0] << " y " << pose.position[1];
    EXPECT_NEAR(page["pose"]["z"].as<double>(), pose.position[2], 0.01);
    EXPECT_EQ(page["step_count"].as<int>(-1), bus.StepsOf(id)) << "the page's step count is not the bus's";
    EXPECT_GE(page["step_rows"].as<int>(0), std::min(bus.StepsOf(id), 1));
    // The zones the bus carries, and the goto's goal.
    std::vector<std::string> bus_zones;
    {
      std::lock_guard<std::mutex> lock(bus.mutex);
      for (const auto& z : bus.zones.zones) bus_zones.push_back(z.name);
    }
    EXPECT_EQ(bus_zones, std::vector<std::string>{"humphrey"});
    EXPECT_EQ(page["zones"].as<std::vector<std::string>>(std::vector<std::string>{}), bus_zones);
    ASSERT_TRUE(page["goal"] && page["goal"].size() == 3) << "no goal on the page";
    EXPECT_NEAR(page["goal"][0].as<double>(), kGoalX, 1e-6);
    EXPECT_NEAR(page["goal"][1].as<double>(), kGoalY, 1e-6);
    EXPECT_NEAR(page["goal"][2].as<double>(), kGoalR, 1e-6);
    // Drawn: the estimate (#4ea1ff) at the bus's POSE; the zone's outline (#ff5c8a) and the
    // goal's (#7bd88f) on most of their circles (a path may cross one).
    const YAML::Node colours = page["colours"];
    ASSERT_EQ(colours.size(), 17u);
    EXPECT_TRUE(Near(colours[0], 0x4e, 0xa1, 0xff, 40)) << "no rover drawn at the bus's POSE: " << YAML::Dump(colours[0]);
    int zone = 0, goal = 0;
    for (int i = 1; i <= 8; ++i) zone += Near(colours[i], 0xff, 0x5c, 0x8a, 60);
    for (int i = 9; i <= 16; ++i) goal += Near(colours[i], 0x7b, 0xd8, 0x8f, 60);
    EXPECT_GE(zone, 6) << "the keep-out zone is not drawn where the bus has it";
    EXPECT_GE(goal, 6) << "the goal disc is not drawn where the goto has it";
  }
  ASSERT_TRUE(ask("{\"op\":\"screenshot\",\"path\":" + Quote(dir + "/paused.png") + "}"));
  std::cout << "screenshot while paused: " << dir << "/paused.png\n";

  // Resume from the page: the drive goes on to the end of the sequence.
  const YAML::Node resumed = ask("{\"op\":\"click\",\"id\":\"resume\"}");
  ASSERT_TRUE(resumed);
  EXPECT_EQ(resumed["result"].as<std::string>().rfind("200: ", 0), 0u) << resumed["result"].as<std::string>();
  ASSERT_TRUE(stack.WaitFor([&] { return bus.LastState(id) == kCompleted || bus.LastState(id) == kAborted; }, 240))
      << "the sequence did not end after the resume";
  EXPECT_EQ(bus.LastState(id), kCompleted) << bus.LastStatus(id)->detail;
  EXPECT_GT(bus.StepsOf(id), steps_paused) << "no step after the resume";
  const rover_msgs::pose_t end = bus.LastPose();
  EXPECT_GT(std::hypot(end.position[0] - at_pause.position[0], end.position[1] - at_pause.position[1]), 0.1)
      << "the rover did not go on after the resume";
  EXPECT_LT(std::hypot(end.position[0] - kGoalX, end.position[1] - kGoalY), kGoalR) << "the goto ended outside its disc";
  {
    YAML::Node page;
    for (int i = 0; i < 40; ++i) {  // the page hears the end at its next event
      page = read_page();
      if (page && page["state"].as<std::string>("") == "completed" &&
          page["step_count"].as<int>(-1) == bus.StepsOf(id))
        break;
      stack.set.Poll(250);
    }
    ASSERT_TRUE(page);
    EXPECT_EQ(page["state"].as<std::string>(""), "completed");
    EXPECT_EQ(page["step_count"].as<int>(-1), bus.StepsOf(id));
    const rover_msgs::pose_t pose = bus.LastPose();
    EXPECT_LT(std::hypot(page["pose"]["x"].as<double>() - pose.position[0], page["pose"]["y"].as<double>() - pose.position[1]),
              0.01);
  }
  ASSERT_TRUE(ask("{\"op\":\"screenshot\",\"path\":" + Quote(dir + "/completed.png") + "}"));
  EXPECT_TRUE(fs::file_size(dir + "/paused.png") > 10000) << "a near-empty screenshot";
  std::cout << "screenshot after the drive: " << dir << "/completed.png\n";
}

}  // namespace
}  // namespace rover::test
