// What `./rover console` shows: one screen for the running drive, built from the latest
// message of each kind and redrawn in place. This part knows the messages but not the
// bus: main.cpp feeds it, the tests feed it directly.
//
//   sequence   name, submission, state, elapsed rover time, distance, VO failures
//   command    index/count, line, text; the step of a motion; the executor's detail line
//   steps      the last few STEP_REPORTs: commanded and measured motion, slip, VO or blind
//   VO         the last VO_UPDATE: status, frames, feature counts, time; reason on a failure
//   hazard     state, nearest zone and clearance, roll and pitch against their limits
//   zones      the keep-out zones in force (KEEPOUT_ZONES: the running sequence's; the
//              executor clears them when a sequence starts)
//   pose       x y z, roll pitch yaw, 1-sigma of position (largest horizontal axis), height
//              and heading from the covariance; source, site, odometer
//   processes  each heartbeat: state and detail, age (SILENT past 3 s), dropped messages
#pragma once

#include <rover_msgs/hazard_status_t.hpp>
#include <rover_msgs/heartbeat_t.hpp>
#include <rover_msgs/keepout_zones_t.hpp>
#include <rover_msgs/pose_t.hpp>
#include <rover_msgs/sequence_status_t.hpp>
#include <rover_msgs/step_report_t.hpp>
#include <rover_msgs/vo_update_t.hpp>

#include <deque>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace rover::console {

template <typename Msg>
struct Heard {
  Msg msg;
  double wall_s = 0;  // when it arrived (steady clock, seconds)
};

struct ConsoleState {
  std::optional<Heard<rover_msgs::sequence_status_t>> status;
  std::deque<Heard<rover_msgs::step_report_t>> steps;  // newest last
  std::optional<Heard<rover_msgs::vo_update_t>> vo;
  int vo_ok = 0, vo_failed = 0;  // updates heard (baselines are neither)
  std::optional<Heard<rover_msgs::hazard_status_t>> hazard;
  std::optional<Heard<rover_msgs::pose_t>> pose;
  std::optional<Heard<rover_msgs::keepout_zones_t>> zones;
  std::map<std::string, Heard<rover_msgs::heartbeat_t>> processes;
  std::int64_t rover_utime = 0;  // newest rover time in any message
  std::int64_t messages = 0;

  void On(const rover_msgs::sequence_status_t& m, double wall_s);
  void On(const rover_msgs::step_report_t& m, double wall_s);
  void On(const rover_msgs::vo_update_t& m, double wall_s);
  void On(const rover_msgs::hazard_status_t& m, double wall_s);
  void On(const rover_msgs::pose_t& m, double wall_s);
  void On(const rover_msgs::heartbeat_t& m, double wall_s);
  void On(const rover_msgs::keepout_zones_t& m, double wall_s);
};

struct FrameOptions {
  std::string bus_url;
  int recent_steps = 5;            // step reports shown
  double silent_after_s = 3.0;     // a heartbeat older than this: SILENT (the executor's timeout)
  double listened_s = 0;           // how long the console has listened (for "nothing heard")
};

// The screen, one string per line, without escapes or a trailing newline.
std::vector<std::string> RenderFrame(const ConsoleState& state, double wall_now_s, const FrameOptions& options);

}  // namespace rover::console
