// The conformance kit's side of the bus: it listens to a running driver (every message,
// before any check of the Bus's, so that a bad one is reported, not dropped), keeps rover
// time, and for mobility plays the commander. What it records goes to the checks
// (mobility_checks.hpp, sensor_checks.hpp, camera_checks.hpp).
#pragma once

#include "bus/bus.hpp"
#include "conformance/camera_checks.hpp"
#include "conformance/mobility_checks.hpp"
#include "conformance/sensor_checks.hpp"

#include <rover_msgs/imu_t.hpp>
#include <rover_msgs/rover_clock_t.hpp>

#include <chrono>
#include <functional>
#include <optional>
#include <string>

namespace rover::conformance {

struct ProbeOptions {
  std::string time_source = "rover_sim";  // whose ROVER_CLOCK is rover time (bus.time_source)
  std::string commander = "sequence_executor";  // the name the driver's dead-man listens to
  std::string driver;                     // the driver's heartbeat name; "": rover_sim or mobility_driver
  std::string capture_process = "camera_capture";
  double listen_s = 5.0;                  // sensors: how long to listen
  int requests = 3;                       // camera: how many captures to ask for
  bool drive = false;                     // imu, wheel_odometry: also drive an arc and a turn
};

class Probe {
 public:
  // Listens on `bus`'s LCM, publishes (signed, with pub_seq) through `bus`.
  Probe(bus::Bus& bus, ProbeOptions options);

  // Rover time now: the time source's ROVER_CLOCK extrapolated at its rate, else the system
  // clock (a rover with no simulator: docs/HARDWARE.md, "Rover time").
  std::int64_t RoverNow() const;
  double Wall() const;
  // "" or why the kit cannot run on this bus (a virtual clock).
  const std::string& setup_problem() const { return setup_problem_; }

  void RunMobility(const MobilityLimits& limits, Report& report);
  void RunImu(const ImuLimits& limits, Report& report);
  void RunWheelOdometry(const WheelOdometryLimits& limits, Report& report);
  void RunCamera(const CameraLimits& limits, Report& report);

 private:
  template <class Msg>
  void Listen(const std::string& channel, std::function<void(const Msg&, const Stamp&)> on_message);
  // Handles messages for `seconds` of wall time or until `done()`; the commander heartbeats
  // meanwhile unless silent.
  void Spin(double seconds, const std::function<bool()>& done = nullptr);
  // Sends a command through `via` (default: the kit's own bus, signed when it has a key).
  std::int64_t Command(std::int8_t type, double distance_m, double curvature, double turn_rad, double speed,
                       double turn_rate, bus::Bus* via = nullptr);
  void WaitForClock();
  // Drives an ARC of 0.10 m and a TURN of 0.10 rad as the commander (--drive).
  DriveRecord Drive();
  bool Ended(std::int64_t id) const;
  bool Moving(std::int64_t id) const;

  bus::Bus& bus_;
  ProbeOptions options_;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  std::optional<rover_msgs::rover_clock_t> clock_;
  std::chrono::steady_clock::time_point clock_at_;
  std::string setup_problem_;
  std::vector<std::shared_ptr<void>> raw_;  // the subscriptions' handler objects

  // Recording
  bool recording_mobility_ = false, recording_imu_ = false, recording_odometry_ = false, recording_camera_ = false;
  MobilityTrace mobility_;
  CameraTrace camera_;
  std::vector<Received<rover_msgs::imu_t>> imu_;
  std::string driver_name_;
  // The commander
  bool commander_alive_ = false;
  double next_heartbeat_s_ = 0;
  double last_heartbeat_s_ = 0;  // wall s of the last commander heartbeat sent
  std::int64_t heartbeat_seq_ = 0, next_command_id_ = 0;
  std::vector<std::int64_t> own_heartbeats_;
  std::string other_commander_;
};

}  // namespace rover::conformance
