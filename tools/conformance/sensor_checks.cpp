#include "conformance/sensor_checks.hpp"

#include "bus/validate.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace rover::conformance {

namespace {

std::string Seconds(std::int64_t us) { return Num(static_cast<double>(us) * 1e-6) + " s"; }

}  // namespace

void CheckStream(const std::string& prefix, const std::vector<Stamp>& stamps, const StreamLimits& limits,
                 Report& report) {
  if (!report.Expect(!stamps.empty(), prefix + ".present", "messages", "none")) return;
  // Rate and gaps in the driver's own rover time: a driver under a simulated clock running
  // faster than the wall clock publishes faster in wall time too.
  const std::int64_t span = stamps.back().utime - stamps.front().utime;
  const double rate = span > 0 ? static_cast<double>(stamps.size() - 1) / (static_cast<double>(span) * 1e-6) : 0.0;
  report.Expect(stamps.size() >= 2 && rate >= limits.min_rate_hz, prefix + ".rate",
                "at least " + Num(limits.min_rate_hz, 1) + " Hz",
                Num(rate, 1) + " Hz (" + std::to_string(stamps.size()) + " messages over " + Seconds(span) + ")");

  const auto max_gap_us = static_cast<std::int64_t>(3e6 / limits.min_rate_hz);
  std::int64_t worst_gap = 0;
  std::size_t back_at = 0;
  for (std::size_t i = 1; i < stamps.size(); ++i) {
    const std::int64_t d = stamps[i].utime - stamps[i - 1].utime;
    worst_gap = std::max(worst_gap, d);
    if (d <= 0 && back_at == 0) back_at = i;
  }
  report.Expect(worst_gap <= max_gap_us, prefix + ".gap", "gaps of at most " + Seconds(max_gap_us),
                "a gap of " + Seconds(worst_gap));
  report.Expect(back_at == 0, prefix + ".time.monotonic", "strictly increasing utimes",
                back_at == 0 ? "" :
                "utime " + std::to_string(stamps[back_at].utime) + " after " + std::to_string(stamps[back_at - 1].utime));

  const auto tolerance_us = static_cast<std::int64_t>(limits.clock_tolerance_s * 1e6);
  const Stamp* worst = &stamps.front();
  for (const auto& s : stamps)
    if (std::abs(s.utime - s.clock_utime) > std::abs(worst->utime - worst->clock_utime)) worst = &s;
  report.Expect(std::abs(worst->utime - worst->clock_utime) <= tolerance_us, prefix + ".time.near_clock",
                "utimes within " + Num(limits.clock_tolerance_s, 2) + " s of rover time",
                "utime " + std::to_string(worst->utime) + " when rover time was " + std::to_string(worst->clock_utime) +
                    " (" + Seconds(worst->utime - worst->clock_utime) + " off)");
}

void CheckImu(const std::vector<Received<rover_msgs::imu_t>>& samples, const ImuLimits& limits, Report& report) {
  std::vector<Stamp> stamps;
  for (const auto& s : samples) stamps.push_back(s.at);
  CheckStream("imu", stamps, limits.stream, report);
  if (samples.empty()) return;

  for (const auto& s : samples) {
    if (std::string p = bus::Problem(s.msg); !p.empty()) {
      report.Fail("imu.fields", "finite rates and accelerations, a unit quaternion", p);
      return;  // the physical checks below need sound numbers
    }
  }
  report.Pass("imu.fields");

  // At rest the accelerometer measures the specific force of gravity: R^T (0, 0, -g) in
  // the rover frame (X forward, Y right, Z down), R = q_site_rover.
  for (const auto& s : samples) {
    const Eigen::Vector3d f(s.msg.accel[0], s.msg.accel[1], s.msg.accel[2]);
    const double g = limits.gravity_mps2;
    if (!report.Expect(std::abs(f.norm() - g) <= limits.gravity_tolerance * g, "imu.units.accel",
                       "|accel| " + Num(g, 2) + " m/s^2 at rest (" + Num(limits.gravity_tolerance * 100, 0) + " %)",
                       "|accel| " + Num(f.norm(), 3) + " at utime " + std::to_string(s.msg.utime))) {
      break;
    }
  }
  for (const auto& s : samples) {
    const Eigen::Quaterniond q(s.msg.orientation[0], s.msg.orientation[1], s.msg.orientation[2], s.msg.orientation[3]);
    const Eigen::Vector3d predicted = q.normalized().toRotationMatrix().transpose() * Eigen::Vector3d(0, 0, -1);
    const Eigen::Vector3d f(s.msg.accel[0], s.msg.accel[1], s.msg.accel[2]);
    const double angle_deg =
        f.norm() > 0 ? std::acos(std::clamp(predicted.dot(f.normalized()), -1.0, 1.0)) * 180.0 / M_PI : 180.0;
    if (!report.Expect(angle_deg <= limits.frame_tolerance_deg, "imu.frame.gravity",
                       "accel along R^T (0, 0, -1) of the orientation within " + Num(limits.frame_tolerance_deg, 1) +
                           " deg",
                       Num(angle_deg, 1) + " deg apart: accel (" + Num(f.x(), 2) + ", " + Num(f.y(), 2) + ", " +
                           Num(f.z(), 2) + "), orientation says (" + Num(predicted.x(), 2) + ", " +
                           Num(predicted.y(), 2) + ", " + Num(predicted.z(), 2) + ") x g")) {
      break;
    }
  }
  for (const auto& s : samples) {
    const Eigen::Vector3d w(s.msg.angular_rate[0], s.msg.angular_rate[1], s.msg.angular_rate[2]);
    if (!report.Expect(w.norm() <= limits.max_rest_rate_rps, "imu.units.rate",
                       "|angular_rate| at most " + Num(limits.max_rest_rate_rps, 3) + " rad/s at rest",
                       Num(w.norm(), 4) + " at utime " + std::to_string(s.msg.utime))) {
      break;
    }
  }
}

void CheckWheelOdometry(const std::vector<Received<rover_msgs::wheel_odometry_t>>& samples,
                        const WheelOdometryLimits& limits, Report& report) {
  std::vector<Stamp> stamps;
  for (const auto& s : samples) stamps.push_back(s.at);
  CheckStream("wheel_odometry", stamps, limits.stream, report);
  if (samples.empty()) return;

  for (const auto& s : samples) {
    std::string p = bus::Problem(s.msg);
    if (p.empty() && s.msg.num_wheels < 1) p = "num_wheels 0";
    if (p.empty() && static_cast<std::size_t>(s.msg.num_wheels) != s.msg.wheel_distance_m.size()) {
      p = "num_wheels " + std::to_string(s.msg.num_wheels) + " but " + std::to_string(s.msg.wheel_distance_m.size()) +
          " distances";
    }
    if (!p.empty()) {
      report.Fail("wheel_odometry.fields", "finite distances, 1 to 16 wheels", p);
      return;
    }
  }
  report.Pass("wheel_odometry.fields");

  const auto& first = samples.front().msg;
  for (const auto& s : samples) {
    double moved = std::abs(s.msg.distance_m - first.distance_m);
    std::string what = "distance_m";
    for (int w = 0; w < s.msg.num_wheels && w < first.num_wheels; ++w) {
      const double d = std::abs(s.msg.wheel_distance_m[w] - first.wheel_distance_m[w]);
      if (d > moved) {
        moved = d;
        what = "wheel_distance_m[" + std::to_string(w) + "]";
      }
    }
    if (!report.Expect(moved <= limits.rest_tolerance_m, "wheel_odometry.at_rest",
                       "cumulative distances standing still within " + Num(limits.rest_tolerance_m * 1000, 1) +
                           " mm at rest",
                       what + " moved " + Num(moved, 4) + " m by utime " + std::to_string(s.msg.utime))) {
      break;
    }
  }
}

namespace {

// The last sample at or before `t` and the first at or after it (wall seconds).
template <class Msg>
const Received<Msg>* Before(const std::vector<Received<Msg>>& samples, double t) {
  const Received<Msg>* out = nullptr;
  for (const auto& s : samples)
    if (s.at.wall_s <= t) out = &s;
  return out;
}
template <class Msg>
const Received<Msg>* After(const std::vector<Received<Msg>>& samples, double t) {
  for (const auto& s : samples)
    if (s.at.wall_s >= t) return &s;
  return nullptr;
}

double Yaw(const rover_msgs::imu_t& m) {
  const Eigen::Quaterniond q(m.orientation[0], m.orientation[1], m.orientation[2], m.orientation[3]);
  const Eigen::Matrix3d R = q.normalized().toRotationMatrix();
  return std::atan2(R(1, 0), R(0, 0));  // R = Rz(yaw) Ry(pitch) Rx(roll)
}

}  // namespace

void CheckImuDrive(const std::vector<Received<rover_msgs::imu_t>>& samples, const DriveRecord& drive, Report& report) {
  const auto* from = Before(samples, drive.turn_from_s);
  const auto* to = After(samples, drive.turn_to_s);
  if (from == nullptr || to == nullptr) {
    report.Fail("imu.frame.turn", "IMU samples before and after the turn", "none");
    return;
  }
  double integrated = 0;
  for (std::size_t i = 1; i < samples.size(); ++i) {
    if (samples[i].at.wall_s <= from->at.wall_s || samples[i].at.wall_s > to->at.wall_s) continue;
    integrated += samples[i].msg.angular_rate[2] * static_cast<double>(samples[i].msg.utime - samples[i - 1].msg.utime) * 1e-6;
  }
  const double turned = std::remainder(Yaw(to->msg) - Yaw(from->msg), 2 * M_PI);
  const double sign = drive.turn_rad >= 0 ? 1.0 : -1.0;
  if (!report.Expect(sign * integrated > 0 && sign * turned > 0, "imu.frame.turn",
                     "a clockwise turn of " + Num(drive.turn_rad, 3) +
                         " rad reads a positive angular_rate[2] and a growing yaw (Z down)",
                     "angular_rate[2] integrated to " + Num(integrated, 4) + " rad, yaw changed by " +
                         Num(turned, 4) + " rad")) {
    return;
  }
  report.Expect(std::abs(integrated - turned) <= 0.3 * std::abs(turned) &&
                    std::abs(turned - drive.turn_rad) <= 0.5 * std::abs(drive.turn_rad),
                "imu.units.turn",
                "the yaw rate integrated (rad/s) agreeing with the orientation's yaw change (30 %), and that with the "
                "commanded " + Num(drive.turn_rad, 3) + " rad (50 %)",
                "integrated " + Num(integrated, 4) + " rad, yaw changed by " + Num(turned, 4) + " rad");
}

void CheckWheelOdometryDrive(const std::vector<Received<rover_msgs::wheel_odometry_t>>& samples,
                             const DriveRecord& drive, Report& report) {
  const auto* a0 = Before(samples, drive.arc_from_s);
  const auto* a1 = After(samples, drive.arc_to_s);
  if (report.Expect(a0 && a1, "wheel_odometry.units.distance", "odometry before and after the arc", "none")) {
    const double d = a1->msg.distance_m - a0->msg.distance_m;
    report.Expect(std::abs(d - drive.arc_m) <= 0.1 * std::abs(drive.arc_m), "wheel_odometry.units.distance",
                  "distance_m grows by " + Num(drive.arc_m, 3) + " m over the arc (10 %)",
                  "it grew by " + Num(d, 4));
  }
  const auto* t0 = Before(samples, drive.turn_from_s);
  const auto* t1 = After(samples, drive.turn_to_s);
  if (!report.Expect(t0 && t1 && t0->msg.num_wheels == t1->msg.num_wheels && t0->msg.num_wheels >= 2,
                     "wheel_odometry.frame.turn", "odometry of the same wheels before and after the turn", "none")) {
    return;
  }
  const int n = t0->msg.num_wheels;
  double left = 0, right = 0;
  for (int w = 0; w < n; ++w) {
    const double d = t1->msg.wheel_distance_m[w] - t0->msg.wheel_distance_m[w];
    (w < n / 2 ? left : right) += d / (n / 2);
  }
  bool flagged = false;
  for (const auto& s : samples)
    if (s.at.wall_s > drive.turn_from_s && s.at.wall_s < drive.turn_to_s && s.msg.turning_in_place) flagged = true;
  const double sign = drive.turn_rad >= 0 ? 1.0 : -1.0;
  report.Expect(sign * left > 0 && sign * right < 0 && flagged, "wheel_odometry.frame.turn",
                "in a clockwise turn the left wheels (the first half) forward, the right back, turning_in_place 1",
                "left wheels " + Num(left, 4) + " m, right " + Num(right, 4) + " m, turning_in_place " +
                    (flagged ? "seen" : "never set"));
}

}  // namespace rover::conformance
