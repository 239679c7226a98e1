// What every process gets: arguments (--help, --config, --lcm-url), its YAML config, a
// bus, rover time, a heartbeat, and a clean exit on SIGINT and SIGTERM.
//
// A bad argument or config gets one line naming the argument (or file and key) and what
// was expected, then exit code 2 (RunMain).
#pragma once

#include "bus/bus.hpp"
#include "bus/virtual_time.hpp"
#include "config/yaml_config.hpp"
#include "simtime/compute_profile.hpp"

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace rover::bus {

struct OptionSpec {
  std::string flag;        // e.g. "--world"
  std::string value_name;  // e.g. "FILE"; empty for a switch
  std::string help;
};

// A channel a process publishes. `when` is empty for a channel published in every run,
// else the condition, in a few words ("with capture.hazcam"): `./rover graph` draws those
// dashed, and its test does not expect them on the bus of every run.
struct Publication {
  std::string channel;
  std::string when = "";
};

class Process {
 public:
  // Parses argv. Prints usage and exits 0 on --help. Throws config::ConfigError on a bad
  // argument or config. Opens the bus: --lcm-url, else $ROVER_LCM_URL, else the default.
  // `config_sections` are the top-level keys this process reads from --config; other
  // known sections of the shared rover config are allowed and ignored.
  Process(std::string name, std::string summary, int argc, char** argv,
          std::vector<OptionSpec> options = {}, std::vector<std::string> config_sections = {});

  const std::string& name() const { return name_; }
  // The root of the --config file (an empty mapping when none was given).
  const config::ConfigNode& config() const { return config_; }
  const std::string& config_path() const { return config_path_; }
  std::optional<std::string> option(const std::string& flag) const;
  bool has_switch(const std::string& flag) const { return option(flag).has_value(); }
  Bus& bus() { return bus_; }

  // Rover time in microseconds: the latest ROVER_CLOCK message, or any utime observed.
  // The Bus judges every message's utime against this clock (bus/guard.hpp).
  std::int64_t now() const { return bus_.clock().now(); }
  // Virtual time (`bus.time: virtual`, README "Simulated time"): rover time moves only
  // when every process of the set has finished the current instant. Messages are handed
  // to the callbacks once per clock tick, in one canonical order; ticks and heartbeats
  // run on rover time; and after each tick this process sends its sync report.
  bool virtual_time() const { return virtual_; }
  // A real-time process that only watches (a console started by hand on a running
  // simulation, outside its barrier) follows the time source's clock in either mode, as
  // rover_console does: a virtual clock is observed, so the messages stamped with it pass
  // the time checks, instead of being dropped as another mode's. It never joins the
  // barrier. Off by default: a process that acts on time must run in the bus's mode.
  void set_clock_observer(bool on) { clock_observer_ = on; }
  // The one clock every guard reads (dead-man, heartbeat loss, waits for answers): rover
  // seconds in virtual time, wall seconds otherwise (a real rover, where a limit on a
  // silent peer means wall time).
  double guard_seconds() const;
  void ObserveTime(std::int64_t utime) {
    bus_.clock().Observe(utime, std::chrono::steady_clock::now());
  }
  // Seconds of wall time since start (for dead-peer guards only: rover time comes from messages).
  double wall_seconds() const;

  // Where rover time comes from (docs/HARDWARE.md, "Rover time"), decided here for every
  // process: virtual time (the time source's barrier); on a real clock the time source's
  // ROVER_CLOCK (`bus.time_source`, rover_sim by default); or the system clock (`bus.time:
  // system`: a rover, or rover_sim as hardware). `auto` (no bus.time, no $ROVER_TIME):
  // undecided (rover time unknown, 0) until the time source is heard, or the system clock
  // once bus.time_source_wait_s (2 s) of wall time has passed without it.
  enum class TimeMode { kVirtual, kSourceClock, kSystemClock, kUndecided };
  TimeMode time_mode() const;
  const std::string& time_source() const { return time_source_; }
  // One line on stderr saying so (Run prints it; a process with a loop of its own calls it).
  void AnnounceTime() const;
  // A real clock taken from a time source that has sent no ROVER_CLOCK for
  // `bus.time_source_silent_s` of wall time: rover time stands still, so a process that
  // drives stops the rover (sequence_executor aborts with time_source_lost). Said once on
  // stderr when it falls silent and once when it speaks again (CheckTimeSource, in Run).
  bool time_source_silent() const { return source_silent_; }
  void CheckTimeSource();

  void SetHealth(std::int8_t state, std::string detail);

  // What this process publishes: one list in each main, after its subscriptions and before
  // it runs (HEARTBEAT is added here). With --channels the process prints its channels
  // (`publishes CHANNEL [when ...]`, and `subscribes CHANNEL` for each subscription the
  // bus holds) and exits 0 without running: `./rover graph` draws a deployment from them.
  void DeclarePublications(std::vector<Publication> publications);

  // Loops until SIGINT/SIGTERM or Stop(): dispatches messages, publishes the heartbeat
  // every heartbeat period, and calls `on_tick` every `tick_ms`: of wall time on a
  // rover, of rover time in virtual time.
  void Run(const std::function<void()>& on_tick = nullptr, int tick_ms = 50);
  // Work in hand beyond the callbacks (a render or a map update on a worker thread, an
  // answer held until its compute time has passed): called on every pass of the loop, it
  // publishes what has become due and returns true while work due by now is unfinished.
  // In virtual time the clock waits for it (the process says it is busy, and alive).
  void set_pending_work(std::function<bool()> poll) { pending_work_ = std::move(poll); }
  // Virtual time: the rover time before which this process has nothing of its own to do
  // (0: the next tick; kQuietForGood: nothing until a message comes), asked after each
  // tick and sent in the sync report. While every member of the set is quiet past the next
  // tick and the rover stands still, rover_sim steps the clock straight on, up to
  // sim.idle_step_s at a time (an idle stride: hours parked cost minutes of wall time, not
  // hours). A process that sets none is never quiet, and the clock never strides.
  static constexpr std::int64_t kQuietForGood = std::int64_t{1} << 62;
  void set_quiet_until(std::function<std::int64_t()> quiet_until) { quiet_until_ = std::move(quiet_until); }
  // Rover time a result of work started at `start_utime` is due, with the compute
  // profile's `seconds` (simtime/compute_profile.hpp): charged in virtual time only.
  std::int64_t DueAt(std::int64_t start_utime, double seconds) const;
  // The compute profile (the `compute:` section).
  const simtime::ComputeProfile& compute() const { return compute_; }
  void Stop() { stop_requested_ = true; }
  // Handles the messages already received, for at most max_ms; returns how many. A tick
  // that judges peers by their last messages calls it first: after a stall (a process
  // starved on a busy machine) they wait in the socket, and a tick ahead of them sees
  // them as old as the stall.
  int HandleReceived(int max_ms);
  bool stopping() const;
  void PublishHeartbeat();
  // Seconds between heartbeats in Run (0.25 by default; `bus.heartbeat_period_s`): of
  // wall time on a rover, where a peer silent for a second is taken for dead or hung, of
  // rover time in virtual time.
  void set_heartbeat_period(double seconds) { heartbeat_period_s_ = seconds; }
  // Virtual time: sends this process's sync report for the current instant (Run does; a
  // process with a loop of its own calls it after handling each tick).
  void SendSync(bool busy);

 private:
  std::string name_;
  std::string config_path_;
  config::ConfigNode config_;
  std::map<std::string, std::string> options_;
  Bus bus_;
  // One tick of virtual time: the batch of messages, heartbeat, on_tick, pending work.
  void RunVirtualTick(const std::function<void()>& on_tick, std::int64_t tick_us);
  void RunVirtual(const std::function<void()>& on_tick, int tick_ms);

  std::int64_t heartbeat_seq_ = 0;
  double heartbeat_period_s_ = 0.25;
  bool virtual_ = false;
  bool clock_observer_ = false;
  std::string time_source_ = "rover_sim";
  double source_silent_after_s_ = 1.0;
  double source_wait_s_ = 2.0;
  bool auto_time_ = false;
  bool source_seen_ = false;  // any ROVER_CLOCK of the time source, of either mode
  bool source_heard_ = false, source_silent_ = false;
  std::chrono::steady_clock::time_point source_heard_wall_{};
  // A real-clock ROVER_CLOCK from the time source: the switch from the system clock at the
  // first one, and the end of a silence.
  void OnSourceClock();
  std::function<bool()> pending_work_;
  std::function<std::int64_t()> quiet_until_;
  simtime::ComputeProfile compute_;
  std::unique_ptr<SyncSender> sync_;
  std::int64_t sync_seq_ = 0;
  bool clock_moved_ = false;        // a new instant: its batch is sealed, its tick not yet run
  std::int64_t sealing_utime_ = -1;  // the newest instant a clock message announced
  std::chrono::steady_clock::time_point clock_moved_wall_{};
  std::int64_t last_tick_utime_ = -1;
  std::int64_t next_tick_utime_ = 0, next_heartbeat_utime_ = 0;
  std::int8_t health_state_ = 0;
  std::string health_detail_;
  std::atomic<bool> stop_requested_{false};
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

// Runs a process body: ConfigError -> its one line on stderr, exit 2; any other
// exception -> "<name>: error: <what>", exit 1.
int RunMain(const std::string& name, const std::function<int()>& body);

// Parses "1.5,2,0.3" into numbers; throws ConfigError naming `what` when malformed.
std::vector<double> ParseNumberList(const std::string& text, std::size_t expected_count,
                                    const std::string& what);

// The top-level sections of the shared rover config (configs/rover.yaml).
const std::vector<std::string>& KnownConfigSections();

}  // namespace rover::bus
