// Options of the pose estimator (section `estimator:` of configs/rover.yaml).
// See estimator_example.yaml for a commented sample.
#pragma once

#include <string>
#include <vector>

#include "config/yaml_config.hpp"

namespace rover::estimation {

// What a VO update does to heading. MER's IMU drifted less than 3 deg/hour, so on Mars
// VO "was typically used to update rover position only" (Maimone 2005, sec. 1); the
// default fuses VO's yaw change with the gyro's, weighted by their variances, which
// reduces to "position only" when the gyro is far better and to "replace" when VO is.
enum class VoHeadingMode {
  kFuse,     // variance-weighted mean of the VO and gyro yaw changes over [from, to]
  kReplace,  // the VO yaw change replaces the gyro's over [from, to]
  kIgnore,   // heading stays with the IMU; VO corrects position only
};

struct EstimatorOptions {
  // Wheel-odometry error, 1-sigma as a fraction of the distance driven. Odometry errors are
  // mostly systematic (slip on one soil, wheel radius), so sigma grows linearly with
  // distance, not with its square root: 2 % of 10 m is 0.2 m whatever the step size.
  double along_track_sigma_fraction = 0.02;
  double cross_track_sigma_fraction = 0.02;
  // Along the rover's up axis (elevation): the IMU knows pitch well, so smaller.
  double vertical_sigma_fraction = 0.01;
  // Slip VO has measured raises the wheels' sigma. Each VO update over which the wheels
  // drove at least slip_min_distance_m measures their error along and across track, as a
  // fraction of that distance; the wheels' sigma fractions are then the larger of the ones
  // above and the worst of the last slip_memory_updates such measurements. Ground that slips
  // 15 % keeps slipping about as much on the next step, and a 2 % sigma there claims a
  // position several sigmas off between VO updates. 0: off.
  int slip_memory_updates = 3;
  double slip_min_distance_m = 0.1;

  // Gyro drift: the 1-sigma of the gyro's bias about the vertical before any VO (heading
  // sigma grows linearly with time until VO has measured the bias). MER's LN-200: < 3 deg/h.
  double gyro_drift_rad_per_s = 3.0 * 3.14159265358979323846 / 180.0 / 3600.0;
  // Angle random walk: white gyro noise, heading variance grows by arw^2 per second.
  double gyro_random_walk_rad_per_sqrt_s = 0.15 * 3.14159265358979323846 / 180.0 / 60.0;
  // Bias instability as a random walk of the bias: its variance grows by this^2 per second,
  // so a bias VO has measured is never believed to better than this allows.
  double gyro_bias_walk_rad_per_s_per_sqrt_s =
      0.5 * 3.14159265358979323846 / 180.0 / 3600.0 / 60.0;
  // Gyro scale-factor error: heading sigma grows by this fraction of each yaw change.
  double gyro_scale_sigma_fraction = 0.001;
  // Roll and pitch 1-sigma: the IMU levels itself on gravity, so this does not grow.
  double attitude_sigma_rad = 0.2 * 3.14159265358979323846 / 180.0;
  // Uncertainty at start and after Reset().
  double initial_position_sigma_m = 0.0;
  double initial_yaw_sigma_rad = 0.0;

  // Pose history kept for VO updates, in rover time not at rest and in samples (both
  // bound it).
  // A VO update whose `from` is older than the history is refused.
  double history_s = 600.0;
  int history_max_samples = 50000;

  VoHeadingMode vo_heading = VoHeadingMode::kFuse;
  // VO's yaw sigma as the estimator weighs it: VO's own (its covariance's yaw row and
  // column) times this factor. VO's yaw errors persist from step to step (a bias of a few
  // thousandths of a degree per step over a leg) while its covariance is of one step: summed
  // over 10 to 30 updates they were 1.1 to 1.6 times the sigma it claimed (README, "VO's yaw").
  double vo_yaw_sigma_factor = 1.0;
  // VO's yaw bias: a yaw error VO makes in proportion to the distance it measures (rad per
  // metre), a state of its own learnt against the gyro (README, "VO's yaw bias"): its
  // 1-sigma, and the distance over which it is correlated (a first-order Gauss-Markov
  // process in VO's travel; 0: one constant bias). sigma 0: no such state (VO's yaw errors
  // are taken as independent from step to step).
  double vo_yaw_bias_sigma_rad_per_m = 0.0;
  double vo_yaw_bias_length_m = 0.0;
  // A VO update whose `to` is at most this far after the latest IMU/odometry message is
  // applied at the latest message, as if the rover stood still since then (captures happen
  // with the rover stopped); further in the future it is refused (kToInFuture) and the
  // caller may retry it after more input. 0 = always wait for input past `to`.
  double vo_future_tolerance_s = 0.5;

  // At rest (zero-velocity update). A rover whose wheels have not turned for zupt_settle_s
  // (wheel odometry heard within zupt_odometry_timeout_s) and whose gyro reads under
  // zupt_max_rate_rad_per_s is standing still: its heading is held (the gyro's yaw drift is
  // not integrated) and neither heading nor position sigma grows, however long it stands
  // (a night). The drift it reads meanwhile measures the gyro's bias: every
  // zupt_bias_segment_s of rest is one measurement (its yaw change over its length, noise
  // arw^2/T + 2 zupt_yaw_reading_sigma^2/T^2), fused into the bias estimate and its sigma.
  // The wheels' word is the last odometry message's: an IMU sample newer than it is held
  // provisionally, and the next message decides (wheels still: it was rest; wheels turned:
  // its yaw was the start of the motion and is given back to the heading).
  bool zero_velocity_updates = true;
  double zupt_settle_s = 0.5;
  double zupt_odometry_timeout_s = 3.0;
  double zupt_max_rate_rad_per_s = 0.5 * 3.14159265358979323846 / 180.0;
  double zupt_bias_segment_s = 60.0;
  double zupt_yaw_reading_sigma_rad = 0.001 * 3.14159265358979323846 / 180.0;

  // During a turn in place the body does not travel; some encoders still report a
  // body distance. When true, that distance is not integrated into position.
  bool ignore_distance_while_turning_in_place = true;

  // Throws std::invalid_argument naming the field when a value is out of range.
  void Validate() const;
};

// Reads the `estimator:` section. Keys (all optional; defaults above):
//   along_track_sigma_pct, cross_track_sigma_pct, vertical_sigma_pct   (percent)
//   slip_memory_updates, slip_min_distance_m
//   gyro_drift_deg_per_hour, gyro_scale_sigma_pct, attitude_sigma_deg,
//   gyro_random_walk_deg_per_sqrt_hour, gyro_bias_walk_deg_per_hour_per_sqrt_hour
//   initial_position_sigma_m, initial_yaw_sigma_deg
//   history_s, history_max_samples
//   vo_heading: fuse | replace | ignore
//   vo_future_tolerance_s, vo_yaw_sigma_factor, ignore_distance_while_turning_in_place
//   vo_yaw_bias_sigma_deg_per_m, vo_yaw_bias_length_m
//   zero_velocity_updates, zupt_settle_s, zupt_odometry_timeout_s, zupt_max_rate_deg_s,
//   zupt_bias_segment_s, zupt_yaw_reading_sigma_deg
// `extra_keys` are keys the caller (the process shell) reads itself from the same section;
// any other key is rejected. Throws config::ConfigError naming file and key.
EstimatorOptions LoadEstimatorOptions(const config::ConfigNode& section,
                                      const std::vector<std::string>& extra_keys = {});

}  // namespace rover::estimation
