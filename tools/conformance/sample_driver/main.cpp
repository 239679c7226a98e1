// sample_mobility_driver: the skeleton of a mobility driver on the bus (docs/HARDWARE.md,
// "Writing a mobility driver"). It passes `./rover conformance mobility`, imu and
// wheel_odometry. The parts a real driver replaces are SampleMobility::Advance (the motors)
// and the IMU sample (the real IMU's driver); the rest is the contract:
//   - heartbeat as mobility_driver (Process::Run: 4 a second);
//   - MOBILITY_COMMAND -> SampleMobility::Execute; every status change published at once;
//   - MOBILITY_STATUS 4 times a second as well; WHEEL_ODOMETRY at 10 Hz; IMU at 20 Hz;
//   - the dead-man (mobility/deadman.hpp) checked before each control cycle;
//   - utimes in rover time: with no simulator's clock on the bus, the system clock
//     (docs/HARDWARE.md, "Rover time").
#include "bus/channels.hpp"
#include "bus/process.hpp"
#include "mobility/deadman.hpp"
#include "sample_driver/sample_mobility.hpp"

#include <rover_msgs/heartbeat_t.hpp>
#include <rover_msgs/imu_t.hpp>
#include <rover_msgs/mobility_command_t.hpp>
#include <rover_msgs/mobility_status_t.hpp>
#include <rover_msgs/wheel_odometry_t.hpp>

#include <chrono>
#include <cmath>
#include <iostream>

using namespace rover;

namespace {

std::int64_t RoverNow() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

rover_msgs::mobility_status_t ToMsg(const sample_driver::Status& s, std::int64_t utime) {
  rover_msgs::mobility_status_t m{};
  m.utime = utime;
  m.command_id = s.command_id;
  m.state = static_cast<std::int8_t>(s.state);
  m.wheel_distance_m = s.wheel_distance_m;
  m.wheel_turn_rad = s.wheel_turn_rad;
  m.detail = s.detail;
  return m;
}

}  // namespace

int main(int argc, char** argv) {
  return bus::RunMain("mobility_driver", [&]() -> int {
    bus::Process proc("mobility_driver",
                      "The sample mobility driver (tools/conformance/sample_driver): executes MOBILITY_COMMAND\n"
                      "on a simulated drive train; writes MOBILITY_STATUS, WHEEL_ODOMETRY and IMU. A real\n"
                      "driver keeps its shape and drives motors instead. Config: mobility.deadman_s,\n"
                      "sensors.imu.gravity_mps2.",
                      argc, argv);
    mobility::Deadman deadman(mobility::LoadDeadmanOptions(proc.config()));
    double gravity = 9.80665;
    proc.config()["sensors"]["imu"].Get("gravity_mps2", gravity, 0.1, 100.0);
    sample_driver::SampleMobility drive;

    auto publish = [&](const sample_driver::Status& s) {
      proc.bus().Publish(channels::kMobilityStatus, ToMsg(s, RoverNow()));
    };
    proc.bus().Subscribe<rover_msgs::mobility_command_t>(
        channels::kMobilityCommand, [&](const rover_msgs::mobility_command_t& m) {
          deadman.OnCommanderMessage(proc.guard_seconds());
          sample_driver::Command c;
          c.id = m.command_id;
          c.type = m.type;
          c.distance_m = m.distance_m;
          c.curvature_per_m = m.curvature_per_m;
          c.turn_rad = m.turn_rad;
          c.speed_mps = m.speed_mps;
          c.turn_rate_rps = m.turn_rate_rps;
          for (const auto& s : drive.Execute(c)) {
            if (s.state == sample_driver::State::kFault) std::cerr << "mobility_driver: " << s.detail << "\n";
            publish(s);
          }
        });
    proc.bus().Subscribe<rover_msgs::heartbeat_t>(
        channels::kHeartbeat,
        [&](const rover_msgs::heartbeat_t& hb) { deadman.OnHeartbeat(hb.process, proc.guard_seconds()); }, 1000);

    auto last = std::chrono::steady_clock::now();
    std::int64_t next_status = 0, next_odometry = 0, next_imu = 0;
    proc.Run(
        [&] {
          const auto now = std::chrono::steady_clock::now();
          const double dt = std::chrono::duration<double>(now - last).count();
          last = now;
          // 1. The dead-man, before the motion advances.
          if (const auto why = deadman.Check(drive.moving(), proc.guard_seconds())) {
            std::cerr << "mobility_driver: command " << drive.status().command_id << ": " << *why << "\n";
            if (const auto s = drive.Halt(*why)) publish(*s);
          }
          // 2. The control cycle.
          if (const auto s = drive.Advance(dt)) publish(*s);
          // 3. What the rest of the stack reads.
          const std::int64_t t = RoverNow();
          if (t >= next_status) {
            publish(drive.status());
            next_status = t + 250000;
          }
          if (t >= next_odometry) {
            rover_msgs::wheel_odometry_t m{};
            m.utime = t;
            m.num_wheels = static_cast<std::int32_t>(drive.wheel_distance_m().size());
            m.wheel_distance_m.assign(drive.wheel_distance_m().begin(), drive.wheel_distance_m().end());
            m.distance_m = drive.body_distance_m();
            m.curvature_per_m = drive.curvature_per_m();
            m.turning_in_place = drive.turning_in_place() ? 1 : 0;
            proc.bus().Publish(channels::kWheelOdometry, m);
            next_odometry = t + 100000;
          }
          if (t >= next_imu) {
            // A level rover: orientation is the yaw alone (about Z, down: + clockwise), the
            // accelerometer reads the specific force R^T (0, 0, -g) = (0, 0, -g).
            rover_msgs::imu_t m{};
            m.utime = t;
            m.orientation[0] = std::cos(drive.yaw_rad() / 2);
            m.orientation[3] = std::sin(drive.yaw_rad() / 2);
            m.angular_rate[2] = drive.yaw_rate_rps();
            m.accel[2] = -gravity;
            proc.bus().Publish(channels::kImu, m);
            next_imu = t + 50000;
          }
        },
        10);
    return 0;
  });
}
