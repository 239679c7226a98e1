#include "bus/process.hpp"
#include "bus/lcm_url_check.hpp"

#include "bus/channels.hpp"
#include "bus/signing.hpp"
#include "config/number_list.hpp"

#include <rover_msgs/heartbeat_t.hpp>
#include <rover_msgs/rover_clock_t.hpp>

#include <malloc.h>

#include <csignal>
#include <cstdlib>
#include <iostream>
#include <cmath>
#include <sstream>

namespace rover::bus {

namespace {

std::atomic<bool> g_signalled{false};

void OnSignal(int) { g_signalled = true; }

void InstallSignalHandlers() {
  struct sigaction action {};
  action.sa_handler = OnSignal;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

std::string Usage(const std::string& name, const std::string& summary,
                  const std::vector<OptionSpec>& options) {
  std::ostringstream os;
  os << "usage: " << name << " [options]\n\n" << summary << "\n\noptions:\n";
  auto line = [&os](const std::string& flag, const std::string& value, const std::string& help) {
    std::string left = "  " + flag + (value.empty() ? "" : " " + value);
    if (left.size() < 26) left.resize(26, ' ');
    os << left << " " << help << "\n";
  };
  line("--help", "", "print this help and exit");
  line("--config", "FILE", "YAML config (see configs/rover.yaml)");
  line("--lcm-url", "URL", std::string("LCM URL (default: $ROVER_LCM_URL, else ") +
                               kDefaultLcmUrl + ")");
  line("--key", "FILE", "the deployment's key for signed commands (default: auth.key_file, else $ROVER_KEY_FILE)");
  line("--channels", "", "print the channels this process publishes and subscribes, and exit (./rover graph)");
  for (const auto& o : options) line(o.flag, o.value_name, o.help);
  return os.str();
}

// The bus URL, checked before LCM sees it (a bad one is a bad argument: exit 2, one line).
std::string ChooseUrl(const std::string& name, int argc, char** argv) {
  std::string url = kDefaultLcmUrl, from;
  for (int i = 1; i + 1 < argc; ++i) {
    if (std::string(argv[i]) == "--lcm-url") {
      url = argv[i + 1];
      from = "argument --lcm-url";
    }
  }
  if (from.empty()) {
    if (const char* env = std::getenv("ROVER_LCM_URL"); env != nullptr && *env != '\0') {
      url = env;
      from = "$ROVER_LCM_URL";
    }
  }
  if (const std::string problem = LcmUrlProblem(url); !problem.empty()) {
    throw config::ConfigError(name + ": " + (from.empty() ? "LCM URL" : from) + ": " + url + ": " + problem +
                              " (expected " + kLcmUrlExpected + ")");
  }
  return url;
}

// Parsed before the Bus is constructed so that --help works with no bus at all.
std::map<std::string, std::string> ParseArgs(const std::string& name, const std::string& summary,
                                             int argc, char** argv,
                                             const std::vector<OptionSpec>& options) {
  std::map<std::string, std::string> parsed;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      std::cout << Usage(name, summary, options);
      std::exit(0);
    }
    const OptionSpec* spec = nullptr;
    static const std::vector<OptionSpec> builtin = {{"--config", "FILE", ""},
                                                    {"--lcm-url", "URL", ""},
                                                    {"--key", "FILE", ""},
                                                    {"--channels", "", ""}};
    for (const auto& o : builtin)
      if (o.flag == arg) spec = &o;
    for (const auto& o : options)
      if (o.flag == arg) spec = &o;
    if (spec == nullptr) {
      throw config::ConfigError(name + ": argument " + arg +
                                ": unknown option (expected one of the options in --help)");
    }
    if (spec->value_name.empty()) {
      parsed[arg] = "";
      continue;
    }
    if (i + 1 >= argc) {
      throw config::ConfigError(name + ": argument " + arg + ": missing value (expected " +
                                spec->value_name + ")");
    }
    parsed[arg] = argv[++i];
  }
  return parsed;
}

// The `bus:` section: how far from the rover clock a message's utime may be.
TimeWindow LoadTimeWindow(const config::ConfigNode& section) {
  TimeWindow w;
  section.CheckKeys({"max_ahead_wall_s", "max_ahead_rover_s", "max_behind_wall_s",
                     "max_behind_rover_s", "resync_wall_s", "resync_count", "max_clock_step_s",
                     "time", "time_source", "time_source_silent_s", "time_source_wait_s", "heartbeat_period_s",
                     "filter_in_kernel", "read_own_socket"});
  section.Get("max_clock_step_s", w.max_clock_step_s, 0.001, 3600.0);
  section.Get("max_ahead_wall_s", w.max_ahead_wall_s, 0.0, 3600.0);
  section.Get("max_ahead_rover_s", w.max_ahead_rover_s, 0.0, 86400.0);
  section.Get("max_behind_wall_s", w.max_behind_wall_s, 0.0, 3600.0);
  section.Get("max_behind_rover_s", w.max_behind_rover_s, 0.0, 86400.0);
  section.Get("resync_wall_s", w.resync_wall_s, 0.1, 3600.0);
  section.Get("resync_count", w.resync_count, 1, 1000000);
  return w;
}

// The `compute:` section (simtime/compute_profile.hpp): a named profile, any figure of
// which may be set on its own.
simtime::ComputeProfile LoadComputeProfile(const config::ConfigNode& section) {
  section.CheckKeys({"profile", "capture_s", "vo_s", "map_s", "hazcam_map_s", "plan_s"});
  std::string name = "embedded";
  section.GetEnum("profile", name, {"instant", "embedded", "mer"});
  simtime::ComputeProfile p = simtime::NamedProfile(name);
  section.Get("capture_s", p.capture_s, 0.0, 3600.0);
  section.Get("vo_s", p.vo_s, 0.0, 3600.0);
  section.Get("map_s", p.map_s, 0.0, 3600.0);
  section.Get("hazcam_map_s", p.hazcam_map_s, 0.0, 3600.0);
  section.Get("plan_s", p.plan_s, 0.0, 3600.0);
  return p;
}

}  // namespace

const std::vector<std::string>& KnownConfigSections() {
  static const std::vector<std::string> sections = {
      "mobility", "sensors",  "sim",    "estimator",       "hazards", "executor", "vo",
      "camera",   "visual_odometry",    "capture",         "bus",     "auth",     "compute",
      "clearance"};
  return sections;
}

Process::Process(std::string name, std::string summary, int argc, char** argv,
                 std::vector<OptionSpec> options, std::vector<std::string> config_sections)
    : name_(std::move(name)),
      options_(ParseArgs(name_, summary, argc, argv, options)),
      bus_(ChooseUrl(name_, argc, argv)) {
  if (auto it = options_.find("--config"); it != options_.end()) {
    config_path_ = it->second;
    config_ = config::ConfigNode::LoadFile(config_path_);
    std::vector<std::string> allowed = KnownConfigSections();
    allowed.insert(allowed.end(), config_sections.begin(), config_sections.end());
    config_.CheckKeys(allowed);
  } else {
    config_ = config::ConfigNode::FromString("{}", "(no config)");
  }
  bus_.set_publisher(name_);
  const auto bus_section = config_["bus"];
  bus_.clock().set_window(LoadTimeWindow(bus_section));
  // The time mode: `bus.time`, else $ROVER_TIME (the launcher and the scenario runner set
  // it for a set, so every process of the set agrees), else auto (docs/HARDWARE.md, "Rover
  // time"): the time source's clock if it is heard within bus.time_source_wait_s of
  // start, else the system clock.
  std::string time_mode = "auto";
  if (const char* env = std::getenv("ROVER_TIME"); env != nullptr && *env != '\0') {
    time_mode = env;
    if (time_mode != "real" && time_mode != "virtual" && time_mode != "system" && time_mode != "auto") {
      throw config::ConfigError(name_ + ": $ROVER_TIME: \"" + time_mode + "\": expected real, virtual, system or auto");
    }
  }
  // system: a real clock that is the system clock, with no time source at all (a rover;
  // rover_sim as the rover's hardware): the same as real with bus.time_source: system.
  bus_section.GetEnum("time", time_mode, {"real", "virtual", "system", "auto"});
  auto_time_ = time_mode == "auto";
  if (time_mode == "system") time_source_ = "system";
  if (time_mode != "system") bus_section.Get("time_source", time_source_);
  if (time_source_.empty()) {
    throw config::ConfigError(config_path_ + ": bus.time_source: empty (expected a process name, or system)");
  }
  bus_section.Get("time_source_silent_s", source_silent_after_s_, 0.05, 3600.0);
  bus_section.Get("time_source_wait_s", source_wait_s_, 0.0, 3600.0);
  bus_section.Get("heartbeat_period_s", heartbeat_period_s_, 0.01, 60.0);
  // Datagrams on channels this process does not subscribe to, dropped by the kernel
  // (bus/kernel_filter.hpp): what is delivered is the same, without the wake-ups.
  bool filter_in_kernel = true;
  bus_section.Get("filter_in_kernel", filter_in_kernel);
  bus_.FilterInKernel(filter_in_kernel);
  compute_ = LoadComputeProfile(config_["compute"]);
  virtual_ = time_mode == "virtual";
  if (virtual_ && time_source_ == "system") {
    throw config::ConfigError(config_path_ + ": bus.time_source: system with virtual time (expected the process that "
                              "owns the virtual clock, rover_sim; the system clock is for a real clock)");
  }
  // The system clock from the start when asked for (the time source itself keeps its own).
  if (!virtual_ && time_source_ == "system") bus_.clock().set_system(true);
  if (virtual_) {
    // Each message wakes this process's thread once, not LCM's receive thread and then it.
    bool read_own_socket = true;
    bus_section.Get("read_own_socket", read_own_socket);
    if (read_own_socket && UdpmPort(bus_.url()) > 0) bus_.ReadOwnSocket();
    bus_.clock().set_virtual(true);
    // Every message waits for the tick it belongs to; the clock itself is acted on at once.
    bus_.set_deferred(true, {channels::kClock});
    sync_ = std::make_unique<SyncSender>(bus_.url());
  }
  // Commands this process publishes are signed, and those it receives checked, when it
  // holds the deployment's key (bus/signing.hpp).
  if (const AuthSettings auth = LoadAuthSettings(config_, option("--key"), name_); auth.key) {
    bus_.set_auth(MakeBusAuth(*auth.key, name_));
  }
  InstallSignalHandlers();
  // The clock is taken only from the deployment's time source (`bus.time_source`), in the
  // mode this process runs in, never backwards (RoverClock::AcceptClock), and, with a
  // key, only signed by the time source (the Bus has checked the tag and its counter).
  bus_.Subscribe<rover_msgs::rover_clock_t>(
      channels::kClock,
      [this](const rover_msgs::rover_clock_t& msg) {
        const char* type = rover_msgs::rover_clock_t::getTypeName();
        const auto stamp = StampOf(msg);
        // The time source keeps its own time: any clock it hears is its own or forged.
        if (name_ == time_source_) return;
        if (bus_.clock().system()) {
          bus_.Drop(channels::kClock, type,
                    time_source_ == "system"
                        ? "rover time here is the system clock (bus.time: system)"
                        : "rover time here is the system clock: no ROVER_CLOCK came within bus.time_source_wait_s of start");
          return;
        }
        if (stamp->first != PublisherId(time_source_)) {
          bus_.Drop(channels::kClock, type, "not from the time source '" + time_source_ + "' (bus.time_source)");
          return;
        }
        if (bus_.has_auth() && msg.auth.sender.rfind(time_source_ + "@", 0) != 0) {
          bus_.Drop(channels::kClock, type,
                    "signed by '" + msg.auth.sender + "', not by the time source '" + time_source_ + "'");
          return;
        }
        source_seen_ = true;  // a clock is on this bus: auto never falls back to the system clock
        const bool virtual_clock = msg.mode == rover_msgs::rover_clock_t::MODE_VIRTUAL;
        if (virtual_clock != virtual_ && clock_observer_ && !virtual_) {
          bus_.clock().ObserveClock(msg.utime, msg.rate, std::chrono::steady_clock::now());
          return;
        }
        if (virtual_clock != virtual_) {
          bus_.Drop(channels::kClock, type,
                    std::string(virtual_clock ? "a virtual" : "a real-time") + " clock, and this process runs in " +
                        (virtual_ ? "virtual" : "real") + " time (bus.time)");
          return;
        }
        if (!virtual_) OnSourceClock();
        if (const std::string why = bus_.clock().AcceptClock(msg.utime, stamp->second, msg.rate, virtual_clock,
                                                             std::chrono::steady_clock::now());
            !why.empty()) {
          bus_.Drop(channels::kClock, type, why);
          return;
        }
        // A new instant: the messages received so far belong to the one before it.
        // It is sealed once every message the clock's cut names has come (simtime/cut.hpp).
        if (virtual_ && msg.utime > std::max(last_tick_utime_, sealing_utime_)) {
          bus_.ClockMoved(msg.utime, CutOf(msg));
          sealing_utime_ = msg.utime;
          clock_moved_wall_ = std::chrono::steady_clock::now();
          clock_moved_ = true;
        }
      },
      1000);
}

Process::TimeMode Process::time_mode() const {
  if (virtual_) return TimeMode::kVirtual;
  if (bus_.clock().system()) return TimeMode::kSystemClock;
  return source_heard_ || time_source_ == name_ ? TimeMode::kSourceClock : TimeMode::kUndecided;
}

void Process::AnnounceTime() const {
  std::cerr << name_ << ": rover time: ";
  if (virtual_) {
    std::cerr << "virtual, " << time_source_ << "'s clock and barrier (bus.time: virtual)\n";
  } else if (time_source_ == "system") {
    std::cerr << "the system clock (bus.time: system)\n";
  } else if (time_source_ == name_) {
    std::cerr << "this process's own clock, published on ROVER_CLOCK (it is bus.time_source)\n";
  } else if (time_mode() == TimeMode::kSourceClock) {
    std::cerr << time_source_ << "'s ROVER_CLOCK (bus.time_source)\n";
  } else if (auto_time_) {
    std::cerr << time_source_ << "'s ROVER_CLOCK if it is heard within " << source_wait_s_
              << " s, else the system clock (bus.time: auto)\n";
  } else {
    std::cerr << time_source_ << "'s ROVER_CLOCK, once it is heard (bus.time: real)\n";
  }
}

void Process::OnSourceClock() {
  const auto now = std::chrono::steady_clock::now();
  if (!source_heard_) {
    source_heard_ = true;
    std::cerr << name_ << ": rover time: " << time_source_ << "'s ROVER_CLOCK, heard after " << wall_seconds()
              << " s\n";
  } else if (source_silent_) {
    std::cerr << name_ << ": the time source " << time_source_ << " speaks again after "
              << std::chrono::duration<double>(now - source_heard_wall_).count() << " s of wall time; work resumes\n";
  }
  source_silent_ = false;
  source_heard_wall_ = now;
}

void Process::CheckTimeSource() {
  if (virtual_) return;
  // auto: no clock within the wait, so there is none: a rover. The system clock, for good
  // (a simulated clock heard later need not be near it, and times never go back).
  if (auto_time_ && !source_seen_ && !bus_.clock().system() && time_source_ != name_ &&
      wall_seconds() >= source_wait_s_) {
    bus_.clock().set_system(true);
    std::cerr << name_ << ": rover time: the system clock: no ROVER_CLOCK from " << time_source_ << " within "
              << source_wait_s_ << " s of start (bus.time_source_wait_s)\n";
    return;
  }
  if (!source_heard_ || source_silent_) return;
  const double silent_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - source_heard_wall_).count();
  if (silent_s < source_silent_after_s_) return;
  source_silent_ = true;
  std::cerr << name_ << ": the time source " << time_source_ << " fell silent: no ROVER_CLOCK for " << silent_s
            << " s of wall time (bus.time_source_silent_s " << source_silent_after_s_
            << "); rover time stands still, a drive stops, until it speaks again\n";
}

double Process::guard_seconds() const { return virtual_ ? static_cast<double>(now()) * 1e-6 : wall_seconds(); }

std::int64_t Process::DueAt(std::int64_t start_utime, double seconds) const {
  return virtual_ ? start_utime + static_cast<std::int64_t>(std::llround(seconds * 1e6)) : start_utime;
}

void Process::SendSync(bool busy) {
  if (!sync_) return;
  simtime::SyncReport report = bus_.SyncState(name_, last_tick_utime_, busy);
  report.quiet_until = !busy && quiet_until_ ? quiet_until_() : 0;
  sync_->Send(report);
}

void Process::RunVirtualTick(const std::function<void()>& on_tick, std::int64_t tick_us) {
  const std::int64_t t = bus_.clock().clock_utime();
  last_tick_utime_ = t;
  bus_.DispatchBatch();
  if (t >= next_heartbeat_utime_) {
    PublishHeartbeat();
    next_heartbeat_utime_ = t + static_cast<std::int64_t>(heartbeat_period_s_ * 1e6);
  }
  if (on_tick && t >= next_tick_utime_) {
    on_tick();
    next_tick_utime_ = t + tick_us;
  }
}

// Virtual time: nothing here reads the wall clock except to say "alive" (a sync report
// every 0.25 s of wall time, busy or not): the clock's liveness limit is the only wall
// time rule in simulation.
void Process::RunVirtual(const std::function<void()>& on_tick, int tick_ms) {
  using Clock = std::chrono::steady_clock;
  const std::int64_t tick_us = std::int64_t{tick_ms} * 1000;
  auto last_sync = Clock::now() - std::chrono::seconds(10);
  bool changed = true, was_busy = false;
  while (!stopping()) {
    // The new instant's batch, once all of it has come. A message below the cut that has
    // not come a wall second after the clock was lost on the way (a socket overflowed in a
    // freeze): the batch goes without it, with one line.
    std::string missing;
    if (clock_moved_ &&
        (bus_.SealWhenReady(Clock::now() - clock_moved_wall_ > std::chrono::seconds(1), &missing) ||
         !bus_.seal_pending())) {
      if (!missing.empty()) {
        std::cerr << name_ << ": rover time " << sealing_utime_ << ": the batch goes without messages lost on the way ("
                  << missing << ")\n";
      }
      clock_moved_ = false;
      RunVirtualTick(on_tick, tick_us);
      changed = true;
    }
    const bool busy = last_tick_utime_ >= 0 && pending_work_ && pending_work_();
    const auto now = Clock::now();
    // One report an instant, after its tick (and when busy changes, and to say "alive"):
    // what arrives meanwhile need not be reported, as every member seals its batch by the
    // clock's cut (simtime/barrier.hpp, "One round an instant").
    if (changed || busy != was_busy || now - last_sync > std::chrono::milliseconds(250)) {
      SendSync(busy);
      last_sync = now;
      was_busy = busy;
      changed = false;
    }
    // One message a pass, so that a clock message is acted on before those behind it and
    // a flood cannot hold back the sync report. No probe for more after it: the next
    // pass's wait returns at once when more has come, and a probe that finds nothing is a
    // system call a message (docs/SIMTIME_LOG.md, "System calls an instant").
    bus_.Handle(busy ? 2 : 50);
  }
}

std::optional<std::string> Process::option(const std::string& flag) const {
  if (auto it = options_.find(flag); it != options_.end()) return it->second;
  return std::nullopt;
}

double Process::wall_seconds() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

void Process::SetHealth(std::int8_t state, std::string detail) {
  health_state_ = state;
  health_detail_ = std::move(detail);
}

void Process::DeclarePublications(std::vector<Publication> publications) {
  if (!has_switch("--channels")) return;
  publications.insert(publications.begin(), Publication{channels::kHeartbeat, ""});
  std::ostringstream os;
  os << "process " << name_ << "\n";
  for (const auto& p : publications) os << "publishes " << p.channel << (p.when.empty() ? "" : " when " + p.when) << "\n";
  for (const auto& channel : bus_.subscribed()) os << "subscribes " << channel << "\n";
  std::cout << os.str() << std::flush;
  // No unwinding: worker threads a process has started need not be stopped for a listing.
  std::_Exit(0);
}

bool Process::stopping() const { return stop_requested_ || g_signalled; }

void Process::PublishHeartbeat() {
  rover_msgs::heartbeat_t hb{};
  hb.utime = now();
  hb.process = name_;
  hb.seq = heartbeat_seq_++;
  hb.state = health_state_;
  hb.detail = health_detail_;
  hb.dropped = bus_.dropped();
  if (bus_.dropped() > 0 && hb.detail.empty()) hb.detail = "last drop: " + bus_.last_drop();
  bus_.Publish(channels::kHeartbeat, hb);
}

int Process::HandleReceived(int max_ms) {
  if (virtual_) return 0;  // messages wait for their tick; a stall changes nothing
  using Clock = std::chrono::steady_clock;
  const auto until = Clock::now() + std::chrono::milliseconds(max_ms);
  int handled = 0;
  while (Clock::now() < until && bus_.Handle(0)) ++handled;
  return handled;
}

void Process::Run(const std::function<void()>& on_tick, int tick_ms) {
  if (has_switch("--channels")) {
    // Not thrown: the worker threads a program may hold would make unwinding abort.
    std::cerr << name_ << ": argument --channels: this program declares no channels "
                          "(expected a process that calls DeclarePublications)\n";
    std::_Exit(2);
  }
  AnnounceTime();
  if (const std::string w = SmallReceiveBufferWarning(name_, bus_.url(), bus_.subscribed()); !w.empty()) {
    std::cerr << w << "\n";
  }
  if (virtual_) return RunVirtual(on_tick, tick_ms);
  using Clock = std::chrono::steady_clock;
  auto next_heartbeat = Clock::now();
  auto next_tick = Clock::now();
  while (!stopping()) {
    const auto now = Clock::now();
    if (now >= next_heartbeat) {
      PublishHeartbeat();
      next_heartbeat = now + std::chrono::duration_cast<Clock::duration>(
                                 std::chrono::duration<double>(heartbeat_period_s_));
    }
    if (on_tick && now >= next_tick) {
      on_tick();
      next_tick = now + std::chrono::milliseconds(tick_ms);
    }
    if (pending_work_) pending_work_();
    CheckTimeSource();
    const auto wait = std::min(next_heartbeat, on_tick ? next_tick : next_heartbeat) - Clock::now();
    const int wait_ms = static_cast<int>(
        std::max<long>(0, std::chrono::duration_cast<std::chrono::milliseconds>(wait).count()));
    bus_.Handle(std::min(wait_ms, 100));
  }
}

namespace {

// A process that allocates an image-sized buffer for every pair (OpenCV's SGBM sizes its
// cost buffers per call) would otherwise take each one from the kernel with mmap, fault in
// its pages and unmap it again: glibc maps blocks over its threshold (128 KiB at first,
// rising only with what was freed) and trims the heap's free top over 128 KiB. Keeping
// blocks up to 32 MiB (glibc's ceiling) in the heap, and up to 64 MiB of its free top,
// lets the next pair reuse the pages: the demo's hazard_monitor took about 15 % less CPU
// (docs/SIMTIME_LOG.md, "Freed buffers kept"). The bytes computed are the same.
void KeepFreedBuffers() {
  mallopt(M_MMAP_THRESHOLD, 32 * 1024 * 1024);
  mallopt(M_TRIM_THRESHOLD, 64 * 1024 * 1024);
}

}  // namespace

int RunMain(const std::string& name, const std::function<int()>& body) {
  KeepFreedBuffers();
  try {
    return body();
  } catch (const config::ConfigError& e) {
    std::cerr << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << name << ": error: " << e.what() << "\n";
    return 1;
  }
}

std::vector<double> ParseNumberList(const std::string& text, std::size_t expected_count,
                                    const std::string& what) {
  std::vector<double> values;
  if (!config::ParseNumberList(text, &values) || values.size() != expected_count) {
    throw config::ConfigError(what + ": \"" + text + "\": expected " +
                              std::to_string(expected_count) +
                              " finite numbers separated by commas");
  }
  return values;
}

}  // namespace rover::bus
