// The mobility contract (docs/HARDWARE.md, "Contracts"): MOBILITY_COMMAND in,
// MOBILITY_STATUS out. The probe (probe.hpp) plays the commander: it sends commands, falls
// silent for the dead-man, sends bad commands, and records everything; these checks judge
// the record, one probe step at a time.
#pragma once

#include "conformance/report.hpp"

#include <rover_msgs/heartbeat_t.hpp>
#include <rover_msgs/mobility_status_t.hpp>
#include <rover_msgs/wheel_odometry_t.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace rover::conformance {

struct SentCommand {
  std::int64_t id = 0;
  std::int8_t type = 0;  // mobility_command_t::TYPE_*
  double distance_m = 0, curvature_per_m = 0, turn_rad = 0, speed_mps = 0, turn_rate_rps = 0;
  double wall_s = 0;  // when it was sent
};

struct MobilityTrace {
  std::vector<Received<rover_msgs::mobility_status_t>> statuses;
  std::vector<Received<rover_msgs::heartbeat_t>> driver_heartbeats;
  std::vector<Received<rover_msgs::wheel_odometry_t>> odometry;
  std::vector<SentCommand> commands;
  double end_wall_s = 0;  // when the probe stopped listening
  // The dead-man step: the commander (heartbeats and commands) fell silent at
  // `silent_from_s` and spoke again at `silent_until_s` (wall seconds).
  double silent_from_s = -1, silent_until_s = -1;
};

struct MobilityLimits {
  double answer_s = 1.0;            // a command's first status, wall seconds
  double deadman_s = 1.5;           // the driver's mobility.deadman_s
  double deadman_margin_s = 1.0;    // the stop may come this much after the limit
  double clock_tolerance_s = 0.5;
  double idle_status_gap_s = 2.0;
  double moving_status_gap_s = 0.6;
  double heartbeat_gap_s = 1.5;
  double amount_tolerance = 0.10;   // distance and angle
  double duration_tolerance = 0.30; // distance / speed, angle / rate
};

// mobility.status.*, mobility.time.*, mobility.heartbeat over the whole record.
void CheckStatusStream(const MobilityTrace& trace, const MobilityLimits& limits, Report& report);
// mobility.stop.idle_answer: STOP `stop_id` sent at rest.
void CheckIdleStop(const MobilityTrace& trace, std::int64_t stop_id, const MobilityLimits& limits, Report& report);
// mobility.arc.* or mobility.turn.* and their units: the motion `id` ran to its end.
void CheckMotion(const MobilityTrace& trace, std::int64_t id, const MobilityLimits& limits, Report& report);
// mobility.stop.answer, mobility.stop.stays: STOP `stop_id` during motion `motion_id`.
void CheckStop(const MobilityTrace& trace, std::int64_t motion_id, std::int64_t stop_id, const MobilityLimits& limits,
               Report& report);
// mobility.deadman.*: motion `motion_id`, the commander silent over the trace's window.
void CheckDeadman(const MobilityTrace& trace, std::int64_t motion_id, const MobilityLimits& limits, Report& report);
// `rule` (mobility.bad.*): command `id` refused with FAULT, or, when `drop_allowed` (a
// message the bus's field checks drop), dropped and counted in the driver's heartbeat;
// never MOVING.
void CheckRefusal(const MobilityTrace& trace, std::int64_t id, const std::string& rule, bool drop_allowed,
                  const MobilityLimits& limits, Report& report);

// `rule` (mobility.auth.*): command `id`, a motion sent `how` (unsigned, or signed with
// another key) to a driver that holds the deployment's key, not obeyed: no MOVING or DONE
// for it and WHEEL_ODOMETRY still (1 cm) until the next command. Refusing it aloud (FAULT)
// or in silence (dropped) are both fine.
void CheckNotObeyed(const MobilityTrace& trace, std::int64_t id, const std::string& rule, const std::string& how,
                    Report& report);

}  // namespace rover::conformance
