// The mobility dead-man: a motion in progress stops by itself when its commander goes
// silent, as flight mobility software does. A commander that dies mid-step (a crash, a
// kill -9, a packet that killed it) must not leave the wheels turning until the step ends.
//
// Evidence that the commander is alive: its heartbeat (once a wall second) and any
// mobility command. Time is the WALL clock in seconds (any monotonic
// origin): the guard is against a dead peer, and rover time may run 50x faster in
// simulation or stand still while the simulator holds its clock.
//
// It knows nothing of LCM or of the simulator: rover_sim and a real mobility driver feed
// it the same way (common/mobility/README.md, "The mobility interface").
#pragma once

#include "config/yaml_config.hpp"

#include <optional>
#include <string>

namespace rover::mobility {

struct DeadmanOptions {
  // Wall seconds of commander silence that stop a motion (`mobility.deadman_s`). The
  // commander's heartbeat comes once a wall second: 1.5 s stops the rover within 2 s of
  // the commander's death, and tolerates one heartbeat half a second late.
  double timeout_s = 1.5;
  // The process whose heartbeat counts (a heartbeat from anyone else does not).
  std::string commander = "sequence_executor";
};

inline constexpr double kMinDeadmanS = 0.2;
inline constexpr double kMaxDeadmanS = 60.0;

// Reads root["mobility"]["deadman_s"] (absent: the default) in [kMinDeadmanS, kMaxDeadmanS].
// Throws config::ConfigError naming the file and key.
DeadmanOptions LoadDeadmanOptions(const config::ConfigNode& root);

class Deadman {
 public:
  // Throws std::invalid_argument if timeout_s is outside [kMinDeadmanS, kMaxDeadmanS].
  explicit Deadman(DeadmanOptions options = {});

  // A heartbeat from `process` at wall time `wall_s`; counts only from the commander.
  void OnHeartbeat(const std::string& process, double wall_s);
  // Any other message from the commander: a mobility command.
  void OnCommanderMessage(double wall_s);

  // Call every loop of the mobility process, before it advances the motion, with whether
  // a motion is executing. Returns the detail to report with STOPPED when the motion must
  // stop now, else nothing. While no motion executes it never trips.
  std::optional<std::string> Check(bool moving, double wall_s) const;

  // Wall seconds since the commander was last heard (infinite before it ever was).
  double SilenceS(double wall_s) const;
  const DeadmanOptions& options() const { return options_; }

 private:
  DeadmanOptions options_;
  std::optional<double> last_heard_s_;
};

}  // namespace rover::mobility
