// The fault suite's rig: the full sim_vo deployment on a private LCM bus, a harness bus
// that watches it (heartbeats, sequence status, mobility status, truth), and an injector
// that publishes raw packets. Every process exit is recorded with what was sent last, so
// a failure says which packet killed which process.
#pragma once

#include "auth/auth.hpp"
#include "bus/bus.hpp"
#include "bus/channels.hpp"
#include "bus/signing.hpp"
#include "fault_inject/packets.hpp"
#include "integration/run_support.hpp"
#include "launch/process_set.hpp"
#include "scenario/scenario_overrides.hpp"

#include <lcm/lcm-cpp.hpp>
#include <rover_msgs/hazard_status_t.hpp>
#include <rover_msgs/heartbeat_t.hpp>
#include <rover_msgs/mobility_status_t.hpp>
#include <rover_msgs/rover_clock_t.hpp>
#include <rover_msgs/sequence_control_t.hpp>
#include <rover_msgs/sequence_status_t.hpp>
#include <rover_msgs/sequence_submit_t.hpp>
#include <rover_msgs/sim_truth_t.hpp>
#include <rover_msgs/step_report_t.hpp>

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <chrono>
#include <csignal>
#include <deque>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace rover::test {

using Clock = std::chrono::steady_clock;
inline double Since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// What a test counts, printed and written to test-out/fault_counts/ for the lead to quote.
struct FaultCounts {
  long packets = 0;     // hostile packets sent
  long deaths = 0;      // processes that died of anything but our kill -9
  long kills = 0;       // kill -9 we sent
  long safe_stops = 0;  // kills after which the rover stopped within the bound
};

// The six processes of configs/deploy/sim_vo.yaml.
inline const std::vector<std::string>& DeployedProcesses() {
  static const std::vector<std::string> names = {"rover_sim",       "camera_capture", "visual_odometry",
                                                 "state_estimator", "hazard_monitor", "sequence_executor"};
  return names;
}

// A drive north over the demo's ground (4 steps of 50 cm, VO at each), long enough to be
// under way while packets fly or a process dies.
inline std::string DriveSequence(const std::string& drive, int step_cm = 50) {
  return "vo on step " + std::to_string(step_cm) + " cm maxturn 18 deg failures 10 then continue\n" +
         "limit time 900 s\n" + drive + "\n";
}

class FaultRig {
 public:
  // `keyed`: the deployment with authenticated commands (configs/deploy/sim_vo_auth.yaml)
  // with a key made here; the rig signs what it submits, the injector never does.
  explicit FaultRig(const std::string& name, bool keyed = false)
      : name_(name), out_(OutDir("fault_" + name)), url_(PrivateUrl(11)), bus_(url_), injector_(url_) {
    // Deployment paths are relative to the repository root.
    std::filesystem::current_path(SourceDir());
    bus_.set_publisher("fault_test");
    if (keyed) {
      key_ = out_ + "/rover.key";
      auth::GenerateKeyFile(key_);
      bus_.set_auth(bus::MakeBusAuth(auth::Key::LoadFile(key_), "fault_test"));
    }
    bus_.lcm().subscribe(channels::kMobilityCommand, &FaultRig::OnRawCommand, this);
    bus_.lcm().subscribe(channels::kClock, &FaultRig::OnRawClock, this);
    bus_.lcm().subscribe(channels::kHeartbeat, &FaultRig::OnRawHeartbeat, this);
    const YAML::Node rover = YAML::LoadFile(SourceDir() + "/configs/rover.yaml");
    heartbeat_timeout_s_ = rover["executor"]["heartbeat_timeout_s"].as<double>();
    Watch();
  }
  ~FaultRig() { StopAll(); }

  const std::string& url() const { return url_; }
  // Virtual time (README, "Simulated time"): every process started from now on gets
  // ROVER_TIME=virtual, and rover_sim's --hold-for makes them the clock's barrier.
  void set_virtual(bool on) { virtual_ = on; }
  // The last ROVER_CLOCK rover_sim sent, as sent (for a replay), and the last HEARTBEAT a
  // process sent.
  const std::vector<std::uint8_t>& last_clock_bytes() const { return last_clock_; }
  const std::vector<std::uint8_t>& last_heartbeat_bytes(const std::string& process) const {
    static const std::vector<std::uint8_t> none;
    auto it = last_heartbeat_.find(process);
    return it == last_heartbeat_.end() ? none : it->second;
  }
  const std::string& out() const { return out_; }
  double heartbeat_timeout_s() const { return heartbeat_timeout_s_; }
  FaultCounts& counts() { return counts_; }
  const std::vector<std::string>& deaths() const { return deaths_; }

  // Starts every process of sim_vo on this rig's bus and waits for their heartbeats.
  // The simulator holds its clock until the others are up (as the scenario runner does)
  // and runs at `rate` rover seconds per wall second (sim.rate is 50).
  bool StartAll(double rate = 50) {
    set_ = std::make_unique<launch::ProcessSet>(std::string(ROVER_BINARY_DIR) + "/bin",
                                                NewLogDir(), false);
    labels_.clear();
    heard_.clear();
    truth_.reset();
    if (status_) wheels_done_m_ += status_->wheel_distance_m;
    status_.reset();
    std::string others;
    for (const auto& p : DeployedProcesses())
      if (p != "rover_sim") others += (others.empty() ? "" : ",") + p;
    for (const auto& p : DeployedProcesses()) {
      launch::ProcessSpec spec = Spec(p);
      if (p == "rover_sim") {
        for (const char* a : {"--start", "0,0,0", "--rate"}) spec.args.push_back(a);
        spec.args.push_back(std::to_string(rate));
        spec.args.push_back("--hold-for");
        spec.args.push_back(others);
      }
      Start(spec);
    }
    return WaitHeard(DeployedProcesses(), 30);
  }

  // Starts one process again (after a kill), under a new label; waits for its heartbeat.
  bool Restart(const std::string& process) {
    heard_.erase(process);
    Start(Spec(process));
    return WaitHeard({process}, 20);
  }

  void StopAll() {
    if (!set_) return;
    Pump(0);
    set_->StopAll(2000);
    set_.reset();
  }

  // Sends kill -9 to a process; its exit is then expected, not a death.
  void Kill(const std::string& process) {
    killed_.insert(labels_.at(process));
    set_->Signal(labels_.at(process), SIGKILL);
    ++counts_.kills;
    Note("kill -9 " + process);
  }

  // Sends SIGSTOP or SIGCONT to a process: a frozen process is hung, not dead.
  void Freeze(const std::string& process, bool frozen) {
    set_->Signal(labels_.at(process), frozen ? SIGSTOP : SIGCONT);
    Note(std::string(frozen ? "SIGSTOP " : "SIGCONT ") + process);
  }

  // Waits until `process` has caught up with rover time after a freeze (its heartbeat is
  // within 2 s of the clock): until then its socket may still overflow with the backlog,
  // and a sequence submitted meanwhile can be lost with it.
  bool WaitCaughtUp(const std::string& process, double seconds) {
    return PumpUntil(seconds, [&] {
      auto it = last_heartbeat_.find(process);
      if (it == last_heartbeat_.end()) return false;
      rover_msgs::heartbeat_t hb;
      if (hb.decode(it->second.data(), 0, static_cast<int>(it->second.size())) < 0) return false;
      return now_utime_ > 0 && hb.utime >= now_utime_ - 2000000;
    });
  }

  // Until the hazard monitor, heard after this call, can decide a step again (SAFE: it holds
  // a fresh pose). A restarted process is back once its heartbeat is heard, but a restarted
  // estimator's first pose reaches the monitor only later: a sequence sent in between meets
  // "pose is 3.3 s old" and aborts hazard_unknown, as it should (seen beside a CPU burner).
  bool WaitHazardSafe(double seconds) {
    const auto start = Clock::now();
    return PumpUntil(seconds, [&] { return hazard_safe_at_ > start; });
  }

  std::int64_t Submit(const std::string& text) {
    rover_msgs::sequence_submit_t m{};
    m.utime = now_utime_;
    m.submission_id = ++submission_id_;
    m.name = name_ + "_" + std::to_string(submission_id_) + ".seq";
    m.text = text;
    steps_[submission_id_] = 0;
    bus_.Publish(channels::kSequenceSubmit, m);
    return submission_id_;
  }

  void Abort(const std::string& reason) {
    rover_msgs::sequence_control_t m{};
    m.utime = now_utime_;
    m.action = rover_msgs::sequence_control_t::ACTION_ABORT;
    m.reason = reason;
    bus_.Publish(channels::kSequenceControl, m);
  }

  // Handles the bus and reaps exits for `seconds` of wall time, or until `done()`.
  template <class Done>
  bool PumpUntil(double seconds, Done done) {
    const auto start = Clock::now();
    for (;;) {
      bus_.Handle(5);
      Reap();
      if (done()) return true;
      if (Since(start) >= seconds) return false;
    }
  }
  void Pump(double seconds) {
    PumpUntil(seconds, [] { return false; });
  }

  std::optional<rover_msgs::sequence_status_t> Final(std::int64_t id) const {
    const auto it = final_.find(id);
    if (it == final_.end()) return std::nullopt;
    return it->second;
  }
  std::optional<rover_msgs::sequence_status_t> WaitFinal(std::int64_t id, double seconds) {
    PumpUntil(seconds, [&] { return final_.count(id) > 0; });
    return Final(id);
  }
  bool WaitSteps(std::int64_t id, int n, double seconds) {
    return PumpUntil(seconds, [&] { return steps_[id] >= n; });
  }
  // Until the rover is driving (its latest status says MOVING and truth advances).
  bool WaitMoving(double seconds) {
    return PumpUntil(seconds, [&] {
      return status_ && status_->state == rover_msgs::mobility_status_t::STATE_MOVING &&
             Since(last_advance_) < 0.1;
    });
  }

  // Watches truth for `window_s` after `since`: the wall time from `since` to the last
  // advance of the true odometer, or nullopt when it still advances at the end.
  std::optional<double> StopLatency(Clock::time_point since, double window_s) {
    PumpUntil(window_s - Since(since), [] { return false; });
    if (Since(last_advance_) < 0.5) return std::nullopt;  // still rolling
    return std::max(0.0, std::chrono::duration<double>(last_advance_ - since).count());
  }
  double odometer() const { return truth_ ? truth_->odometer_m : 0.0; }
  // The distance rover_sim's wheels rolled over every command so far (its own report, not
  // truth): on cobbles and sand the truth advances less, by the slip.
  double wheels_rolled() const { return wheels_done_m_ + (status_ ? status_->wheel_distance_m : 0.0); }
  std::string mobility_detail() const {
    if (!status_) return "no MOBILITY_STATUS";
    return "MOBILITY_STATUS state " + std::to_string(status_->state) + " '" + status_->detail + "'";
  }

  // Processes whose last heartbeat is older than `max_age_s` (wedged or dead).
  std::vector<std::string> Silent(double max_age_s) const {
    std::vector<std::string> silent;
    for (const auto& p : DeployedProcesses()) {
      const auto it = heard_.find(p);
      if (it == heard_.end() || Since(it->second) > max_age_s) silent.push_back(p);
    }
    return silent;
  }
  std::int64_t dropped(const std::string& process) const {
    const auto it = dropped_.find(process);
    return it == dropped_.end() ? 0 : it->second;
  }

  // Publishes packets one at a time, `interval_ms` apart, reaping exits in between, so a
  // death names the packet that preceded it.
  void Inject(const std::vector<fault::Packet>& packets, int interval_ms) {
    injecting_ = true;  // from here on, MOBILITY_COMMAND packets may be ours
    for (const auto& p : packets) {
      if (injector_.publish(p.channel, p.bytes.data(), static_cast<unsigned int>(p.bytes.size())) != 0) {
        ADD_FAILURE() << "LCM refused to send " << p.label << " (" << p.bytes.size() << " bytes)";
        continue;
      }
      ++counts_.packets;
      recent_.push_back(p.label);
      if (recent_.size() > 5) recent_.pop_front();
      Pump(interval_ms / 1000.0);
    }
  }

  std::int64_t now_utime() const { return now_utime_; }

  // The MOBILITY_COMMAND packets seen so far, byte for byte (to replay them).
  std::vector<fault::Packet> CapturedCommands() const {
    std::vector<fault::Packet> out;
    for (std::size_t i = 0; i < commands_.size(); ++i) {
      out.push_back({channels::kMobilityCommand,
                     "MOBILITY_COMMAND replayed: command " + std::to_string(i + 1) + " as the executor sent it",
                     commands_[i], ""});
    }
    return out;
  }

  // One line per test for the lead: printed and kept in test-out/fault_counts/.
  void Report() const {
    std::ostringstream line;
    line << "fault counts: " << name_ << ": packets sent " << counts_.packets << ", deaths " << counts_.deaths
         << ", kills " << counts_.kills << ", safe stops " << counts_.safe_stops;
    std::cout << line.str() << "\n";
    const std::string dir = std::string(ROVER_BINARY_DIR) + "/test-out/fault_counts";
    std::filesystem::create_directories(dir);
    std::ofstream(dir + "/" + name_ + ".txt") << line.str() << "\n";
  }

  void Note(const std::string& line) {
    std::cout << "[" << name_ << " " << std::fixed << std::setprecision(1) << Since(start_) << " s] " << line
              << "\n"
              << std::flush;
  }

 private:
  launch::ProcessSpec Spec(const std::string& process) const {
    const auto deployment = launch::LoadDeployment(SourceDir() + "/configs/deploy/" +
                                                   (key_.empty() ? "sim_vo.yaml" : "sim_vo_auth.yaml"));
    for (auto spec : deployment.processes) {
      if (spec.name != process) continue;
      for (auto& a : spec.args) {
        if (a == "build/keys/rover.key") a = key_;  // the key this rig made
        if (a == "configs/rover.yaml" && !virtual_) a = RealClockConfig();
      }
      if (process == "sequence_executor") {
        // A restarted executor reports the sequence it was running as interrupted.
        spec.args.push_back("--state-file");
        spec.args.push_back(out_ + "/executor.state");
      }
      return spec;
    }
    throw std::runtime_error("sim_vo.yaml has no process " + process);
  }

  // On a real clock the executor's waits for the hazard monitor's reply and status are
  // wall time (a rover's limit), and the monitor answers a step only once it has mapped
  // the pair. At 50x rover time on a machine this suite may share with other work (4
  // burners and -j2: load 14), that mapping has taken more than the 5 s default, and a
  // new sequence aborted `hazard_unknown` though nothing was wrong. Those waits are not
  // what these tests prove (a dead or hung monitor is caught by its heartbeat, within
  // heartbeat_timeout_s), so this rig gives them 30 s: a copy of configs/rover.yaml with
  // only those two keys changed. In virtual time the waits are rover time and the
  // monitor's mapping is charged from the compute profile, so the original is used.
  std::string RealClockConfig() const {
    const std::string copy = out_ + "/rover.yaml";
    if (!std::filesystem::exists(copy)) {
      std::vector<tools::ConfigOverride> waits = {{"executor.hazard_reply_wait_s", YAML::Node(30.0)},
                                                  {"executor.hazard_status_wait_s", YAML::Node(30.0)}};
      tools::PrepareRunConfigs(SourceDir() + "/configs/rover.yaml", waits,
                               SourceDir() + "/configs/worlds/flat_rock_course.yaml", {}, out_);
    }
    return copy;
  }

  void Start(launch::ProcessSpec spec) {
    const std::string process = spec.name;
    spec.program = process;
    spec.name = process + (starts_[process]++ ? "#" + std::to_string(starts_[process]) : "");
    labels_[process] = spec.name;
    std::vector<std::string> env = {"ROVER_LCM_URL=" + url_};
    if (virtual_) env.push_back("ROVER_TIME=virtual");
    set_->Start(spec, env);
    Note("started " + spec.name);
  }

  std::string NewLogDir() {
    const std::string dir = out_ + "/run" + std::to_string(++runs_);
    std::filesystem::create_directories(dir);
    return dir;
  }

  bool WaitHeard(const std::vector<std::string>& processes, double seconds) {
    const auto start = Clock::now();
    const bool ok = PumpUntil(seconds, [&] {
      for (const auto& p : processes)
        if (!heard_.count(p) || heard_.at(p) < start) return false;
      return true;
    });
    if (!ok) {
      for (const auto& p : processes)
        if (!heard_.count(p)) ADD_FAILURE() << p << " sent no heartbeat within " << seconds << " s";
    }
    return ok;
  }

  void Reap() {
    if (!set_) return;
    for (const auto& [label, how] : set_->Poll(0)) {
      if (killed_.count(label)) continue;
      std::string last;
      for (const auto& r : recent_) last += "\n    " + r;
      const std::string death = label + " " + how + (recent_.empty() ? "" : "; the last packets sent:" + last) +
                                " (its output: " + out_ + "/run" + std::to_string(runs_) + "/" + label + ".log)";
      deaths_.push_back(death);
      ++counts_.deaths;
      Note("DEATH: " + death);
    }
  }

  void OnRawCommand(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    const auto* p = static_cast<const std::uint8_t*>(rbuf->data);
    if (!injecting_) commands_.emplace_back(p, p + rbuf->data_size);
  }
  void OnRawClock(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    const auto* p = static_cast<const std::uint8_t*>(rbuf->data);
    if (!injecting_) last_clock_.assign(p, p + rbuf->data_size);
  }
  void OnRawHeartbeat(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    rover_msgs::heartbeat_t hb;
    if (injecting_ || hb.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) < 0) return;
    const auto* p = static_cast<const std::uint8_t*>(rbuf->data);
    last_heartbeat_[hb.process].assign(p, p + rbuf->data_size);
  }

  static bool From(std::int64_t pub_seq, const char* process) {
    return static_cast<std::uint32_t>(static_cast<std::uint64_t>(pub_seq) >> 32) == bus::PublisherId(process);
  }

  void Watch() {
    bus_.Subscribe<rover_msgs::heartbeat_t>(channels::kHeartbeat, [this](const rover_msgs::heartbeat_t& h) {
      for (const auto& p : DeployedProcesses()) {
        if (h.process != p) continue;
        heard_[p] = Clock::now();
        dropped_[p] = h.dropped;
      }
    }, 100);
    bus_.Subscribe<rover_msgs::rover_clock_t>(channels::kClock, [this](const rover_msgs::rover_clock_t& c) {
      if (From(c.pub_seq, "rover_sim")) now_utime_ = c.utime;
    });
    bus_.Subscribe<rover_msgs::sim_truth_t>(channels::kSimTruth, [this](const rover_msgs::sim_truth_t& t) {
      if (!From(t.pub_seq, "rover_sim")) return;
      if (!truth_ || t.odometer_m > truth_->odometer_m + 1e-6) last_advance_ = Clock::now();
      truth_ = t;
    }, 1000);
    bus_.Subscribe<rover_msgs::mobility_status_t>(channels::kMobilityStatus,
                                                  [this](const rover_msgs::mobility_status_t& s) {
                                                    if (!From(s.pub_seq, "rover_sim")) return;
                                                    if (status_ && status_->command_id != s.command_id)
                                                      wheels_done_m_ += status_->wheel_distance_m;
                                                    status_ = s;
                                                  }, 1000);
    bus_.Subscribe<rover_msgs::hazard_status_t>(channels::kHazardStatus, [this](const rover_msgs::hazard_status_t& h) {
      if (From(h.pub_seq, "hazard_monitor") && h.state == rover_msgs::hazard_status_t::STATE_SAFE)
        hazard_safe_at_ = Clock::now();
    }, 100);
    bus_.Subscribe<rover_msgs::step_report_t>(channels::kStepReport, [this](const rover_msgs::step_report_t& r) {
      if (From(r.pub_seq, "sequence_executor")) ++steps_[r.submission_id];
    }, 100);
    bus_.Subscribe<rover_msgs::sequence_status_t>(
        channels::kSequenceStatus, [this](const rover_msgs::sequence_status_t& s) {
          if (!From(s.pub_seq, "sequence_executor")) return;
          using S = rover_msgs::sequence_status_t;
          if ((s.state == S::STATE_COMPLETED || s.state == S::STATE_ABORTED || s.state == S::STATE_REJECTED) &&
              !final_.count(s.submission_id)) {
            final_[s.submission_id] = s;
            Note("sequence " + std::to_string(s.submission_id) + " final: state " + std::to_string(s.state) +
                 " " + s.abort_reason + " '" + s.detail + "'");
          }
        }, 100);
  }

  std::string name_;
  std::string out_;
  std::string url_;
  std::string key_;  // empty: no keys
  bus::Bus bus_;
  lcm::LCM injector_;
  double heartbeat_timeout_s_ = 3.0;
  std::unique_ptr<launch::ProcessSet> set_;
  std::map<std::string, std::string> labels_;  // process -> label of its current instance
  std::map<std::string, int> starts_;
  std::set<std::string> killed_;               // labels we killed
  int runs_ = 0;
  std::map<std::string, Clock::time_point> heard_;
  std::map<std::string, std::int64_t> dropped_;
  std::map<std::int64_t, int> steps_;
  std::map<std::int64_t, rover_msgs::sequence_status_t> final_;
  std::optional<rover_msgs::sim_truth_t> truth_;
  std::optional<rover_msgs::mobility_status_t> status_;
  double wheels_done_m_ = 0;  // wheel distance of the commands before status_'s
  Clock::time_point hazard_safe_at_{};  // the last SAFE hazard status heard
  Clock::time_point last_advance_{};
  std::int64_t now_utime_ = 0;
  bool virtual_ = false;
  std::vector<std::uint8_t> last_clock_;
  std::map<std::string, std::vector<std::uint8_t>> last_heartbeat_;
  std::int64_t submission_id_ = 0;
  std::deque<std::string> recent_;
  std::vector<fault::Bytes> commands_;  // MOBILITY_COMMAND packets before any injection
  bool injecting_ = false;
  std::vector<std::string> deaths_;
  FaultCounts counts_;
  Clock::time_point start_ = Clock::now();
};

}  // namespace rover::test
