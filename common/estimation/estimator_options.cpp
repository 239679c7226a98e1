#include "estimation/estimator_options.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace rover::estimation {

namespace {

constexpr double kDeg = M_PI / 180.0;

void RequireRange(const char* name, double value, double lo, double hi) {
  if (!std::isfinite(value) || value < lo || value > hi) {
    std::ostringstream os;
    os << "EstimatorOptions." << name << " = " << value << ": expected a finite value in [" << lo
       << ", " << hi << "]";
    throw std::invalid_argument(os.str());
  }
}

}  // namespace

void EstimatorOptions::Validate() const {
  RequireRange("along_track_sigma_fraction", along_track_sigma_fraction, 0.0, 1.0);
  RequireRange("cross_track_sigma_fraction", cross_track_sigma_fraction, 0.0, 1.0);
  RequireRange("vertical_sigma_fraction", vertical_sigma_fraction, 0.0, 1.0);
  RequireRange("slip_memory_updates", slip_memory_updates, 0, 1000);
  RequireRange("slip_min_distance_m", slip_min_distance_m, 1e-3, 1e3);
  RequireRange("gyro_drift_rad_per_s", gyro_drift_rad_per_s, 0.0, 1.0);
  RequireRange("gyro_random_walk_rad_per_sqrt_s", gyro_random_walk_rad_per_sqrt_s, 0.0, 1.0);
  RequireRange("gyro_bias_walk_rad_per_s_per_sqrt_s", gyro_bias_walk_rad_per_s_per_sqrt_s, 0.0, 1.0);
  RequireRange("gyro_scale_sigma_fraction", gyro_scale_sigma_fraction, 0.0, 1.0);
  RequireRange("attitude_sigma_rad", attitude_sigma_rad, 0.0, M_PI);
  RequireRange("initial_position_sigma_m", initial_position_sigma_m, 0.0, 1e6);
  RequireRange("initial_yaw_sigma_rad", initial_yaw_sigma_rad, 0.0, M_PI);
  RequireRange("history_s", history_s, 1e-3, 1e7);
  RequireRange("history_max_samples", history_max_samples, 2, 1e8);
  RequireRange("vo_future_tolerance_s", vo_future_tolerance_s, 0.0, 3600.0);
  RequireRange("vo_yaw_sigma_factor", vo_yaw_sigma_factor, 1e-3, 1e3);
  RequireRange("vo_yaw_bias_sigma_rad_per_m", vo_yaw_bias_sigma_rad_per_m, 0.0, 0.1);
  RequireRange("vo_yaw_bias_length_m", vo_yaw_bias_length_m, 0.0, 1e6);
  RequireRange("zupt_settle_s", zupt_settle_s, 0.0, 3600.0);
  RequireRange("zupt_odometry_timeout_s", zupt_odometry_timeout_s, 1e-3, 3600.0);
  RequireRange("zupt_max_rate_rad_per_s", zupt_max_rate_rad_per_s, 0.0, 1.0);
  RequireRange("zupt_bias_segment_s", zupt_bias_segment_s, 1.0, 86400.0);
  RequireRange("zupt_yaw_reading_sigma_rad", zupt_yaw_reading_sigma_rad, 0.0, 0.1);
}

EstimatorOptions LoadEstimatorOptions(const config::ConfigNode& section,
                                      const std::vector<std::string>& extra_keys) {
  EstimatorOptions o;
  if (section.IsNull()) return o;
  std::vector<std::string> keys = {"along_track_sigma_pct",
                                   "cross_track_sigma_pct",
                                   "vertical_sigma_pct",
                                   "slip_memory_updates",
                                   "slip_min_distance_m",
                                   "gyro_drift_deg_per_hour",
                                   "gyro_scale_sigma_pct",
                                   "gyro_random_walk_deg_per_sqrt_hour",
                                   "gyro_bias_walk_deg_per_hour_per_sqrt_hour",
                                   "attitude_sigma_deg",
                                   "initial_position_sigma_m",
                                   "initial_yaw_sigma_deg",
                                   "history_s",
                                   "history_max_samples",
                                   "vo_heading",
                                   "vo_future_tolerance_s",
                                   "vo_yaw_sigma_factor",
                                   "vo_yaw_bias_sigma_deg_per_m",
                                   "vo_yaw_bias_length_m",
                                   "ignore_distance_while_turning_in_place",
                                   "zero_velocity_updates",
                                   "zupt_settle_s",
                                   "zupt_odometry_timeout_s",
                                   "zupt_max_rate_deg_s",
                                   "zupt_bias_segment_s",
                                   "zupt_yaw_reading_sigma_deg"};
  keys.insert(keys.end(), extra_keys.begin(), extra_keys.end());
  section.CheckKeys(keys);

  auto pct = [&](const char* key, double& fraction) {
    double v = fraction * 100.0;
    section.Get(key, v, 0.0, 100.0);
    fraction = v / 100.0;
  };
  pct("along_track_sigma_pct", o.along_track_sigma_fraction);
  pct("cross_track_sigma_pct", o.cross_track_sigma_fraction);
  pct("vertical_sigma_pct", o.vertical_sigma_fraction);
  pct("gyro_scale_sigma_pct", o.gyro_scale_sigma_fraction);

  double drift_deg_h = o.gyro_drift_rad_per_s / kDeg * 3600.0;
  section.Get("gyro_drift_deg_per_hour", drift_deg_h, 0.0, 3600.0);
  o.gyro_drift_rad_per_s = drift_deg_h * kDeg / 3600.0;

  // deg/sqrt(h) -> rad/sqrt(s): sqrt(3600 s) = 60.
  double arw = o.gyro_random_walk_rad_per_sqrt_s / kDeg * 60.0;
  section.Get("gyro_random_walk_deg_per_sqrt_hour", arw, 0.0, 3600.0);
  o.gyro_random_walk_rad_per_sqrt_s = arw * kDeg / 60.0;
  // deg/h/sqrt(h) -> rad/s/sqrt(s).
  double bias_walk = o.gyro_bias_walk_rad_per_s_per_sqrt_s / kDeg * 3600.0 * 60.0;
  section.Get("gyro_bias_walk_deg_per_hour_per_sqrt_hour", bias_walk, 0.0, 3600.0);
  o.gyro_bias_walk_rad_per_s_per_sqrt_s = bias_walk * kDeg / 3600.0 / 60.0;

  double att_deg = o.attitude_sigma_rad / kDeg;
  section.Get("attitude_sigma_deg", att_deg, 0.0, 180.0);
  o.attitude_sigma_rad = att_deg * kDeg;

  section.Get("initial_position_sigma_m", o.initial_position_sigma_m, 0.0, 1e6);
  double yaw0_deg = o.initial_yaw_sigma_rad / kDeg;
  section.Get("initial_yaw_sigma_deg", yaw0_deg, 0.0, 180.0);
  o.initial_yaw_sigma_rad = yaw0_deg * kDeg;

  section.Get("history_s", o.history_s, 1e-3, 1e7);
  section.Get("history_max_samples", o.history_max_samples, 2, 100000000);

  std::string mode = "fuse";
  section.GetEnum("vo_heading", mode, {"fuse", "replace", "ignore"});
  o.vo_heading = mode == "replace"  ? VoHeadingMode::kReplace
                 : mode == "ignore" ? VoHeadingMode::kIgnore
                                    : VoHeadingMode::kFuse;
  section.Get("vo_future_tolerance_s", o.vo_future_tolerance_s, 0.0, 3600.0);
  section.Get("vo_yaw_sigma_factor", o.vo_yaw_sigma_factor, 1e-3, 1e3);
  double vo_bias_deg_m = o.vo_yaw_bias_sigma_rad_per_m / kDeg;
  section.Get("vo_yaw_bias_sigma_deg_per_m", vo_bias_deg_m, 0.0, 5.0);
  o.vo_yaw_bias_sigma_rad_per_m = vo_bias_deg_m * kDeg;
  section.Get("vo_yaw_bias_length_m", o.vo_yaw_bias_length_m, 0.0, 1e6);
  section.Get("slip_memory_updates", o.slip_memory_updates, 0, 1000);
  section.Get("slip_min_distance_m", o.slip_min_distance_m, 1e-3, 1e3);
  section.Get("ignore_distance_while_turning_in_place", o.ignore_distance_while_turning_in_place);
  section.Get("zero_velocity_updates", o.zero_velocity_updates);
  section.Get("zupt_settle_s", o.zupt_settle_s, 0.0, 3600.0);
  section.Get("zupt_odometry_timeout_s", o.zupt_odometry_timeout_s, 1e-3, 3600.0);
  double zupt_rate_deg_s = o.zupt_max_rate_rad_per_s * 180.0 / M_PI;
  section.Get("zupt_max_rate_deg_s", zupt_rate_deg_s, 0.0, 57.0);
  o.zupt_max_rate_rad_per_s = zupt_rate_deg_s * M_PI / 180.0;
  section.Get("zupt_bias_segment_s", o.zupt_bias_segment_s, 1.0, 86400.0);
  double yaw_reading_deg = o.zupt_yaw_reading_sigma_rad * 180.0 / M_PI;
  section.Get("zupt_yaw_reading_sigma_deg", yaw_reading_deg, 0.0, 5.0);
  o.zupt_yaw_reading_sigma_rad = yaw_reading_deg * M_PI / 180.0;
  return o;
}

}  // namespace rover::estimation
