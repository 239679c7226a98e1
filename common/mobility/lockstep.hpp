// Lockstep between the simulated rover's clock and the state estimator (rover_sim).
//
// Faster than real time, a consumer that stalls for a moment on a busy computer would see
// its inputs age by (stall x rate): at 50x, 2 s of pose age is 40 ms of wall time. So the
// clock runs at most `max_lead_s` of rover time ahead of the latest POSE, and waits for
// the estimator, but only for a live estimator that has posed since it (re)started: a
// dead one (no heartbeat for `alive_s` of wall time) is left to the executor's heartbeat
// check, and a restarted one needs the clock to run before it can pose at all.
#pragma once

#include <cstdint>
#include <string>

namespace rover::mobility {

class EstimatorLockstep {
 public:
  EstimatorLockstep(double max_lead_s, double alive_s) : max_lead_s_(max_lead_s), alive_s_(alive_s) {}

  void OnHeartbeat(const std::string& process, std::int64_t seq, double wall_s) {
    if (process != "state_estimator") return;
    if (seq < last_seq_) posed_since_start_ = false;  // restarted: its count began again
    last_seq_ = seq;
    last_heartbeat_wall_s_ = wall_s;
    heard_ = true;
  }

  void OnPose(std::int64_t utime) {
    if (!posed_since_start_ || utime > last_pose_utime_) last_pose_utime_ = utime;
    posed_since_start_ = true;
  }

  // Whether the clock at `sim_utime` should wait for the estimator now.
  bool ShouldWait(std::int64_t sim_utime, double wall_s) const {
    if (max_lead_s_ <= 0 || !posed_since_start_) return false;
    if (heard_ && wall_s - last_heartbeat_wall_s_ > alive_s_) return false;
    return static_cast<double>(sim_utime - last_pose_utime_) > max_lead_s_ * 1e6;
  }

 private:
  double max_lead_s_;
  double alive_s_;
  std::int64_t last_pose_utime_ = 0;
  std::int64_t last_seq_ = -1;
  double last_heartbeat_wall_s_ = 0;
  bool heard_ = false;
  bool posed_since_start_ = false;
};

}  // namespace rover::mobility
