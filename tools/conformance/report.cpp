#include "conformance/report.hpp"

#include <algorithm>
#include <cstdio>
#include <map>
#include <stdexcept>

namespace rover::conformance {

namespace {

// The rules as docs/HARDWARE.md states them ("Contracts"): keep the two in step.
const std::map<std::string, std::vector<Rule>>& Contracts() {
  static const std::map<std::string, std::vector<Rule>> contracts = {
      {"mobility",
       {{"mobility.status.present", "MOBILITY_STATUS is published"},
        {"mobility.status.fields", "every status has finite wheel distance and turn and a known state"},
        {"mobility.status.rate_idle", "at rest, a status at least every 2 s"},
        {"mobility.status.rate_moving", "while moving, a status at least every 0.6 s (a few a second)"},
        {"mobility.time.monotonic", "status utimes never go back"},
        {"mobility.time.near_clock", "status utimes are within the tolerance of rover time"},
        {"mobility.heartbeat", "the driver heartbeats on HEARTBEAT at least once a second"},
        {"mobility.stop.idle_answer", "a STOP at rest is answered STOPPED with its command id"},
        {"mobility.arc.moving", "an ARC is answered MOVING with its command id"},
        {"mobility.arc.done", "an ARC ends DONE when the wheels have rolled its distance"},
        {"mobility.units.distance", "wheel_distance_m is metres: DONE reports the commanded distance (10 %)"},
        {"mobility.units.speed", "speed_mps is metres per rover second: the ARC takes distance / speed (30 %)"},
        {"mobility.turn.moving", "a TURN is answered MOVING with its command id"},
        {"mobility.turn.done", "a TURN ends DONE when the wheels have turned its angle"},
        {"mobility.units.turn", "wheel_turn_rad is radians: DONE reports the commanded angle (10 %)"},
        {"mobility.units.turn_rate", "turn_rate_rps is radians per rover second: the TURN takes angle / rate (30 %)"},
        {"mobility.stop.answer", "a STOP during a motion is answered STOPPED at once"},
        {"mobility.stop.stays", "after a STOP nothing moves: no MOVING, the wheel distance stands still"},
        {"mobility.deadman.alive", "a motion goes on while the commander heartbeats"},
        {"mobility.deadman.stop", "a motion stops, STOPPED, within the dead-man limit after the commander falls silent"},
        {"mobility.deadman.detail", "the dead-man's STOPPED status says dead-man in its detail"},
        {"mobility.bad.curvature", "an ARC beyond the curvature limit is refused FAULT, naming the value; nothing moves"},
        {"mobility.bad.speed", "a negative speed is refused FAULT; nothing moves"},
        {"mobility.bad.not_finite", "a NaN distance is refused FAULT or dropped (counted in the heartbeat); nothing moves"},
        {"mobility.bad.type", "an unknown command type is refused FAULT or dropped (counted); nothing moves"},
        {"mobility.auth.unsigned", "--key: with keys on, an unsigned command is not obeyed; nothing moves"},
        {"mobility.auth.wrong_key", "--key: with keys on, a command signed with another key is not obeyed; nothing moves"}}},
      {"imu",
       {{"imu.present", "IMU is published"},
        {"imu.fields", "finite rates and accelerations, a unit quaternion"},
        {"imu.rate", "at least the minimum rate, in rover time"},
        {"imu.gap", "no gap longer than three periods of the minimum rate"},
        {"imu.time.monotonic", "utimes strictly increase"},
        {"imu.time.near_clock", "utimes are within the tolerance of rover time"},
        {"imu.units.accel", "accel is m/s^2 of specific force: at rest its norm is gravity (10 %)"},
        {"imu.frame.gravity", "at rest accel is R^T (0, 0, -g) of the orientation (rover frame, Z down; w x y z)"},
        {"imu.units.rate", "angular_rate is rad/s: at rest below 0.05"},
        {"imu.frame.turn", "--drive: a clockwise turn reads a positive yaw rate and a growing yaw (Z down)"},
        {"imu.units.turn", "--drive: the integrated yaw rate agrees with the orientation's yaw change (30 %), that with the turn (50 %)"}}},
      {"wheel_odometry",
       {{"wheel_odometry.present", "WHEEL_ODOMETRY is published"},
        {"wheel_odometry.fields", "finite distances, 1 to 16 wheels, as many distances as wheels"},
        {"wheel_odometry.rate", "at least the minimum rate (8 Hz), in rover time"},
        {"wheel_odometry.gap", "no gap longer than three periods of the minimum rate"},
        {"wheel_odometry.time.monotonic", "utimes strictly increase"},
        {"wheel_odometry.time.near_clock", "utimes are within the tolerance of rover time"},
        {"wheel_odometry.at_rest", "at rest the cumulative distances stand still (1 mm)"},
        {"wheel_odometry.units.distance", "--drive: distance_m grows by the arc's distance in metres (10 %)"},
        {"wheel_odometry.frame.turn", "--drive: in a clockwise turn the left wheels roll forward, the right back, turning_in_place 1"}}},
      {"camera",
       {{"camera.answer", "every CAPTURE_REQUEST gets its STEREO_FRAME, or a heartbeat DEGRADED or FAULT naming the failure"},
        {"camera.frames", "at least one request gets a frame"},
        {"camera.once", "one frame per request"},
        {"camera.purpose", "the frame carries the request's purpose"},
        {"camera.fields", "camera models and encodings the bus accepts"},
        {"camera.size", "each image has its camera model's size (and the expected size when given)"},
        {"camera.pairing", "left and right of one size and encoding; the right camera to the right of the left"},
        {"camera.time.order", "frame utimes strictly increase"},
        {"camera.time.capture", "a frame's utime is between its request and its arrival, in rover time"},
        {"camera.time.pair", "the two images' exposure times (left_utime, right_utime) agree within the pairing tolerance"}}},
  };
  return contracts;
}

}  // namespace

const std::vector<std::string>& ContractNames() {
  static const std::vector<std::string> names = {"mobility", "imu", "wheel_odometry", "camera"};
  return names;
}

const std::vector<Rule>& RulesOf(const std::string& contract) {
  const auto it = Contracts().find(contract);
  if (it == Contracts().end()) {
    throw std::invalid_argument("no contract '" + contract + "' (expected mobility, imu, wheel_odometry or camera)");
  }
  return it->second;
}

std::string NeededOption(const std::string& contract, const std::string& rule) {
  for (const auto& r : RulesOf(contract)) {
    if (r.id != rule) continue;
    for (const char* option : {"--drive", "--key"})
      if (r.text.rfind(std::string(option) + ":", 0) == 0) return option;
  }
  return "";
}

std::string FailureLine(const Finding& f) { return "FAIL " + f.rule + ": expected " + f.expected + "; seen " + f.seen; }

void Report::Fail(const std::string& rule, const std::string& expected, const std::string& seen) {
  if (Failed(rule)) return;
  failures_.push_back({rule, expected, seen});
}

void Report::Pass(const std::string& rule) {
  if (!Passed(rule)) passed_.push_back(rule);
}

bool Report::Expect(bool ok, const std::string& rule, const std::string& expected, const std::string& seen) {
  if (ok) {
    Pass(rule);
  } else {
    Fail(rule, expected, seen);
  }
  return ok;
}

bool Report::Failed(const std::string& rule) const {
  return std::any_of(failures_.begin(), failures_.end(), [&](const Finding& f) { return f.rule == rule; });
}

bool Report::Passed(const std::string& rule) const {
  return !Failed(rule) && std::find(passed_.begin(), passed_.end(), rule) != passed_.end();
}

std::vector<std::string> Report::Unchecked(const std::string& contract) const {
  std::vector<std::string> out;
  for (const auto& r : RulesOf(contract))
    if (!Failed(r.id) && !Passed(r.id)) out.push_back(r.id);
  return out;
}

std::string Num(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*f", digits, v);
  return buf;
}

}  // namespace rover::conformance
