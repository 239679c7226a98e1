// ./rover console [--once] [--wait S] [--lcm-url URL]
//
// One live screen for the running drive (console_view.hpp says what it shows), redrawn in
// place twice a second with plain ANSI escapes (cursor home, clear to end of line), so it
// reads the same in any terminal and over ssh, with no curses dependency. Ctrl-C leaves.
// --once listens for --wait seconds (default 2.5: every process heartbeats once a second),
// prints one frame without escapes and exits: 0, or 3 when nothing at all was heard.
#include "bus/bus.hpp"
#include "bus/channels.hpp"
#include "bus/process.hpp"
#include "config/yaml_config.hpp"
#include "console/console_view.hpp"

#include <rover_msgs/rover_clock_t.hpp>

#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <iostream>

using rover::config::ConfigError;

namespace {

volatile std::sig_atomic_t g_stop = 0;
void OnSignal(int) { g_stop = 1; }

double Now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

double PositiveSeconds(const std::string& flag, const std::string& text) {
  try {
    std::size_t used = 0;
    const double v = std::stod(text, &used);
    if (used == text.size() && v > 0 && v <= 3600) return v;
  } catch (const std::exception&) {
  }
  throw ConfigError("rover_console: argument " + flag + ": \"" + text + "\": expected seconds, > 0 and <= 3600");
}

int TerminalColumns() {
  winsize ws{};
  if (ioctl(STDOUT_FILENO, TIOCGWINSZ, &ws) == 0 && ws.ws_col > 0) return ws.ws_col;
  return 0;
}

// Redraws in place: home, each line cut to the terminal's width and cleared to its end,
// then everything below the frame cleared.
void Draw(const std::vector<std::string>& lines) {
  const int columns = TerminalColumns();
  std::string out = "\x1b[H";
  for (const auto& line : lines) {
    out += columns > 0 && static_cast<int>(line.size()) > columns ? line.substr(0, columns) : line;
    out += "\x1b[K\n";
  }
  out += "\x1b[J";
  std::cout << out << std::flush;
}

}  // namespace

int main(int argc, char** argv) {
  return rover::bus::RunMain("rover_console", [&]() -> int {
    std::string url;
    bool once = false;
    double wait_s = 2.5, period_s = 0.5;
    for (int i = 1; i < argc; ++i) {
      const std::string arg = argv[i];
      if (arg == "--help" || arg == "-h") {
        std::cout << "usage: rover_console [--once] [--wait S] [--period S] [--lcm-url URL]\n\n"
                     "One live screen for the running drive, redrawn in place: the sequence and its\n"
                     "state, the command and step, commanded and measured motion of the last steps,\n"
                     "slip, the last VO status and its counts, the hazard state, the keep-out zones in\n"
                     "force, the pose and its 1-sigma, and every process's heartbeat (SILENT after 3 s)\n"
                     "with its dropped-message count. Ctrl-C leaves.\n"
                     "--once: listen --wait S (default 2.5), print one frame, exit (3: nothing heard).\n"
                     "--period S: redraw interval (default 0.5).\n"
                     "The bus: --lcm-url, else $ROVER_LCM_URL, else the default bus.\n";
        return 0;
      } else if (arg == "--once") {
        once = true;
      } else if (arg == "--wait" && i + 1 < argc) {
        wait_s = PositiveSeconds(arg, argv[++i]);
      } else if (arg == "--period" && i + 1 < argc) {
        period_s = PositiveSeconds(arg, argv[++i]);
      } else if (arg == "--lcm-url" && i + 1 < argc) {
        url = argv[++i];
      } else {
        throw ConfigError("rover_console: argument " + arg + ": unexpected (see --help)");
      }
    }
    if (url.empty()) {
      const char* env = std::getenv("ROVER_LCM_URL");
      url = env != nullptr && *env ? env : rover::bus::kDefaultLcmUrl;
    }

    rover::bus::Bus bus(url);
    bus.set_publisher("rover_console");
    rover::console::ConsoleState state;
    auto feed = [&](const auto& m) { state.On(m, Now()); };
    namespace ch = rover::channels;
    bus.Subscribe<rover_msgs::sequence_status_t>(ch::kSequenceStatus, feed, 50);
    bus.Subscribe<rover_msgs::step_report_t>(ch::kStepReport, feed, 50);
    bus.Subscribe<rover_msgs::vo_update_t>(ch::kVoUpdate, feed, 50);
    bus.Subscribe<rover_msgs::hazard_status_t>(ch::kHazardStatus, feed, 50);
    bus.Subscribe<rover_msgs::pose_t>(ch::kPose, feed, 100);
    bus.Subscribe<rover_msgs::heartbeat_t>(ch::kHeartbeat, feed, 100);
    bus.Subscribe<rover_msgs::keepout_zones_t>(ch::kKeepOutZones, feed, 10);
    // The rover clock, as every process keeps it: messages with implausible times are dropped.
    bus.Subscribe<rover_msgs::rover_clock_t>(ch::kClock, [&](const rover_msgs::rover_clock_t& m) {
      bus.clock().ObserveClock(m.utime, m.rate, std::chrono::steady_clock::now());
      state.rover_utime = std::max(state.rover_utime, m.utime);
    });

    std::signal(SIGINT, OnSignal);
    std::signal(SIGTERM, OnSignal);
    const double start = Now();
    rover::console::FrameOptions options;
    options.bus_url = url;
    auto frame = [&] {
      options.listened_s = Now() - start;
      return rover::console::RenderFrame(state, Now(), options);
    };

    if (once) {
      while (!g_stop && Now() - start < wait_s) bus.Handle(50);
      for (const auto& line : frame()) std::cout << line << "\n";
      if (state.messages == 0) {
        std::cerr << "rover_console: nothing heard on " << url << " in " << wait_s
                  << " s (is a process set running on this bus? on one machine LCM needs a multicast "
                     "route: sudo ip route add 224.0.0.0/4 dev lo)\n";
        return 3;
      }
      return 0;
    }

    const bool tty = isatty(STDOUT_FILENO) != 0;
    if (tty) std::cout << "\x1b[2J\x1b[?25l" << std::flush;  // clear, hide the cursor
    double next_draw = start;
    while (!g_stop) {
      bus.Handle(50);
      if (Now() < next_draw) continue;
      if (tty) {
        Draw(frame());
      } else {  // piped: one frame after another
        for (const auto& line : frame()) std::cout << line << "\n";
        std::cout << "\n" << std::flush;
      }
      next_draw = Now() + (tty ? period_s : std::max(period_s, 2.0));
    }
    if (tty) std::cout << "\x1b[?25h" << std::flush;  // the cursor back
    return 0;
  });
}
