// The conformance checks on made-up records whose verdicts are known: a stream at a known
// rate, an IMU whose accelerometer agrees with its orientation or not by a known angle, a
// mobility driver's statuses with a known unit error, a dead-man on time or never, frames
// whose cameras are swapped.
#include "bus/convert.hpp"
#include "bus/image_encode.hpp"
#include "conformance/camera_checks.hpp"
#include "conformance/mobility_checks.hpp"
#include "conformance/sensor_checks.hpp"
#include "config/yaml_config.hpp"
#include "geometry/camera_io.hpp"

#include <rover_msgs/mobility_command_t.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace rover::conformance {
namespace {

using rover_msgs::mobility_command_t;
using rover_msgs::mobility_status_t;

std::string LineOf(const Report& r, const std::string& rule) {
  for (const auto& f : r.failures())
    if (f.rule == rule) return FailureLine(f);
  return "";
}

std::vector<Stamp> Stream(double hz, double seconds, std::int64_t offset_us = 0) {
  std::vector<Stamp> s;
  for (int i = 0; i < static_cast<int>(hz * seconds); ++i) {
    const auto t = static_cast<std::int64_t>(1000000 + i * 1e6 / hz);
    s.push_back({i / hz, t + offset_us, t});
  }
  return s;
}

TEST(ConformanceStream, RateGapOrderAndClock) {
  Report good;
  CheckStream("imu", Stream(20, 5), {10.0, 0.5}, good);
  EXPECT_TRUE(good.ok()) << FailureLine(good.failures().front());
  EXPECT_TRUE(good.Passed("imu.rate"));
  EXPECT_TRUE(good.Passed("imu.time.near_clock"));

  Report slow;
  CheckStream("imu", Stream(5, 5), {10.0, 0.5}, slow);
  EXPECT_EQ(LineOf(slow, "imu.rate"), "FAIL imu.rate: expected at least 10.0 Hz; seen 5.0 Hz (25 messages over 4.800 s)");
  EXPECT_FALSE(slow.Failed("imu.gap"));  // 0.2 s is within three periods of 10 Hz

  auto back = Stream(20, 2);
  std::swap(back[10], back[11]);
  Report order;
  CheckStream("imu", back, {10.0, 0.5}, order);
  EXPECT_TRUE(order.Failed("imu.time.monotonic"));

  Report off;
  CheckStream("wheel_odometry", Stream(10, 2, 2000000), {8.0, 0.5}, off);
  EXPECT_NE(LineOf(off, "wheel_odometry.time.near_clock").find("(2.000 s off)"), std::string::npos)
      << LineOf(off, "wheel_odometry.time.near_clock");

  Report none;
  CheckStream("imu", {}, {10.0, 0.5}, none);
  EXPECT_EQ(LineOf(none, "imu.present"), "FAIL imu.present: expected messages; seen none");
}

std::vector<Received<rover_msgs::imu_t>> Imu(double roll_rad, const Eigen::Vector3d& accel, double rate_z = 0) {
  std::vector<Received<rover_msgs::imu_t>> out;
  for (const auto& s : Stream(20, 2)) {
    rover_msgs::imu_t m{};
    m.utime = s.utime;
    m.orientation[0] = std::cos(roll_rad / 2);
    m.orientation[1] = std::sin(roll_rad / 2);
    for (int i = 0; i < 3; ++i) m.accel[i] = accel[i];
    m.angular_rate[2] = rate_z;
    out.push_back({s, m});
  }
  return out;
}

TEST(ConformanceImu, GravityAgreesWithTheOrientationInTheRoverFrame) {
  const double g = 3.711, roll = 10.0 * M_PI / 180.0;
  ImuLimits limits;
  limits.gravity_mps2 = g;
  // Rolled about X by 10 deg: R^T (0, 0, -g) = (0, -g sin(roll), -g cos(roll)), written out.
  Report good;
  CheckImu(Imu(roll, {0, -g * std::sin(roll), -g * std::cos(roll)}), limits, good);
  EXPECT_TRUE(good.ok()) << FailureLine(good.failures().front());
  EXPECT_TRUE(good.Passed("imu.frame.gravity"));
  // The Y axis flipped (a left-handed or Y-left frame): 2 x 10 deg apart.
  Report flipped;
  CheckImu(Imu(roll, {0, g * std::sin(roll), -g * std::cos(roll)}), limits, flipped);
  EXPECT_NE(LineOf(flipped, "imu.frame.gravity").find("seen 20.0 deg apart"), std::string::npos)
      << LineOf(flipped, "imu.frame.gravity");
  EXPECT_FALSE(flipped.Failed("imu.units.accel"));
  // Z up: gravity's specific force reads +g.
  Report z_up;
  CheckImu(Imu(0, {0, 0, g}), limits, z_up);
  EXPECT_NE(LineOf(z_up, "imu.frame.gravity").find("seen 180.0 deg apart"), std::string::npos);
  // Accelerations in g, not m/s^2.
  Report in_g;
  CheckImu(Imu(0, {0, 0, -1.0}), limits, in_g);
  EXPECT_EQ(LineOf(in_g, "imu.units.accel"),
            "FAIL imu.units.accel: expected |accel| 3.71 m/s^2 at rest (10 %); seen |accel| 1.000 at utime 1000000");
  // A rate in deg/s of a 0.03 rad/s drift reads 1.7.
  Report degrees;
  CheckImu(Imu(0, {0, 0, -g}, 0.03 * 180 / M_PI), limits, degrees);
  EXPECT_TRUE(degrees.Failed("imu.units.rate"));
  Report radians;
  CheckImu(Imu(0, {0, 0, -g}, 0.03), limits, radians);
  EXPECT_FALSE(radians.Failed("imu.units.rate"));
}

TEST(ConformanceWheelOdometry, AtRestAndFields) {
  std::vector<Received<rover_msgs::wheel_odometry_t>> samples;
  for (const auto& s : Stream(10, 2)) {
    rover_msgs::wheel_odometry_t m{};
    m.utime = s.utime;
    m.num_wheels = 6;
    m.wheel_distance_m.assign(6, 1.5);
    m.distance_m = 1.5;
    samples.push_back({s, m});
  }
  Report good;
  CheckWheelOdometry(samples, {}, good);
  EXPECT_TRUE(good.ok()) << FailureLine(good.failures().front());
  samples.back().msg.wheel_distance_m[4] += 0.02;
  Report creeping;
  CheckWheelOdometry(samples, {}, creeping);
  EXPECT_NE(LineOf(creeping, "wheel_odometry.at_rest").find("wheel_distance_m[4] moved 0.0200 m"), std::string::npos)
      << LineOf(creeping, "wheel_odometry.at_rest");
  samples.back().msg.num_wheels = 5;
  Report short_list;
  CheckWheelOdometry(samples, {}, short_list);
  EXPECT_EQ(LineOf(short_list, "wheel_odometry.fields"),
            "FAIL wheel_odometry.fields: expected finite distances, 1 to 16 wheels; seen num_wheels 5 but 6 distances");
}

// A driver's record: statuses at 4 Hz of rover time = wall time, from t = 0.
class Driver {
 public:
  MobilityTrace trace;
  double t = 0;
  void Status(std::int64_t id, int state, double distance = 0, double turn = 0, const std::string& detail = "") {
    rover_msgs::mobility_status_t m{};
    m.utime = 1000000 + static_cast<std::int64_t>(t * 1e6);
    m.command_id = id;
    m.state = static_cast<std::int8_t>(state);
    m.wheel_distance_m = distance;
    m.wheel_turn_rad = turn;
    m.detail = detail;
    trace.statuses.push_back({{t, m.utime, m.utime}, m});
  }
  void Send(std::int64_t id, std::int8_t type, double distance, double turn, double speed, double rate) {
    trace.commands.push_back({id, type, distance, 0, turn, speed, rate, t});
  }
  // Moves for `seconds` at `speed`, reporting 4 times a second.
  void Move(std::int64_t id, double seconds, double speed, double scale = 1.0) {
    const double start = t;
    for (; t < start + seconds - 1e-9; t += 0.25) Status(id, mobility_status_t::STATE_MOVING, (t - start) * speed * scale);
  }
};

TEST(ConformanceMobility, AnArcInMillimetresFailsTheDistanceUnit) {
  Driver d;
  d.Send(1, mobility_command_t::TYPE_ARC, 0.10, 0, 0.05, 0);
  d.t = 0.05;
  d.Move(1, 2.0, 0.05);
  d.Status(1, mobility_status_t::STATE_DONE, 0.10);
  d.trace.end_wall_s = d.t + 0.5;
  Report good;
  CheckMotion(d.trace, 1, {}, good);
  EXPECT_TRUE(good.ok()) << FailureLine(good.failures().front());
  EXPECT_TRUE(good.Passed("mobility.units.speed"));

  d.trace.statuses.back().msg.wheel_distance_m = 100.0;
  Report mm;
  CheckMotion(d.trace, 1, {}, mm);
  EXPECT_EQ(LineOf(mm, "mobility.units.distance"),
            "FAIL mobility.units.distance: expected wheel_distance_m 0.100 (10 %) at DONE; seen 100.0000");
}

TEST(ConformanceMobility, DeadmanOnTimeTooEarlyAndNever) {
  auto run = [](double stop_after_silence_s) {
    Driver d;
    d.Send(5, mobility_command_t::TYPE_ARC, 2.0, 0, 0.05, 0);
    d.t = 0.05;
    d.Move(5, 2.5, 0.05);  // alive for 2.5 s
    d.trace.silent_from_s = 2.5;
    if (stop_after_silence_s >= 0) {
      d.Move(5, stop_after_silence_s, 0.05);
      d.t = 2.5 + stop_after_silence_s;
      d.Status(5, mobility_status_t::STATE_STOPPED, 0.1, 0, "dead-man: nothing from sequence_executor");
    } else {
      d.Move(5, 3.5, 0.05);
    }
    d.trace.silent_until_s = 6.0;
    d.trace.end_wall_s = 6.5;
    Report r;
    CheckDeadman(d.trace, 5, {}, r);
    return r;
  };
  const Report on_time = run(1.6);
  EXPECT_TRUE(on_time.Passed("mobility.deadman.stop"));
  EXPECT_TRUE(on_time.Passed("mobility.deadman.detail"));
  const Report early = run(0.5);
  EXPECT_TRUE(early.Failed("mobility.deadman.stop"));
  const Report never = run(-1);
  EXPECT_EQ(LineOf(never, "mobility.deadman.stop"),
            "FAIL mobility.deadman.stop: expected STOPPED for command 5 1.25 to 2.50 s after the commander fell "
            "silent; seen MOVING for command 5 3.50 s after the commander fell silent");
}

TEST(ConformanceMobility, StopAnsweredOrIgnored) {
  Driver d;
  d.Send(7, mobility_command_t::TYPE_ARC, 2.0, 0, 0.05, 0);
  d.t = 0.05;
  d.Move(7, 1.5, 0.05);
  d.Send(8, mobility_command_t::TYPE_STOP, 0, 0, 0, 0);
  MobilityTrace ignored = d.trace;
  d.t += 0.02;
  d.Status(7, mobility_status_t::STATE_STOPPED, 0.07, 0, "stopped by command 8");
  d.Status(8, mobility_status_t::STATE_STOPPED, 0, 0, "stop");
  d.t += 1.0;
  d.Status(8, mobility_status_t::STATE_STOPPED);
  d.trace.end_wall_s = d.t;
  Report answered;
  CheckStop(d.trace, 7, 8, {}, answered);
  EXPECT_TRUE(answered.ok()) << FailureLine(answered.failures().front());

  Driver on(std::move(d));
  on.trace = ignored;
  on.t = 1.55;
  on.Move(7, 2.0, 0.05);
  on.trace.end_wall_s = on.t;
  Report r;
  CheckStop(on.trace, 7, 8, {}, r);
  EXPECT_NE(LineOf(r, "mobility.stop.answer").find("seen MOVING for command 7"), std::string::npos)
      << LineOf(r, "mobility.stop.answer");
}

TEST(ConformanceMobility, RefusalByFaultOrCountedDrop) {
  Driver d;
  rover_msgs::heartbeat_t hb{};
  hb.process = "mobility_driver";
  hb.dropped = 3;
  d.trace.driver_heartbeats.push_back({{0.0, 0, 0}, hb});
  d.Send(9, 7, 0.1, 0, 0.05, 0);
  d.t = 0.1;
  d.Status(9, mobility_status_t::STATE_FAULT, 0, 0, "command 9 refused: unknown type 7");
  d.trace.end_wall_s = 1.0;
  Report fault;
  CheckRefusal(d.trace, 9, "mobility.bad.type", true, {}, fault);
  EXPECT_TRUE(fault.Passed("mobility.bad.type"));

  d.trace.statuses.clear();
  hb.dropped = 4;
  d.trace.driver_heartbeats.push_back({{0.3, 0, 0}, hb});
  Report dropped;
  CheckRefusal(d.trace, 9, "mobility.bad.type", true, {}, dropped);
  EXPECT_TRUE(dropped.Passed("mobility.bad.type"));
  Report must_fault;
  CheckRefusal(d.trace, 9, "mobility.bad.curvature", false, {}, must_fault);
  EXPECT_TRUE(must_fault.Failed("mobility.bad.curvature"));

  d.Status(9, mobility_status_t::STATE_MOVING);
  Report moved;
  CheckRefusal(d.trace, 9, "mobility.bad.type", true, {}, moved);
  EXPECT_EQ(LineOf(moved, "mobility.bad.type"),
            "FAIL mobility.bad.type: expected command 9 refused, nothing moving; seen MOVING for command 9");
}

rover_msgs::image_t Gray(int w, int h) {
  return rover::bus::EncodeImage(cv::Mat(h, w, CV_8UC1, cv::Scalar(128)), false);
}

TEST(ConformanceCamera, FramesAnswersAndSwappedCameras) {
  const auto rig = geometry::LoadStereoRig(config::ConfigNode::FromString(
      "left: {type: pinhole, width: 64, height: 48, fx: 60, fy: 60, cx: 31.5, cy: 23.5, position: [0, -0.1, -1], rpy_deg: [0, 0, 0]}\n"
      "right: {type: pinhole, width: 64, height: 48, fx: 60, fy: 60, cx: 31.5, cy: 23.5, position: [0, 0.1, -1], rpy_deg: [0, 0, 0]}\n",
      "rig"));
  CameraTrace trace;
  trace.requests.push_back({11, "vo", 1000000, 0.0});
  trace.requests.push_back({12, "vo", 2000000, 1.0});
  rover_msgs::stereo_frame_t f{};
  f.frame_id = 11;
  f.utime = 1000000;
  f.purpose = "vo";
  f.left = Gray(64, 48);
  f.right = Gray(64, 48);
  f.left_model = rover::bus::CameraModelToMsg(*rig.left);
  f.right_model = rover::bus::CameraModelToMsg(*rig.right);
  f.pose_at_capture.orientation[0] = 1;
  f.left_utime = 999400;  // the right exposed 1.2 ms after the left
  f.right_utime = 1000600;
  trace.frames.push_back({{0.5, f.utime, 1100000}, f});
  trace.end_wall_s = 3.0;
  CameraLimits limits;
  limits.answer_s = 0.9;
  {
    Report paired;
    CheckCamera(trace, limits, paired);
    EXPECT_TRUE(paired.Passed("camera.time.pair"));
    // Further apart than the pairing tolerance, either way round.
    limits.pair_tolerance_ms = 1.0;
    Report apart;
    CheckCamera(trace, limits, apart);
    EXPECT_EQ(LineOf(apart, "camera.time.pair"),
              "FAIL camera.time.pair: expected left_utime and right_utime within 1.000 ms of each other, both within "
              "0.50 s of utime; seen frame 11: right exposed 1.200 ms after left");
    std::swap(trace.frames[0].msg.left_utime, trace.frames[0].msg.right_utime);
    Report before;
    CheckCamera(trace, limits, before);
    EXPECT_NE(LineOf(before, "camera.time.pair").find("right exposed -1.200 ms after left"), std::string::npos);
    limits.pair_tolerance_ms = 2.0;
    // A source that leaves them unset.
    trace.frames[0].msg.left_utime = trace.frames[0].msg.right_utime = 0;
    Report unset;
    CheckCamera(trace, limits, unset);
    EXPECT_NE(LineOf(unset, "camera.time.pair").find("frame 11: left_utime 0, right_utime 0 with utime 1000000"),
              std::string::npos)
        << LineOf(unset, "camera.time.pair");
    trace.frames[0].msg.left_utime = trace.frames[0].msg.right_utime = f.utime;
  }
  // Request 12 got nothing, and nothing said why.
  Report silent;
  CheckCamera(trace, limits, silent);
  EXPECT_TRUE(silent.Passed("camera.pairing"));
  EXPECT_TRUE(silent.Passed("camera.size"));
  EXPECT_EQ(LineOf(silent, "camera.answer"),
            "FAIL camera.answer: expected STEREO_FRAME 12, or a DEGRADED or FAULT heartbeat naming the failure, within "
            "0.9 s; seen neither, and no heartbeat from the capture process");
  // The same with camera_capture's heartbeat saying why.
  rover_msgs::heartbeat_t hb{};
  hb.process = "camera_capture";
  hb.state = rover_msgs::heartbeat_t::STATE_DEGRADED;
  hb.detail = "capture failed: genicam: right camera (serial GV02): not found";
  trace.capture_heartbeats.push_back({{1.5, 0, 0}, hb});
  Report reported;
  CheckCamera(trace, limits, reported);
  EXPECT_TRUE(reported.Passed("camera.answer"));
  // Cameras swapped; an image of the wrong size; a frame stamped before its request.
  std::swap(trace.frames[0].msg.left_model, trace.frames[0].msg.right_model);
  trace.frames[0].msg.utime = 200000;
  Report swapped;
  CheckCamera(trace, limits, swapped);
  EXPECT_NE(LineOf(swapped, "camera.pairing").find("the right camera -0.200 m to the right"), std::string::npos)
      << LineOf(swapped, "camera.pairing");
  EXPECT_TRUE(swapped.Failed("camera.time.capture"));
  trace.frames[0].msg.right = Gray(32, 48);
  Report sized;
  CheckCamera(trace, limits, sized);
  EXPECT_TRUE(sized.Failed("camera.size"));
}

// A turn of 0.1 rad at 0.1 rad/s from wall second 1 to 2: the IMU's yaw rate and yaw, the
// wheels' signs, as a conforming driver reports them, and with one sign flipped.
TEST(ConformanceDrive, TurnSignsInTheImuAndTheWheels) {
  DriveRecord drive;
  drive.arc_from_s = -1;
  drive.arc_to_s = -0.5;
  drive.arc_m = 0.1;
  drive.turn_from_s = 0.9;
  drive.turn_to_s = 2.1;
  drive.turn_rad = 0.1;
  auto imu = [](double rate_sign) {
    std::vector<Received<rover_msgs::imu_t>> out;
    for (const auto& s : Stream(20, 3)) {
      rover_msgs::imu_t m{};
      m.utime = s.utime;
      const double yaw = 0.1 * std::clamp(s.wall_s - 1.0, 0.0, 1.0);
      m.orientation[0] = std::cos(yaw / 2);
      m.orientation[3] = std::sin(yaw / 2);
      m.angular_rate[2] = rate_sign * (s.wall_s > 1.0 && s.wall_s <= 2.0 ? 0.1 : 0.0);
      out.push_back({s, m});
    }
    return out;
  };
  Report good;
  CheckImuDrive(imu(1.0), drive, good);
  EXPECT_TRUE(good.Passed("imu.frame.turn"));
  EXPECT_TRUE(good.Passed("imu.units.turn"));
  Report flipped;
  CheckImuDrive(imu(-1.0), drive, flipped);
  EXPECT_TRUE(flipped.Failed("imu.frame.turn"));
  Report degrees;
  CheckImuDrive(imu(180.0 / M_PI), drive, degrees);
  EXPECT_FALSE(degrees.Failed("imu.frame.turn"));
  EXPECT_TRUE(degrees.Failed("imu.units.turn"));

  auto wheels = [](double left_sign) {
    std::vector<Received<rover_msgs::wheel_odometry_t>> out;
    for (const auto& s : Stream(10, 3, 0)) {
      rover_msgs::wheel_odometry_t m{};
      m.utime = s.utime;
      m.num_wheels = 6;
      const double d = 0.05 * std::clamp(s.wall_s - 1.0, 0.0, 1.0);
      for (int w = 0; w < 6; ++w) m.wheel_distance_m.push_back((w < 3 ? left_sign : -left_sign) * d);
      m.turning_in_place = s.wall_s > 1.0 && s.wall_s < 2.0;
      out.push_back({{s.wall_s, s.utime, s.clock_utime}, m});
    }
    return out;
  };
  Report turn;
  CheckWheelOdometryDrive(wheels(1.0), drive, turn);
  EXPECT_TRUE(turn.Passed("wheel_odometry.frame.turn"));
  EXPECT_TRUE(turn.Failed("wheel_odometry.units.distance"));  // no arc in this record
  Report swapped;
  CheckWheelOdometryDrive(wheels(-1.0), drive, swapped);
  EXPECT_NE(LineOf(swapped, "wheel_odometry.frame.turn").find("seen left wheels -0.0500 m, right 0.0500 m"),
            std::string::npos)
      << LineOf(swapped, "wheel_odometry.frame.turn");
}

TEST(ConformanceRules, EveryContractHasRulesAndUnknownIsNamed) {
  for (const auto& name : ContractNames()) EXPECT_FALSE(RulesOf(name).empty()) << name;
  EXPECT_THROW(RulesOf("lidar"), std::invalid_argument);
  Report r;
  r.Fail("imu.rate", "a", "b");
  r.Fail("imu.rate", "c", "d");
  r.Pass("imu.rate");
  EXPECT_EQ(r.failures().size(), 1u);
  EXPECT_FALSE(r.Passed("imu.rate"));
  EXPECT_EQ(r.Unchecked("imu").size(), RulesOf("imu").size() - 1);
}

}  // namespace
}  // namespace rover::conformance
