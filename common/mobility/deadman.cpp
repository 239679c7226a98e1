#include "mobility/deadman.hpp"

#include <algorithm>
#include <cstdio>
#include <limits>
#include <stdexcept>

namespace rover::mobility {

DeadmanOptions LoadDeadmanOptions(const config::ConfigNode& root) {
  DeadmanOptions o;
  // The rest of `mobility:` is checked by MobilityOptions::Load.
  root["mobility"].Get("deadman_s", o.timeout_s, kMinDeadmanS, kMaxDeadmanS);
  return o;
}

Deadman::Deadman(DeadmanOptions options) : options_(std::move(options)) {
  if (!(options_.timeout_s >= kMinDeadmanS && options_.timeout_s <= kMaxDeadmanS)) {
    throw std::invalid_argument("dead-man timeout " + std::to_string(options_.timeout_s) +
                                " s is outside [0.2, 60] s");
  }
}

void Deadman::OnHeartbeat(const std::string& process, double wall_s) {
  if (process == options_.commander) OnCommanderMessage(wall_s);
}

void Deadman::OnCommanderMessage(double wall_s) {
  last_heard_s_ = last_heard_s_ ? std::max(*last_heard_s_, wall_s) : wall_s;
}

double Deadman::SilenceS(double wall_s) const {
  if (!last_heard_s_) return std::numeric_limits<double>::infinity();
  return wall_s - *last_heard_s_;
}

std::optional<std::string> Deadman::Check(bool moving, double wall_s) const {
  if (!moving) return std::nullopt;
  const double silence = SilenceS(wall_s);
  if (silence <= options_.timeout_s) return std::nullopt;
  char text[200];
  if (last_heard_s_) {
    std::snprintf(text, sizeof(text),
                  "dead-man: nothing from %s for %.1f s of wall time (limit %.1f s); stopped",
                  options_.commander.c_str(), silence, options_.timeout_s);
  } else {
    std::snprintf(text, sizeof(text),
                  "dead-man: nothing from %s within %.1f s of wall time; stopped",
                  options_.commander.c_str(), options_.timeout_s);
  }
  return std::string(text);
}

}  // namespace rover::mobility
