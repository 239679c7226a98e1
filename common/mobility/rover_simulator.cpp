#include "mobility/rover_simulator.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace rover::mobility {

namespace {

constexpr double kDeg = M_PI / 180.0;

void RequireFinite(double v, const char* name, std::int64_t id) {
  if (!std::isfinite(v)) {
    std::ostringstream os;
    os << "mobility command " << id << ": " << name << " is " << v << " (expected a finite number)";
    throw std::invalid_argument(os.str());
  }
}

template <typename... Numbers>
std::string Format(const char* fmt, Numbers... numbers) {
  char buf[200];
  std::snprintf(buf, sizeof(buf), fmt, static_cast<double>(numbers)...);
  return buf;
}

}  // namespace

MotionCommand MotionCommand::Arc(std::int64_t id, double distance_m, double curvature_per_m) {
  MotionCommand c;
  c.id = id;
  c.type = Type::kArc;
  c.distance_m = distance_m;
  c.curvature_per_m = curvature_per_m;
  return c;
}

MotionCommand MotionCommand::Turn(std::int64_t id, double turn_rad) {
  MotionCommand c;
  c.id = id;
  c.type = Type::kTurn;
  c.turn_rad = turn_rad;
  return c;
}

MotionCommand MotionCommand::Stop(std::int64_t id) {
  MotionCommand c;
  c.id = id;
  c.type = Type::kStop;
  return c;
}

const char* MobilityStateName(MobilityState s) {
  switch (s) {
    case MobilityState::kIdle: return "idle";
    case MobilityState::kMoving: return "moving";
    case MobilityState::kDone: return "done";
    case MobilityState::kStopped: return "stopped";
    case MobilityState::kFault: return "fault";
  }
  return "unknown";
}

geometry::Pose RoverTruth::T_site_rover() const {
  geometry::Pose T = geometry::Pose::Identity();
  T.linear() = q_site_rover.toRotationMatrix();
  T.translation() = position;
  return T;
}

RoverSimulator::RoverSimulator(const terrain::World& world, MobilityOptions options,
                               std::int64_t start_utime)
    : RoverSimulator(world, std::move(options), world.options().start.x, world.options().start.y,
                     world.options().start.yaw_deg * kDeg, start_utime) {}

RoverSimulator::RoverSimulator(const terrain::World& world, MobilityOptions options, double x,
                               double y, double yaw_rad, std::int64_t start_utime)
    : world_(world),
      options_(std::move(options)),
      x_(x),
      y_(y),
      yaw_(geometry::WrapAngle(yaw_rad)),
      slip_rng_(terrain::SubSeed(options_.seed, 11)),
      imu_rng_(terrain::SubSeed(options_.seed, 12)) {
  const auto& o = options_;
  auto require = [](bool ok, const std::string& what) {
    if (!ok) throw std::invalid_argument("rover simulator: " + what);
  };
  require(std::isfinite(x) && std::isfinite(y) && std::isfinite(yaw_rad),
          "start pose must be finite");
  require(world.Contains(x, y), Format("start (%.3f, %.3f) is off the map", x, y));
  require(o.imu.rate_hz > 0.0, Format("imu rate_hz %g must be > 0", o.imu.rate_hz));
  require(o.encoders.rate_hz > 0.0, Format("encoder rate_hz %g must be > 0", o.encoders.rate_hz));
  require(o.max_substep_s > 0.0, Format("max_substep_s %g must be > 0", o.max_substep_s));
  require(o.geometry.speed_mps > 0.0 && o.geometry.turn_rate_rps > 0.0,
          "default speed and turn rate must be > 0");
  require(o.slip.dragged.wheel >= -1 && o.slip.dragged.wheel < kNumWheels,
          Format("dragged wheel index %g out of range", o.slip.dragged.wheel));
  for (int i = 0; i < kNumWheels; ++i) {
    wheel_xy_[i] = o.geometry.WheelPosition(i);
    mean_wheel_arm_ += wheel_xy_[i].norm() / kNumWheels;
  }
  if (o.rock_collision.fault) {
    for (const auto& r : world.rocks()) {
      if (r.height_m > o.rock_collision.max_height_m) tall_rocks_.push_back(&r);
    }
  }
  utime_ = start_utime;
  imu_period_us_ = std::max<std::int64_t>(1, std::llround(1e6 / o.imu.rate_hz));
  encoder_period_us_ = std::max<std::int64_t>(1, std::llround(1e6 / o.encoders.rate_hz));
  next_imu_us_ = utime_ + imu_period_us_;
  next_encoder_us_ = utime_ + encoder_period_us_;
  // The plane fit uses the attitude to place the wheels; a few passes settle it.
  for (int k = 0; k < 4; ++k) FollowTerrain();
  status_.utime = utime_;
  last_imu_ = MakeImuSample();
  out_.imu.reserve(64);
  out_.odometry.reserve(64);
  out_.status.reserve(8);
  pending_status_.reserve(8);
}

void RoverSimulator::SetStatus(MobilityState state, const std::string& detail) {
  status_.state = state;
  status_.detail = detail;
  status_.utime = utime_;
  pending_status_.push_back(status_);
}

void RoverSimulator::Halt(const std::string& detail) {
  if (!moving()) return;
  target_ = 0.0;
  SetStatus(MobilityState::kStopped, detail);
}

void RoverSimulator::Command(const MotionCommand& c) {
  RequireFinite(c.distance_m, "distance_m", c.id);
  RequireFinite(c.curvature_per_m, "curvature_per_m", c.id);
  RequireFinite(c.turn_rad, "turn_rad", c.id);
  RequireFinite(c.speed_mps, "speed_mps", c.id);
  RequireFinite(c.turn_rate_rps, "turn_rate_rps", c.id);
  const auto& g = options_.geometry;
  if (c.speed_mps < 0.0 || c.turn_rate_rps < 0.0) {
    throw std::invalid_argument("mobility command " + std::to_string(c.id) +
                                ": speed and turn rate must be >= 0 (0 = default)");
  }
  if (c.type == MotionCommand::Type::kArc && std::abs(c.curvature_per_m) > g.max_curvature_per_m) {
    throw std::invalid_argument(
        "mobility command " + std::to_string(c.id) +
        Format(": curvature %g 1/m is beyond the limit %g 1/m", c.curvature_per_m,
               g.max_curvature_per_m));
  }
  if (moving()) {
    SetStatus(MobilityState::kStopped,
              (c.type == MotionCommand::Type::kStop ? "stopped by command " : "preempted by command ") +
                  std::to_string(c.id));
  }
  command_ = c;
  progress_ = 0.0;
  status_.command_id = c.id;
  status_.wheel_distance_m = 0.0;
  status_.wheel_turn_rad = 0.0;
  switch (c.type) {
    case MotionCommand::Type::kStop:
      target_ = 0.0;
      SetStatus(MobilityState::kStopped, "stop");
      return;
    case MotionCommand::Type::kArc:
      target_ = std::abs(c.distance_m);
      rate_ = c.speed_mps > 0.0 ? c.speed_mps : g.speed_mps;
      break;
    case MotionCommand::Type::kTurn:
      target_ = std::abs(c.turn_rad);
      rate_ = c.turn_rate_rps > 0.0 ? c.turn_rate_rps : g.turn_rate_rps;
      break;
  }
  if (target_ <= 0.0) {
    SetStatus(MobilityState::kDone, "nothing to do");
  } else {
    SetStatus(MobilityState::kMoving, "");
  }
}

const StepOutput& RoverSimulator::Step(double dt_s) {
  if (!(dt_s > 0.0) || !std::isfinite(dt_s)) {
    throw std::invalid_argument(Format("RoverSimulator::Step: dt %g s must be finite and > 0", dt_s));
  }
  out_.imu.clear();
  out_.odometry.clear();
  out_.status.clear();
  const std::int64_t end = utime_ + std::max<std::int64_t>(1, std::llround(dt_s * 1e6));
  const std::int64_t max_sub =
      std::max<std::int64_t>(1, std::llround(options_.max_substep_s * 1e6));
  while (utime_ < end) {
    const std::int64_t next =
        std::min({end, next_imu_us_, next_encoder_us_, utime_ + max_sub});
    const double dt = static_cast<double>(next - utime_) * 1e-6;
    utime_ = next;
    Advance(dt);
    if (utime_ == next_imu_us_) {
      last_imu_ = MakeImuSample();
      out_.imu.push_back(last_imu_);
      next_imu_us_ += imu_period_us_;
    }
    if (utime_ == next_encoder_us_) {
      out_.odometry.push_back(Odometry());
      next_encoder_us_ += encoder_period_us_;
    }
  }
  out_.status.insert(out_.status.end(), pending_status_.begin(), pending_status_.end());
  pending_status_.clear();
  return out_;
}

MobilityStatus RoverSimulator::RunUntilIdle(double max_s, double dt_s) {
  const std::int64_t stop_at = utime_ + std::llround(max_s * 1e6);
  // Deliver the status change of Command() even if nothing moves.
  Step(dt_s);
  while (moving() && utime_ < stop_at) Step(dt_s);
  return status_;
}

double RoverSimulator::SoilSlipAt(double pitch_travel_deg) const {
  double s = 0.0;
  for (int i = 0; i < kNumWheels; ++i) {
    s += Interpolate(options_.slip.For(wheel_soil_[i]).slip_vs_pitch, pitch_travel_deg);
  }
  return s / kNumWheels;
}

double RoverSimulator::LongitudinalSlip(double pitch_travel_deg) const {
  const double on_ground = SoilSlipAt(pitch_travel_deg);
  // Each climbing wheel's share of the weight must be lifted up its climb grade: to the
  // traction of all six that is a steeper slope to drive up.
  double climb = 0.0;
  for (int i = 0; i < kNumWheels; ++i) climb += std::min(wheel_climb_grade_[i], 3.0);
  if (climb <= 0.0) return on_ground;
  const double grade = std::tan(pitch_travel_deg * kDeg) +
                       options_.slip.rock_climb_grade * climb / kNumWheels;
  const double with_rocks = SoilSlipAt(std::atan(grade) / kDeg);
  // Rocks stall the rover (its wheels spin) but do not push it back downhill.
  return std::max(on_ground, std::min(with_rocks, options_.slip.rock_stall_slip));
}

void RoverSimulator::AddWheelMotion(double amount, bool turning) {
  const auto& dragged = options_.slip.dragged;
  double body = 0.0;
  for (int i = 0; i < kNumWheels; ++i) {
    const Eigen::Vector2d& w = wheel_xy_[i];
    double factor;
    if (turning) {
      // Clockwise from above (+): the left side rolls forward, the right side backward.
      factor = w.norm() * (w.y() < 0.0 ? 1.0 : -1.0);
    } else {
      // Each wheel rolls along its own arc about the turn centre at y = 1/curvature.
      const double k = command_.curvature_per_m;
      const double along = 1.0 - k * w.y();
      factor = std::copysign(std::hypot(along, k * w.x()), along);
    }
    double reading = amount * factor;
    if (i == dragged.wheel && dragged.encoder == DraggedWheel::Encoder::kZero) reading = 0.0;
    wheel_true_[i] += reading;
    if (!turning && std::abs(factor) > 1e-9) body += reading / factor;
  }
  if (!turning) odometry_distance_ += body / kNumWheels;
}

void RoverSimulator::Advance(double dt) {
  const Eigen::Matrix3d R_prev = R_;
  const Eigen::Vector3d p_prev(x_, y_, z_);

  // Slip noise: unit Ornstein-Uhlenbeck processes, scaled per soil below.
  const double a = std::exp(-dt / options_.slip.noise_time_s);
  const double b = std::sqrt(std::max(0.0, 1.0 - a * a));
  slip_noise_ = a * slip_noise_ + b * slip_rng_.Normal();
  drift_noise_ = a * drift_noise_ + b * slip_rng_.Normal();

  double ds_fwd = 0.0, ds_lat = 0.0, dyaw = 0.0;
  Eigen::Vector2d extra_xy = Eigen::Vector2d::Zero();
  // Cross slope: + when the right side is higher. Drift goes downslope.
  const double cross_deg = std::atan(plane_slope_right_) / kDeg;
  double mean_noise = 0.0, mean_drift = 0.0, mean_turn_slip = 0.0;
  for (int i = 0; i < kNumWheels; ++i) {
    const SoilSlip& s = options_.slip.For(wheel_soil_[i]);
    mean_noise += s.noise_std / kNumWheels;
    mean_drift += s.DriftAt(cross_deg) / kNumWheels;
    mean_turn_slip += s.turn_slip / kNumWheels;
  }

  if (moving()) {
    const double step = std::min(rate_ * dt, target_ - progress_);
    progress_ += step;
    const auto& dragged = options_.slip.dragged;
    if (command_.type == MotionCommand::Type::kArc) {
      const double ds_w = std::copysign(step, command_.distance_m);
      const double pitch_travel_deg =
          std::atan(plane_slope_fwd_) / kDeg * (command_.distance_m >= 0.0 ? 1.0 : -1.0);
      slip_ = LongitudinalSlip(pitch_travel_deg) + mean_noise * slip_noise_;
      if (dragged.wheel >= 0) slip_ += dragged.extra_slip;
      lateral_slip_ = -std::copysign(mean_drift, cross_deg) + 0.5 * mean_noise * drift_noise_;
      ds_fwd = ds_w * (1.0 - slip_);
      ds_lat = std::abs(ds_w) * lateral_slip_;
      dyaw = command_.curvature_per_m * ds_w;
      if (dragged.wheel >= 0) {
        // The dragged wheel holds its side back: the rover yaws toward it.
        dyaw += (dragged.wheel < 3 ? -1.0 : 1.0) * dragged.yaw_per_m * std::abs(ds_w);
      }
      AddWheelMotion(ds_w, false);
      status_.wheel_distance_m = std::copysign(progress_, command_.distance_m);
    } else {
      const double dtheta = std::copysign(step, command_.turn_rad);
      slip_ = mean_turn_slip + mean_noise * slip_noise_;
      lateral_slip_ = 0.0;
      dyaw = dtheta * (1.0 - slip_);
      // Turning in place on a slope the rover creeps downslope.
      const Eigen::Vector2d fwd(std::cos(yaw_), std::sin(yaw_)), right(-std::sin(yaw_), std::cos(yaw_));
      const Eigen::Vector2d grad = plane_slope_fwd_ * fwd + plane_slope_right_ * right;
      const double gn = grad.norm();
      if (gn > 1e-9) {
        const double travel = std::abs(dtheta) * mean_wheel_arm_;
        double creep = 0.0;  // per metre the wheels roll, at the full slope angle
        for (int i = 0; i < kNumWheels; ++i) {
          creep += options_.slip.For(wheel_soil_[i]).DriftAt(std::atan(gn) / kDeg) / kNumWheels;
        }
        extra_xy = -grad / gn * travel * creep;
      }
      AddWheelMotion(dtheta, true);
      status_.wheel_turn_rad = std::copysign(progress_, command_.turn_rad);
    }
    if (progress_ >= target_ - 1e-12) {
      std::ostringstream detail;
      if (command_.type == MotionCommand::Type::kArc) {
        detail << "wheels rolled " << status_.wheel_distance_m << " m";
      } else {
        detail << "wheels turned " << status_.wheel_turn_rad / kDeg << " deg";
      }
      SetStatus(MobilityState::kDone, detail.str());
    }
  } else {
    slip_ = 0.0;
    lateral_slip_ = 0.0;
  }

  const double yaw_mid = yaw_ + 0.5 * dyaw;
  const double fwd_h = ds_fwd * std::cos(pitch_), lat_h = ds_lat * std::cos(roll_);
  x_ += fwd_h * std::cos(yaw_mid) - lat_h * std::sin(yaw_mid) + extra_xy.x();
  y_ += fwd_h * std::sin(yaw_mid) + lat_h * std::cos(yaw_mid) + extra_xy.y();
  yaw_ = geometry::WrapAngle(yaw_ + dyaw);

  if (ds_fwd != 0.0 || ds_lat != 0.0 || dyaw != 0.0 || extra_xy.x() != 0.0 || extra_xy.y() != 0.0) {
    const bool on_map = FollowTerrain();
    odometer_ += (Eigen::Vector3d(x_, y_, z_) - p_prev).norm();
    if (!on_map && moving()) {
      Fault(Format("a wheel left the map at (%.2f, %.2f)", x_, y_));
    } else if (moving() && !tall_rocks_.empty()) {
      CheckRocks(p_prev);
    }
  }
  // Body rates from the attitude change over the substep.
  const Eigen::AngleAxisd delta(R_prev.transpose() * R_);
  body_rate_ = delta.axis() * (delta.angle() / dt);

  // Gyro bias about the vertical plus angle random walk: the attitude's yaw drifts.
  const double bias = options_.imu.yaw_drift_deg_per_hour * kDeg / 3600.0;
  const double arw = options_.imu.yaw_random_walk_deg_per_sqrt_hour * kDeg / 60.0;
  yaw_error_ += bias * dt + arw * std::sqrt(dt) * imu_rng_.Normal();
}

void RoverSimulator::Fault(const std::string& detail) { SetStatus(MobilityState::kFault, detail); }

void RoverSimulator::CheckRocks(const Eigen::Vector3d& p_prev) {
  // A rock whose surface under the footprint rises over the belly's clearance stops the
  // rover if this substep moved it closer. The rock's highest point under the footprint is
  // where the footprint comes nearest its centre (a half-ellipsoid falls away from there):
  // its top when the centre is under the body, only its low rim when a corner grazes it.
  const double hl = 0.5 * options_.geometry.footprint_length_m;
  const double hw = 0.5 * options_.geometry.footprint_width_m;
  const double clearance = options_.rock_collision.max_height_m;
  const double c = std::cos(yaw_), s = std::sin(yaw_);
  for (const terrain::Rock* r : tall_rocks_) {
    const Eigen::Vector2d d = r->position - Eigen::Vector2d(x_, y_);
    const double u = c * d.x() + s * d.y(), v = -s * d.x() + c * d.y();
    const double gap = std::hypot(std::max(std::abs(u) - hl, 0.0), std::max(std::abs(v) - hw, 0.0));
    const double under = terrain::RockHeightAt(*r, gap);
    if (under <= clearance) continue;
    const double before = (r->position - p_prev.head<2>()).norm();
    if (d.norm() < before) {
      Fault("rock " + r->name + Format(" (%.2f m tall, centred at (%.2f, %.2f)) %.2f m high under the footprint, over the "
                                       "%.2f m clearance, the rover at (%.2f, %.2f)",
                                       r->height_m, r->position.x(), r->position.y(), under, clearance, x_, y_));
      return;
    }
  }
}

double RoverSimulator::ClimbGrade(double x, double y, double travel_x, double travel_y) const {
  // Rock height = surface - ground; a wheel of radius r meets a rock's rise over r ahead.
  const double r = options_.geometry.wheel_radius_m;
  const double ax = x + r * travel_x, ay = y + r * travel_y;
  const double here = world_.Elevation(x, y) - world_.GroundElevation(x, y);
  const double ahead = world_.Elevation(ax, ay) - world_.GroundElevation(ax, ay);
  return std::max(0.0, ahead - here) / r;
}

bool RoverSimulator::FollowTerrain() {
  // Fit elevation = a + b*u + c*v to the six wheel contacts, with (u, v) the horizontal
  // offsets along the heading and to its right. Using the projected offsets (not the
  // nominal wheel positions) keeps pitch equal to the slope on steep ground.
  const double cy = std::cos(yaw_), sy = std::sin(yaw_);
  // The direction the wheels roll: backward on a reverse drive.
  const double sign =
      command_.type == MotionCommand::Type::kArc && command_.distance_m < 0.0 ? -1.0 : 1.0;
  const double travel_x = sign * cy, travel_y = sign * sy;
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  bool on_map = true;
  for (int i = 0; i < kNumWheels; ++i) {
    const Eigen::Vector3d d = R_ * Eigen::Vector3d(wheel_xy_[i].x(), wheel_xy_[i].y(), 0.0);
    const double wx = x_ + d.x(), wy = y_ + d.y();
    on_map = on_map && world_.Contains(wx, wy);
    const double h = world_.Elevation(wx, wy);
    wheel_soil_[i] = world_.SoilAt(wx, wy);
    wheel_climb_grade_[i] = ClimbGrade(wx, wy, travel_x, travel_y);
    const Eigen::Vector3d row(1.0, cy * d.x() + sy * d.y(), -sy * d.x() + cy * d.y());
    A += row * row.transpose();
    rhs += row * h;
  }
  const Eigen::Vector3d plane = A.ldlt().solve(rhs);
  plane_slope_fwd_ = plane.y();
  plane_slope_right_ = plane.z();
  z_ = -plane.x();
  pitch_ = std::atan(plane_slope_fwd_);
  const double n = std::sqrt(1.0 + plane.y() * plane.y() + plane.z() * plane.z());
  roll_ = std::asin(std::clamp(-plane.z() / n, -1.0, 1.0));
  R_ = geometry::RotationFromRpy(roll_, pitch_, yaw_);
  return on_map;
}

ImuSample RoverSimulator::MakeImuSample() {
  const auto& o = options_.imu;
  ImuSample s;
  s.utime = utime_;
  const double roll = roll_ + o.tilt_noise_deg * kDeg * imu_rng_.Normal();
  const double pitch = pitch_ + o.tilt_noise_deg * kDeg * imu_rng_.Normal();
  s.q_site_rover =
      Eigen::Quaterniond(geometry::RotationFromRpy(roll, pitch, yaw_ + yaw_error_)).normalized();
  const double bias = o.yaw_drift_deg_per_hour * kDeg / 3600.0;
  s.angular_rate_rps = body_rate_ + Eigen::Vector3d(0.0, 0.0, bias);
  for (int k = 0; k < 3; ++k) s.angular_rate_rps[k] += o.rate_noise_deg_s * kDeg * imu_rng_.Normal();
  // Specific force at rest: gravity is +Z (down) in the site frame, so f = (0, 0, -g).
  s.accel_mps2 = R_.transpose() * Eigen::Vector3d(0.0, 0.0, -o.gravity_mps2);
  for (int k = 0; k < 3; ++k) s.accel_mps2[k] += o.accel_noise_mps2 * imu_rng_.Normal();
  return s;
}

WheelOdometrySample RoverSimulator::Odometry() const {
  WheelOdometrySample s;
  s.utime = utime_;
  const double res = options_.encoders.resolution_m;
  for (int i = 0; i < kNumWheels; ++i) {
    s.wheel_distance_m[i] = res > 0.0 ? std::round(wheel_true_[i] / res) * res : wheel_true_[i];
  }
  s.distance_m = odometry_distance_;
  const bool active = moving();
  s.turning_in_place = active && command_.type == MotionCommand::Type::kTurn;
  s.curvature_per_m =
      active && command_.type == MotionCommand::Type::kArc ? command_.curvature_per_m : 0.0;
  return s;
}

RoverTruth RoverSimulator::Truth() const {
  RoverTruth t;
  t.utime = utime_;
  // Origin above the contact plane, along its up normal (the rover's -Z axis).
  t.position = Eigen::Vector3d(x_, y_, z_) - options_.geometry.origin_height_m * R_.col(2);
  t.q_site_rover = Eigen::Quaterniond(R_).normalized();
  t.rpy = Eigen::Vector3d(roll_, pitch_, yaw_);
  t.odometer_m = odometer_;
  t.slip = slip_;
  t.lateral_slip = lateral_slip_;
  t.soil = world_.SoilAt(x_, y_);
  t.command_id = status_.command_id;
  return t;
}

}  // namespace rover::mobility
