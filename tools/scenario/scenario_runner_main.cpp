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

#include <rover_msgs/heartbeat_t.hpp>
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

// Two buses on LCM 1.3.1 must differ by port: each run picks its own from its pid.
std::string PrivateUrl() {
  const int port = 20000 + 2 * static_cast<int>(getpid() % 10000);  // even: the sync reports use port + 1
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
    if (!lcm_.good()) throw std::runtime_error("cannot open the sync bus " + rover::bus::SyncUrl(url));
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

}  // namespace

int main(int argc, char** argv) {
  return rover::bus::RunMain("scenario_runner", [&]() -> int {
    std::string scenario_path, out_dir, url, rate_arg;
    bool quiet = false, plot = true;
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
        return 0;
      } else if (arg == "--out" && i + 1 < argc) {
        out_dir = argv[++i];
      } else if (arg == "--lcm-url" && i + 1 < argc) {
        url = argv[++i];
      } else if (arg == "--quiet") {
        quiet = true;
      } else if (arg == "--no-plot") {
        plot = false;
      } else if (arg == "--rate" && i + 1 < argc) {
        rate_arg = argv[++i];  // rover_sim checks it (a number, or max)
      } else if (scenario_path.empty() && arg.rfind("--", 0) != 0) {
        scenario_path = arg;
      } else {
        throw ConfigError("scenario_runner: argument " + arg +
                          ": unexpected (expected SCENARIO.yaml --out DIR)");
      }
    }
    if (scenario_path.empty()) throw ConfigError("scenario_runner: missing SCENARIO.yaml");
    if (out_dir.empty()) throw ConfigError("scenario_runner: missing --out DIR");
    const auto spec = rover::tools::LoadScenario(scenario_path);
    const auto deployment = rover::launch::LoadDeployment(spec.deployment);
    const std::string sequence_text = ReadSequenceFile(spec.sequence);
    std::vector<std::string> then_texts;
    for (const auto& f : spec.then_sequences) then_texts.push_back(ReadSequenceFile(f));
    fs::create_directories(out_dir);
    // The scenario's seeds and overrides go into copies in DIR; the processes read those.
    const auto configs = rover::tools::PrepareRunConfigs(spec.rover_config, spec.overrides, spec.world,
                                                         spec.world_overrides, out_dir);
    const auto rover_config = rover::config::ConfigNode::LoadFile(configs.rover_config);
    const auto footprint = rover::hazards::LoadHazardOptions(rover_config["hazards"], {"publish_hz"}).footprint;
    // The estimator starts at the height of the ground under the start point, from the same
    // world the simulator builds; a rock there is not the ground (the rover stands on its
    // wheels). The rover origin sits mobility.geometry.origin_height_m above the contacts.
    const rover::terrain::World world(rover::terrain::WorldOptions::LoadFile(configs.world));
    double origin_height_m = 0.0;
    rover_config["mobility"]["geometry"].Get("origin_height_m", origin_height_m);
    const double start_z = world.StartHeight(spec.start_x, spec.start_y, origin_height_m);
    if (url.empty()) url = PrivateUrl();

    fs::create_directories(out_dir);
    const std::string log_path = out_dir + "/log.lcm";
    fs::remove(log_path);
    // The executor keeps its running sequence here (a restart reports it interrupted); a
    // new run starts with none.
    const std::string state_path = out_dir + "/executor_state.yaml";
    fs::remove(state_path);
    std::signal(SIGINT, OnSignal);
    std::signal(SIGTERM, OnSignal);
    const auto wall_start = std::chrono::steady_clock::now();
    auto wall = [&] {
      return std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
    };

    rover::bus::Bus bus(url);
    bus.set_publisher("scenario_runner");
    if (const auto key = ExecutorKey(deployment)) bus.set_auth(rover::bus::MakeBusAuth(*key, "scenario_runner"));
    std::set<std::string> alive;
    std::optional<rover_msgs::sequence_status_t> final_status;
    std::int64_t submission_id = 1;
    int steps_seen = 0;
    std::string last_line;
    bus.Subscribe<rover_msgs::heartbeat_t>(rover::channels::kHeartbeat,
                                           [&](const rover_msgs::heartbeat_t& hb) {
                                             alive.insert(hb.process);
                                           });
    bus.Subscribe<rover_msgs::step_report_t>(rover::channels::kStepReport,
                                             [&](const rover_msgs::step_report_t&) {
                                               ++steps_seen;
                                             });
    bus.Subscribe<rover_msgs::sequence_status_t>(
        rover::channels::kSequenceStatus, [&](const rover_msgs::sequence_status_t& st) {
          if (st.submission_id != submission_id) return;
          if (!quiet && st.detail != last_line) {
            std::cout << "[t=" << std::fixed << std::setprecision(1) << st.elapsed_s << " s] "
                      << st.detail << "\n" << std::flush;
            last_line = st.detail;
          }
          if (st.state == rover_msgs::sequence_status_t::STATE_COMPLETED ||
              st.state == rover_msgs::sequence_status_t::STATE_ABORTED ||
              st.state == rover_msgs::sequence_status_t::STATE_REJECTED) {
            if (!final_status) final_status = st;
            // The next sequence on the same running stack, when this one completed.
            if (st.state == rover_msgs::sequence_status_t::STATE_COMPLETED &&
                submission_id <= static_cast<std::int64_t>(spec.then_sequences.size())) {
              rover_msgs::sequence_submit_t next{};
              next.submission_id = ++submission_id;
              next.name = spec.then_sequences[static_cast<std::size_t>(submission_id - 2)];
              next.text = then_texts[static_cast<std::size_t>(submission_id - 2)];
              bus.Publish(rover::channels::kSequenceSubmit, next);
              final_status.reset();
            }
          }
        });

    // Virtual time (README, "Simulated time"): the runner and the recorder are members of
    // the set too, so that the sequence goes in at the first instant and the log holds
    // every message of every instant, whatever the machine's load.
    const bool virtual_time = deployment.time == "virtual";
    if (virtual_time) {
      bus.clock().set_virtual(true);
      // As every member: what comes in an instant is handed over when the clock's cut says
      // all of it has come (simtime/barrier.hpp, "One round an instant").
      bus.set_deferred(true, {rover::channels::kClock});
    }
    const std::vector<std::string> env = {"ROVER_LCM_URL=" + url, "ROVER_TIME=" + deployment.time};
    rover::bus::SyncSender sync(url);
    std::int64_t instant = -1;  // the rover time the runner has finished (-1: before the clock)
    std::int64_t clock_seen = -1;
    double clock_seen_wall = 0;
    bus.Subscribe<rover_msgs::rover_clock_t>(rover::channels::kClock, [&](const rover_msgs::rover_clock_t& c) {
      if (rover::bus::StampOf(c)->first != rover::bus::PublisherId("rover_sim") || c.utime <= clock_seen) return;
      clock_seen = c.utime;
      clock_seen_wall = wall();
      if (virtual_time) bus.ClockMoved(c.utime, rover::bus::CutOf(c));
    }, 10000);
    auto send_sync = [&] { sync.Send(bus.SyncState("scenario_runner", instant, false)); };
    // The recorder first, and heard on the bus before any process starts, so that the log
    // holds every publisher from its first message (the completeness check expects each
    // count to start at 0). It stops last, after the processes, and flushes.
    rover::launch::ProcessSet recorder(rover::launch::BinDir(), out_dir, false);
    recorder.Start({"rover_recorder", "rover_recorder", {"--lcm-url", url, log_path}}, env);
    while (!virtual_time && !alive.count("rover_recorder") && !g_stop && wall() < 10) {
      bus.Handle(50);
      for (const auto& [name, how] : recorder.Poll(0)) {
        throw std::runtime_error("rover_recorder " + how + " at start (see " + out_dir +
                                 "/rover_recorder.log)");
      }
    }
    if (!virtual_time && !alive.count("rover_recorder")) {
      throw std::runtime_error("rover_recorder sent no heartbeat within 10 s");
    }
    rover::launch::ProcessSet set(rover::launch::BinDir(), out_dir, false);
    std::string others;  // the simulator holds its clock until these are up
    for (const auto& p : deployment.processes)
      if (p.name != "rover_sim") others += (others.empty() ? "" : ",") + p.name;
    std::ofstream commands(out_dir + "/commands.txt");
    for (auto p : deployment.processes) {
      ReplaceConfig(p.args, spec.rover_config, configs.rover_config);
      if (p.name == "rover_sim") {
        SetOption(p.args, "--world", configs.world);
        SetOption(p.args, "--start",
                  Num(spec.start_x) + "," + Num(spec.start_y) + "," + Num(spec.start_yaw_deg));
        SetOption(p.args, "--rate", rate_arg.empty() ? Num(spec.sim_rate) : rate_arg);
        SetOption(p.args, "--hold-for", virtual_time ? others + ",rover_recorder,scenario_runner" : others);
      } else if (p.name == "camera_capture") {
        SetOption(p.args, "--world", configs.world);
      } else if (p.name == "sequence_executor") {
        SetOption(p.args, "--state-file", state_path);
      } else if (p.name == "state_estimator") {
        if (HasOption(p.args, "--world")) SetOption(p.args, "--world", configs.world);
        SetOption(p.args, "--start", Num(spec.start_x) + "," + Num(spec.start_y) + "," +
                                         Num(start_z) + "," + Num(spec.start_yaw_deg));
      }
      set.Start(p, env);
      commands << p.name;
      for (const auto& a : p.args) commands << " " << a;
      commands << "\n";
    }
    commands.close();
    std::cout << "scenario " << spec.name << ": " << deployment.processes.size()
              << " processes on " << url << "; output in " << out_dir << "/\n" << std::flush;

    rover::tools::ScenarioSummary partial;
    auto note = [&](const std::string& e) {
      partial.process_events.push_back(e);
      std::cout << e << "\n" << std::flush;
    };
    // Wait until every process has said it is alive (in virtual time: until the clock
    // starts, which it does when every member, this runner included, has reported).
    bool ready = false;
    auto last_hello = wall() - 1;
    while (virtual_time && clock_seen < 0 && !g_stop && wall() < 30) {
      if (wall() - last_hello > 0.2) {
        send_sync();
        last_hello = wall();
      }
      bus.Handle(20);
      for (const auto& [name, how] : set.Poll(0)) note(name + " " + how + " at start");
    }
    if (virtual_time && clock_seen < 0) note("the clock did not start within 30 s (see rover_sim.log)");
    if (virtual_time) ready = true;
    while (!virtual_time && !ready && !g_stop && wall() < 30) {
      bus.Handle(50);
      for (const auto& [name, how] : set.Poll(0)) note(name + " " + how + " at start");
      ready = true;
      for (const auto& p : deployment.processes) ready = ready && alive.count(p.name) > 0;
    }
    if (!ready) note("not every process sent a heartbeat within 30 s");

    rover_msgs::sequence_submit_t submit{};
    submit.submission_id = 1;
    submit.name = spec.sequence;
    submit.text = sequence_text;
    bus.Publish(rover::channels::kSequenceSubmit, submit);

    bool killed = false;
    std::optional<double> done_at;
    std::optional<std::int64_t> final_utime;
    auto last_sync = wall();
    // The run's limit. On a real clock it is timeout_s of wall time. In virtual time it is
    // rover time, timeout_s x the scenario's sim_rate from the submission (what timeout_s
    // means at the rate the scenario was written for), so that load cannot change where a
    // run is cut; the one wall-time rule is a liveness limit on the clock itself.
    const std::int64_t submitted_at = std::max<std::int64_t>(clock_seen, 0);
    const auto rover_limit_us = static_cast<std::int64_t>(spec.timeout_s * spec.sim_rate * 1e6);
    std::int64_t clock_moved = clock_seen;
    double clock_moved_wall = wall();
    auto within_limit = [&] {
      if (!virtual_time) return wall() < spec.timeout_s;
      if (clock_seen != clock_moved) {
        clock_moved = clock_seen;
        clock_moved_wall = wall();
      }
      return clock_seen - submitted_at < rover_limit_us && wall() - clock_moved_wall < kClockStallS;
    };
    bool report_due = false;
    std::optional<SyncWatch> sync_watch;
    if (virtual_time && !spec.kill_process.empty()) sync_watch.emplace(url);
    while (!g_stop && within_limit()) {
      if (virtual_time) {
        // One instant at a time: what came in it is counted, then the runner reports it
        // finished. It ends 2 s of rover time after the final status (the last messages:
        // stop, final pose, truth) by not finishing that instant: the clock stops there.
        if (bus.Handle(20)) {
          const auto burst_end = wall() + 0.02;
          while (wall() < burst_end && bus.Handle(0)) {
          }
        }
        if (final_utime && clock_seen >= *final_utime + 2000000) break;
        // The new instant's batch once all of it has come (a message lost on the way is
        // given up a wall second after its clock, as in every process).
        std::string missing;
        bool sealed = false;
        if (bus.seal_pending() && bus.SealWhenReady(wall() - clock_seen_wall > 1.0, &missing)) {
          if (!missing.empty()) std::cerr << "scenario_runner: a batch went without " << missing << "\n";
          bus.DispatchBatch();
          instant = clock_seen;
          sealed = true;
        }
        if (final_status && !final_utime) final_utime = final_status->utime;  // the executor's instant
        report_due = report_due || sealed;
      } else {
        bus.Handle(20);
      }
      for (const auto& [name, how] : set.Poll(0)) {
        if (killed && name == spec.kill_process) continue;
        note(name + " " + how + " unexpectedly");
      }
      if (!spec.kill_process.empty() && !killed && steps_seen >= spec.kill_after_steps &&
          steps_seen > 0) {
        note("injected fault: killing " + spec.kill_process + " after " +
             std::to_string(steps_seen) + " steps");
        if (sync_watch && !sync_watch->WaitFinished(spec.kill_process, instant, 5.0)) {
          note(spec.kill_process + " had not finished rover time " + std::to_string(instant) +
               " within 5 s of wall time: killed anyway");
        }
        set.Signal(spec.kill_process, SIGKILL);
        killed = true;
      }
      // The instant is reported finished only now, after an injected kill: the clock cannot
      // move on before it, so the process dies at the same instant in every run.
      if (virtual_time && (report_due || wall() - last_sync > 0.25)) {
        send_sync();
        last_sync = wall();
        report_due = false;
      }
      if (final_status && !done_at) done_at = wall();
      // Let the last messages (stop, final pose, truth) reach the log.
      if (!virtual_time && done_at && wall() - *done_at > 1.0) break;
    }
    if (!final_status && !virtual_time) note("no final status within " + Num(spec.timeout_s) + " s");
    if (!final_status && virtual_time && wall() - clock_moved_wall >= kClockStallS) {
      note("the clock stood still for " + Num(kClockStallS) +
           " s of wall time with no final status (a hung rover_sim? see rover_sim.log)");
    } else if (!final_status && virtual_time) {
      note("no final status within " + Num(rover_limit_us / 1e6) + " s of rover time (timeout_s " +
           Num(spec.timeout_s) + " at sim_rate " + Num(spec.sim_rate) + ")");
    }
    // The clock first, so that nothing moves while the others stop (in virtual time it
    // waits for this runner, which has stopped reporting: the log ends at one instant).
    set.Signal("rover_sim", SIGTERM);
    for (const double until = wall() + 5; set.Running("rover_sim") && wall() < until;) set.Poll(20);
    set.StopAll();
    recorder.Signal("rover_recorder", SIGTERM);  // it writes what it holds, then exits
    bool log_whole = true;
    for (const double until = wall() + 10; recorder.Running("rover_recorder") && wall() < until;) {
      for (const auto& [name, how] : recorder.Poll(50)) {
        if (how != "exited with code 0") {
          note(name + " " + how + " (see " + out_dir + "/rover_recorder.log)");
          log_whole = false;  // exit 1: a write failed (a full disk); a crash: the same for us
        }
      }
    }
    recorder.StopAll();

    auto summary = rover::tools::SummarizeLog(log_path, footprint);
    summary.log_digest = rover::logcheck::DigestLog(log_path).sha256_hex;
    summary.rover_time = rover::tools::BreakdownFromLog(log_path);
    {
      // Truth clearance to the rocks the rover cannot drive over (the simulator faults on them).
      double max_height_m = 0.3;
      rover_config["mobility"]["rock_collision"].Get("max_height_m", max_height_m);
      std::vector<rover::tools::RockDisc> rocks;
      for (const auto& r : world.rocks()) {
        if (r.height_m > max_height_m) rocks.push_back({r.name, r.position.x(), r.position.y(), 0.5 * r.diameter_m});
      }
      rover::tools::AddRockClearance(rocks, footprint, &summary);
    }
    summary.scenario = spec.name;
    summary.wall_time_s = wall();
    summary.process_events = partial.process_events;
    const std::string summary_path = out_dir + "/summary.json";
    const bool summary_written = WriteWhole(summary_path, rover::tools::SummaryJson(summary));
    const std::string summary_error = summary_written ? "" : std::strerror(errno);
    std::cout << "\n" << rover::tools::SummaryText(summary);
    // The figures come from the log: a log that could not be written whole says less than
    // the drive did. The executor's own last word, heard live, says how the drive ended.
    if (!log_whole) {
      std::cout << "  THE LOG IS NOT WHOLE: rover_recorder could not write " << log_path
                << " (see " << out_dir << "/rover_recorder.log; a full disk?): the figures above are of "
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
    std::string missed;
    const bool as_expected = rover::tools::AsExpected(spec, summary, &missed);
    if (!spec.expect_outcome.empty()) {
      std::cout << "  expected: " << spec.expect_outcome
                << (spec.expect_abort_reason.empty() ? "" : " (" + spec.expect_abort_reason + ")")
                << (as_expected ? " - as expected\n" : " - NOT as expected: " + missed + "\n");
    }
    if (summary_written && log_whole) {
      std::cout << "  wrote " << summary_path << " and " << log_path << "\n";
    } else {
      std::cout << "  NOT WRITTEN: " << (summary_written ? "" : summary_path + " (" + summary_error + ")")
                << (summary_written || log_whole ? "" : " and ") << (log_whole ? "" : log_path + " (partial)")
                << "\n";
    }
    if (plot && log_whole) RunPlot(out_dir);
    // Exit 1 when the run did not end, ended other than the scenario expects, or its
    // record could not be written.
    return summary.outcome == "incomplete" || !as_expected || !summary_written || !log_whole ? 1 : 0;
  });
}
