#include "bus/validate.hpp"

#include <cmath>
#include <initializer_list>

namespace rover::bus {

namespace {

// The first check that fails, in the order given.
std::string First(std::initializer_list<std::string> problems) {
  for (const auto& p : problems)
    if (!p.empty()) return p;
  return "";
}

std::string Finite(const char* field, const double* v, int n) {
  for (int i = 0; i < n; ++i)
    if (!std::isfinite(v[i])) {
      std::string where(field);
      if (n > 1) where.append("[").append(std::to_string(i)).append("]");
      return where.append(" is not finite");
    }
  return "";
}
std::string Finite(const char* field, double v) { return Finite(field, &v, 1); }

std::string Quaternion(const char* field, const double q[4]) {
  if (auto p = Finite(field, q, 4); !p.empty()) return p;
  const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  if (std::abs(n - 1.0) > 1e-3) return std::string(field) + " is not a unit quaternion (norm " + std::to_string(n) + ")";
  return "";
}

std::string Covariance(const char* field, const double c[6][6]) {
  for (int r = 0; r < 6; ++r) {
    if (auto p = Finite(field, c[r], 6); !p.empty()) return p;
    if (c[r][r] < 0) return std::string(field) + " has a negative variance";
  }
  return "";
}

template <class T>
std::string Enum(const char* field, T value, int first, int last) {
  if (value < first || value > last)
    return std::string(field) + " " + std::to_string(value) + " is unknown (expected " +
           std::to_string(first) + " to " + std::to_string(last) + ")";
  return "";
}

std::string NonNegative(const char* field, double v) {
  if (!(v >= 0)) return std::string(field) + " is negative";
  return "";
}

std::string CameraModel(const char* field, const rover_msgs::camera_model_t& c) {
  if (c.width <= 0 || c.height <= 0 || c.width > 65535 || c.height > 65535)
    return std::string(field) + " size " + std::to_string(c.width) + "x" + std::to_string(c.height) +
           " is out of range (expected 1 to 65535)";
  if (c.num_params < 0 || c.num_params > 64) return std::string(field) + ".num_params is out of range (expected 0 to 64)";
  return Finite(field, c.params.data(), c.num_params);
}

std::string Image(const char* field, const rover_msgs::image_t& img) {
  // The image's own size and encoding are checked against the camera model by the
  // receiver (common/imaging), which can say what it expected; here only the enum.
  return Enum(field, img.encoding, 0, 2);
}

}  // namespace

std::string Problem(const rover_msgs::capture_request_t& m) {
  if (m.purpose != "vo" && m.purpose != "vo_baseline" && m.purpose != "science" && m.purpose != "periodic" &&
      m.purpose != "look")
    return "purpose '" + m.purpose + "' is unknown (expected vo, vo_baseline, science, periodic or look)";
  if (const std::string p = First({Finite("pan_rad", m.pan_rad), Finite("tilt_rad", m.tilt_rad)}); !p.empty())
    return p;
  if (std::abs(m.pan_rad) > M_PI || std::abs(m.tilt_rad) > 0.5 * M_PI)
    return "pointing pan " + std::to_string(m.pan_rad) + " rad, tilt " + std::to_string(m.tilt_rad) +
           " rad is out of range (expected |pan| <= pi, |tilt| <= pi/2)";
  return "";
}

std::string Problem(const rover_msgs::hazard_query_t& m) {
  if (m.num_poses <= 0 || m.num_poses > 10000) return "num_poses is out of range (expected 1 to 10000)";
  return First({Finite("x", m.x.data(), m.num_poses), Finite("y", m.y.data(), m.num_poses),
                Finite("yaw", m.yaw.data(), m.num_poses), Finite("margin_m", m.margin_m),
                NonNegative("margin_m", m.margin_m)});
}

std::string Problem(const rover_msgs::hazard_reply_t& m) { return Enum("verdict", m.verdict, 0, 2); }

std::string Problem(const rover_msgs::traversability_map_t& m) {
  if (m.rows < 0 || m.cols < 0 || m.rows > 400 || m.cols > 400)
    return "size " + std::to_string(m.rows) + "x" + std::to_string(m.cols) + " is out of range (expected 0 to 400 a side)";
  if (m.num_cells != m.rows * m.cols)
    return "num_cells " + std::to_string(m.num_cells) + " is not rows x cols (" + std::to_string(m.rows * m.cols) + ")";
  if (!(m.cell_m > 0) || !std::isfinite(m.cell_m)) return "cell_m is not a finite value > 0";
  for (int k = 0; k < m.num_cells; ++k) {
    if (auto p = Enum("state", m.state[k], 0, 3); !p.empty()) return "cell " + std::to_string(k) + ": " + p;
    if (!std::isfinite(m.goodness[k]) || !std::isfinite(m.step_m[k]) || !std::isfinite(m.elevation_m[k]) ||
        !std::isfinite(m.sigma_m[k]))
      return "cell " + std::to_string(k) + " is not finite";
  }
  return First({Finite("origin_x", m.origin_x), Finite("origin_y", m.origin_y),
                Finite("footprint_length_m", m.footprint_length_m), Finite("footprint_width_m", m.footprint_width_m),
                Finite("footprint_center_forward_m", m.footprint_center_forward_m),
                Finite("blind_margin_m", m.blind_margin_m), NonNegative("blind_margin_m", m.blind_margin_m),
                Finite("max_unknown_fraction", m.max_unknown_fraction),
                NonNegative("max_unknown_fraction", m.max_unknown_fraction),
                Finite("hidden_patch_m", m.hidden_patch_m), NonNegative("hidden_patch_m", m.hidden_patch_m),
                Finite("max_scattered_unknown_fraction", m.max_scattered_unknown_fraction),
                NonNegative("max_scattered_unknown_fraction", m.max_scattered_unknown_fraction),
                Finite("max_driven_step_m", m.max_driven_step_m),
                NonNegative("max_driven_step_m", m.max_driven_step_m),
                Finite("caution_goodness", m.caution_goodness),
                m.caution_goodness >= 0.0 && m.caution_goodness <= 1.0
                    ? ""
                    : "caution_goodness " + std::to_string(m.caution_goodness) + " is out of range (expected 0 to 1)"});
}

std::string Problem(const rover_msgs::hazard_status_t& m) {
  return First({Enum("state", m.state, 0, 2), Finite("roll_rad", m.roll_rad), Finite("pitch_rad", m.pitch_rad)});
}

std::string Problem(const rover_msgs::heartbeat_t& m) {
  if (m.process.empty() || m.process.size() > 64) return "process name is empty or longer than 64 characters";
  return Enum("state", m.state, 0, 2);
}

std::string Problem(const rover_msgs::imu_t& m) {
  return First({Quaternion("orientation", m.orientation), Finite("angular_rate", m.angular_rate, 3),
                Finite("accel", m.accel, 3)});
}

std::string Problem(const rover_msgs::keepout_zones_t& m) {
  if (m.num_zones < 0 || m.num_zones > 1000) return "num_zones is out of range (expected 0 to 1000)";
  for (const auto& z : m.zones) {
    if (auto p = Enum("zone shape", z.shape, 0, 1); !p.empty()) return p;
    if (auto p = First({Finite("zone center", z.center, 2), Finite("zone radius_m", z.radius_m),
                        Finite("zone vertices_x", z.vertices_x.data(), z.num_vertices),
                        Finite("zone vertices_y", z.vertices_y.data(), z.num_vertices)});
        !p.empty())
      return "zone '" + z.name + "': " + p;
  }
  return "";
}

std::string Problem(const rover_msgs::mobility_command_t& m) {
  return First({Enum("type", m.type, 0, 2), Finite("distance_m", m.distance_m),
                Finite("curvature_per_m", m.curvature_per_m), Finite("turn_rad", m.turn_rad),
                Finite("speed_mps", m.speed_mps), Finite("turn_rate_rps", m.turn_rate_rps)});
}

std::string Problem(const rover_msgs::mobility_status_t& m) {
  return First({Enum("state", m.state, 0, 4), Finite("wheel_distance_m", m.wheel_distance_m),
                Finite("wheel_turn_rad", m.wheel_turn_rad)});
}

std::string Problem(const rover_msgs::new_site_t& m) {
  if (m.site_index < 0) return "site_index is negative";
  return "";
}

std::string Problem(const rover_msgs::pose_t& m) {
  return First({Finite("position", m.position, 3), Quaternion("orientation", m.orientation),
                Covariance("covariance", m.covariance), Enum("source", m.source, 0, 1),
                Finite("odometer_m", m.odometer_m)});
}

std::string Problem(const rover_msgs::rover_clock_t& m) {
  if (!(m.rate >= 0) || !std::isfinite(m.rate) || m.rate > 1e4)
    return "rate is out of range (expected 0, as fast as the barrier allows, to 10000)";
  if (m.n_cut < 0 || m.n_cut > 4096) return "n_cut is out of range (expected 0 to 4096 entries)";
  for (int i = 0; i < m.n_cut; ++i) {
    if (m.cut_count[static_cast<std::size_t>(i)] < 0) return "cut_count is negative (expected a message count)";
  }
  if (m.n_complete < 0 || m.n_complete > 4096)
    return "n_complete is out of range (expected 0 to 4096 publishers)";
  return Enum("mode", m.mode, 0, 1);
}

std::string Problem(const rover_msgs::sequence_control_t& m) { return Enum("action", m.action, 0, 2); }

std::string Problem(const rover_msgs::sequence_status_t& m) { return Enum("state", m.state, 0, 5); }

std::string Problem(const rover_msgs::sequence_submit_t& m) {
  if (m.name.size() > 4096) return "name is longer than 4096 characters";
  return "";
}

std::string Problem(const rover_msgs::sim_truth_t& m) {
  return First({Finite("position", m.position, 3), Quaternion("orientation", m.orientation),
                Finite("rpy", m.rpy, 3)});
}

std::string Problem(const rover_msgs::step_report_t& m) {
  if (m.vo_status < -1 || m.vo_status > 10) return "vo_status " + std::to_string(m.vo_status) + " is unknown";
  return Enum("choice", m.choice, 0, 2);
}

std::string Problem(const rover_msgs::stereo_frame_t& m) {
  return First({CameraModel("left_model", m.left_model), CameraModel("right_model", m.right_model),
                Image("left.encoding", m.left), Image("right.encoding", m.right),
                Problem(m.pose_at_capture).empty() ? "" : "pose_at_capture: " + Problem(m.pose_at_capture)});
}

std::string Problem(const rover_msgs::vo_update_t& m) {
  if (auto p = Enum("status", m.status, 0, 10); !p.empty()) return p;
  if (m.status != rover_msgs::vo_update_t::STATUS_OK) return "";
  return First({Finite("delta_position", m.delta_position, 3),
                Quaternion("delta_orientation", m.delta_orientation), Covariance("covariance", m.covariance)});
}

std::string Problem(const rover_msgs::wheel_odometry_t& m) {
  if (m.num_wheels < 0 || m.num_wheels > 16) return "num_wheels is out of range (expected 0 to 16)";
  return First({Finite("wheel_distance_m", m.wheel_distance_m.data(), m.num_wheels),
                Finite("distance_m", m.distance_m), Finite("curvature_per_m", m.curvature_per_m)});
}

}  // namespace rover::bus
