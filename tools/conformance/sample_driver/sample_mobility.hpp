// A sample mobility driver's logic (docs/HARDWARE.md, "Writing a mobility driver"): what a
// real driver must do with commands, no LCM, no motors. It executes arcs and turns at a
// commanded or default speed, reports each change of state, refuses what it cannot do with
// a detail naming the value, and counts the wheels' rolled distance. A real driver keeps this
// shape and replaces Advance() with its motor controller: command the wheel speeds, read
// the encoders back. `sample_mobility_driver` (main.cpp) puts it on the bus and passes
// `./rover conformance mobility`.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace rover::sample_driver {

// As mobility_command_t.
enum class CommandType : std::int8_t { kArc = 0, kTurn = 1, kStop = 2 };
// As mobility_status_t's STATE_*.
enum class State : std::int8_t { kIdle = 0, kMoving = 1, kDone = 2, kStopped = 3, kFault = 4 };

struct Command {
  std::int64_t id = 0;
  std::int8_t type = 0;  // CommandType, as received: an unknown one is refused
  double distance_m = 0, curvature_per_m = 0, turn_rad = 0, speed_mps = 0, turn_rate_rps = 0;
};

struct Status {
  std::int64_t command_id = -1;
  State state = State::kIdle;
  double wheel_distance_m = 0;  // rolled in this command (metres, unsigned)
  double wheel_turn_rad = 0;    // turned in this command (radians, unsigned)
  std::string detail;
};

struct SampleMobilityOptions {
  double speed_mps = 0.04;            // default when a command says 0
  double turn_rate_rps = 0.05;
  double max_curvature_per_m = 4.0;
  double max_speed_mps = 0.2;
  double track_m = 1.0;               // left to right wheel centres
};

class SampleMobility {
 public:
  explicit SampleMobility(SampleMobilityOptions options = {});

  // Starts `c` (a STOP stops at once; any new command replaces the one in progress), or
  // refuses it with FAULT naming the value. Returns the status changes it caused, in order.
  std::vector<Status> Execute(const Command& c);
  // Advances the motion by `dt_s` of rover time; the status change when it ended.
  std::optional<Status> Advance(double dt_s);
  // The dead-man (or anything else) stops the motion in progress with `detail`.
  std::optional<Status> Halt(const std::string& detail);

  const Status& status() const { return status_; }
  bool moving() const { return status_.state == State::kMoving; }
  // Cumulative signed rolled distance of the six wheels (left front, left middle, left
  // rear, right front, right middle, right rear), and of the body.
  const std::array<double, 6>& wheel_distance_m() const { return wheels_; }
  double body_distance_m() const { return body_m_; }
  double yaw_rad() const { return yaw_rad_; }
  // Commanded rates now (for the IMU sample: a level rover turning at this rate).
  double yaw_rate_rps() const { return yaw_rate_rps_; }
  double curvature_per_m() const { return moving() && command_.type == 0 ? command_.curvature_per_m : 0.0; }
  bool turning_in_place() const { return moving() && command_.type == 1; }

 private:
  Status Refuse(const Command& c, const std::string& why);
  Status Set(State s, std::string detail);

  SampleMobilityOptions options_;
  Command command_;
  Status status_;
  double target_ = 0, rate_ = 0;
  std::array<double, 6> wheels_{};
  double body_m_ = 0, yaw_rad_ = 0, yaw_rate_rps_ = 0;
};

}  // namespace rover::sample_driver
