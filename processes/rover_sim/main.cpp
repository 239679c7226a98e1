// rover_sim: the simulated rover on its terrain (common/terrain, common/mobility).
// Owns the rover clock in simulation and runs it faster than real time (--rate).
// Reads MOBILITY_COMMAND; writes ROVER_CLOCK, IMU, WHEEL_ODOMETRY, MOBILITY_STATUS and
// SIM_TRUTH (truth: read only by tests and evaluation).
// The dead-man (common/mobility/deadman.hpp): a motion stops by itself when the
// sequence_executor's HEARTBEAT and MOBILITY_COMMAND have both been silent for
// mobility.deadman_s (of wall time on a real clock, of rover time in virtual time).
//
// Virtual time (README, "Simulated time"; common/simtime/barrier.hpp): the clock moves
// by sim.tick_s only when every process of --hold-for has finished the current instant
// and this process has every command sent to it, and at most `rate` times as fast as the wall
// clock (`--rate max`: as fast as the barrier allows). A process that holds the clock and
// says nothing for sim.barrier_timeout_s of wall time is declared lost: the rover stops
// and the clock runs on without it, so the executor finds it lost.
#include "bus/channels.hpp"
#include "bus/convert.hpp"
#include "bus/process.hpp"
#include "bus/virtual_time.hpp"
#include "mobility/deadman.hpp"
#include "mobility/rover_simulator.hpp"
#include "simtime/barrier.hpp"
#include "terrain/world.hpp"

#include <rover_msgs/heartbeat_t.hpp>
#include <rover_msgs/imu_t.hpp>
#include <rover_msgs/mobility_command_t.hpp>
#include <rover_msgs/mobility_status_t.hpp>
#include <rover_msgs/pose_t.hpp>
#include <rover_msgs/rover_clock_t.hpp>
#include <rover_msgs/sim_truth_t.hpp>
#include <rover_msgs/wheel_odometry_t.hpp>

#include <chrono>
#include <cmath>
#include <iostream>
#include <set>
#include <sstream>
#include <thread>

#include <poll.h>

using namespace rover;

namespace {

// sim.rate and --rate: rover seconds per wall second.
constexpr double kMinRate = 0.1, kMaxRate = 10000.0;

struct SimOptions {
  double rate = 50.0;        // rover seconds per wall second; 0: as fast as the barrier allows
  double step_s = 0.01;      // rover time per simulation step
  double truth_hz = 20.0;    // SIM_TRUTH
  double clock_hz = 50.0;    // ROVER_CLOCK (real time)
  double status_hz = 4.0;    // periodic MOBILITY_STATUS (changes are sent at once)
  std::int64_t start_utime = 1000000;
  double tick_s = 0.1;             // virtual time: one instant of the barrier
  double barrier_timeout_s = 10.0;  // virtual time: wall seconds before a silent process is lost
};

SimOptions LoadSimOptions(const config::ConfigNode& section) {
  SimOptions o;
  section.CheckKeys({"rate", "step_s", "truth_hz", "clock_hz", "status_hz", "start_utime", "tick_s",
                     "barrier_timeout_s"});
  section.Get("tick_s", o.tick_s, 0.01, 1.0);
  section.Get("barrier_timeout_s", o.barrier_timeout_s, 0.1, 600.0);
  if (section.Has("rate") && section["rate"].AsString() == "max") {
    o.rate = 0;
  } else {
    section.Get("rate", o.rate, kMinRate, kMaxRate);  // or max (above)
  }
  section.Get("step_s", o.step_s, 0.001, 0.1);
  section.Get("truth_hz", o.truth_hz, 1.0, 1000.0);
  section.Get("clock_hz", o.clock_hz, 1.0, 1000.0);
  section.Get("status_hz", o.status_hz, 0.5, 100.0);
  section.Get("start_utime", o.start_utime);
  return o;
}

rover_msgs::mobility_status_t ToMsg(const mobility::MobilityStatus& s) {
  rover_msgs::mobility_status_t m{};
  m.utime = s.utime;
  m.command_id = s.command_id;
  m.state = static_cast<std::int8_t>(s.state);
  m.wheel_distance_m = s.wheel_distance_m;
  m.wheel_turn_rad = s.wheel_turn_rad;
  m.detail = s.detail;
  return m;
}

// Waits up to `ms` for a message on either bus and handles what has arrived: on the sync
// bus every report already there (up to a bound, so that a flood cannot hold the loop),
// so that the barrier is judged once per burst of reports rather than once per report.
void HandleEither(lcm::LCM& a, lcm::LCM* b, int ms) {
  pollfd fds[2] = {{a.getFileno(), POLLIN, 0}, {b ? b->getFileno() : -1, POLLIN, 0}};
  if (::poll(fds, b ? 2 : 1, ms) <= 0) return;
  if (fds[0].revents & POLLIN) a.handleTimeout(0);
  if (b && (fds[1].revents & POLLIN)) {
    for (int i = 0; i < 256 && b->handleTimeout(0) > 0; ++i) {
    }
  }
}

// The sync reports of the set, into the barrier (on the sync bus: bus/virtual_time.hpp).
struct SyncListener {
  simtime::Barrier* barrier;
  const bus::Process* proc;
  void OnMessage(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    rover_msgs::sim_sync_t m;
    try {
      bus::DecodeAllocationCap cap(16 * static_cast<std::size_t>(rbuf->data_size) + 65536);
      if (m.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) < 0) return;
    } catch (const std::exception&) {
      return;  // a hostile packet on the sync port: not a member's report
    }
    barrier->Report(bus::FromMsg(m), proc->wall_seconds());
  }
};

}  // namespace

int main(int argc, char** argv) {
  return bus::RunMain("rover_sim", [&]() -> int {
    bus::Process proc("rover_sim",
                      "The simulated rover: arcs and turns on a height field with slip, IMU and\n"
                      "wheel encoders. Owns the rover clock. Reads MOBILITY_COMMAND; writes\n"
                      "ROVER_CLOCK, IMU, WHEEL_ODOMETRY, MOBILITY_STATUS, SIM_TRUTH.\n"
                      "Config: `mobility:`, `sensors:` and `sim:` sections (configs/rover.yaml).\n"
                      "In virtual time ($ROVER_TIME=virtual or bus.time) the clock waits for every\n"
                      "process of --hold-for to finish each instant (README, \"Simulated time\").",
                      argc, argv,
                      {{"--world", "FILE", "world YAML (configs/worlds/)"},
                       {"--start", "X,Y,YAW_DEG", "start pose (default: the world's start)"},
                       {"--rate", "R|max", "rover seconds per wall second (overrides sim.rate); max: as fast as the barrier allows (virtual time)"},
                       {"--hold-for", "NAMES", "comma-separated processes the clock waits for: before it starts, and in virtual time at every instant"}});
    SimOptions options = LoadSimOptions(proc.config()["sim"]);
    if (auto r = proc.option("--rate")) {  // the same range as sim.rate
      if (*r == "max") {
        options.rate = 0;
      } else {
        options.rate = bus::ParseNumberList(*r, 1, "rover_sim: argument --rate")[0];
        if (!(options.rate >= kMinRate && options.rate <= kMaxRate)) {
          std::ostringstream range;
          range << "[" << kMinRate << ", " << kMaxRate << "]";
          throw config::ConfigError("rover_sim: argument --rate: \"" + *r + "\": expected max or a number in " +
                                    range.str());
        }
      }
    }
    if (options.rate <= 0 && !proc.virtual_time()) {
      throw config::ConfigError("rover_sim: rate max (0) needs virtual time (expected $ROVER_TIME=virtual or bus.time: virtual, or a rate > 0)");
    }
    const auto world_path = proc.option("--world");
    if (!world_path) throw config::ConfigError("rover_sim: missing argument --world FILE (expected a world YAML)");
    const terrain::World world(terrain::WorldOptions::LoadFile(*world_path));
    const auto mobility_options = mobility::MobilityOptions::Load(proc.config());
    mobility::Deadman deadman(mobility::LoadDeadmanOptions(proc.config()));

    std::unique_ptr<mobility::RoverSimulator> sim;
    if (auto s = proc.option("--start")) {
      const auto v = bus::ParseNumberList(*s, 3, "rover_sim: argument --start");
      try {
        sim = std::make_unique<mobility::RoverSimulator>(world, mobility_options, v[0], v[1],
                                                         v[2] * M_PI / 180.0, options.start_utime);
      } catch (const std::invalid_argument& e) {
        throw config::ConfigError("rover_sim: argument --start: " + std::string(e.what()));
      }
    } else {
      sim = std::make_unique<mobility::RoverSimulator>(world, mobility_options, options.start_utime);
    }
    proc.ObserveTime(sim->utime());

    proc.bus().Subscribe<rover_msgs::mobility_command_t>(
        channels::kMobilityCommand, [&](const rover_msgs::mobility_command_t& m) {
          deadman.OnCommanderMessage(proc.guard_seconds());
          mobility::MotionCommand c;
          c.id = m.command_id;
          c.distance_m = m.distance_m;
          c.curvature_per_m = m.curvature_per_m;
          c.turn_rad = m.turn_rad;
          c.speed_mps = m.speed_mps;
          c.turn_rate_rps = m.turn_rate_rps;
          switch (m.type) {
            case rover_msgs::mobility_command_t::TYPE_ARC: c.type = mobility::MotionCommand::Type::kArc; break;
            case rover_msgs::mobility_command_t::TYPE_TURN: c.type = mobility::MotionCommand::Type::kTurn; break;
            case rover_msgs::mobility_command_t::TYPE_STOP: c.type = mobility::MotionCommand::Type::kStop; break;
            default: {
              rover_msgs::mobility_status_t st{};
              st.utime = sim->utime();
              st.command_id = m.command_id;
              st.state = rover_msgs::mobility_status_t::STATE_FAULT;
              st.detail = "command " + std::to_string(m.command_id) + ": unknown type " +
                          std::to_string(m.type) + " (expected 0 arc, 1 turn, 2 stop)";
              proc.bus().Publish(channels::kMobilityStatus, st);
              return;
            }
          }
          try {
            sim->Command(c);
          } catch (const std::invalid_argument& e) {
            rover_msgs::mobility_status_t st{};
            st.utime = sim->utime();
            st.command_id = m.command_id;
            st.state = rover_msgs::mobility_status_t::STATE_FAULT;
            st.detail = "command " + std::to_string(m.command_id) + " refused: " + e.what();
            proc.bus().Publish(channels::kMobilityStatus, st);
          }
        });

    std::vector<std::string> members;
    if (auto names = proc.option("--hold-for")) {
      std::stringstream ss(*names);
      for (std::string n; std::getline(ss, n, ',');)
        if (!n.empty() && n != "rover_sim") members.push_back(n);
    }
    std::set<std::string> waiting(members.begin(), members.end());  // real time: heartbeats before start
    proc.bus().Subscribe<rover_msgs::heartbeat_t>(
        channels::kHeartbeat, [&](const rover_msgs::heartbeat_t& hb) {
          waiting.erase(hb.process);
          deadman.OnHeartbeat(hb.process, proc.guard_seconds());
        }, 1000);

    // What one simulation step produced, on the bus.
    const auto period = [](double hz) { return static_cast<std::int64_t>(1e6 / hz); };
    std::int64_t next_truth = sim->utime(), next_status = sim->utime();
    auto publish_step = [&](const mobility::StepOutput& out) {
      for (const auto& s : out.imu) {
        rover_msgs::imu_t m{};
        m.utime = s.utime;
        bus::QuaternionToArray(s.q_site_rover, m.orientation);
        for (int i = 0; i < 3; ++i) {
          m.angular_rate[i] = s.angular_rate_rps[i];
          m.accel[i] = s.accel_mps2[i];
        }
        proc.bus().Publish(channels::kImu, m);
      }
      for (const auto& s : out.odometry) {
        rover_msgs::wheel_odometry_t m{};
        m.utime = s.utime;
        m.num_wheels = static_cast<std::int32_t>(s.wheel_distance_m.size());
        m.wheel_distance_m.assign(s.wheel_distance_m.begin(), s.wheel_distance_m.end());
        m.distance_m = s.distance_m;
        m.curvature_per_m = s.curvature_per_m;
        m.turning_in_place = s.turning_in_place;
        proc.bus().Publish(channels::kWheelOdometry, m);
      }
      for (const auto& s : out.status) proc.bus().Publish(channels::kMobilityStatus, ToMsg(s));
      const std::int64_t now = sim->utime();
      if (now >= next_status) {
        auto st = sim->status();
        st.utime = now;
        proc.bus().Publish(channels::kMobilityStatus, ToMsg(st));
        next_status += period(options.status_hz);
      }
      if (now >= next_truth) {
        const auto t = sim->Truth();
        rover_msgs::sim_truth_t m{};
        m.utime = t.utime;
        for (int i = 0; i < 3; ++i) {
          m.position[i] = t.position[i];
          m.rpy[i] = t.rpy[i];
        }
        bus::QuaternionToArray(t.q_site_rover, m.orientation);
        m.odometer_m = t.odometer_m;
        m.slip = t.slip;
        m.soil = terrain::SoilName(t.soil);
        m.command_id = t.command_id;
        proc.bus().Publish(channels::kSimTruth, m);
        next_truth += period(options.truth_hz);
      }
    };
    auto publish_clock = [&](std::int64_t now, const simtime::Cut* cut = nullptr) {
      rover_msgs::rover_clock_t m{};
      if (cut) bus::SetCut(*cut, &m);
      m.utime = now;
      // Virtual time has no fixed ratio to the wall clock (the pacing is only a ceiling): 0,
      // so that a run at 50x and one as fast as possible publish the same bytes.
      m.rate = proc.virtual_time() ? 0.0 : options.rate;
      m.mode = proc.virtual_time() ? rover_msgs::rover_clock_t::MODE_VIRTUAL : rover_msgs::rover_clock_t::MODE_REAL;
      proc.bus().Publish(channels::kClock, m);
    };
    auto check_deadman = [&] {
      if (const auto why = deadman.Check(sim->moving(), proc.guard_seconds())) {
        std::cerr << "rover_sim: command " << sim->status().command_id << ": " << *why << "\n";
        sim->Halt(*why);
      }
    };

    if (proc.virtual_time()) {
      // ---- Virtual time: one instant at a time, when the whole set has finished it. ----
      // rover_sim is a member too: the clock must also wait for the commands sent to it.
      std::vector<std::string> with_clock = members;
      with_clock.push_back("rover_sim");
      simtime::Barrier barrier(with_clock, options.barrier_timeout_s, "rover_sim");
      lcm::LCM sync_bus(bus::SyncUrl(proc.bus().url()));
      if (!sync_bus.good()) throw std::runtime_error("cannot open the sync bus " + bus::SyncUrl(proc.bus().url()));
      SyncListener listener{&barrier, &proc};
      sync_bus.subscribe(bus::kSimSyncChannel, &SyncListener::OnMessage, &listener)->setQueueCapacity(10000);
      const double hold_start = proc.wall_seconds();
      barrier.Report(proc.bus().SyncState("rover_sim", -1, false), proc.wall_seconds());
      while (!barrier.AllHeard() && !proc.stopping()) {
        HandleEither(proc.bus().lcm(), &sync_bus, 50);
        if (proc.wall_seconds() - hold_start > 30) {
          throw std::runtime_error("--hold-for: no sync report within 30 s from: " + barrier.Holding(-1));
        }
      }
      std::int64_t t = sim->utime();
      const std::int64_t tick_us = static_cast<std::int64_t>(std::llround(options.tick_s * 1e6));
      const std::int64_t rover_start = t;
      const double wall_start = proc.wall_seconds();
      std::int64_t next_heartbeat = t;
      // The clock carries the cut (simtime/cut.hpp): what the members had published when
      // they finished the last instant, and what this process has sent for the new one.
      auto cut_now = [&] {
        simtime::Cut cut = barrier.Published();
        const auto own = bus::PublisherId("rover_sim");
        for (const auto& [channel, count] : proc.bus().SyncState("rover_sim", t, false).published) {
          cut.Set(channel, own, count);
        }
        cut.Set(channels::kClock, own, 0);  // the clock is acted on at once, never batched
        return cut;
      };
      auto begin_instant = [&] {
        proc.ObserveTime(t);
        const simtime::Cut cut = cut_now();
        publish_clock(t, &cut);
        if (t >= next_heartbeat) {
          proc.PublishHeartbeat();
          next_heartbeat = t + static_cast<std::int64_t>(0.25e6);
        }
      };
      begin_instant();
      double tick_wall = proc.wall_seconds(), last_note = tick_wall, last_announce = tick_wall;
      while (!proc.stopping()) {
        // 1. Everyone has finished instant t, and what was sent to rover_sim has come.
        double last_pass = proc.wall_seconds();
        while (!proc.stopping()) {
          // A pass long after the last (this process was stopped or starved): the others'
          // silence meanwhile is not theirs to answer for.
          if (proc.wall_seconds() - last_pass > 1.0) tick_wall = proc.wall_seconds();
          last_pass = proc.wall_seconds();
          barrier.Report(proc.bus().SyncState("rover_sim", t, false), proc.wall_seconds());
          if (barrier.Finished(t)) break;
          std::vector<std::string> forgiven;
          const auto lost = barrier.DeclareLost(t, proc.wall_seconds(), tick_wall, &forgiven);
          for (const auto& line : forgiven) {
            std::cerr << "rover_sim: messages lost on the way (" << line << ") after "
                      << options.barrier_timeout_s << " s of wall time: forgiven, the clock runs on\n";
          }
          for (const auto& name : lost) {
            const std::string why = "process " + name + " lost: it held the clock for " +
                                    std::to_string(options.barrier_timeout_s) +
                                    " s of wall time without a word (sim.barrier_timeout_s)";
            std::cerr << "rover_sim: " << why << "; the rover stops and the clock runs on without it\n";
            sim->Halt(why);
          }
          // A member back from a freeze may have lost the clock messages in between, and
          // takes a jump of more than bus.max_clock_step_s only when the next clock message
          // confirms it: while such a member holds the clock, the instant is announced again
          // (twice a second). Never in a run without a fault, whose log it would change.
          if (proc.wall_seconds() - std::max(last_announce, tick_wall) > 0.5 &&
              barrier.FarBehind(t, static_cast<std::int64_t>(1e6))) {
            const simtime::Cut cut = cut_now();
            publish_clock(t, &cut);
            last_announce = proc.wall_seconds();
          }
          if (proc.wall_seconds() - std::max(last_note, tick_wall) > 10.0) {
            std::cerr << "rover_sim: the clock waits at " << t << ": " << barrier.Holding(t) << "\n";
            last_note = proc.wall_seconds();
          }
          // Woken by any report or message; the timeout serves only the wall-time rules
          // above (0.5 s and more), so it need not spin.
          HandleEither(proc.bus().lcm(), &sync_bus, 20);
        }
        if (proc.stopping()) break;  // stopped while waiting: the instant is not finished
        // 2. No faster than `rate` times the wall clock.
        if (options.rate > 0) {
          const double due = wall_start + (t + tick_us - rover_start) * 1e-6 / options.rate;
          while (!proc.stopping() && proc.wall_seconds() < due) {
            HandleEither(proc.bus().lcm(), &sync_bus, std::max(1, static_cast<int>((due - proc.wall_seconds()) * 1000)));
          }
          if (proc.stopping()) break;
        }
        // 3. The next instant: what came during this one acts first (commands, heartbeats).
        proc.bus().SealBatch(t + tick_us);
        proc.bus().DispatchBatch();
        const std::int64_t until = t + tick_us;
        while (sim->utime() < until) {
          check_deadman();
          publish_step(sim->Step(options.step_s));
        }
        t = sim->utime();
        begin_instant();
        tick_wall = proc.wall_seconds();
      }
      return 0;
    }

    // ---- Real time: the clock runs at `rate` times the wall clock, as on a rover. ----
    const auto hold_start = std::chrono::steady_clock::now();
    double next_hold_heartbeat_wall = 0;
    while (!waiting.empty() && !proc.stopping()) {
      // Once a wall second, as everywhere: every heartbeat on the bus (this one included)
      // wakes Handle(), so sending one per wake-up floods the bus.
      if (proc.wall_seconds() >= next_hold_heartbeat_wall) {
        proc.PublishHeartbeat();
        next_hold_heartbeat_wall = proc.wall_seconds() + 1.0;
      }
      proc.bus().Handle(200);
      if (std::chrono::steady_clock::now() - hold_start > std::chrono::seconds(30)) {
        std::string list;
        for (const auto& n : waiting) list += " " + n;
        throw std::runtime_error("--hold-for: no heartbeat within 30 s from:" + list);
      }
    }
    std::int64_t next_clock = sim->utime();
    const auto wall_start = std::chrono::steady_clock::now();
    const std::int64_t rover_start = sim->utime();
    double next_heartbeat_wall = 0;
    while (!proc.stopping()) {
      while (proc.bus().Handle(0)) {
      }
      check_deadman();
      publish_step(sim->Step(options.step_s));
      const std::int64_t now = sim->utime();
      proc.ObserveTime(now);
      if (now >= next_clock) {
        publish_clock(now);
        next_clock += period(options.clock_hz);
      }
      if (proc.wall_seconds() >= next_heartbeat_wall) {
        proc.PublishHeartbeat();
        next_heartbeat_wall = proc.wall_seconds() + 0.25;
      }
      // Pace rover time at `rate` times the wall clock.
      const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
      const double ahead_s = (now - rover_start) * 1e-6 / options.rate - wall;
      if (ahead_s > 0) {
        proc.bus().Handle(static_cast<int>(ahead_s * 1000.0));
        const double wall2 = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
        const double still = (now - rover_start) * 1e-6 / options.rate - wall2;
        if (still > 0) std::this_thread::sleep_for(std::chrono::duration<double>(still));
      }
    }
    return 0;
  });
}
