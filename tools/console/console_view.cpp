#include "console/console_view.hpp"

#include "sequence/executor.hpp"
#include "vo/visual_odometry.hpp"

#include <Eigen/Core>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace rover::console {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;
constexpr int kLabelWidth = 10;

// A number with `decimals` decimals; never "-0.0".
std::string Fixed(double v, int decimals) {
  if (std::abs(v) < 0.5 * std::pow(10.0, -decimals)) v = 0.0;
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

std::string Upper(std::string s) {
  for (char& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

std::string Pad(const std::string& s, std::size_t width) {
  return s.size() >= width ? s + " " : s + std::string(width - s.size(), ' ');
}

// "LABEL     text": every section starts at the same column.
std::string Line(const std::string& label, const std::string& text) { return Pad(label, kLabelWidth) + text; }

std::string Ago(double wall_now_s, double heard_s) { return Fixed(std::max(0.0, wall_now_s - heard_s), 1) + " s ago"; }

std::string SequenceStateName(int state) {
  return Upper(sequence::ToString(static_cast<sequence::SequenceState>(state)));
}

std::string VoStatusName(int status) {
  if (status < 0) return "none";
  return vo::ToString(static_cast<vo::VoStatus>(status));
}

// Whether a command drives (its steps mean something); settings and images have none.
bool IsMotionText(const std::string& text) {
  const auto parsed = sequence::ParseSequence(text, "status");
  return parsed.ok() && parsed.sequence.commands.size() == 1 && sequence::IsMotion(parsed.sequence.commands.front());
}

bool Finished(int state) {
  return state == rover_msgs::sequence_status_t::STATE_COMPLETED ||
         state == rover_msgs::sequence_status_t::STATE_ABORTED ||
         state == rover_msgs::sequence_status_t::STATE_REJECTED;
}

void SequenceLines(const ConsoleState& s, double now, const FrameOptions& o, std::vector<std::string>& out) {
  if (!s.status) {
    out.push_back(Line("SEQUENCE", "no SEQUENCE_STATUS heard in " + Fixed(o.listened_s, 1) +
                                       " s (is sequence_executor running on this bus?)"));
    return;
  }
  const auto& st = s.status->msg;
  std::string head = st.sequence_name.empty() ? "(no sequence)" : st.sequence_name;
  head += " (#" + std::to_string(st.submission_id) + ")  " + SequenceStateName(st.state);
  if (!st.abort_reason.empty()) head += ": " + st.abort_reason;
  head += "  t=" + Fixed(st.elapsed_s, 1) + " s  driven " + Fixed(st.distance_m, 2) + " m  VO failures " +
          std::to_string(st.vo_failures) + "   (" + Ago(now, s.status->wall_s) + ")";
  out.push_back(Line("SEQUENCE", head));
  // The command in force: while running, or where an abort stopped it.
  const bool at_command = st.command_index >= 0 && st.command_index < st.num_commands &&
                          (!Finished(st.state) || st.state == rover_msgs::sequence_status_t::STATE_ABORTED);
  const std::string command_line = "line " + std::to_string(st.command_line) + ": " + st.command_text;
  if (at_command) {
    out.push_back(Line("COMMAND", std::to_string(st.command_index + 1) + "/" + std::to_string(st.num_commands) +
                                      ", " + command_line +
                                      (IsMotionText(st.command_text) ? "   step " + std::to_string(st.step_index + 1) : "")));
  } else if (!Finished(st.state) && st.num_commands > 0) {
    out.push_back(Line("COMMAND", "waiting to start (" + std::to_string(st.num_commands) + " commands)"));
  }
  // The executor's line, unless it only repeats the command.
  if (!st.detail.empty() && !(at_command && st.detail == command_line)) out.push_back(Line("", st.detail));
}

void StepLines(const ConsoleState& s, int recent, std::vector<std::string>& out) {
  if (s.steps.empty()) {
    out.push_back(Line("STEPS", "no STEP_REPORT heard yet"));
    return;
  }
  out.push_back(Line("STEPS", "cmd.step  commanded          measured           slip     measured by"));
  const std::size_t first = s.steps.size() > static_cast<std::size_t>(std::max(0, recent))
                                ? s.steps.size() - static_cast<std::size_t>(std::max(0, recent))
                                : 0;
  for (std::size_t i = first; i < s.steps.size(); ++i) {
    const auto& r = s.steps[i].msg;
    const bool drove = std::abs(r.commanded_distance_m) > 1e-6;
    std::string by = r.vo_status == rover_msgs::vo_update_t::STATUS_OK ? "VO"
                     : r.vo_status < 0 ? "wheel odometry (VO off)"
                                       : "wheel odometry (VO " + VoStatusName(r.vo_status) + ")";
    out.push_back(Line("", Pad(std::to_string(r.command_index + 1) + "." + std::to_string(r.step_index + 1), 10) +
                               Pad(Fixed(r.commanded_distance_m, 3) + " m " + Fixed(r.commanded_turn_rad * kRadToDeg, 1) + " deg", 19) +
                               Pad(Fixed(r.estimated_distance_m, 3) + " m " + Fixed(r.estimated_turn_rad * kRadToDeg, 1) + " deg", 19) +
                               Pad(drove ? Fixed(r.slip_pct, 1) + " %" : "-", 9) + by));
  }
}

void VoLines(const ConsoleState& s, double now, std::vector<std::string>& out) {
  if (!s.vo) {
    out.push_back(Line("VO", "no VO_UPDATE heard yet"));
    return;
  }
  const auto& u = s.vo->msg;
  out.push_back(Line("VO", VoStatusName(u.status) + "  frames " + std::to_string(u.from_frame_id) + " -> " +
                               std::to_string(u.to_frame_id) + "  detected " + std::to_string(u.num_detected) +
                               "  matched " + std::to_string(u.num_matched) + "  tracked " +
                               std::to_string(u.num_tracked) + "  inliers " + std::to_string(u.num_inliers) + "  " +
                               Fixed(u.ms_total, 0) + " ms   (" + Ago(now, s.vo->wall_s) + "; " +
                               std::to_string(s.vo_ok) + " ok, " + std::to_string(s.vo_failed) + " failed)"));
  if (!u.reason.empty()) out.push_back(Line("", u.reason));
}

void HazardLines(const ConsoleState& s, double now, std::vector<std::string>& out) {
  if (!s.hazard) {
    out.push_back(Line("HAZARD", "no HAZARD_STATUS heard yet"));
    return;
  }
  const auto& h = s.hazard->msg;
  static const char* names[] = {"SAFE", "VIOLATION", "UNKNOWN (the rover stops)"};
  std::string text = h.state >= 0 && h.state <= 2 ? names[h.state] : "state " + std::to_string(h.state);
  if (h.keepout_violated) text += "  keep-out " + h.zone_name;
  if (h.tilt_violated) text += "  tilt";
  if (!h.zone_name.empty() && std::isfinite(h.min_clearance_m)) {
    text += "  nearest zone " + h.zone_name + " " + Fixed(h.min_clearance_m, 2) + " m";
  } else if (h.zone_name.empty()) {
    text += "  no keep-out zone";
  }
  text += "  roll " + Fixed(h.roll_rad * kRadToDeg, 1) + "/" + Fixed(h.roll_limit_rad * kRadToDeg, 0) + " deg  pitch " +
          Fixed(h.pitch_rad * kRadToDeg, 1) + "/" + Fixed(h.pitch_limit_rad * kRadToDeg, 0) + " deg   (" +
          Ago(now, s.hazard->wall_s) + ")";
  out.push_back(Line("HAZARD", text));
  if (!h.detail.empty()) out.push_back(Line("", h.detail));
}

// The set the executor last sent the hazard monitor (it replaces the previous one).
// KEEPOUT_ZONES is sent when the set changes, so a console started later has not heard it:
// then the hazard monitor's status (1 Hz) says whether it holds any, and the nearest.
void ZoneLines(const ConsoleState& s, std::vector<std::string>& out) {
  const std::string nearest = s.hazard ? s.hazard->msg.zone_name : "";
  if (!s.zones) {
    if (!s.hazard) {
      out.push_back(Line("ZONES", "no KEEPOUT_ZONES or HAZARD_STATUS heard yet"));
    } else if (nearest.empty()) {
      out.push_back(Line("ZONES", "none in force (the hazard monitor holds none)"));
    } else {
      out.push_back(Line("ZONES", "the hazard monitor holds zones, nearest " + nearest +
                                      " (the whole set shows when the executor next sends it)"));
    }
    return;
  }
  const auto& zones = s.zones->msg.zones;
  if (zones.empty()) {
    out.push_back(Line("ZONES", "none in force (a sequence's zones are cleared when the next one starts)" +
                                    (nearest.empty() ? std::string()
                                                     : "; the hazard monitor's own config adds zones, nearest " + nearest)));
    return;
  }
  std::string text = std::to_string(zones.size()) + " in force:";
  for (const auto& z : zones) {
    text += " " + z.name;
    if (z.shape == rover_msgs::keepout_zone_t::SHAPE_CIRCLE) {
      text += " (circle " + Fixed(z.center[0], 2) + " " + Fixed(z.center[1], 2) + " m r " + Fixed(z.radius_m, 2) + " m)";
    } else {
      text += " (polygon, " + std::to_string(z.num_vertices) + " vertices)";
    }
  }
  out.push_back(Line("ZONES", text));
}

void PoseLines(const ConsoleState& s, double now, std::vector<std::string>& out) {
  if (!s.pose) {
    out.push_back(Line("POSE", "no POSE heard yet"));
    return;
  }
  const auto& p = s.pose->msg;
  const Eigen::Quaterniond q(p.orientation[0], p.orientation[1], p.orientation[2], p.orientation[3]);
  const Eigen::Matrix3d R = q.normalized().toRotationMatrix();
  // R = Rz(yaw) Ry(pitch) Rx(roll) (geometry/pose.hpp).
  const double yaw = std::atan2(R(1, 0), R(0, 0));
  const double pitch = std::asin(std::clamp(-R(2, 0), -1.0, 1.0));
  const double roll = std::atan2(R(2, 1), R(2, 2));
  Eigen::Matrix2d xy;
  xy << p.covariance[0][0], p.covariance[0][1], p.covariance[1][0], p.covariance[1][1];
  const double sigma_xy =
      std::sqrt(std::max(0.0, Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(xy, Eigen::EigenvaluesOnly).eigenvalues().maxCoeff()));
  out.push_back(Line("POSE", "x " + Fixed(p.position[0], 3) + "  y " + Fixed(p.position[1], 3) + "  z " +
                                 Fixed(p.position[2], 3) + " m   roll " + Fixed(roll * kRadToDeg, 1) + "  pitch " +
                                 Fixed(pitch * kRadToDeg, 1) + "  yaw " + Fixed(yaw * kRadToDeg, 1) + " deg   (" +
                                 Ago(now, s.pose->wall_s) + ")"));
  out.push_back(Line("", "1-sigma: position " + Fixed(sigma_xy, 3) + " m, height " +
                             Fixed(std::sqrt(std::max(0.0, p.covariance[2][2])), 3) + " m, heading " +
                             Fixed(std::sqrt(std::max(0.0, p.covariance[5][5])) * kRadToDeg, 2) + " deg   source " +
                             (p.source == rover_msgs::pose_t::SOURCE_VO ? "VO" : "wheel+IMU") + ", site " +
                             std::to_string(p.site_index) + ", odometer " + Fixed(p.odometer_m, 2) + " m"));
}

void ProcessLines(const ConsoleState& s, double now, const FrameOptions& o, std::vector<std::string>& out) {
  if (s.processes.empty()) {
    out.push_back(Line("PROCESSES", "no HEARTBEAT heard in " + Fixed(o.listened_s, 1) + " s"));
    return;
  }
  out.push_back(Line("PROCESSES", Pad("name", 20) + Pad("state", 10) + Pad("heartbeat", 13) + Pad("dropped", 9) + "detail"));
  static const char* states[] = {"ok", "DEGRADED", "FAULT"};
  for (const auto& [name, h] : s.processes) {
    const bool silent = now - h.wall_s > o.silent_after_s;
    const int st = h.msg.state;
    const std::string state = silent ? "SILENT" : st >= 0 && st <= 2 ? states[st] : "state " + std::to_string(st);
    out.push_back(Line("", Pad(name, 20) + Pad(state, 10) + Pad(Ago(now, h.wall_s), 13) +
                               Pad(std::to_string(h.msg.dropped), 9) + h.msg.detail));
  }
}

}  // namespace

void ConsoleState::On(const rover_msgs::sequence_status_t& m, double wall_s) {
  status = Heard<rover_msgs::sequence_status_t>{m, wall_s};
  rover_utime = std::max(rover_utime, m.utime);
  ++messages;
}

void ConsoleState::On(const rover_msgs::step_report_t& m, double wall_s) {
  // A new submission starts a new list.
  if (!steps.empty() && steps.back().msg.submission_id != m.submission_id) steps.clear();
  steps.push_back({m, wall_s});
  while (steps.size() > 20) steps.pop_front();
  rover_utime = std::max(rover_utime, m.utime);
  ++messages;
}

void ConsoleState::On(const rover_msgs::vo_update_t& m, double wall_s) {
  vo = Heard<rover_msgs::vo_update_t>{m, wall_s};
  if (m.status == rover_msgs::vo_update_t::STATUS_OK) ++vo_ok;
  else if (m.status != rover_msgs::vo_update_t::STATUS_BASELINE) ++vo_failed;
  rover_utime = std::max(rover_utime, m.utime);
  ++messages;
}

void ConsoleState::On(const rover_msgs::hazard_status_t& m, double wall_s) {
  hazard = Heard<rover_msgs::hazard_status_t>{m, wall_s};
  rover_utime = std::max(rover_utime, m.utime);
  ++messages;
}

void ConsoleState::On(const rover_msgs::pose_t& m, double wall_s) {
  pose = Heard<rover_msgs::pose_t>{m, wall_s};
  rover_utime = std::max(rover_utime, m.utime);
  ++messages;
}

void ConsoleState::On(const rover_msgs::keepout_zones_t& m, double wall_s) {
  zones = Heard<rover_msgs::keepout_zones_t>{m, wall_s};
  rover_utime = std::max(rover_utime, m.utime);
  ++messages;
}

void ConsoleState::On(const rover_msgs::heartbeat_t& m, double wall_s) {
  processes[m.process] = {m, wall_s};
  ++messages;
}

std::vector<std::string> RenderFrame(const ConsoleState& s, double now, const FrameOptions& o) {
  std::vector<std::string> out;
  out.push_back("ROVER CONSOLE   bus " + (o.bus_url.empty() ? std::string("?") : o.bus_url) + "   rover time " +
                (s.rover_utime > 0 ? Fixed(s.rover_utime * 1e-6, 1) + " s" : std::string("unknown")) + "   " +
                std::to_string(s.messages) + " messages heard");
  out.push_back("");
  SequenceLines(s, now, o, out);
  out.push_back("");
  StepLines(s, o.recent_steps, out);  // the last few, oldest first
  out.push_back("");
  VoLines(s, now, out);
  HazardLines(s, now, out);
  ZoneLines(s, out);
  PoseLines(s, now, out);
  out.push_back("");
  ProcessLines(s, now, o, out);
  for (auto& line : out) line.erase(line.find_last_not_of(' ') + 1);
  return out;
}

}  // namespace rover::console
