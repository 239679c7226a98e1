// Rover geometry, slip model and sensor options for the simulated rover.
//
// Loaded from the `mobility:` and `sensors:` sections of configs/rover.yaml; other
// sections of that file belong to other modules and are not read here. Every key and
// default is listed in common/mobility/README.md.
#pragma once

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "config/yaml_config.hpp"
#include "terrain/world.hpp"

namespace rover::mobility {

inline constexpr int kNumWheels = 6;
// Wheel indices; the same order in every per-wheel array and in wheel_odometry_t.
enum Wheel : int {
  kLeftFront = 0,
  kLeftMiddle = 1,
  kLeftRear = 2,
  kRightFront = 3,
  kRightMiddle = 4,
  kRightRear = 5,
};
const char* WheelName(int wheel);  // "left_front", ...
// Throws std::invalid_argument naming the word.
int WheelFromName(const std::string& name);

// MER-like six-wheel rocker-bogie. Wheels sit at x = +wheelbase/2, 0, -wheelbase/2 and
// y = -track/2 (left), +track/2 (right) in the rover frame (X forward, Y right, Z down).
// The rover frame origin is origin_height_m above the centre of the wheel contact plane,
// along its normal.
struct RoverGeometry {
  double wheelbase_m = 1.1;   // front axle to rear axle
  double track_m = 1.0;       // left wheel centre to right wheel centre
  double wheel_radius_m = 0.125;
  double footprint_length_m = 1.6;  // body outline for keep-out, centred on the origin
  double footprint_width_m = 1.4;
  double origin_height_m = 0.0;
  double speed_mps = 0.04;                   // default drive speed (MER: about 4 cm/s)
  double turn_rate_rps = 3.0 * M_PI / 180.0;  // default turn-in-place rate
  double max_curvature_per_m = 4.0;          // tightest arc accepted (1 / radius)

  // Wheel contact point (x forward, y right) in the rover frame.
  Eigen::Vector2d WheelPosition(int wheel) const;
};

// Piecewise linear through (x, y) points sorted by x, constant beyond the ends; 0 when
// empty. The slip tables below.
double Interpolate(const std::vector<Eigen::Vector2d>& table, double x);

// Slip on one soil. Longitudinal slip s = 1 - (true motion along the heading) / (wheel
// rolled distance): 0 = no slip, 1 = wheels spin in place, > 1 = the rover slides back
// while the wheels drive forward (Sol 206), < 0 = it runs ahead of its wheels downhill.
struct SoilSlip {
  // (pitch along the direction of travel in deg, + = uphill; slip) points, sorted by
  // pitch; linear in between, constant beyond the ends.
  std::vector<Eigen::Vector2d> slip_vs_pitch;
  // Sideways slip: drift downslope per metre rolled (the tangent of the crab angle) at a
  // cross slope in deg. Either (cross slope deg, drift) points, sorted, linear in between
  // and constant beyond the last (loose soil crabs more and more steeply toward its angle
  // of repose), or, when the table is empty, drift_per_deg x the cross slope.
  std::vector<Eigen::Vector2d> drift_vs_cross_slope;
  double drift_per_deg = 0.0;
  // Fraction of a commanded turn in place that is lost.
  double turn_slip = 0.0;
  // Standard deviation of the slowly varying slip noise (fraction).
  double noise_std = 0.0;

  // Drift downslope per metre rolled at this cross slope (deg, either sign).
  double DriftAt(double cross_slope_deg) const;
};

// One wheel that does not turn and is dragged (Spirit's right front wheel).
struct DraggedWheel {
  int wheel = -1;  // -1 = none
  // kZero: the wheel's encoder reads no motion. kCommanded: it reads the commanded motion
  // (the motor turns, the wheel skids).
  enum class Encoder { kZero, kCommanded } encoder = Encoder::kZero;
  double extra_slip = 0.08;  // added to longitudinal slip while driving
  double yaw_per_m = 0.02;   // rad of yaw toward the dragged side per metre rolled
};

struct SlipOptions {
  std::array<SoilSlip, terrain::kNumSoils> soils;  // indexed by terrain::Soil
  double noise_time_s = 5.0;  // correlation time of the slip noise
  // Rocks under the wheels. A wheel climbing a rock must be lifted by the traction of
  // all six: its climb grade (the rise of the rock over one wheel radius ahead, capped at
  // 3) x rock_climb_grade / 6 adds to the grade the rover drives up, and the slip is read
  // from each wheel's soil table at that steeper grade. On loose sand two wheels on cobble
  // faces stall the rover (the MER testbed rock course reached 85 %); on packed soil and
  // rock the same cobbles cost little. Rocks stall the rover but never push it back: the
  // slip they add stops at rock_stall_slip.
  double rock_climb_grade = 0.8;
  double rock_stall_slip = 0.85;
  DraggedWheel dragged;
  SlipOptions();  // MER-like defaults per soil (see mobility_options.cpp)
  const SoilSlip& For(terrain::Soil s) const { return soils[static_cast<int>(s)]; }
  SoilSlip& For(terrain::Soil s) { return soils[static_cast<int>(s)]; }
};

struct ImuOptions {
  double rate_hz = 20.0;
  // Gyro bias about the vertical: the attitude's yaw drifts this much per hour.
  double yaw_drift_deg_per_hour = 3.0;
  double yaw_random_walk_deg_per_sqrt_hour = 0.15;  // angle random walk on yaw
  double tilt_noise_deg = 0.03;    // white noise on roll and pitch (from gravity)
  double rate_noise_deg_s = 0.02;  // white noise on the angular rates
  double accel_noise_mps2 = 0.005;
  double gravity_mps2 = 3.711;  // Mars
};

struct EncoderOptions {
  double rate_hz = 10.0;      // >= 8 Hz
  double resolution_m = 0.0;  // quantization of each wheel's distance; 0 = none
};

struct RockCollision {
  // A rock whose surface under the footprint rises higher than this stops the rover with a
  // fault: the belly would hit it. Its top counts when the body comes over its centre, only
  // its rim's height when the footprint's edge grazes it (terrain::RockHeightAt). Disabled
  // when fault is false.
  bool fault = true;
  double max_height_m = 0.3;
};

struct MobilityOptions {
  std::uint64_t seed = 1;
  RoverGeometry geometry;
  SlipOptions slip;
  RockCollision rock_collision;
  double max_substep_s = 0.01;  // Step() integrates in pieces no longer than this
  ImuOptions imu;
  EncoderOptions encoders;

  // Reads root["mobility"] and root["sensors"]["imu" | "wheel_encoders"]; absent keys keep
  // their defaults. Throws config::ConfigError naming file and key.
  static MobilityOptions Load(const config::ConfigNode& root);
  static MobilityOptions LoadFile(const std::string& path);
};

}  // namespace rover::mobility
