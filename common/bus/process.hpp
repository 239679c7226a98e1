// What every process gets: arguments (--help, --config, --lcm-url), its YAML config, a
// bus, rover time, a heartbeat, and a clean exit on SIGINT and SIGTERM.
//
// A bad argument or config gets one line naming the argument (or file and key) and what
// was expected, then exit code 2 (RunMain).
#pragma once

#include "bus/bus.hpp"
#include "config/yaml_config.hpp"

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace rover::bus {

struct OptionSpec {
  std::string flag;        // e.g. "--world"
  std::string value_name;  // e.g. "FILE"; empty for a switch
  std::string help;
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
  void ObserveTime(std::int64_t utime) {
    bus_.clock().Observe(utime, std::chrono::steady_clock::now());
  }
  // Seconds of wall time since start (for dead-peer guards only: rover time comes from messages).
  double wall_seconds() const;

  void SetHealth(std::int8_t state, std::string detail);

  // Loops until SIGINT/SIGTERM or Stop(): dispatches messages, publishes the heartbeat
  // once a wall second, and calls `on_tick` every `tick_ms` of wall time.
  void Run(const std::function<void()>& on_tick = nullptr, int tick_ms = 50);
  void Stop() { stop_requested_ = true; }
  // Handles the messages already received, for at most max_ms; returns how many. A tick
  // that judges peers by their last messages calls it first: after a stall (a process
  // starved on a busy machine) they wait in the socket, and a tick ahead of them sees
  // them as old as the stall.
  int HandleReceived(int max_ms);
  bool stopping() const;
  void PublishHeartbeat();
  // Wall seconds between heartbeats in Run (1 by default). The commander of a motion beats
  // faster, so that a mobility dead-man of 1.5 s tolerates a stall of over a second.
  void set_heartbeat_period(double seconds) { heartbeat_period_s_ = seconds; }

 private:
  std::string name_;
  std::string config_path_;
  config::ConfigNode config_;
  std::map<std::string, std::string> options_;
  Bus bus_;
  std::int64_t heartbeat_seq_ = 0;
  double heartbeat_period_s_ = 1.0;
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
