// The operator's command line to a running sequence_executor:
//   rover_seq submit FILE [--no-follow]   check FILE locally, submit it, follow it to the end
//   rover_seq status [--once]             follow the running sequence (or print one status)
//   rover_seq abort [REASON]              abort the running sequence; the rover stops
//   rover_seq pause [REASON]              pause the running sequence between steps
//   rover_seq resume [REASON]             resume a paused sequence
//   rover_seq keygen FILE                 write a new deployment key (mode 0600)
// Uses --lcm-url, else $ROVER_LCM_URL, else the default bus. With --key FILE, else
// $ROVER_KEY_FILE, submit, abort, pause and resume are signed with the deployment's key (common/auth),
// as an executor with `auth:` in its config requires.
// A submit that no executor answers within 4 s ends with exit 3 and one line naming the
// URL and the likely causes (README, "Several hosts"): ttl=0, no multicast route on the
// LAN interface, another group or port on the executor's host, the executor not running.
// abort, pause and resume first hear the executor's status (it publishes one a second):
// with no sequence to act on they say so and exit 4 (abort still commands a stop).
// Exit codes: 0 done, 1 the sequence aborted or was rejected, 2 a bad
// argument, URL or file, 3 no executor heard or it did not act, 4 nothing to act on.
#include "auth/auth.hpp"
#include "bus/bus.hpp"
#include "bus/channels.hpp"
#include "bus/lcm_url_check.hpp"
#include "bus/process.hpp"
#include "bus/signing.hpp"
#include "config/file_read.hpp"
#include "launch/lcm_url.hpp"
#include "sequence/executor.hpp"

#include <rover_msgs/heartbeat_t.hpp>
#include <rover_msgs/sequence_control_t.hpp>
#include <rover_msgs/sequence_status_t.hpp>
#include <rover_msgs/sequence_submit_t.hpp>

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <iomanip>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>

using rover::config::ConfigError;
using rover_msgs::sequence_status_t;

namespace {

bool Terminal(int s) {
  return s == sequence_status_t::STATE_COMPLETED || s == sequence_status_t::STATE_ABORTED ||
         s == sequence_status_t::STATE_REJECTED;
}

// Whether a command drives (its steps mean something); settings and images have none.
bool IsMotionText(const std::string& text) {
  const auto parsed = rover::sequence::ParseSequence(text, "status");
  return parsed.ok() && parsed.sequence.commands.size() == 1 &&
         rover::sequence::IsMotion(parsed.sequence.commands.front());
}

// One line per status. The position (command, and step of a motion) only while a command
// runs, or where an abort happened; the command's text once (the detail often holds it).
void Print(const sequence_status_t& st) {
  const auto state = static_cast<rover::sequence::SequenceState>(st.state);
  std::cout << std::fixed << std::setprecision(1) << "[" << rover::sequence::ToString(state) << " t=" << st.elapsed_s
            << " s] " << st.sequence_name;
  const bool at_command = st.command_index >= 0 && st.command_index < st.num_commands &&
                          (st.state == sequence_status_t::STATE_RUNNING ||
                           st.state == sequence_status_t::STATE_PAUSED ||
                           st.state == sequence_status_t::STATE_ABORTED);
  std::string what = st.detail;
  if (at_command) {
    std::cout << " command " << st.command_index + 1 << "/" << st.num_commands;
    if (IsMotionText(st.command_text)) std::cout << " step " << st.step_index + 1;
    if (!st.command_text.empty() && what.find(st.command_text) == std::string::npos) {
      what = "line " + std::to_string(st.command_line) + ": " + st.command_text + (what.empty() ? "" : " - " + what);
    }
  }
  std::cout << std::setprecision(2) << " pose " << st.pose[0] << "," << st.pose[1] << " m";
  if (!st.abort_reason.empty()) std::cout << " abort_reason=" << st.abort_reason;
  if (!what.empty()) std::cout << " - " << what;
  std::cout << "\n" << std::flush;
}

double Now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// How long a submit waits for the executor to answer (a status of the submission) before
// it says that nothing answered, and why that might be.
constexpr double kAnswerWaitS = 4.0;

// Follows statuses (of `submission_id`, or of any sequence when < 0) until a terminal
// one: exit 0 when it completed, 1 when it was aborted or rejected. With `once`, prints
// the first status heard and returns 0. 3 when no status is heard for `silence_s`, or,
// for a submission, when the executor has not answered it within kAnswerWaitS.
// `send` (the submit) runs once the subscriptions are in place, so no answer can be missed.
int Follow(rover::bus::Bus& bus, std::int64_t submission_id, bool once, double silence_s,
           bool signed_commands, const std::function<void()>& send = nullptr) {
  std::string last;
  int result = -1;
  double last_heard = 0;  // set when the submit has gone
  bool answered = false;               // a status of this submission was heard
  bool executor_heard = false;         // the executor's heartbeat or any status
  std::int64_t executor_dropped = -1;  // its count of dropped messages, first heard
  std::int64_t executor_dropped_now = -1;
  bus.Subscribe<sequence_status_t>(rover::channels::kSequenceStatus, [&](const sequence_status_t& st) {
    executor_heard = true;
    if (result >= 0 || (submission_id >= 0 && st.submission_id != submission_id)) return;
    answered = true;
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
  bus.Subscribe<rover_msgs::heartbeat_t>(rover::channels::kHeartbeat, [&](const rover_msgs::heartbeat_t& hb) {
    if (hb.process != "sequence_executor") return;
    executor_heard = true;
    if (executor_dropped < 0) executor_dropped = hb.dropped;
    executor_dropped_now = hb.dropped;
  });
  if (send) send();
  const double start = Now();
  last_heard = start;
  while (result < 0) {
    bus.Handle(100);
    if (submission_id >= 0 && !answered && Now() - start > kAnswerWaitS) {
      if (!executor_heard) {
        std::cerr << "rover_seq: no answer to submission " << submission_id << " within " << kAnswerWaitS
                  << " s: no sequence_executor heard on " << bus.url()
                  << " (no sequence status, no executor heartbeat), so the submit reached no executor; "
                  << rover::launch::NothingHeardCauses(bus.url(), "sequence_executor") << "\n";
      } else {
        std::cerr << "rover_seq: sequence_executor is heard on " << bus.url()
                  << " but did not answer submission " << submission_id << " within " << kAnswerWaitS << " s"
                  << (executor_dropped_now > executor_dropped ? " (it dropped a message meanwhile)" : "")
                  << (signed_commands ? ": does it hold the same key as --key / $ROVER_KEY_FILE?"
                                      : ": if it requires signed commands, pass --key FILE or set $ROVER_KEY_FILE")
                  << "\n";
      }
      return 3;
    }
    if (Now() - last_heard > silence_s) {
      std::cerr << "rover_seq: no sequence status heard for " << silence_s << " s on " << bus.url();
      if (submission_id >= 0) {
        std::cerr << " (sequence_executor stopped reporting submission " << submission_id
                  << ": did it stop, or the bus between the hosts break?)\n";
      } else if (executor_heard) {
        std::cerr << " (sequence_executor is heard but reported nothing)\n";
      } else {
        std::cerr << " (no sequence_executor heard either; "
                  << rover::launch::NothingHeardCauses(bus.url(), "sequence_executor") << ")\n";
      }
      return 3;
    }
  }
  return result;
}

// The key from --key, else $ROVER_KEY_FILE; none when neither is given.
std::optional<rover::auth::Key> LoadKey(const std::string& flag_value) {
  std::string path = flag_value;
  const char* env = std::getenv("ROVER_KEY_FILE");
  if (path.empty() && env != nullptr) path = env;
  if (path.empty()) return std::nullopt;
  try {
    return rover::auth::Key::LoadFile(path);
  } catch (const rover::auth::KeyError& e) {
    throw ConfigError(std::string("rover_seq: ") + (flag_value.empty() ? "$ROVER_KEY_FILE: " : "--key: ") +
                      e.what());
  }
}

// A bus for the operator's commands: signed as "rover_seq" when there is a key.
std::unique_ptr<rover::bus::Bus> OpenBus(const std::string& url,
                                         const std::optional<rover::auth::Key>& key) {
  std::unique_ptr<rover::bus::Bus> bus;
  try {
    bus = std::make_unique<rover::bus::Bus>(url);
  } catch (const std::runtime_error& e) {  // a URL this host cannot open: a bad argument
    throw ConfigError(std::string("rover_seq: ") + e.what());
  }
  bus->set_publisher("rover_seq");
  if (key) bus->set_auth(rover::bus::MakeBusAuth(*key, "rover_seq"));
  return bus;
}

// What the executor's statuses and heartbeats say, heard while a control command waits.
struct ExecutorWatch {
  std::optional<sequence_status_t> status;  // the last status heard
  bool heartbeat = false;
  std::int64_t dropped_first = -1, dropped_now = -1;  // its count of dropped messages

  void Subscribe(rover::bus::Bus& bus) {
    bus.Subscribe<sequence_status_t>(rover::channels::kSequenceStatus,
                                     [this](const sequence_status_t& st) { status = st; });
    bus.Subscribe<rover_msgs::heartbeat_t>(rover::channels::kHeartbeat, [this](const rover_msgs::heartbeat_t& hb) {
      if (hb.process != "sequence_executor") return;
      heartbeat = true;
      if (dropped_first < 0) dropped_first = hb.dropped;
      dropped_now = hb.dropped;
    });
  }
  // Handles the bus until `done` holds or `seconds` pass; whether it held.
  bool WaitFor(rover::bus::Bus& bus, double seconds, const std::function<bool()>& done) {
    const double start = Now();
    while (!done()) {
      if (Now() - start > seconds) return false;
      bus.Handle(100);
    }
    return true;
  }
  bool Active() const {
    return status && (status->state == sequence_status_t::STATE_RUNNING ||
                      status->state == sequence_status_t::STATE_PAUSED);
  }
};

// "no sequence has run" / "the last sequence, NAME, completed" / "NAME is running".
std::string Describe(const sequence_status_t& st) {
  const std::string state = rover::sequence::ToString(static_cast<rover::sequence::SequenceState>(st.state));
  if (st.state == sequence_status_t::STATE_IDLE) return "the executor is idle: no sequence has run";
  if (Terminal(st.state)) {
    return "the last sequence, " + st.sequence_name + ", " + state +
           (st.abort_reason.empty() ? "" : " (" + st.abort_reason + ")");
  }
  return st.sequence_name + " is " + state;
}

// Why the executor did not act on a command it was sent: one line, exit 3.
int NotActedOn(const ExecutorWatch& watch, const std::string& sub, bool signed_commands, const std::string& url) {
  std::cerr << "rover_seq: " << sub << " sent on " << url << " but sequence_executor did not act on it within "
            << kAnswerWaitS << " s"
            << (watch.dropped_now > watch.dropped_first ? " (it dropped a message meanwhile)" : "")
            << (signed_commands ? ": does it hold the same key as --key / $ROVER_KEY_FILE?"
                                : ": if it requires signed commands, pass --key FILE or set $ROVER_KEY_FILE")
            << "\n";
  return 3;
}

// abort, pause, resume: hear the executor's state first (its status comes once a second),
// act only on a sequence there is, and wait for the status that shows the effect.
int Control(const std::string& sub, const std::string& reason, const std::string& url,
            const std::optional<rover::auth::Key>& key) {
  auto bus = OpenBus(url, key);
  ExecutorWatch watch;
  watch.Subscribe(*bus);
  rover_msgs::sequence_control_t msg{};
  msg.action = sub == "abort"   ? rover_msgs::sequence_control_t::ACTION_ABORT
               : sub == "pause" ? rover_msgs::sequence_control_t::ACTION_PAUSE
                                : rover_msgs::sequence_control_t::ACTION_RESUME;
  msg.reason = reason;
  const char* sent = key ? " sent (signed): " : " sent: ";
  // An abort goes at once: stopping is never delayed by waiting for a status.
  if (sub == "abort") bus->Publish(rover::channels::kSequenceControl, msg);
  if (!watch.WaitFor(*bus, kAnswerWaitS, [&] { return watch.status.has_value(); })) {
    std::cerr << "rover_seq: " << sub << ": no sequence status heard within " << kAnswerWaitS << " s on " << url
              << (watch.heartbeat ? " (sequence_executor is heard but reported nothing)"
                                  : ": no sequence_executor heard; " +
                                        rover::launch::NothingHeardCauses(url, "sequence_executor"))
              << "\n";
    return 3;
  }
  if (sub == "abort") {
    // The abort's own status (aborted, reason operator), or a sequence still going.
    auto aborted = [&] {
      return watch.status->state == sequence_status_t::STATE_ABORTED && watch.status->abort_reason == "operator" &&
             watch.status->detail.find("operator abort: " + reason) != std::string::npos;
    };
    if (!watch.Active() && !aborted()) {
      std::cerr << "rover_seq: nothing to abort: " << Describe(*watch.status) << " (a stop was commanded anyway)\n";
      return 4;
    }
    if (!watch.WaitFor(*bus, kAnswerWaitS, aborted)) return NotActedOn(watch, sub, key.has_value(), url);
    std::cout << "abort" << sent << reason << "\n";
    Print(*watch.status);
    return 0;
  }
  const auto state = watch.status->state;
  if (sub == "pause" ? state != sequence_status_t::STATE_RUNNING
                     : state != sequence_status_t::STATE_PAUSED && state != sequence_status_t::STATE_RUNNING) {
    std::cerr << "rover_seq: nothing to " << sub << ": " << Describe(*watch.status)
              << (state == sequence_status_t::STATE_PAUSED ? " (already paused)" : "") << "\n";
    return 4;
  }
  bus->Publish(rover::channels::kSequenceControl, msg);
  std::cout << sub << sent << reason;
  if (sub == "pause") {
    std::cout << " (" << watch.status->sequence_name
              << " pauses between steps: the current step finishes first)\n";
    // A dropped command (unsigned on a signed stack) shows in the executor's next heartbeats.
    const std::int64_t before = watch.dropped_now;
    watch.WaitFor(*bus, 1.0, [] { return false; });
    if (before >= 0 && watch.dropped_now > before) return NotActedOn(watch, sub, key.has_value(), url);
    return 0;
  }
  if (state == sequence_status_t::STATE_RUNNING) {
    std::cout << " (" << watch.status->sequence_name << " is running, not paused: a pause not yet in effect is cancelled)\n";
    return 0;
  }
  std::cout << "\n";
  if (!watch.WaitFor(*bus, kAnswerWaitS, [&] { return watch.status->state != sequence_status_t::STATE_PAUSED; })) {
    return NotActedOn(watch, sub, key.has_value(), url);
  }
  Print(*watch.status);
  return watch.status->state == sequence_status_t::STATE_ABORTED ? 1 : 0;
}

// The usage of one subcommand, or of all ("" or an unknown name).
std::string Usage(const std::string& sub) {
  const std::string common =
      "\nThe bus: --lcm-url URL, else $ROVER_LCM_URL, else the default bus.\n"
      "Exit codes: 0 done; 1 the sequence aborted or was rejected; 2 a bad argument, URL or\n"
      "file; 3 no sequence_executor heard, or it did not act on the command (the likely cause\n"
      "is named); 4 nothing to act on (no sequence running to pause or abort, none paused).\n";
  const std::string keyed =
      "--key FILE (else $ROVER_KEY_FILE): sign with the deployment's key (an executor that\n"
      "holds a key refuses unsigned commands).\n";
  if (sub == "submit") {
    return "usage: rover_seq submit FILE [--no-follow] [--key FILE] [--lcm-url URL]\n\n"
           "Checks FILE (one line on the first error, exit 1), submits it to the running\n"
           "sequence_executor and follows it to the end: exit 0 when it completed, 1 when it was\n"
           "aborted or rejected, 3 when no executor answers within 4 s (the likely causes are\n"
           "named). --no-follow: submit and exit 0.\n" + keyed + common;
  }
  if (sub == "status") {
    return "usage: rover_seq status [--once] [--lcm-url URL]\n\n"
           "Follows the running sequence, one line per change, until it ends (exit 0 completed,\n"
           "1 aborted or rejected, 3 silence for 5 s). --once: print the first status heard.\n" + common;
  }
  if (sub == "abort") {
    return "usage: rover_seq abort [REASON] [--key FILE] [--lcm-url URL]\n\n"
           "Aborts the running sequence: the executor commands STOP and skips the rest\n"
           "(reason \"operator\"; REASON, default \"operator abort\", goes in its detail). Waits\n"
           "for the executor's status that says so. With no sequence running or paused it still\n"
           "commands STOP, says there was nothing to abort, and exits 4.\n" + keyed + common;
  }
  if (sub == "pause") {
    return "usage: rover_seq pause [REASON] [--key FILE] [--lcm-url URL]\n\n"
           "Pauses the running sequence between steps: the current step finishes first, then\n"
           "the executor holds (state paused) until resume or abort. With no sequence running\n"
           "(the executor's status says so) it sends nothing, says so and exits 4.\n" + keyed + common;
  }
  if (sub == "resume") {
    return "usage: rover_seq resume [REASON] [--key FILE] [--lcm-url URL]\n\n"
           "Resumes a paused sequence at its next step (the executor aborts with process_lost\n"
           "if a process it needs has gone silent meanwhile; exit 1). Waits for the executor's\n"
           "status that says it runs. On a running sequence it cancels a pause not yet in\n"
           "effect; with none running or paused it sends nothing, says so and exits 4.\n" + keyed + common;
  }
  if (sub == "keygen") {
    return "usage: rover_seq keygen FILE\n\n"
           "Writes a new random deployment key to FILE, mode 0600; never replaces a file.\n"
           "Give every computer and operator of the deployment a copy.\n";
  }
  return "usage: rover_seq SUBCOMMAND [ARGS] [--lcm-url URL] [--key FILE]\n\n"
         "  submit FILE [--no-follow]   check FILE, submit it, follow it to the end\n"
         "  status [--once]             follow the running sequence\n"
         "  abort [REASON]              abort the running sequence (the rover stops)\n"
         "  pause [REASON]              pause the running sequence between steps\n"
         "  resume [REASON]             resume a paused sequence\n"
         "  keygen FILE                 write a new deployment key (mode 0600)\n\n"
         "rover_seq SUBCOMMAND --help describes one. submit exits 3 when no executor answers\n"
         "within 4 s, naming the likely causes.\n" + keyed + common;
}

}  // namespace

int main(int argc, char** argv) {
  return rover::bus::RunMain("rover_seq", [&]() -> int {
    std::vector<std::string> args(argv + 1, argv + argc);
    std::string url, key_flag;
    bool once = false, follow = true, help = false;
    std::vector<std::string> positional;
    for (std::size_t i = 0; i < args.size(); ++i) {
      if (args[i] == "--lcm-url") {
        if (i + 1 >= args.size()) throw ConfigError("rover_seq: argument --lcm-url: missing value (expected a udpm:// URL)");
        url = args[++i];
      } else if (args[i] == "--key") {
        if (i + 1 >= args.size()) throw ConfigError("rover_seq: argument --key: missing value (expected FILE)");
        key_flag = args[++i];
      } else if (args[i] == "--once") {
        once = true;
      } else if (args[i] == "--no-follow") {
        follow = false;
      } else if (args[i] == "--help" || args[i] == "-h") {
        help = true;
      } else {
        positional.push_back(args[i]);
      }
    }
    if (help) {
      std::cout << Usage(positional.empty() ? "" : positional[0]);
      return 0;
    }
    if (positional.empty()) {
      throw ConfigError("rover_seq: missing subcommand (expected submit, status, abort, pause, resume or keygen; see --help)");
    }
    std::string url_from = "--lcm-url";
    if (url.empty()) {
      const char* env = std::getenv("ROVER_LCM_URL");
      url_from = env != nullptr && *env ? "$ROVER_LCM_URL" : "the default bus";
      url = env != nullptr && *env ? env : rover::bus::kDefaultLcmUrl;
    }
    // A bad URL is a bad argument (exit 2), not a sequence's outcome.
    // The executor is reached over UDP multicast only (another provider reaches no executor).
    std::string problem = rover::bus::LcmUrlProblem(url);
    if (problem.empty() && url.rfind("udpm://", 0) != 0) problem = "not a udpm:// URL";
    if (!problem.empty() && positional[0] != "keygen") {
      throw ConfigError("rover_seq: " + url_from + " " + url + ": " + problem + " (expected " +
                        rover::bus::kLcmUrlExpected + ")");
    }
    const std::string sub = positional[0];
    if (sub == "keygen") {
      if (positional.size() != 2) throw ConfigError("rover_seq keygen: expected exactly one FILE");
      try {
        rover::auth::GenerateKeyFile(positional[1]);
      } catch (const rover::auth::KeyError& e) {
        throw ConfigError(std::string("rover_seq keygen: ") + e.what());
      }
      std::cout << "wrote a new key to " << positional[1]
                << " (mode 0600): give every computer and operator of this deployment a copy\n";
      return 0;
    }
    if (sub == "submit") {
      if (positional.size() != 2) throw ConfigError("rover_seq submit: expected exactly one FILE");
      // A FIFO, a device or a file over 1 MiB is refused, not read.
      const std::string text = rover::config::ReadBoundedRegularFile(
          positional[1], rover::config::kMaxSequenceFileBytes, "sequence file");
      // Check before anything goes on the bus: the executor checks again.
      const auto check = rover::sequence::ParseSequence(text, positional[1]);
      if (!check.ok()) {
        std::cerr << check.errors.front().ToString() << "\n";
        return 1;
      }
      const auto key = LoadKey(key_flag);
      auto bus = OpenBus(url, key);
      rover_msgs::sequence_submit_t msg{};
      msg.submission_id = static_cast<std::int64_t>(Now() * 1e3);
      msg.name = positional[1];
      msg.text = text;
      auto send = [&] {
        bus->Publish(rover::channels::kSequenceSubmit, msg);
        std::cout << (key ? "submitted (signed) " : "submitted ") << positional[1] << " as "
                  << msg.submission_id << " on " << bus->url() << "\n" << std::flush;
      };
      if (!follow) {
        send();
        return 0;
      }
      return Follow(*bus, msg.submission_id, false, 10.0, key.has_value(), send);
    }
    if (sub == "status") {
      auto bus = OpenBus(url, std::nullopt);
      return Follow(*bus, -1, once, 5.0, false);
    }
    if (sub == "abort" || sub == "pause" || sub == "resume") {
      if (positional.size() > 2) {
        throw ConfigError("rover_seq " + sub + ": expected at most one REASON (quote it), got " +
                          std::to_string(positional.size() - 1) + " words");
      }
      return Control(sub, positional.size() > 1 ? positional[1] : "operator " + sub, url, LoadKey(key_flag));
    }
    throw ConfigError("rover_seq: unknown subcommand " + sub +
                      " (expected submit, status, abort, pause, resume or keygen; see --help)");
  });
}
