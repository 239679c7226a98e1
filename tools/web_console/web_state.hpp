// What the web console shows, built from the latest message of each kind (the bus feeds
// it, the HTTP threads read it; every member function is thread-safe). Knows the messages
// but neither the bus nor HTTP, so tests feed it directly.
//
// StateJson() is the page's whole picture, one JSON object (the keys are listed in
// README "The web console"): the estimate with its 3-sigma position ellipse, truth in
// simulation, both paths, the traversability map, keep-out zones, the goal disc of a
// running goto, the sequence's text and current line, the last steps, VO, hazards and
// every process's heartbeat. LeftImagePng() is the newest NAVCAM left image, reduced.
#pragma once

#include <rover_msgs/hazard_status_t.hpp>
#include <rover_msgs/heartbeat_t.hpp>
#include <rover_msgs/keepout_zones_t.hpp>
#include <rover_msgs/pose_t.hpp>
#include <rover_msgs/sequence_status_t.hpp>
#include <rover_msgs/sequence_submit_t.hpp>
#include <rover_msgs/sim_truth_t.hpp>
#include <rover_msgs/step_report_t.hpp>
#include <rover_msgs/stereo_frame_t.hpp>
#include <rover_msgs/traversability_map_t.hpp>
#include <rover_msgs/vo_update_t.hpp>

#include <cstdint>
#include <deque>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace rover::web {

// The goal disc of a goto command line ("goto 5 m 3 m within 0.3 m ..."), if it is one.
struct GoalDisc {
  double x = 0, y = 0, radius = 0;
};
std::optional<GoalDisc> GoalOf(const std::string& command_text);

// The 3-sigma ellipse of a 2x2 position covariance (site x north, y east): semi-axes in
// metres, and the major axis's heading in degrees (0 north, 90 east).
struct Ellipse {
  double major_m = 0, minor_m = 0, heading_deg = 0;
};
Ellipse ThreeSigmaEllipse(double cxx, double cxy, double cyy);

// Where a playback of a log is (log_playback.hpp): the state's "playback" key.
struct PlaybackInfo {
  std::string log;
  std::int64_t first_utime = 0, last_utime = 0, at_utime = 0;
};

struct WebStateOptions {
  std::string bus_url;
  bool commands_enabled = false;  // an operator secret is configured
  bool signing = false;           // commands are signed with the deployment's key
  int recent_steps = 30;
  double silent_after_s = 3.0;    // a heartbeat older than this: silent
  std::size_t max_path_points = 4000;
};

class WebState {
 public:
  explicit WebState(WebStateOptions options) : options_(std::move(options)) {}

  // `wall_s`: when it arrived (steady clock, seconds).
  void On(const rover_msgs::pose_t& m, double wall_s);
  void On(const rover_msgs::sim_truth_t& m, double wall_s);
  void On(const rover_msgs::traversability_map_t& m, double wall_s);
  void On(const rover_msgs::keepout_zones_t& m, double wall_s);
  void On(const rover_msgs::sequence_status_t& m, double wall_s);
  void On(const rover_msgs::sequence_submit_t& m, double wall_s);
  void On(const rover_msgs::step_report_t& m, double wall_s);
  void On(const rover_msgs::vo_update_t& m, double wall_s);
  void On(const rover_msgs::hazard_status_t& m, double wall_s);
  void On(const rover_msgs::heartbeat_t& m, double wall_s);
  void On(const rover_msgs::stereo_frame_t& m, double wall_s);
  void OnRoverClock(std::int64_t utime);
  // Why the stack will refuse this console's commands (command_watch.hpp), once known:
  // the state's commands.key_problem, a banner on the page.
  void SetKeyProblem(std::string problem);

  // The whole picture as one JSON object; "playback" is null live, else `playback`.
  std::string StateJson(double wall_now_s, const PlaybackInfo* playback = nullptr) const;

  // The newest left image as a PNG at most `max_width` pixels wide (8-bit gray); empty
  // with `why` set when there is none or it cannot be decoded.
  std::string LeftImagePng(int max_width, std::string* why) const;

  std::int64_t messages() const;

 private:
  struct Point {
    double x, y;
  };
  static void AddToPath(std::vector<Point>& path, double x, double y, std::size_t max_points);

  WebStateOptions options_;
  mutable std::mutex mutex_;
  std::int64_t messages_ = 0;
  std::int64_t rover_utime_ = 0;
  std::string key_problem_;
  std::optional<rover_msgs::pose_t> pose_;
  std::vector<Point> pose_path_;
  std::int32_t pose_path_site_ = -1;
  std::optional<rover_msgs::sim_truth_t> truth_;
  std::vector<Point> truth_path_;
  std::optional<rover_msgs::traversability_map_t> map_;
  std::int64_t map_count_ = 0;
  std::optional<rover_msgs::keepout_zones_t> zones_;
  std::optional<rover_msgs::sequence_status_t> status_;
  std::deque<std::pair<std::int64_t, rover_msgs::sequence_submit_t>> submits_;  // id, newest last
  std::deque<rover_msgs::step_report_t> steps_;
  // Steps heard per submission (the newest few), for the step count of the sequence shown:
  // the table keeps only the last recent_steps.
  std::deque<std::pair<std::int64_t, int>> step_counts_;
  std::optional<rover_msgs::vo_update_t> vo_;
  int vo_ok_ = 0, vo_failed_ = 0;
  std::optional<rover_msgs::hazard_status_t> hazard_;
  std::map<std::string, std::pair<rover_msgs::heartbeat_t, double>> processes_;
  // The newest left image and the size its camera model says it has.
  std::optional<rover_msgs::image_t> left_;
  std::int64_t left_frame_id_ = -1, left_utime_ = 0;
  std::int64_t pair_skew_us_ = 0;  // right_utime - left_utime of that frame
  int left_model_width_ = 0, left_model_height_ = 0;
  std::string left_purpose_;
  // One cached PNG (frame id, width) -> bytes: every page asks for the same one.
  mutable std::int64_t png_frame_ = -1;
  mutable int png_width_ = 0;
  mutable std::string png_;
};

// "running", "paused", ... for sequence_status_t::state.
std::string SequenceStateName(int state);
// "ok", "too_few_features", ... for vo_update_t::status.
std::string VoStatusName(int status);

}  // namespace rover::web
