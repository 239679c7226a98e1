#include "sample_driver/sample_mobility.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace rover::sample_driver {

SampleMobility::SampleMobility(SampleMobilityOptions options) : options_(options) {}

Status SampleMobility::Set(State s, std::string detail) {
  status_.state = s;
  status_.detail = std::move(detail);
  return status_;
}

Status SampleMobility::Refuse(const Command& c, const std::string& why) {
  // The motion in progress, if any, goes on: a refused command changes nothing.
  Status s;
  s.command_id = c.id;
  s.state = State::kFault;
  s.detail = "command " + std::to_string(c.id) + " refused: " + why;
  return s;
}

std::vector<Status> SampleMobility::Execute(const Command& c) {
  std::ostringstream why;
  const double values[] = {c.distance_m, c.curvature_per_m, c.turn_rad, c.speed_mps, c.turn_rate_rps};
  const char* names[] = {"distance_m", "curvature_per_m", "turn_rad", "speed_mps", "turn_rate_rps"};
  for (int i = 0; i < 5; ++i)
    if (!std::isfinite(values[i])) why << names[i] << " is not finite";
  if (why.str().empty() && (c.type < 0 || c.type > 2)) why << "unknown type " << int{c.type} << " (expected 0 arc, 1 turn, 2 stop)";
  if (why.str().empty() && (c.speed_mps < 0 || c.speed_mps > options_.max_speed_mps)) {
    why << "speed_mps " << c.speed_mps << " is outside [0, " << options_.max_speed_mps << "]";
  }
  if (why.str().empty() && c.turn_rate_rps < 0) why << "turn_rate_rps " << c.turn_rate_rps << " is negative";
  if (why.str().empty() && c.type == 0 && std::abs(c.curvature_per_m) > options_.max_curvature_per_m) {
    why << "curvature_per_m " << c.curvature_per_m << " is beyond the limit " << options_.max_curvature_per_m;
  }
  if (!why.str().empty()) return {Refuse(c, why.str())};

  std::vector<Status> changes;
  if (moving()) {
    changes.push_back(Set(State::kStopped, (c.type == 2 ? "stopped by command " : "preempted by command ") +
                                               std::to_string(c.id)));
  }
  command_ = c;
  status_.command_id = c.id;
  status_.wheel_distance_m = 0;
  status_.wheel_turn_rad = 0;
  yaw_rate_rps_ = 0;
  switch (static_cast<CommandType>(c.type)) {
    case CommandType::kStop:
      target_ = 0;
      changes.push_back(Set(State::kStopped, "stop"));
      return changes;
    case CommandType::kArc:
      target_ = std::abs(c.distance_m);
      rate_ = c.speed_mps > 0 ? c.speed_mps : options_.speed_mps;
      break;
    case CommandType::kTurn:
      target_ = std::abs(c.turn_rad);
      rate_ = c.turn_rate_rps > 0 ? c.turn_rate_rps : options_.turn_rate_rps;
      break;
  }
  changes.push_back(target_ > 0 ? Set(State::kMoving, "") : Set(State::kDone, "nothing to do"));
  return changes;
}

std::optional<Status> SampleMobility::Advance(double dt_s) {
  if (!moving()) return std::nullopt;
  // A real driver: command the wheel speeds for this motion here, and read back the
  // encoders; this sample moves exactly as commanded.
  double& done = command_.type == 0 ? status_.wheel_distance_m : status_.wheel_turn_rad;
  const double step = std::min(rate_ * dt_s, target_ - done);
  done += step;
  if (command_.type == 0) {
    const double sign = command_.distance_m < 0 ? -1.0 : 1.0;
    // Each side rolls the body path scaled by its distance from the turn's centre.
    for (int w = 0; w < 6; ++w) {
      const double y = (w < 3 ? -0.5 : 0.5) * options_.track_m;
      wheels_[w] += sign * step * (1.0 - command_.curvature_per_m * y);
    }
    body_m_ += sign * step;
    yaw_rad_ += sign * step * command_.curvature_per_m;
    yaw_rate_rps_ = dt_s > 0 ? sign * step * command_.curvature_per_m / dt_s : 0.0;
  } else {
    const double sign = command_.turn_rad < 0 ? -1.0 : 1.0;
    // Clockwise (+): the left wheels roll forward, the right ones back.
    for (int w = 0; w < 6; ++w) wheels_[w] += (w < 3 ? 1.0 : -1.0) * sign * step * 0.5 * options_.track_m;
    yaw_rad_ += sign * step;
    yaw_rate_rps_ = dt_s > 0 ? sign * step / dt_s : 0.0;
  }
  if (done >= target_ - 1e-12) {
    yaw_rate_rps_ = 0;
    return Set(State::kDone, "");
  }
  return std::nullopt;
}

std::optional<Status> SampleMobility::Halt(const std::string& detail) {
  if (!moving()) return std::nullopt;
  yaw_rate_rps_ = 0;
  return Set(State::kStopped, detail);
}

}  // namespace rover::sample_driver
