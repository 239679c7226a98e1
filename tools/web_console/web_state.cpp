#include "web_console/web_state.hpp"

#include "bus/image_view.hpp"
#include "imaging/image_check.hpp"
#include "report/json_writer.hpp"
#include "sequence/executor.hpp"
#include "sequence/parser.hpp"
#include "vo/visual_odometry.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <variant>

namespace rover::web {
namespace {

constexpr double kDeg = 180.0 / M_PI;

// A compact JSON emitter (the page parses it many times a second): key/value pairs are
// appended with a comma when needed. Numbers and strings as tools::JsonWriter writes them.
class Json {
 public:
  Json& Begin(char c) { Comma(); out_ += c; first_ = true; return *this; }
  Json& End(char c) { out_ += c; first_ = false; return *this; }
  Json& Key(const std::string& k) { Comma(); out_ += tools::JsonWriter::Quote(k) + ":"; first_ = true; return *this; }
  Json& Num(double v) { Comma(); out_ += tools::JsonWriter::Number(v); return *this; }
  Json& Int(long long v) { Comma(); out_ += std::to_string(v); return *this; }
  Json& Str(const std::string& s) { Comma(); out_ += tools::JsonWriter::Quote(s); return *this; }
  Json& Bool(bool b) { Comma(); out_ += b ? "true" : "false"; return *this; }
  Json& Null() { Comma(); out_ += "null"; return *this; }
  // A number with a fixed count of decimals (coordinates: millimetres).
  Json& Fixed(double v, int decimals) {
    Comma();
    if (!std::isfinite(v)) { out_ += "null"; return *this; }
    char buf[48];
    std::snprintf(buf, sizeof(buf), "%.*f", decimals, v);
    out_ += buf;
    return *this;
  }
  const std::string& str() const { return out_; }

 private:
  void Comma() {
    if (!first_) out_ += ',';
    first_ = false;
  }
  std::string out_;
  bool first_ = true;
};

// Roll, pitch, yaw (rad) of q = w x y z, R = Rz(yaw) Ry(pitch) Rx(roll).
void Euler(const double q[4], double* roll, double* pitch, double* yaw) {
  const double w = q[0], x = q[1], y = q[2], z = q[3];
  *roll = std::atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y));
  *pitch = std::asin(std::clamp(2 * (w * y - z * x), -1.0, 1.0));
  *yaw = std::atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z));
}

std::string HazardStateName(int s) {
  switch (s) {
    case rover_msgs::hazard_status_t::STATE_SAFE: return "safe";
    case rover_msgs::hazard_status_t::STATE_VIOLATION: return "violation";
    case rover_msgs::hazard_status_t::STATE_UNKNOWN: return "unknown";
    default: return "state " + std::to_string(s);
  }
}

std::string HealthName(int s) {
  switch (s) {
    case rover_msgs::heartbeat_t::STATE_OK: return "ok";
    case rover_msgs::heartbeat_t::STATE_DEGRADED: return "degraded";
    case rover_msgs::heartbeat_t::STATE_FAULT: return "fault";
    default: return "state " + std::to_string(s);
  }
}

}  // namespace

std::string SequenceStateName(int state) {
  if (state < 0 || state > 5) return "state " + std::to_string(state);
  return sequence::ToString(static_cast<sequence::SequenceState>(state));
}

std::string VoStatusName(int status) {
  if (status < 0) return "none";
  if (status > 10) return "status " + std::to_string(status);
  return vo::ToString(static_cast<vo::VoStatus>(status));
}

std::optional<GoalDisc> GoalOf(const std::string& command_text) {
  if (command_text.find("goto") == std::string::npos) return std::nullopt;
  const auto parsed = sequence::ParseSequence(command_text, "status");
  if (!parsed.ok() || parsed.sequence.commands.size() != 1) return std::nullopt;
  const auto* go = std::get_if<sequence::Goto>(&parsed.sequence.commands.front().action);
  if (go == nullptr) return std::nullopt;
  return GoalDisc{go->target.x(), go->target.y(), go->tolerance_m};
}

Ellipse ThreeSigmaEllipse(double cxx, double cxy, double cyy) {
  // Eigenvalues of the symmetric 2x2 matrix, in closed form.
  const double mean = 0.5 * (cxx + cyy);
  const double half_diff = 0.5 * (cxx - cyy);
  const double r = std::sqrt(half_diff * half_diff + cxy * cxy);
  const double l1 = std::max(0.0, mean + r), l2 = std::max(0.0, mean - r);
  Ellipse e;
  e.major_m = 3.0 * std::sqrt(l1);
  e.minor_m = 3.0 * std::sqrt(l2);
  // The major axis's direction: angle from x (north) toward y (east).
  e.heading_deg = 0.5 * std::atan2(2 * cxy, cxx - cyy) * kDeg;
  return e;
}

void WebState::AddToPath(std::vector<Point>& path, double x, double y, std::size_t max_points) {
  if (!path.empty() && std::hypot(path.back().x - x, path.back().y - y) < 0.02) return;
  if (path.size() >= max_points) {
    // Keep every other point of the older half: the path stays whole, coarser where old.
    std::vector<Point> thinned;
    const std::size_t half = path.size() / 2;
    for (std::size_t i = 0; i < half; i += 2) thinned.push_back(path[i]);
    thinned.insert(thinned.end(), path.begin() + static_cast<std::ptrdiff_t>(half), path.end());
    path.swap(thinned);
  }
  path.push_back({x, y});
}

void WebState::On(const rover_msgs::pose_t& m, double) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++messages_;
  rover_utime_ = std::max(rover_utime_, m.utime);
  if (m.site_index != pose_path_site_) pose_path_.clear();  // a new site frame: old points mean nothing
  pose_path_site_ = m.site_index;
  if (pose_ && m.utime < pose_->utime - 1000000) {  // the estimator restarted
    pose_path_.clear();
  }
  pose_ = m;
  AddToPath(pose_path_, m.position[0], m.position[1], options_.max_path_points);
}

void WebState::On(const rover_msgs::sim_truth_t& m, double) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++messages_;
  rover_utime_ = std::max(rover_utime_, m.utime);
  if (truth_ && m.utime < truth_->utime - 1000000) truth_path_.clear();
  truth_ = m;
  AddToPath(truth_path_, m.position[0], m.position[1], options_.max_path_points);
}

void WebState::On(const rover_msgs::traversability_map_t& m, double) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++messages_;
  map_ = m;
  ++map_count_;
}

void WebState::On(const rover_msgs::keepout_zones_t& m, double) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++messages_;
  zones_ = m;
}

void WebState::On(const rover_msgs::sequence_status_t& m, double) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++messages_;
  rover_utime_ = std::max(rover_utime_, m.utime);
  status_ = m;
}

void WebState::On(const rover_msgs::sequence_submit_t& m, double) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++messages_;
  submits_.emplace_back(m.submission_id, m);
  submits_.back().second.auth = {};
  while (submits_.size() > 8) submits_.pop_front();
}

void WebState::On(const rover_msgs::step_report_t& m, double) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++messages_;
  steps_.push_back(m);
  while (static_cast<int>(steps_.size()) > options_.recent_steps) steps_.pop_front();
  auto count = std::find_if(step_counts_.begin(), step_counts_.end(),
                            [&m](const auto& c) { return c.first == m.submission_id; });
  if (count != step_counts_.end()) {
    ++count->second;
  } else {
    step_counts_.emplace_back(m.submission_id, 1);
    while (step_counts_.size() > 8) step_counts_.pop_front();
  }
}

void WebState::On(const rover_msgs::vo_update_t& m, double) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++messages_;
  vo_ = m;
  if (m.status == rover_msgs::vo_update_t::STATUS_OK) {
    ++vo_ok_;
  } else if (m.status != rover_msgs::vo_update_t::STATUS_BASELINE) {
    ++vo_failed_;
  }
}

void WebState::On(const rover_msgs::hazard_status_t& m, double) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++messages_;
  hazard_ = m;
}

void WebState::On(const rover_msgs::heartbeat_t& m, double wall_s) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++messages_;
  processes_[m.process] = {m, wall_s};
}

void WebState::On(const rover_msgs::stereo_frame_t& m, double) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++messages_;
  left_ = m.left;
  left_frame_id_ = m.frame_id;
  left_utime_ = m.utime;
  pair_skew_us_ = m.right_utime - m.left_utime;
  left_model_width_ = m.left_model.width;
  left_model_height_ = m.left_model.height;
  left_purpose_ = m.purpose;
}

void WebState::OnRoverClock(std::int64_t utime) {
  std::lock_guard<std::mutex> lock(mutex_);
  rover_utime_ = std::max(rover_utime_, utime);
}

void WebState::SetKeyProblem(std::string problem) {
  std::lock_guard<std::mutex> lock(mutex_);
  key_problem_ = std::move(problem);
}

std::int64_t WebState::messages() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return messages_;
}

std::string WebState::LeftImagePng(int max_width, std::string* why) const {
  rover_msgs::image_t image;
  std::int64_t frame_id = 0;
  int model_w = 0, model_h = 0;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!left_) {
      *why = "no STEREO_FRAME heard yet";
      return "";
    }
    if (png_frame_ == left_frame_id_ && png_width_ == max_width) return png_;
    image = *left_;
    frame_id = left_frame_id_;
    model_w = left_model_width_;
    model_h = left_model_height_;
  }
  // Decoding and encoding happen outside the lock: the bus thread goes on meanwhile.
  cv::Mat decoded;
  if (std::string bad = imaging::DecodeCheckedImage(bus::ImageViewOf(image), model_w, model_h,
                                                    imaging::ImageLimits{}, decoded);
      !bad.empty()) {
    *why = "frame " + std::to_string(frame_id) + ": left image: " + bad;
    return "";
  }
  cv::Mat gray8;
  if (decoded.depth() == CV_16U) {
    decoded.convertTo(gray8, CV_8U, 1.0 / 256.0);
  } else {
    gray8 = decoded;
  }
  if (gray8.cols > max_width) {
    const int h = std::max(1, static_cast<int>(std::lround(gray8.rows * double(max_width) / gray8.cols)));
    cv::Mat small;
    cv::resize(gray8, small, cv::Size(max_width, h), 0, 0, cv::INTER_AREA);
    gray8 = small;
  }
  std::vector<unsigned char> png;
  if (!cv::imencode(".png", gray8, png)) {
    *why = "frame " + std::to_string(frame_id) + ": PNG encoding failed";
    return "";
  }
  std::string bytes(png.begin(), png.end());
  std::lock_guard<std::mutex> lock(mutex_);
  png_frame_ = frame_id;
  png_width_ = max_width;
  png_ = bytes;
  return bytes;
}

std::string WebState::StateJson(double wall_now_s, const PlaybackInfo* playback) const {
  std::lock_guard<std::mutex> lock(mutex_);
  Json j;
  j.Begin('{');
  j.Key("bus").Str(options_.bus_url);
  j.Key("messages").Int(messages_);
  j.Key("rover_time_s").Num(rover_utime_ * 1e-6);
  j.Key("commands").Begin('{');
  j.Key("enabled").Bool(options_.commands_enabled);
  j.Key("signed").Bool(options_.signing);
  j.Key("key_problem").Str(key_problem_);
  j.End('}');
  j.Key("playback");
  if (playback != nullptr) {
    j.Begin('{').Key("log").Str(playback->log);
    j.Key("first_s").Fixed(playback->first_utime * 1e-6, 6).Key("last_s").Fixed(playback->last_utime * 1e-6, 6);
    j.Key("at_s").Fixed(playback->at_utime * 1e-6, 6).End('}');
  } else {
    j.Null();
  }

  j.Key("pose");
  if (pose_) {
    const auto& p = *pose_;
    double roll, pitch, yaw;
    Euler(p.orientation, &roll, &pitch, &yaw);
    const Ellipse e = ThreeSigmaEllipse(p.covariance[0][0], p.covariance[0][1], p.covariance[1][1]);
    j.Begin('{');
    j.Key("utime").Int(p.utime);
    j.Key("x").Fixed(p.position[0], 4).Key("y").Fixed(p.position[1], 4).Key("z").Fixed(p.position[2], 4);
    j.Key("roll_deg").Fixed(roll * kDeg, 3).Key("pitch_deg").Fixed(pitch * kDeg, 3).Key("yaw_deg").Fixed(yaw * kDeg, 3);
    j.Key("sigma_x_m").Num(std::sqrt(std::max(0.0, p.covariance[0][0])));
    j.Key("sigma_y_m").Num(std::sqrt(std::max(0.0, p.covariance[1][1])));
    j.Key("sigma_z_m").Num(std::sqrt(std::max(0.0, p.covariance[2][2])));
    j.Key("sigma_yaw_deg").Num(std::sqrt(std::max(0.0, p.covariance[5][5])) * kDeg);
    j.Key("ellipse_3sigma").Begin('{');
    j.Key("major_m").Num(e.major_m).Key("minor_m").Num(e.minor_m).Key("heading_deg").Num(e.heading_deg);
    j.End('}');
    j.Key("source").Str(p.source == rover_msgs::pose_t::SOURCE_VO ? "vo" : "wheel_imu");
    j.Key("site").Int(p.site_index);
    j.Key("odometer_m").Num(p.odometer_m);
    j.End('}');
  } else {
    j.Null();
  }

  j.Key("truth");
  if (truth_) {
    const auto& t = *truth_;
    j.Begin('{');
    j.Key("utime").Int(t.utime);
    j.Key("x").Fixed(t.position[0], 4).Key("y").Fixed(t.position[1], 4).Key("z").Fixed(t.position[2], 4);
    j.Key("roll_deg").Fixed(t.rpy[0] * kDeg, 3).Key("pitch_deg").Fixed(t.rpy[1] * kDeg, 3);
    j.Key("yaw_deg").Fixed(t.rpy[2] * kDeg, 3);
    j.Key("slip").Num(t.slip).Key("soil").Str(t.soil).Key("odometer_m").Num(t.odometer_m);
    j.End('}');
  } else {
    j.Null();
  }

  auto path = [&j](const std::vector<Point>& pts) {
    j.Begin('[');
    for (const auto& p : pts) j.Fixed(p.x, 3).Fixed(p.y, 3);
    j.End(']');
  };
  j.Key("path");
  path(pose_path_);
  j.Key("truth_path");
  path(truth_path_);

  j.Key("map");
  if (map_) {
    const auto& m = *map_;
    std::string cells(static_cast<std::size_t>(std::max(0, m.num_cells)), '0');
    int counts[4] = {0, 0, 0, 0};
    for (int k = 0; k < m.num_cells; ++k) {
      const int s = std::clamp<int>(m.state[k], 0, 3);
      cells[k] = static_cast<char>('0' + s);
      ++counts[s];
    }
    j.Begin('{');
    j.Key("count").Int(map_count_);
    j.Key("utime").Int(m.utime);
    j.Key("last_frame_id").Int(m.last_frame_id);
    j.Key("origin_x").Fixed(m.origin_x, 4).Key("origin_y").Fixed(m.origin_y, 4).Key("cell_m").Num(m.cell_m);
    j.Key("rows").Int(m.rows).Key("cols").Int(m.cols);
    j.Key("unknown").Int(counts[0]).Key("safe").Int(counts[1]).Key("caution").Int(counts[2]).Key("unsafe").Int(counts[3]);
    j.Key("cells").Str(cells);  // row-major, index i*cols + j: 0 unknown, 1 safe, 2 caution, 3 unsafe
    j.End('}');
  } else {
    j.Null();
  }

  j.Key("zones").Begin('[');
  if (zones_) {
    for (const auto& z : zones_->zones) {
      j.Begin('{');
      j.Key("name").Str(z.name);
      if (z.shape == rover_msgs::keepout_zone_t::SHAPE_CIRCLE) {
        j.Key("shape").Str("circle");
        j.Key("x").Fixed(z.center[0], 4).Key("y").Fixed(z.center[1], 4).Key("radius_m").Num(z.radius_m);
      } else {
        j.Key("shape").Str("polygon");
        j.Key("vertices").Begin('[');
        for (int k = 0; k < z.num_vertices; ++k) j.Fixed(z.vertices_x[k], 4).Fixed(z.vertices_y[k], 4);
        j.End(']');
      }
      j.End('}');
    }
  }
  j.End(']');

  j.Key("status");
  const rover_msgs::sequence_submit_t* submit = nullptr;
  if (status_) {
    const auto& s = *status_;
    for (const auto& [id, m] : submits_)
      if (id == s.submission_id) submit = &m;
    j.Begin('{');
    j.Key("submission_id").Int(s.submission_id);
    j.Key("name").Str(s.sequence_name);
    j.Key("state").Str(SequenceStateName(s.state));
    j.Key("num_commands").Int(s.num_commands).Key("command_index").Int(s.command_index);
    j.Key("command_line").Int(s.command_line).Key("command_text").Str(s.command_text);
    j.Key("step_index").Int(s.step_index);
    j.Key("abort_reason").Str(s.abort_reason).Key("detail").Str(s.detail);
    j.Key("elapsed_s").Num(s.elapsed_s).Key("distance_m").Num(s.distance_m).Key("vo_failures").Int(s.vo_failures);
    j.End('}');
  } else {
    j.Null();
  }
  // The sequence's text, when this console heard it submitted (from any operator).
  j.Key("sequence_text");
  if (submit != nullptr) {
    j.Str(submit->text);
  } else {
    j.Null();
  }
  j.Key("goal");
  if (const auto goal = status_ ? GoalOf(status_->command_text) : std::nullopt; goal) {
    j.Begin('{').Key("x").Fixed(goal->x, 4).Key("y").Fixed(goal->y, 4).Key("radius_m").Num(goal->radius).End('}');
  } else {
    j.Null();
  }

  // Every step heard for the sequence in the status (the table below keeps the last few).
  int step_count = 0;
  for (const auto& [id, n] : step_counts_)
    if (status_ && id == status_->submission_id) step_count = n;
  j.Key("step_count").Int(step_count);
  // The table is the sequence in the status's: an earlier sequence's steps are not this one's.
  j.Key("steps").Begin('[');
  for (const auto& s : steps_) {
    if (status_ && s.submission_id != status_->submission_id) continue;
    j.Begin('{');
    j.Key("submission_id").Int(s.submission_id);
    j.Key("command_index").Int(s.command_index).Key("step_index").Int(s.step_index);
    j.Key("commanded_m").Num(s.commanded_distance_m).Key("commanded_deg").Num(s.commanded_turn_rad * kDeg);
    j.Key("measured_m").Num(s.estimated_distance_m).Key("measured_deg").Num(s.estimated_turn_rad * kDeg);
    j.Key("slip_pct").Num(s.slip_pct);
    j.Key("vo").Str(s.vo_status < 0 ? "blind" : VoStatusName(s.vo_status));
    j.Key("choice").Str(s.choice >= 0 && s.choice <= 2 ? sequence::ToString(static_cast<sequence::StepChoice>(s.choice))
                                                      : "choice " + std::to_string(s.choice));
    j.End('}');
  }
  j.End(']');

  j.Key("vo");
  if (vo_) {
    const auto& v = *vo_;
    j.Begin('{');
    j.Key("status").Str(VoStatusName(v.status)).Key("reason").Str(v.reason);
    j.Key("from_frame").Int(v.from_frame_id).Key("to_frame").Int(v.to_frame_id);
    j.Key("detected").Int(v.num_detected).Key("matched").Int(v.num_matched);
    j.Key("tracked").Int(v.num_tracked).Key("inliers").Int(v.num_inliers);
    j.Key("ms_total").Num(v.ms_total);
    j.Key("ok").Int(vo_ok_).Key("failed").Int(vo_failed_);
    j.End('}');
  } else {
    j.Null();
  }

  j.Key("hazard");
  if (hazard_) {
    const auto& h = *hazard_;
    j.Begin('{');
    j.Key("state").Str(HazardStateName(h.state));
    j.Key("keepout_violated").Bool(h.keepout_violated != 0).Key("tilt_violated").Bool(h.tilt_violated != 0);
    j.Key("zone").Str(h.zone_name).Key("clearance_m").Num(h.min_clearance_m);
    j.Key("roll_deg").Num(h.roll_rad * kDeg).Key("pitch_deg").Num(h.pitch_rad * kDeg);
    j.Key("roll_limit_deg").Num(h.roll_limit_rad * kDeg).Key("pitch_limit_deg").Num(h.pitch_limit_rad * kDeg);
    j.Key("detail").Str(h.detail);
    j.End('}');
  } else {
    j.Null();
  }

  j.Key("processes").Begin('[');
  for (const auto& [name, heard] : processes_) {
    const double age = std::max(0.0, wall_now_s - heard.second);
    j.Begin('{');
    j.Key("name").Str(name);
    j.Key("state").Str(age > options_.silent_after_s ? "silent" : HealthName(heard.first.state));
    j.Key("age_s").Num(age).Key("dropped").Int(heard.first.dropped).Key("detail").Str(heard.first.detail);
    j.End('}');
  }
  j.End(']');

  j.Key("image");
  if (left_) {
    j.Begin('{').Key("frame_id").Int(left_frame_id_).Key("utime").Int(left_utime_);
    j.Key("width").Int(left_->width).Key("height").Int(left_->height).Key("pair_skew_us").Int(pair_skew_us_);
    j.Key("encoding").Str(imaging::EncodingName(left_->encoding)).Key("purpose").Str(left_purpose_).End('}');
  } else {
    j.Null();
  }
  j.End('}');
  return j.str();
}

}  // namespace rover::web
