// The operator's command line to a running sequence_executor:
//   rover_seq submit FILE [--no-follow]   check FILE locally, submit it, follow it to the end
//   rover_seq status [--once]             follow the running sequence (or print one status)
//   rover_seq abort [REASON]              abort the running sequence; the rover stops
// Uses --lcm-url, else $ROVER_LCM_URL, else the default bus.
#include "bus/bus.hpp"
#include "bus/channels.hpp"
#include "bus/process.hpp"
#include "sequence/executor.hpp"

#include <rover_msgs/heartbeat_t.hpp>
#include <rover_msgs/sequence_control_t.hpp>
#include <rover_msgs/sequence_status_t.hpp>
#include <rover_msgs/sequence_submit_t.hpp>

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>

using rover::config::ConfigError;
using rover_msgs::sequence_status_t;

namespace {

bool Terminal(int s) {
  return s == sequence_status_t::STATE_COMPLETED || s == sequence_status_t::STATE_ABORTED ||
         s == sequence_status_t::STATE_REJECTED;
}

void Print(const sequence_status_t& st) {
  const auto state = static_cast<rover::sequence::SequenceState>(st.state);
  std::cout << std::fixed << std::setprecision(1) << "[" << rover::sequence::ToString(state) << " t=" << st.elapsed_s
            << " s] " << st.sequence_name;
  if (st.command_index >= 0) {
    std::cout << " command " << st.command_index + 1 << "/" << st.num_commands << " (line "
              << st.command_line << ": " << st.command_text << ") step " << st.step_index + 1;
  }
  std::cout << std::setprecision(2) << " pose " << st.pose[0] << "," << st.pose[1] << " m";
  if (!st.abort_reason.empty()) std::cout << " abort_reason=" << st.abort_reason;
  if (!st.detail.empty()) std::cout << " - " << st.detail;
  std::cout << "\n" << std::flush;
}

double Now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// Follows statuses (of `submission_id`, or of any sequence when < 0) until a terminal
// one: exit 0 when it completed, 1 when it was aborted or rejected. With `once`, prints
// the first status heard and returns 0. 3 when no status is heard for `silence_s`.
int Follow(rover::bus::Bus& bus, std::int64_t submission_id, bool once, double silence_s) {
  std::string last;
  int result = -1;
  double last_heard = Now();
  bus.Subscribe<sequence_status_t>(rover::channels::kSequenceStatus, [&](const sequence_status_t& st) {
    if (result >= 0 || (submission_id >= 0 && st.submission_id != submission_id)) return;
    last_heard = Now();
    std::ostringstream key;
    key << static_cast<int>(st.state) << " " << st.command_index << "/" << st.step_index << " " << st.detail;
    if (key.str() != last) Print(st);
    last = key.str();
    if (once) {
      result = 0;
    } else if (Terminal(st.state)) {
      result = st.state == sequence_status_t::STATE_COMPLETED ? 0 : 1;
    }
  });
  while (result < 0) {
    bus.Handle(100);
    if (Now() - last_heard > silence_s) {
      std::cerr << "rover_seq: no sequence status heard for " << silence_s << " s on " << bus.url()
                << " (is sequence_executor running on this bus?)\n";
      return 3;
    }
  }
  return result;
}

}  // namespace

int main(int argc, char** argv) {
  return rover::bus::RunMain("rover_seq", [&]() -> int {
    std::vector<std::string> args(argv + 1, argv + argc);
    std::string url;
    bool once = false, follow = true;
    std::vector<std::string> positional;
    for (std::size_t i = 0; i < args.size(); ++i) {
      if (args[i] == "--lcm-url" && i + 1 < args.size()) {
        url = args[++i];
      } else if (args[i] == "--once") {
        once = true;
      } else if (args[i] == "--no-follow") {
        follow = false;
      } else if (args[i] == "--help" || args[i] == "-h") {
        std::cout << "usage: rover_seq submit FILE [--no-follow] | status [--once] | abort [REASON]"
                     " [--lcm-url URL]\n";
        return 0;
      } else {
        positional.push_back(args[i]);
      }
    }
    if (positional.empty()) {
      throw ConfigError("rover_seq: missing subcommand (expected submit, status or abort)");
    }
    if (url.empty()) {
      const char* env = std::getenv("ROVER_LCM_URL");
      url = env != nullptr && *env ? env : rover::bus::kDefaultLcmUrl;
    }
    const std::string sub = positional[0];
    if (sub == "submit") {
      if (positional.size() != 2) throw ConfigError("rover_seq submit: expected exactly one FILE");
      std::ifstream in(positional[1], std::ios::binary);
      if (!in) throw ConfigError(positional[1] + ": cannot open file (expected a sequence file)");
      std::stringstream ss;
      ss << in.rdbuf();
      // Check before anything goes on the bus: the executor checks again.
      const auto check = rover::sequence::ParseSequence(ss.str(), positional[1]);
      if (!check.ok()) {
        std::cerr << check.errors.front().ToString() << "\n";
        return 1;
      }
      rover::bus::Bus bus(url);
      rover_msgs::sequence_submit_t msg{};
      msg.submission_id = static_cast<std::int64_t>(Now() * 1e3);
      msg.name = positional[1];
      msg.text = ss.str();
      bus.Publish(rover::channels::kSequenceSubmit, msg);
      std::cout << "submitted " << positional[1] << " as " << msg.submission_id << "\n";
      return follow ? Follow(bus, msg.submission_id, false, 10.0) : 0;
    }
    if (sub == "status") {
      rover::bus::Bus bus(url);
      return Follow(bus, -1, once, 5.0);
    }
    if (sub == "abort") {
      rover::bus::Bus bus(url);
      rover_msgs::sequence_control_t msg{};
      msg.action = rover_msgs::sequence_control_t::ACTION_ABORT;
      msg.reason = positional.size() > 1 ? positional[1] : "operator abort";
      bus.Publish(rover::channels::kSequenceControl, msg);
      std::cout << "abort sent: " << msg.reason << "\n";
      return 0;
    }
    throw ConfigError("rover_seq: unknown subcommand " + sub + " (expected submit, status or abort)");
  });
}
