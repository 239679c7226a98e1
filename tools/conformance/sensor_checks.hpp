// The publisher contracts: IMU and WHEEL_ODOMETRY (docs/HARDWARE.md, "Contracts"), judged on
// what a probe heard while the rover stood still. Also the timing rules every stream shares.
#pragma once

#include "conformance/report.hpp"

#include <rover_msgs/imu_t.hpp>
#include <rover_msgs/wheel_odometry_t.hpp>

#include <string>
#include <vector>

namespace rover::conformance {

struct StreamLimits {
  double min_rate_hz = 10.0;       // in rover time
  double clock_tolerance_s = 0.5;  // |utime - rover time at arrival|
};

// `<prefix>.rate`, `.gap`, `.time.monotonic`, `.time.near_clock` over the stamps of one
// stream (in arrival order). `<prefix>.present` when there is none.
void CheckStream(const std::string& prefix, const std::vector<Stamp>& stamps, const StreamLimits& limits,
                 Report& report);

struct ImuLimits {
  StreamLimits stream{10.0, 0.5};
  double gravity_mps2 = 9.80665;
  double gravity_tolerance = 0.10;   // fraction of gravity
  double frame_tolerance_deg = 5.0;  // accel against the orientation's gravity
  double max_rest_rate_rps = 0.05;
};

// The imu.* rules; the rover stood still while `samples` were taken.
void CheckImu(const std::vector<Received<rover_msgs::imu_t>>& samples, const ImuLimits& limits, Report& report);

struct WheelOdometryLimits {
  StreamLimits stream{8.0, 0.5};
  double rest_tolerance_m = 0.001;
};

// The wheel_odometry.* rules; the rover stood still while `samples` were taken.
void CheckWheelOdometry(const std::vector<Received<rover_msgs::wheel_odometry_t>>& samples,
                        const WheelOdometryLimits& limits, Report& report);

// With --drive the probe, as commander, drove an ARC and then a TURN (clockwise, +); the
// windows (wall seconds) span each motion from just before its command to just after its end.
struct DriveRecord {
  double arc_from_s = 0, arc_to_s = 0, arc_m = 0;
  double turn_from_s = 0, turn_to_s = 0, turn_rad = 0;
};

// imu.frame.turn (a clockwise turn reads a positive yaw rate and a growing yaw: Z down) and
// imu.units.turn (the integrated rate agrees with the orientation's yaw change, 30 %, and
// that with the commanded angle, 50 %: slip loses some of a turn).
void CheckImuDrive(const std::vector<Received<rover_msgs::imu_t>>& samples, const DriveRecord& drive, Report& report);
// wheel_odometry.units.distance (distance_m grows by the ARC's distance, 10 %) and
// wheel_odometry.frame.turn (in a clockwise turn the left wheels, the first half, roll
// forward and the right ones back, with turning_in_place set).
void CheckWheelOdometryDrive(const std::vector<Received<rover_msgs::wheel_odometry_t>>& samples,
                             const DriveRecord& drive, Report& report);

}  // namespace rover::conformance
