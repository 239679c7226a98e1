// ./rover scenario SCENARIO.yaml --out DIR
//
// Runs one scenario on a fresh bus (the `rover` script puts it in a private network
// namespace): starts the deployment's processes with the scenario's world and start pose,
// records every channel with rover_recorder to DIR/log.lcm (lcm-logger 1.3.1 loses
// messages at the default sim rate; tools/recorder says why), submits the sequence, follows
// it to the end, stops everything, checks that the log lost nothing (tools/logcheck) and
// writes DIR/summary.json from the log.
// The scenario's seeds and overrides are applied to copies of the rover config and world
// in DIR. Exit status 0 when the run ended as the scenario expects, 1 otherwise.
#include "bus/bus.hpp"
#include "bus/channels.hpp"
#include "bus/process.hpp"
#include "bus/signing.hpp"
#include "bus/virtual_time.hpp"
#include "config/file_read.hpp"
#include "config/yaml_config.hpp"
#include "launch/process_set.hpp"
#include "logcheck/log_digest.hpp"
#include "scenario/scenario.hpp"
#include "hazards/hazard_assessor.hpp"
#include "terrain/world.hpp"

#include <sys/resource.h>

#include <rover_msgs/heartbeat_t.hpp>
#include <rover_msgs/pose_t.hpp>
#include <rover_msgs/sequence_control_t.hpp>
#include <rover_msgs/sim_truth_t.hpp>
#include <rover_msgs/rover_clock_t.hpp>
#include <rover_msgs/sequence_status_t.hpp>
#include <rover_msgs/sequence_submit_t.hpp>
#include <rover_msgs/sim_sync_t.hpp>
#include <rover_msgs/step_report_t.hpp>

#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <cstdio>
#include <cerrno>
#include <algorithm>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <iomanip>
#include <optional>
#include <fstream>
#include <iostream>
#include <map>
#include <set>
#include <vector>
#include <sstream>
#include <thread>

namespace fs = std::filesystem;
using rover::config::ConfigError;

namespace {

// In virtual time, the runner gives up when the clock has not moved for this long of wall
// time: a hung member is declared lost after sim.barrier_timeout_s (10 s) and the clock
// runs on without it, so only a hung clock itself stands still this long.
constexpr double kClockStallS = 60;

volatile std::sig_atomic_t g_stop = 0;
void OnSignal(int) { g_stop = 1; }

std::string ReadSequenceFile(const std::string& path) {  // a FIFO or a device is refused
  return rover::config::ReadBoundedRegularFile(path, rover::config::kMaxSequenceFileBytes, "sequence file");
}

std::string Num(double v) {
  std::ostringstream os;
  os.precision(10);
  os << v;
  return os.str();
}

// Two buses on LCM 1.3.1 must differ by port: each run picks its own from its pid, below
// Linux's ephemeral range (32768 up), where another program's socket could hold it, and
// passes over a pair another program holds (the sync reports use port + 1).
std::string PrivateUrl() {
  int port = 20000 + 2 * static_cast<int>(getpid() % 6000);
  for (int tries = 0; tries < 6000; ++tries) {
    if (rover::bus::UdpPortReceivable(port) && rover::bus::UdpPortReceivable(port + 1)) break;
    port = port + 2 >= 32000 ? 20000 : port + 2;
  }
  return "udpm://239.255.76.67:" + std::to_string(port) + "?ttl=0&recv_buf_size=8388608";
}


// Points every `--config FILE` naming `from` at `to` (the scenario's overridden copy).
void ReplaceConfig(std::vector<std::string>& args, const std::string& from, const std::string& to) {
  if (from == to) return;
  for (std::size_t i = 0; i + 1 < args.size(); ++i) {
    std::error_code ec;
    if (args[i] == "--config" && fs::equivalent(args[i + 1], from, ec)) args[i + 1] = to;
  }
}

// Sets `flag value` in an argument list, replacing the deployment's own value.
void SetOption(std::vector<std::string>& args, const std::string& flag, const std::string& value) {
  for (std::size_t i = 0; i + 1 < args.size(); ++i) {
    if (args[i] == flag) {
      args[i + 1] = value;
      return;
    }
  }
  args.push_back(flag);
  args.push_back(value);
}

// Writes a whole file, or returns false (errno says why): a full disk must not pass for
// a written summary.
bool WriteWhole(const std::string& path, const std::string& text) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) return false;
  const bool written = std::fwrite(text.data(), 1, text.size(), f) == text.size() && std::fflush(f) == 0;
  const int saved = errno;
  const bool closed = std::fclose(f) == 0;
  if (!written) errno = saved;
  return written && closed;
}

bool HasOption(const std::vector<std::string>& args, const std::string& flag) {
  return std::find(args.begin(), args.end(), flag) != args.end();
}

// The key the deployment's executor holds (its --key, else its config's auth.key_file,
// else $ROVER_KEY_FILE, bus/signing.hpp): the runner signs its submit with it, as an
// operator's rover_seq --key does. None when the executor holds none.
std::optional<rover::auth::Key> ExecutorKey(const rover::launch::Deployment& deployment) {
  for (const auto& p : deployment.processes) {
    if (p.name != "sequence_executor") continue;
    std::optional<std::string> key_flag, config_path;
    for (std::size_t i = 0; i + 1 < p.args.size(); ++i) {
      if (p.args[i] == "--key") key_flag = p.args[i + 1];
      if (p.args[i] == "--config") config_path = p.args[i + 1];
    }
    const auto config = config_path ? rover::config::ConfigNode::LoadFile(*config_path)
                                    : rover::config::ConfigNode::FromString("{}", deployment.source);
    return rover::bus::LoadAuthSettings(config, key_flag, "scenario_runner").key;
  }
  return std::nullopt;
}

// The run's pictures (tools/plot: traverse, error, slip, vo_steps) in DIR. A failure is
// one line and leaves the scenario's exit status alone.
void RunPlot(const std::string& out_dir) {
  std::cout << std::flush;
  const std::string bin = rover::launch::BinDir() + "/rover_plot";
  const pid_t pid = fork();
  if (pid == 0) {
    execl(bin.c_str(), bin.c_str(), out_dir.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  int status = 0;
  if (pid < 0 || waitpid(pid, &status, 0) < 0 || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    std::cout << "  plot: failed (" << bin << " " << out_dir << "; exit "
              << (pid > 0 && WIFEXITED(status) ? std::to_string(WEXITSTATUS(status)) : "abnormal")
              << "); the scenario's result stands\n";
  }
}

// Virtual time: the set's sync reports, heard on the sync bus as rover_sim hears them, so
// that an injected kill lands when its process has finished an instant and waits for the
// next (the runner holds the clock meanwhile): the same instant in every run.
class SyncWatch {
 public:
  explicit SyncWatch(const std::string& url) : lcm_(rover::bus::SyncUrl(url)) {
    rover::bus::RequireBus(lcm_, rover::bus::SyncUrl(url), "sync bus");
    lcm_.subscribe(rover::bus::kSimSyncChannel, &SyncWatch::OnMessage, this)->setQueueCapacity(10000);
  }
  // Waits up to `limit_s` of wall time for `process` to report `utime` finished, with no
  // work still owed; whether it did.
  bool WaitFinished(const std::string& process, std::int64_t utime, double limit_s) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(limit_s);
    while (!Finished(process, utime) && std::chrono::steady_clock::now() < until) lcm_.handleTimeout(20);
    return Finished(process, utime);
  }

 private:
  bool Finished(const std::string& process, std::int64_t utime) const {
    const auto it = last_.find(process);
    return it != last_.end() && it->second.first >= utime && !it->second.second;
  }
  void OnMessage(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    rover_msgs::sim_sync_t m;
    try {
      if (m.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) < 0) return;
    } catch (const std::exception&) {
      return;
    }
    last_[m.process] = {m.utime, m.busy != 0};
  }
  lcm::LCM lcm_;
  std::map<std::string, std::pair<std::int64_t, bool>> last_;  // process -> (utime, busy)
};

struct RunnerArgs {
  std::string scenario_path, out_dir, url, rate_arg;
  bool quiet = false, plot = true;
};

// The command line; nothing after --help (printed).
std::optional<RunnerArgs> ParseArgs(int argc, char** argv) {
  RunnerArgs a;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      std::cout << "usage: scenario_runner SCENARIO.yaml --out DIR [--lcm-url URL] [--rate R|max] [--quiet] [--no-plot]\n\n"
                   "Runs a scenario (configs/scenarios/) on a fresh bus, records DIR/log.lcm\n"
                   "with rover_recorder, checks that the log lost nothing and writes\n"
                   "DIR/summary.json. Exit status 1 when the run did not end as the\n"
                   "scenario's `expect:` says. Then draws the run's pictures in DIR with\n"
                   "rover_plot (traverse.png, error.png, slip.png, vo_steps/) unless --no-plot.\n"
                   "--rate overrides the scenario's sim_rate (max: as fast as the barrier allows).\n"
                   "It prints the log's digest: the same scenario and seeds give the same digest\n"
                   "on any load and at any rate (README, \"Simulated time\").\n";
      return std::nullopt;
    } else if (arg == "--out" && i + 1 < argc) {
      a.out_dir = argv[++i];
    } else if (arg == "--lcm-url" && i + 1 < argc) {
      a.url = argv[++i];
    } else if (arg == "--quiet") {
      a.quiet = true;
    } else if (arg == "--no-plot") {
      a.plot = false;
    } else if (arg == "--rate" && i + 1 < argc) {
      a.rate_arg = argv[++i];  // rover_sim checks it (a number, or max)
    } else if (a.scenario_path.empty() && arg.rfind("--", 0) != 0) {
      a.scenario_path = arg;
    } else {
      throw ConfigError("scenario_runner: argument " + arg + ": unexpected (expected SCENARIO.yaml --out DIR)");
    }
  }
  if (a.scenario_path.empty()) throw ConfigError("scenario_runner: missing SCENARIO.yaml");
  if (a.out_dir.empty()) throw ConfigError("scenario_runner: missing --out DIR");
  if (a.url.empty()) a.url = PrivateUrl();
  return a;
}

// What a run is made of: the scenario, its deployment, and the copies of the rover config
// and world in DIR that carry the scenario's seeds and overrides (the processes read those).
struct RunPlan {
  explicit RunPlan(const RunnerArgs& args)
      : spec(rover::tools::LoadScenario(args.scenario_path)),
        deployment(rover::launch::LoadDeployment(spec.deployment)),
        sequence_text(ReadSequenceFile(spec.sequence)),
        then_texts(ReadSequenceFiles(spec.then_sequences)),
        configs(PrepareConfigs(spec, args.out_dir)),
        rover_config(rover::config::ConfigNode::LoadFile(configs.rover_config)),
        footprint(rover::hazards::LoadHazardOptions(rover_config["hazards"], {"publish_hz"}).footprint),
        world(rover::terrain::WorldOptions::LoadFile(configs.world)),
        log_path(args.out_dir + "/log.lcm"),
        state_path(args.out_dir + "/executor_state.yaml") {
    // The estimator starts at the height of the ground under the start point, from the
    // same world the simulator builds; a rock there is not the ground (the rover stands on
    // its wheels). The rover origin sits mobility.geometry.origin_height_m above the
    // contacts.
    double origin_height_m = 0.0;
    rover_config["mobility"]["geometry"].Get("origin_height_m", origin_height_m);
    start_z = world.StartHeight(spec.start_x, spec.start_y, origin_height_m);
  }

  static std::vector<std::string> ReadSequenceFiles(const std::vector<std::string>& paths) {
    std::vector<std::string> texts;
    for (const auto& f : paths) texts.push_back(ReadSequenceFile(f));
    return texts;
  }

  static rover::tools::RunConfigs PrepareConfigs(const rover::tools::ScenarioSpec& spec, const std::string& out_dir) {
    fs::create_directories(out_dir);
    return rover::tools::PrepareRunConfigs(spec.rover_config, spec.overrides, spec.world, spec.world_overrides,
                                           out_dir);
  }

  bool virtual_time() const { return deployment.time == "virtual"; }

  const rover::tools::ScenarioSpec spec;
  const rover::launch::Deployment deployment;
  const std::string sequence_text;
  const std::vector<std::string> then_texts;
  const rover::tools::RunConfigs configs;
  const rover::config::ConfigNode rover_config;
  const rover::hazards::Footprint footprint;
  const rover::terrain::World world;
  double start_z = 0.0;
  const std::string log_path;
  // The executor keeps its running sequence here (a restart reports it interrupted); a
  // new run starts with none.
  const std::string state_path;
};

// The deployment's processes, each pointed at the run's copies, its start pose and rate;
// their command lines go to DIR/commands.txt.
void StartProcesses(const RunPlan& plan, const RunnerArgs& args, const std::vector<std::string>& env,
                    rover::launch::ProcessSet& set) {
  std::string others;  // the simulator holds its clock until these are up
  for (const auto& p : plan.deployment.processes)
    if (p.name != "rover_sim") others += (others.empty() ? "" : ",") + p.name;
  const auto& spec = plan.spec;
  std::ofstream commands(args.out_dir + "/commands.txt");
  for (auto p : plan.deployment.processes) {
    ReplaceConfig(p.args, spec.rover_config, plan.configs.rover_config);
    if (p.name == "rover_sim") {
      SetOption(p.args, "--world", plan.configs.world);
      SetOption(p.args, "--start", Num(spec.start_x) + "," + Num(spec.start_y) + "," + Num(spec.start_yaw_deg));
      SetOption(p.args, "--rate", args.rate_arg.empty() ? Num(spec.sim_rate) : args.rate_arg);
      SetOption(p.args, "--hold-for", plan.virtual_time() ? others + ",rover_recorder,scenario_runner" : others);
    } else if (p.name == "camera_capture") {
      SetOption(p.args, "--world", plan.configs.world);
    } else if (p.name == "sequence_executor") {
      SetOption(p.args, "--state-file", plan.state_path);
    } else if (p.name == "state_estimator") {
      if (HasOption(p.args, "--world")) SetOption(p.args, "--world", plan.configs.world);
      SetOption(p.args, "--start", Num(spec.start_x) + "," + Num(spec.start_y) + "," + Num(plan.start_z) + "," +
                                       Num(spec.start_yaw_deg));
    }
    set.Start(p, env);
    commands << p.name;
    for (const auto& a : p.args) commands << " " << a;
    commands << "\n";
  }
}

// One run on the bus: the recorder and the set started, the sequence submitted and
// followed to its end (with the scenario's injected kill), everything stopped.
class Run {
 public:
  Run(const RunPlan& plan, const RunnerArgs& args)
      : plan_(plan), args_(args), spec_(plan.spec), virtual_time_(plan.virtual_time()),
        wall_start_(std::chrono::steady_clock::now()), bus_(args.url), sync_(args.url),
        env_{"ROVER_LCM_URL=" + args.url, "ROVER_TIME=" + plan.deployment.time},
        recorder_(rover::launch::BinDir(), args.out_dir, false), set_(rover::launch::BinDir(), args.out_dir, false) {
    bus_.set_publisher("scenario_runner");
    if (const auto key = ExecutorKey(plan.deployment)) bus_.set_auth(rover::bus::MakeBusAuth(*key, "scenario_runner"));
    // What it does not follow (IMU, maps, images) is dropped by the kernel, as in every
    // process of the set (bus/kernel_filter.hpp).
    bus_.FilterInKernel(true);
    // In virtual time, read on this thread, not through LCM's receive thread (bus/udpm_receiver.hpp).
    if (virtual_time_ && rover::bus::UdpmPort(args.url) > 0) bus_.ReadOwnSocket();
    Subscribe();
  }

  // Runs it; whether rover_recorder wrote the whole log.
  bool Execute() {
    StartRecorder();
    StartProcesses(plan_, args_, env_, set_);
    std::cout << "scenario " << spec_.name << ": " << plan_.deployment.processes.size() << " processes on "
              << args_.url << "; output in " << args_.out_dir << "/\n"
              << std::flush;
    WaitUntilReady();
    if (died_at_start_) {
      // The set is incomplete and, in virtual time, its clock can never start: nothing to
      // wait for (a misspelt config key ends a run here, with its process's error).
      Note("the sequence was not submitted: a process of the set exited at start");
      return StopEverything();
    }
    Submit();
    Follow();
    NoteWhyUnfinished();
    return StopEverything();
  }

  double wall() const { return std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start_).count(); }
  const std::vector<std::string>& process_events() const { return process_events_; }
  const std::optional<rover_msgs::sequence_status_t>& final_status() const { return final_status_; }
  const std::vector<rover::tools::ScenarioSummary::RestCheck>& rest_checks() const { return rest_checks_; }
  // Each process's CPU seconds once stopped: the set, the recorder, and this runner so far
  // (it decodes what it follows: its share is part of a run's cost).
  std::vector<std::pair<std::string, double>> cpu_s() const {
    auto cpu = set_.CpuSeconds();
    for (const auto& c : recorder_.CpuSeconds()) cpu.push_back(c);
    rusage self{};
    getrusage(RUSAGE_SELF, &self);
    cpu.emplace_back("scenario_runner", rover::launch::CpuSeconds(self));
    return cpu;
  }

 private:
  void Note(const std::string& e) {
    process_events_.push_back(e);
    std::cout << e << "\n" << std::flush;
  }

  void Subscribe() {
    bus_.Subscribe<rover_msgs::heartbeat_t>(rover::channels::kHeartbeat,
                                            [this](const rover_msgs::heartbeat_t& hb) { alive_.insert(hb.process); });
    bus_.Subscribe<rover_msgs::step_report_t>(rover::channels::kStepReport,
                                              [this](const rover_msgs::step_report_t&) { ++steps_seen_; });
    bus_.Subscribe<rover_msgs::sequence_status_t>(
        rover::channels::kSequenceStatus, [this](const rover_msgs::sequence_status_t& st) { OnStatus(st); });
    // The estimate and the truth, for the checks after a pause or an idle (RestCheck): only
    // in a scenario that has either, as each is a message an instant to take (the summary's
    // other figures come from the log).
    if (spec_.pause_after_steps > 0 || spec_.then_idle_s > 0) {
      bus_.Subscribe<rover_msgs::pose_t>(rover::channels::kPose, [this](const rover_msgs::pose_t& p) { pose_ = p; }, 100);
      bus_.Subscribe<rover_msgs::sim_truth_t>(rover::channels::kSimTruth,
                                              [this](const rover_msgs::sim_truth_t& t) { truth_ = t; }, 100);
    }
    // Virtual time (README, "Simulated time"): the runner and the recorder are members of
    // the set too, so that the sequence goes in at the first instant and the log holds
    // every message of every instant, whatever the machine's load.
    if (virtual_time_) {
      bus_.clock().set_virtual(true);
      // As every member: what comes in an instant is handed over when the clock's cut says
      // all of it has come (simtime/barrier.hpp, "One round an instant").
      bus_.set_deferred(true, {rover::channels::kClock});
    }
    bus_.Subscribe<rover_msgs::rover_clock_t>(rover::channels::kClock, [this](const rover_msgs::rover_clock_t& c) {
      if (rover::bus::StampOf(c)->first != rover::bus::PublisherId("rover_sim") || c.utime <= clock_seen_) return;
      clock_seen_ = c.utime;
      clock_seen_wall_ = wall();
      if (virtual_time_) bus_.ClockMoved(c.utime, rover::bus::CutOf(c));
    }, 10000);
  }

  void OnStatus(const rover_msgs::sequence_status_t& st) {
    if (st.submission_id != submission_id_) return;
    OnPausedStatus(st);
    if (!args_.quiet && st.detail != last_line_) {
      std::cout << "[t=" << std::fixed << std::setprecision(1) << st.elapsed_s << " s] " << st.detail << "\n"
                << std::flush;
      last_line_ = st.detail;
    }
    if (st.state != rover_msgs::sequence_status_t::STATE_COMPLETED &&
        st.state != rover_msgs::sequence_status_t::STATE_ABORTED &&
        st.state != rover_msgs::sequence_status_t::STATE_REJECTED) {
      return;
    }
    if (!final_status_) final_status_ = st;
    // The next sequence on the same running stack, when this one completed (after the
    // scenario's idle, the rover parked: ActWhenDue).
    if (st.state == rover_msgs::sequence_status_t::STATE_COMPLETED &&
        submission_id_ <= static_cast<std::int64_t>(spec_.then_sequences.size())) {
      final_status_.reset();
      if (spec_.then_idle_s > 0) {
        // Parked from the first completed status (the executor repeats it while idle).
        if (parked_after_ != submission_id_) parked_at_ = std::max<std::int64_t>(clock_seen_, 0);
        parked_after_ = submission_id_;
      } else {
        SubmitNext();
      }
    }
  }

  void OnPausedStatus(const rover_msgs::sequence_status_t& st) {
    if (st.submission_id == 1 && st.state == rover_msgs::sequence_status_t::STATE_PAUSED && pause_sent_ && !paused_at_) {
      paused_at_ = std::max<std::int64_t>(clock_seen_, 0);
    }
  }

  void SubmitNext() {
    rover_msgs::sequence_submit_t next{};
    next.submission_id = ++submission_id_;
    next.name = spec_.then_sequences[static_cast<std::size_t>(submission_id_ - 2)];
    next.text = plan_.then_texts[static_cast<std::size_t>(submission_id_ - 2)];
    bus_.Publish(rover::channels::kSequenceSubmit, next);
    acted_at_ = instant_;
  }

  void Control(std::int8_t action, const std::string& reason) {
    rover_msgs::sequence_control_t c{};
    c.utime = std::max<std::int64_t>(instant_, 0);
    c.action = action;
    c.reason = reason;
    bus_.Publish(rover::channels::kSequenceControl, c);
    acted_at_ = instant_;
  }

  // The operator's day (ScenarioSpec: pause, then_idle_s), at the instant each is due.
  void ActWhenDue() {
    const std::int64_t now = std::max<std::int64_t>(virtual_time_ ? instant_ : clock_seen_, 0);
    if (spec_.pause_after_steps > 0 && !pause_sent_ && submission_id_ == 1 && steps_seen_ >= spec_.pause_after_steps) {
      Note("operator: pause after " + std::to_string(steps_seen_) + " steps, for " + Num(spec_.pause_for_s) +
           " s of rover time");
      Control(rover_msgs::sequence_control_t::ACTION_PAUSE, "scenario: a pause");
      pause_sent_ = true;
    }
    if (paused_at_ && !resume_sent_ && now >= *paused_at_ + static_cast<std::int64_t>(spec_.pause_for_s * 1e6)) {
      CheckAfterRest("pause", (now - *paused_at_) * 1e-6);
      Control(rover_msgs::sequence_control_t::ACTION_RESUME, "scenario: the pause is over");
      resume_sent_ = true;
    }
    if (parked_at_ && now >= *parked_at_ + static_cast<std::int64_t>(spec_.then_idle_s * 1e6)) {
      CheckAfterRest("idle", (now - *parked_at_) * 1e-6);
      parked_at_.reset();
      SubmitNext();
    }
  }

  // The rover time of this runner's next action (Process::set_quiet_until): nothing of its
  // own to do before it, so the clock may stride while everything else is quiet too.
  std::int64_t QuietUntil() const {
    if (acted_at_ >= instant_) return 0;  // what it sent this instant is on its way: the next one is a tick
    if (final_status_) return 0;  // the last instants of a run are ticks, as they always were
    std::int64_t until = rover::bus::Process::kQuietForGood;
    if (paused_at_ && !resume_sent_) until = std::min(until, *paused_at_ + static_cast<std::int64_t>(spec_.pause_for_s * 1e6));
    if (parked_at_) until = std::min(until, *parked_at_ + static_cast<std::int64_t>(spec_.then_idle_s * 1e6));
    if (spec_.pause_after_steps > 0 && !pause_sent_) until = 0;  // counting steps
    return until;
  }

  // The estimate against truth after a pause or an idle: horizontal position and heading
  // errors, and their NEES against the pose's own covariance.
  void CheckAfterRest(const std::string& after, double rested_s) {
    if (!pose_ || !truth_) {
      Note("after the " + after + ": no pose or truth heard to check against");
      return;
    }
    rover::tools::ScenarioSummary::RestCheck c;
    c.after = after;
    c.rested_s = rested_s;
    const double ex = pose_->position[0] - truth_->position[0], ey = pose_->position[1] - truth_->position[1];
    c.position_error_m = std::hypot(ex, ey);
    const auto yaw_of = [](const double q[4]) {
      return std::atan2(2.0 * (q[0] * q[3] + q[1] * q[2]), 1.0 - 2.0 * (q[2] * q[2] + q[3] * q[3]));
    };
    double dyaw = yaw_of(pose_->orientation) - yaw_of(truth_->orientation);
    dyaw = std::atan2(std::sin(dyaw), std::cos(dyaw));
    c.heading_error_deg = dyaw * 180.0 / M_PI;
    const double var_yaw = pose_->covariance[5][5];
    c.heading_sigma_deg = std::sqrt(std::max(0.0, var_yaw)) * 180.0 / M_PI;
    c.heading_nees = var_yaw > 0 ? dyaw * dyaw / var_yaw : 0.0;
    const double a = pose_->covariance[0][0], b = pose_->covariance[0][1], d = pose_->covariance[1][1];
    const double det = a * d - b * b;
    c.horizontal_nees = det > 0 ? (d * ex * ex - 2 * b * ex * ey + a * ey * ey) / det : 0.0;
    rest_checks_.push_back(c);
    std::ostringstream os;
    os << std::fixed << std::setprecision(4) << "after " << std::setprecision(1) << rested_s << " s "
       << (after == "pause" ? "paused" : "parked") << ": estimate - truth " << std::setprecision(4)
       << c.position_error_m << " m, heading " << c.heading_error_deg << " deg";
    Note(os.str());
  }

  void SendSync() {
    auto report = bus_.SyncState("scenario_runner", instant_, false);
    report.quiet_until = QuietUntil();
    sync_.Send(report);
  }

  // The recorder first, and heard on the bus before any process starts, so that the log
  // holds every publisher from its first message (the completeness check expects each
  // count to start at 0). It stops last, after the processes, and flushes.
  void StartRecorder() {
    fs::remove(plan_.log_path);
    fs::remove(plan_.state_path);
    recorder_.Start({"rover_recorder", "rover_recorder", {"--lcm-url", args_.url, plan_.log_path}}, env_);
    while (!virtual_time_ && !alive_.count("rover_recorder") && !g_stop && wall() < 10) {
      bus_.Handle(50);
      for (const auto& [name, how] : recorder_.Poll(0)) {
        throw std::runtime_error("rover_recorder " + how + " at start (see " + args_.out_dir + "/rover_recorder.log)");
      }
    }
    if (!virtual_time_ && !alive_.count("rover_recorder")) {
      throw std::runtime_error("rover_recorder sent no heartbeat within 10 s");
    }
  }

  // Until every process has said it is alive (in virtual time: until the clock starts,
  // which it does when every member, this runner included, has reported).
  void WaitUntilReady() {
    bool ready = false;
    auto last_hello = wall() - 1;
    while (virtual_time_ && clock_seen_ < 0 && !g_stop && wall() < 30) {
      if (wall() - last_hello > 0.2) {
        SendSync();
        last_hello = wall();
      }
      bus_.Handle(20);
      NoteDeathsAtStart();
      if (died_at_start_) return;
    }
    if (virtual_time_ && clock_seen_ < 0) Note("the clock did not start within 30 s (see rover_sim.log)");
    if (virtual_time_) ready = true;
    while (!virtual_time_ && !ready && !g_stop && wall() < 30) {
      bus_.Handle(50);
      NoteDeathsAtStart();
      if (died_at_start_) return;
      ready = true;
      for (const auto& p : plan_.deployment.processes) ready = ready && alive_.count(p.name) > 0;
    }
    if (!ready) Note("not every process sent a heartbeat within 30 s");
  }

  // A process that exited before the set was ready, with the last line of its log (its
  // one-line error: a bad config key, a bad argument).
  void NoteDeathsAtStart() {
    for (const auto& [name, how] : set_.Poll(0)) {
      const std::string log = args_.out_dir + "/" + name + ".log";
      std::string line, last;
      for (std::ifstream in(log); std::getline(in, line);)
        if (!line.empty()) last = line;
      Note(name + " " + how + " at start" + (last.empty() ? "" : ": " + last) + " (see " + log + ")");
      died_at_start_ = true;
    }
  }

  void Submit() {
    rover_msgs::sequence_submit_t submit{};
    submit.submission_id = 1;
    submit.name = spec_.sequence_name;
    submit.text = plan_.sequence_text;
    bus_.Publish(rover::channels::kSequenceSubmit, submit);
    acted_at_ = instant_;
    // The run's limit. On a real clock it is timeout_s of wall time. In virtual time it is
    // rover time, timeout_s x the scenario's sim_rate from the submission (what timeout_s
    // means at the rate the scenario was written for), so that load cannot change where a
    // run is cut; the one wall-time rule is a liveness limit on the clock itself.
    submitted_at_ = std::max<std::int64_t>(clock_seen_, 0);
    rover_limit_us_ = static_cast<std::int64_t>(spec_.timeout_s * spec_.sim_rate * 1e6);
    clock_moved_ = clock_seen_;
    clock_moved_wall_ = wall();
  }

  bool WithinLimit() {
    if (!virtual_time_) return wall() < spec_.timeout_s;
    if (clock_seen_ != clock_moved_) {
      clock_moved_ = clock_seen_;
      clock_moved_wall_ = wall();
    }
    return clock_seen_ - submitted_at_ < rover_limit_us_ && wall() - clock_moved_wall_ < kClockStallS;
  }

  // Follows the sequence to its final status, or the run's limit.
  void Follow() {
    auto last_sync = wall();
    double children_polled = 0;
    bool report_due = false;
    std::optional<double> done_at;
    if (virtual_time_ && !spec_.kill_process.empty()) sync_watch_.emplace(args_.url);
    while (!g_stop && WithinLimit()) {
      if (virtual_time_) {
        if (!TakeInstant(&report_due)) break;
      } else {
        bus_.Handle(20);
      }
      // The children's output and exits: on a real clock every pass; in virtual time once an
      // instant (not after each of its messages: a poll of every pipe a message), or every
      // 50 ms of wall time while the clock waits.
      if (!virtual_time_ || report_due || wall() - children_polled > 0.05) {
        children_polled = wall();
        for (const auto& [name, how] : set_.Poll(0)) {
          if (killed_ && name == spec_.kill_process) continue;
          Note(name + " " + how + " unexpectedly");
        }
      }
      InjectKillWhenDue();
      if (!virtual_time_ || report_due) ActWhenDue();
      // The instant is reported finished only now, after an injected kill: the clock cannot
      // move on before it, so the process dies at the same instant in every run.
      if (virtual_time_ && (report_due || wall() - last_sync > 0.25)) {
        SendSync();
        last_sync = wall();
        report_due = false;
      }
      if (final_status_ && !done_at) done_at = wall();
      // Let the last messages (stop, final pose, truth) reach the log.
      if (!virtual_time_ && done_at && wall() - *done_at > 1.0) break;
    }
  }

  // Virtual time, one instant at a time: what came in it is counted, then the runner
  // reports it finished. It ends 2 s of rover time after the final status (the last
  // messages: stop, final pose, truth) by not finishing that instant: the clock stops
  // there. False: that instant has come.
  bool TakeInstant(bool* report_due) {
    // One message a pass, with no probe for more (a system call a message): the next
    // pass's wait returns at once when more has come.
    bus_.Handle(20);
    if (final_utime_ && clock_seen_ >= *final_utime_ + 2000000) return false;
    // The new instant's batch once all of it has come (a message lost on the way is given
    // up a wall second after its clock, as in every process).
    std::string missing;
    bool sealed = false;
    if (bus_.seal_pending() && bus_.SealWhenReady(wall() - clock_seen_wall_ > 1.0, &missing)) {
      if (!missing.empty()) std::cerr << "scenario_runner: a batch went without " << missing << "\n";
      bus_.DispatchBatch();
      instant_ = clock_seen_;
      sealed = true;
    }
    if (final_status_ && !final_utime_) final_utime_ = final_status_->utime;  // the executor's instant
    *report_due = *report_due || sealed;
    return true;
  }

  // The scenario's fault: its process killed once enough steps were reported, at an
  // instant it has finished.
  void InjectKillWhenDue() {
    if (spec_.kill_process.empty() || killed_ || steps_seen_ < spec_.kill_after_steps || steps_seen_ <= 0) return;
    Note("injected fault: killing " + spec_.kill_process + " after " + std::to_string(steps_seen_) + " steps");
    if (sync_watch_ && !sync_watch_->WaitFinished(spec_.kill_process, instant_, 5.0)) {
      Note(spec_.kill_process + " had not finished rover time " + std::to_string(instant_) +
           " within 5 s of wall time: killed anyway");
    }
    set_.Signal(spec_.kill_process, SIGKILL);
    killed_ = true;
  }

  void NoteWhyUnfinished() {
    if (final_status_) return;
    if (!virtual_time_) {
      Note("no final status within " + Num(spec_.timeout_s) + " s");
    } else if (wall() - clock_moved_wall_ >= kClockStallS) {
      Note("the clock stood still for " + Num(kClockStallS) +
           " s of wall time with no final status (a hung rover_sim? see rover_sim.log)");
    } else {
      Note("no final status within " + Num(rover_limit_us_ / 1e6) + " s of rover time (timeout_s " +
           Num(spec_.timeout_s) + " at sim_rate " + Num(spec_.sim_rate) + ")");
    }
  }

  // The clock first, so that nothing moves while the others stop (in virtual time it waits
  // for this runner, which has stopped reporting: the log ends at one instant); the
  // recorder last. Whether it wrote the whole log.
  bool StopEverything() {
    set_.Signal("rover_sim", SIGTERM);
    for (const double until = wall() + 5; set_.Running("rover_sim") && wall() < until;) set_.Poll(20);
    set_.StopAll();
    recorder_.Signal("rover_recorder", SIGTERM);  // it writes what it holds, then exits
    bool log_whole = true;
    for (const double until = wall() + 10; recorder_.Running("rover_recorder") && wall() < until;) {
      for (const auto& [name, how] : recorder_.Poll(50)) {
        if (how != "exited with code 0") {
          Note(name + " " + how + " (see " + args_.out_dir + "/rover_recorder.log)");
          log_whole = false;  // exit 1: a write failed (a full disk); a crash: the same for us
        }
      }
    }
    recorder_.StopAll();
    return log_whole;
  }

  const RunPlan& plan_;
  const RunnerArgs& args_;
  const rover::tools::ScenarioSpec& spec_;
  const bool virtual_time_;
  const std::chrono::steady_clock::time_point wall_start_;
  rover::bus::Bus bus_;
  rover::bus::SyncSender sync_;
  const std::vector<std::string> env_;
  rover::launch::ProcessSet recorder_, set_;
  std::vector<std::string> process_events_;
  std::set<std::string> alive_;
  std::optional<rover_msgs::sequence_status_t> final_status_;
  std::int64_t submission_id_ = 1;
  int steps_seen_ = 0;
  std::string last_line_;
  std::int64_t instant_ = -1;  // the rover time the runner has finished (-1: before the clock)
  std::int64_t clock_seen_ = -1;
  double clock_seen_wall_ = 0;
  std::int64_t submitted_at_ = 0, rover_limit_us_ = 0, clock_moved_ = -1;
  double clock_moved_wall_ = 0;
  std::optional<std::int64_t> final_utime_;
  // The operator's day: the pause sent, when the sequence said paused, the resume sent;
  // when the rover parked before the next sequence; whether this instant sent a command.
  bool pause_sent_ = false, resume_sent_ = false;
  std::int64_t acted_at_ = -2;  // the instant it last sent a command or a sequence in
  std::optional<std::int64_t> paused_at_, parked_at_;
  std::int64_t parked_after_ = 0;  // the submission whose completion parked the rover
  std::optional<rover_msgs::pose_t> pose_;
  std::optional<rover_msgs::sim_truth_t> truth_;
  std::vector<rover::tools::ScenarioSummary::RestCheck> rest_checks_;
  bool died_at_start_ = false;
  bool killed_ = false;
  std::optional<SyncWatch> sync_watch_;
};

// The run's figures from its log, against truth.
rover::tools::ScenarioSummary Summarize(const RunPlan& plan, const Run& run) {
  auto summary = rover::tools::SummarizeLog(plan.log_path, plan.footprint);
  summary.log_digest = rover::logcheck::DigestLog(plan.log_path).sha256_hex;
  summary.rover_time = rover::tools::BreakdownFromLog(plan.log_path);
  // Truth clearance to the discs of the rocks over the collision height (the simulator faults
  // where one rises over the belly's clearance under the footprint; under 0 may be a graze).
  double max_height_m = 0.3;
  plan.rover_config["mobility"]["rock_collision"].Get("max_height_m", max_height_m);
  std::vector<rover::tools::RockDisc> rocks;
  for (const auto& r : plan.world.rocks()) {
    if (r.height_m > max_height_m) rocks.push_back({r.name, r.position.x(), r.position.y(), 0.5 * r.diameter_m});
  }
  rover::tools::AddRockClearance(rocks, plan.footprint, &summary);
  summary.scenario = plan.spec.name;
  summary.wall_time_s = run.wall();
  summary.process_events = run.process_events();
  summary.cpu_s = run.cpu_s();
  summary.rest_checks = run.rest_checks();
  return summary;
}

// The figures come from the log: a log that could not be written whole says less than
// the drive did. The executor's own last word, heard live, says how the drive ended.
void PrintLogNotWhole(const RunPlan& plan, const RunnerArgs& args,
                      const std::optional<rover_msgs::sequence_status_t>& final_status) {
  std::cout << "  THE LOG IS NOT WHOLE: rover_recorder could not write " << plan.log_path << " (see " << args.out_dir
            << "/rover_recorder.log; a full disk?): the figures above are of "
            << "what it holds";
  if (final_status) {
    std::cout << "; on the bus the executor reported the sequence "
              << (final_status->state == rover_msgs::sequence_status_t::STATE_COMPLETED ? "completed"
                  : final_status->state == rover_msgs::sequence_status_t::STATE_ABORTED
                      ? "aborted (" + final_status->abort_reason + ")"
                      : "rejected")
              << " at command " << final_status->command_index + 1 << " of " << final_status->num_commands;
  }
  std::cout << "\n";
}

// Writes summary.json and prints the summary; the exit status: 1 when the run did not
// end, ended other than the scenario expects, or its record could not be written.
int Report(const RunPlan& plan, const RunnerArgs& args, const Run& run, bool log_whole) {
  const auto summary = Summarize(plan, run);
  const std::string summary_path = args.out_dir + "/summary.json";
  const bool summary_written = WriteWhole(summary_path, rover::tools::SummaryJson(summary));
  const std::string summary_error = summary_written ? "" : std::strerror(errno);
  std::cout << "\n" << rover::tools::SummaryText(summary);
  if (!log_whole) PrintLogNotWhole(plan, args, run.final_status());
  std::string missed;
  const auto& spec = plan.spec;
  const bool as_expected = rover::tools::AsExpected(spec, summary, &missed);
  if (!spec.expect_outcome.empty()) {
    std::cout << "  expected: " << spec.expect_outcome
              << (spec.expect_abort_reason.empty() ? "" : " (" + spec.expect_abort_reason + ")")
              << (as_expected ? " - as expected\n" : " - NOT as expected: " + missed + "\n");
  }
  if (summary_written && log_whole) {
    std::cout << "  wrote " << summary_path << " and " << plan.log_path << "\n";
  } else {
    std::cout << "  NOT WRITTEN: " << (summary_written ? "" : summary_path + " (" + summary_error + ")")
              << (summary_written || log_whole ? "" : " and ") << (log_whole ? "" : plan.log_path + " (partial)")
              << "\n";
  }
  if (args.plot && log_whole) RunPlot(args.out_dir);
  return summary.outcome == "incomplete" || !as_expected || !summary_written || !log_whole ? 1 : 0;
}

}  // namespace

int main(int argc, char** argv) {
  return rover::bus::RunMain("scenario_runner", [&]() -> int {
    const auto args = ParseArgs(argc, argv);
    if (!args) return 0;
    const RunPlan plan(*args);
    std::signal(SIGINT, OnSignal);
    std::signal(SIGTERM, OnSignal);
    Run run(plan, *args);
    const bool log_whole = run.Execute();
    return Report(plan, *args, run, log_whole);
  });
}
