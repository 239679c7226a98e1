// rover_sim: the simulated rover on its terrain (common/terrain, common/mobility).
// Owns the rover clock in simulation and runs it faster than real time (--rate).
// Reads MOBILITY_COMMAND; writes ROVER_CLOCK, IMU, WHEEL_ODOMETRY, MOBILITY_STATUS and
// SIM_TRUTH (truth: read only by tests and evaluation).
// The dead-man (common/mobility/deadman.hpp): a motion stops by itself when the
// sequence_executor's HEARTBEAT and MOBILITY_COMMAND have both been silent
// for mobility.deadman_s of WALL time.
#include "bus/channels.hpp"
#include "bus/convert.hpp"
#include "bus/process.hpp"
#include "mobility/deadman.hpp"
#include "mobility/lockstep.hpp"
#include "mobility/rover_simulator.hpp"
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

using namespace rover;

namespace {

// sim.rate and --rate: rover seconds per wall second.
constexpr double kMinRate = 0.1, kMaxRate = 10000.0;

struct SimOptions {
  double rate = 50.0;        // rover seconds per wall second
  double step_s = 0.01;      // rover time per simulation step
  double truth_hz = 20.0;    // SIM_TRUTH
  double clock_hz = 50.0;    // ROVER_CLOCK
  double status_hz = 4.0;    // periodic MOBILITY_STATUS (changes are sent at once)
  std::int64_t start_utime = 1000000;
  // Lockstep with the estimator (common/mobility/lockstep.hpp): the clock runs at most
  // max_lead_s of rover time ahead of the latest POSE of a live estimator, waiting up to
  // lead_wait_s of wall time for it. Faster than real time,
  // a lagging consumer would otherwise see its inputs age by (lag x rate) and trip the
  // staleness checks; a dead one is still caught, by heartbeats and by those checks.
  double max_lead_s = 0.5;
  double lead_wait_s = 0.5;
};

SimOptions LoadSimOptions(const config::ConfigNode& section) {
  SimOptions o;
  section.CheckKeys({"rate", "step_s", "truth_hz", "clock_hz", "status_hz", "start_utime",
                     "max_lead_s", "lead_wait_s"});
  section.Get("max_lead_s", o.max_lead_s, 0.0, 3600.0);
  section.Get("lead_wait_s", o.lead_wait_s, 0.0, 60.0);
  section.Get("rate", o.rate, kMinRate, kMaxRate);
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

}  // namespace

int main(int argc, char** argv) {
  return bus::RunMain("rover_sim", [&]() -> int {
    bus::Process proc("rover_sim",
                      "The simulated rover: arcs and turns on a height field with slip, IMU and\n"
                      "wheel encoders. Owns the rover clock. Reads MOBILITY_COMMAND; writes\n"
                      "ROVER_CLOCK, IMU, WHEEL_ODOMETRY, MOBILITY_STATUS, SIM_TRUTH.\n"
                      "Config: `mobility:`, `sensors:` and `sim:` sections (configs/rover.yaml).",
                      argc, argv,
                      {{"--world", "FILE", "world YAML (configs/worlds/)"},
                       {"--start", "X,Y,YAW_DEG", "start pose (default: the world's start)"},
                       {"--rate", "R", "rover seconds per wall second (overrides sim.rate)"},
                       {"--hold-for", "NAMES", "comma-separated processes whose heartbeats must be heard before the clock starts"}});
    SimOptions options = LoadSimOptions(proc.config()["sim"]);
    if (auto r = proc.option("--rate")) {  // the same range as sim.rate
      options.rate = bus::ParseNumberList(*r, 1, "rover_sim: argument --rate")[0];
      if (!(options.rate >= kMinRate && options.rate <= kMaxRate)) {
        std::ostringstream range;
        range << "[" << kMinRate << ", " << kMaxRate << "]";
        throw config::ConfigError("rover_sim: argument --rate: \"" + *r + "\": expected a number in " +
                                  range.str());
      }
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
          deadman.OnCommanderMessage(proc.wall_seconds());
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

    // Hold the clock until the listed processes are up, so that they see every message
    // from the first one (a replay of the log then reproduces their outputs exactly).
    std::set<std::string> waiting;
    if (auto names = proc.option("--hold-for")) {
      std::stringstream ss(*names);
      for (std::string n; std::getline(ss, n, ',');)
        if (!n.empty()) waiting.insert(n);
    }
    mobility::EstimatorLockstep lockstep(options.max_lead_s, /*alive_s=*/2.0);
    proc.bus().Subscribe<rover_msgs::heartbeat_t>(
        channels::kHeartbeat, [&](const rover_msgs::heartbeat_t& hb) {
          waiting.erase(hb.process);
          deadman.OnHeartbeat(hb.process, proc.wall_seconds());
          lockstep.OnHeartbeat(hb.process, hb.seq, proc.wall_seconds());
        });
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

    const auto period = [](double hz) { return static_cast<std::int64_t>(1e6 / hz); };
    std::int64_t next_truth = sim->utime(), next_clock = sim->utime(), next_status = sim->utime();
    const auto wall_start = std::chrono::steady_clock::now();
    const std::int64_t rover_start = sim->utime();
    double next_heartbeat_wall = 0;

    proc.bus().Subscribe<rover_msgs::pose_t>(channels::kPose, [&](const rover_msgs::pose_t& m) {
      lockstep.OnPose(m.utime);
    }, 1000);

    while (!proc.stopping()) {
      while (proc.bus().Handle(0)) {
      }
      const double wait_start = proc.wall_seconds();
      while (lockstep.ShouldWait(sim->utime(), proc.wall_seconds()) && !proc.stopping() &&
             proc.wall_seconds() - wait_start < options.lead_wait_s) {
        if (proc.wall_seconds() >= next_heartbeat_wall) {  // alive while it waits
          proc.PublishHeartbeat();
          next_heartbeat_wall = proc.wall_seconds() + 1.0;
        }
        proc.bus().Handle(2);
      }
      if (const auto why = deadman.Check(sim->moving(), proc.wall_seconds())) {
        std::cerr << "rover_sim: command " << sim->status().command_id << ": " << *why << "\n";
        sim->Halt(*why);
      }
      const auto& out = sim->Step(options.step_s);
      const std::int64_t now = sim->utime();
      proc.ObserveTime(now);
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
      if (now >= next_clock) {
        rover_msgs::rover_clock_t m{};
        m.utime = now;
        m.rate = options.rate;
        proc.bus().Publish(channels::kClock, m);
        next_clock += period(options.clock_hz);
      }
      // Pace rover time at `rate` times the wall clock.
      const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
      if (proc.wall_seconds() >= next_heartbeat_wall) {
        proc.PublishHeartbeat();
        next_heartbeat_wall = proc.wall_seconds() + 1.0;
      }
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
