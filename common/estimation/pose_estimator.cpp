#include "estimation/pose_estimator.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <sstream>

namespace rover::estimation {

namespace {

using geometry::RpyFromRotation;
using geometry::WrapAngle;

double YawOf(const Eigen::Matrix3d& R) { return RpyFromRotation(R).z(); }

Eigen::Matrix3d Rz(double yaw) {
  return Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
}

// Differences of covariances are symmetric but may be slightly indefinite after a VO
// update lowered one end; project onto the PSD cone.
template <typename Matrix>
Matrix NearestPsd(const Matrix& A) {
  const Matrix S = 0.5 * (A + A.transpose());
  Eigen::SelfAdjointEigenSolver<Matrix> es(S);
  const auto ev = es.eigenvalues().cwiseMax(0.0);
  return es.eigenvectors() * ev.asDiagonal() * es.eigenvectors().transpose();
}

std::string Seconds(int64_t us) {
  std::ostringstream os;
  os << static_cast<double>(us) * 1e-6 << " s";
  return os.str();
}

}  // namespace

const char* ToString(VoUpdateStatus status) {
  switch (status) {
    case VoUpdateStatus::kApplied: return "applied";
    case VoUpdateStatus::kNoHistory: return "no_history";
    case VoUpdateStatus::kFromTooOld: return "from_too_old";
    case VoUpdateStatus::kFromInFuture: return "from_in_future";
    case VoUpdateStatus::kToInFuture: return "to_in_future";
    case VoUpdateStatus::kToNotAfterFrom: return "to_not_after_from";
    case VoUpdateStatus::kNotFinite: return "not_finite";
    case VoUpdateStatus::kBadRotation: return "bad_rotation";
    case VoUpdateStatus::kBadCovariance: return "bad_covariance";
  }
  return "unknown";
}

PoseEstimator::PoseEstimator(const EstimatorOptions& options) : options_(options) {
  options_.Validate();
  P_ = InitialCovariance();
}

PoseEstimator::StateMatrix PoseEstimator::InitialCovariance() const {
  StateMatrix P = StateMatrix::Zero();
  const double s0 = options_.initial_position_sigma_m;
  P.topLeftCorner<3, 3>() = Eigen::Matrix3d::Identity() * s0 * s0;
  P(kHeading, kHeading) = options_.initial_yaw_sigma_rad * options_.initial_yaw_sigma_rad;
  P(kBias, kBias) = options_.gyro_drift_rad_per_s * options_.gyro_drift_rad_per_s;
  P(kVoBias, kVoBias) = options_.vo_yaw_bias_sigma_rad_per_m * options_.vo_yaw_bias_sigma_rad_per_m;
  return P;
}

double PoseEstimator::VoBiasKept(double distance_m) const {
  const double length = options_.vo_yaw_bias_length_m;
  return length > 0.0 ? std::exp(-distance_m / length) : 1.0;
}

double PoseEstimator::vo_yaw_bias_sigma_rad_per_m() const {
  return std::sqrt(std::max(0.0, P_(kVoBias, kVoBias)));
}

double PoseEstimator::gyro_bias_sigma_rad_per_s() const {
  return std::sqrt(std::max(0.0, P_(kBias, kBias)));
}

void PoseEstimator::PropagateHeading(double dt, double abs_dyaw) {
  // The heading error grows by the bias error over dt: F = I + dt e_heading e_bias^T.
  StateMatrix F = StateMatrix::Identity();
  F(kHeading, kBias) = dt;
  P_ = F * P_ * F.transpose();
  const double arw = options_.gyro_random_walk_rad_per_sqrt_s;
  P_(kHeading, kHeading) += arw * arw * dt;
  // The scale-factor error is systematic over a turn: its sigma adds linearly.
  const double s = std::sqrt(std::max(0.0, P_(kHeading, kHeading)));
  const double g = options_.gyro_scale_sigma_fraction * abs_dyaw;
  P_(kHeading, kHeading) += 2.0 * s * g + g * g;
  const double walk = options_.gyro_bias_walk_rad_per_s_per_sqrt_s;
  P_(kBias, kBias) += walk * walk * dt;
}

bool PoseEstimator::StandingStill(int64_t utime, const Eigen::Vector3d& angular_rate) const {
  if (!options_.zero_velocity_updates || !has_odometry_) return false;
  const double since_odometry_s = static_cast<double>(utime - last_odometry_utime_) * 1e-6;
  const double since_motion_s = static_cast<double>(utime - last_wheel_motion_utime_) * 1e-6;
  return since_odometry_s <= options_.zupt_odometry_timeout_s && since_motion_s >= options_.zupt_settle_s &&
         angular_rate.norm() <= options_.zupt_max_rate_rad_per_s;
}

// Zero-velocity update on heading: the wheels stand and the gyro is quiet, so the rover's
// heading has not changed, whatever the IMU's integrated yaw says (its drift). The heading
// error therefore does not grow; only the bias's own walk does.
//
// The wheels' word on rest is the last odometry message's: an IMU sample newer than it is held
// provisionally (kept in unconfirmed_rest_) until the next one says whether the wheels stood
// through it (ConfirmRest) or had started to turn (ResumeHeldMotion). A gentle arc, slower
// than zupt_max_rate, starts with such samples, and their yaw is the arc's, not drift.
void PoseEstimator::HoldHeadingAtRest(int64_t utime, double dt, double dyaw) {
  yaw_offset_ = WrapAngle(yaw_offset_ - dyaw);
  const double walk = options_.gyro_bias_walk_rad_per_s_per_sqrt_s;
  P_(kBias, kBias) += walk * walk * dt;
  if (utime > last_odometry_utime_) {
    unconfirmed_rest_.push_back({utime, dt, dyaw});
  } else {
    AddToRestSegment(dt, dyaw);
  }
}

void PoseEstimator::AddToRestSegment(double dt, double dyaw) {
  rest_segment_s_ += dt;
  rest_segment_dyaw_ += dyaw;
  if (rest_segment_s_ >= options_.zupt_bias_segment_s) {
    FuseRestBias(rest_segment_s_, rest_segment_dyaw_);
    rest_segment_s_ = rest_segment_dyaw_ = 0.0;
  }
}

// Odometry says the wheels stood: the samples held since the last one were at rest. They
// measure the bias only while the rest they belong to goes on.
void PoseEstimator::ConfirmRest() {
  if (at_rest_) {
    for (const HeldSample& h : unconfirmed_rest_) AddToRestSegment(h.dt, h.dyaw);
  }
  unconfirmed_rest_.clear();
}

// Odometry says the wheels turned since the last message: the yaw held since then was the
// start of the motion. It is given back, with the gyro's bias taken off and the heading's
// sigma grown as if it had been integrated, to the pose now and to the history's samples
// of those instants (a VO update may clone from them).
void PoseEstimator::ResumeHeldMotion() {
  if (unconfirmed_rest_.empty()) return;
  const double walk = options_.gyro_bias_walk_rad_per_s_per_sqrt_s;
  double yaw = 0.0, seconds = 0.0, turned = 0.0;
  for (const HeldSample& h : unconfirmed_rest_) {
    P_(kBias, kBias) -= walk * walk * h.dt;  // PropagateHeading walks the bias again
    PropagateHeading(h.dt, std::abs(h.dyaw));
    yaw += h.dyaw - gyro_bias_ * h.dt;
    seconds += h.dt;
    turned += std::abs(h.dyaw);
    const auto it = std::lower_bound(history_.begin(), history_.end(), h.utime,
                                     [](const Sample& s, int64_t t) { return s.utime < t; });
    if (it == history_.end() || it->utime != h.utime) continue;  // replaced by a VO update
    it->q = Eigen::Quaterniond(Rz(yaw) * it->q.toRotationMatrix()).normalized();
    it->P = P_;
    it->gyro_s += seconds;
    it->turned += turned;
    it->at_rest = false;
  }
  yaw_offset_ = WrapAngle(yaw_offset_ + yaw);
  gyro_s_ += seconds;
  turned_rad_ += turned;
  T_site_rover_.linear() = Rz(yaw_offset_) * q_imu_.toRotationMatrix();
  unconfirmed_rest_.clear();
}

// The rest ends: its last segment counts when it is at least a quarter of a full one.
void PoseEstimator::EndRest() {
  if (rest_segment_s_ >= 0.25 * options_.zupt_bias_segment_s) FuseRestBias(rest_segment_s_, rest_segment_dyaw_);
  rest_segment_s_ = rest_segment_dyaw_ = 0.0;
  at_rest_ = false;
}

// A rest segment's yaw drift over its length measures the gyro's bias (rad/s): noise
// arw^2/T from the gyro's white noise and 2 s_r^2/T^2 from the two yaw readings at its ends.
// The update changes the bias estimate only (the heading is held; what the bias did to the
// heading before the rest is VO's to correct), with its sigma and cross terms as such a
// gain leaves them: P_bb R/S and P_xb R/S.
void PoseEstimator::FuseRestBias(double segment_s, double segment_dyaw) {
  if (segment_s <= 0.0) return;
  const double arw = options_.gyro_random_walk_rad_per_sqrt_s;
  const double reading = options_.zupt_yaw_reading_sigma_rad;
  const double R = arw * arw / segment_s + 2.0 * reading * reading / (segment_s * segment_s);
  const double S = P_(kBias, kBias) + R;
  if (!(S > 0.0)) return;
  const double gain = P_(kBias, kBias) / S;
  gyro_bias_ += gain * (segment_dyaw / segment_s - gyro_bias_);
  ConsiderRestBias(R, P_);
  // The bias is one bias before the rest and in it (up to its walk): the samples a VO update
  // will clone from learn it too. Else the next update that spans the rest starts from a
  // `from` that never heard of it, and the measurement is lost (with a VO yaw bias state,
  // the rests are what tell the gyro's bias from VO's).
  for (Sample& h : history_) ConsiderRestBias(R, h.P);
}

// The covariance a bias measurement of noise variance R leaves (its gain on the bias only).
void PoseEstimator::ConsiderRestBias(double R, StateMatrix& P) const {
  const double S = P(kBias, kBias) + R;
  if (!(S > 0.0)) return;
  const double keep = R / S;
  for (int i = 0; i < kStates; ++i) {
    if (i == kBias) continue;
    P(i, kBias) *= keep;
    P(kBias, i) *= keep;
  }
  P(kBias, kBias) *= keep;
}

bool PoseEstimator::AdvanceTime(int64_t utime) {
  if (has_time_ && utime < utime_) {
    ++inputs_rejected_;
    return false;
  }
  utime_ = utime;
  has_time_ = true;
  return true;
}

InputResult PoseEstimator::OnImu(int64_t utime, const Eigen::Quaterniond& q_site_rover,
                                 const Eigen::Vector3d& angular_rate) {
  ImuSample s;
  s.utime = utime;
  s.q_site_rover = q_site_rover;
  s.angular_rate = angular_rate;
  return OnImu(s);
}

InputResult PoseEstimator::OnImu(const ImuSample& imu) {
  const double qn = imu.q_site_rover.norm();
  if (!imu.q_site_rover.coeffs().allFinite() || !imu.angular_rate.allFinite() || qn < 1e-9) {
    ++inputs_rejected_;
    return InputResult::kNotFinite;
  }
  if (!AdvanceTime(imu.utime)) return InputResult::kOutOfOrder;
  const Eigen::Quaterniond q = imu.q_site_rover.normalized();
  const double yaw_imu = YawOf(q.toRotationMatrix());

  if (has_imu_) {
    const double dt = static_cast<double>(imu.utime - last_imu_utime_) * 1e-6;
    const double dyaw = WrapAngle(yaw_imu - YawOf(q_imu_.toRotationMatrix()));
    // Quiet: the gyro's rate and the attitude's own yaw change both under the limit.
    const bool still = StandingStill(imu.utime, imu.angular_rate) &&
                       (dt <= 0.0 || std::abs(dyaw) / dt <= options_.zupt_max_rate_rad_per_s);
    if (at_rest_ && !still) EndRest();
    at_rest_ = still;
    if (at_rest_) {
      HoldHeadingAtRest(imu.utime, dt, dyaw);
    } else {
      // The IMU's heading drifts by the gyro's bias: take off the bias VO has measured.
      yaw_offset_ = WrapAngle(yaw_offset_ - gyro_bias_ * dt);
      turned_rad_ += std::abs(dyaw);
      gyro_s_ += dt;
      PropagateHeading(dt, std::abs(dyaw));
    }
  } else if (pending_reset_yaw_) {
    yaw_offset_ = WrapAngle(*pending_reset_yaw_ - yaw_imu);
    pending_reset_yaw_.reset();
  }
  has_imu_ = true;
  last_imu_utime_ = imu.utime;
  q_imu_ = q;
  angular_rate_ = imu.angular_rate;
  T_site_rover_.linear() = Rz(yaw_offset_) * q.toRotationMatrix();
  Record();
  return InputResult::kAccepted;
}

InputResult PoseEstimator::OnWheelOdometry(int64_t utime, double distance_m,
                                           bool turning_in_place) {
  WheelOdometrySample s;
  s.utime = utime;
  s.distance_m = distance_m;
  s.turning_in_place = turning_in_place;
  return OnWheelOdometry(s);
}

InputResult PoseEstimator::OnWheelOdometry(const WheelOdometrySample& odo) {
  bool finite = std::isfinite(odo.distance_m) && std::isfinite(odo.curvature_per_m);
  for (double w : odo.wheel_distance_m) finite = finite && std::isfinite(w);
  if (!finite) {
    ++inputs_rejected_;
    return InputResult::kNotFinite;
  }
  if (!AdvanceTime(odo.utime)) return InputResult::kOutOfOrder;
  // Any wheel that turned (or a turn in place) ends a rest (EstimatorOptions, "At rest").
  const bool wheels_turned = !has_odometry_ || odo.distance_m != last_distance_m_ || odo.turning_in_place ||
                             odo.wheel_distance_m != wheel_distance_m_;
  if (wheels_turned) {
    ResumeHeldMotion();
    last_wheel_motion_utime_ = odo.utime;
    if (at_rest_) EndRest();  // this sample starts the motion: not one of the rest's
  } else {
    ConfirmRest();
  }
  last_odometry_utime_ = odo.utime;
  const double turn_travel = odo.turning_in_place ? WheelTravelSinceLast(odo.wheel_distance_m) : 0.0;
  wheel_distance_m_ = odo.wheel_distance_m;
  const Eigen::Matrix3d R_now = T_site_rover_.linear();
  if (!has_odometry_) {
    has_odometry_ = true;
    last_distance_m_ = odo.distance_m;
    R_at_last_odometry_ = R_now;
    Record();
    return InputResult::kAccepted;
  }
  double delta = odo.distance_m - last_distance_m_;
  last_distance_m_ = odo.distance_m;
  if (odo.turning_in_place && options_.ignore_distance_while_turning_in_place) delta = 0.0;
  GrowPositionCovarianceInTurn(turn_travel);

  if (delta != 0.0) {
    // Midpoint rule: the mean of the forward axes at both ends follows an arc or a change
    // of slope to second order.
    Eigen::Vector3d forward = R_at_last_odometry_.col(0) + R_now.col(0);
    if (forward.norm() < 1e-9) forward = R_now.col(0);
    forward.normalize();
    T_site_rover_.translation() += forward * delta;
    odometer_m_ += std::abs(delta);
    GrowPositionCovariance(forward * delta);
  }
  R_at_last_odometry_ = R_now;
  Record();
  return InputResult::kAccepted;
}

void PoseEstimator::GrowPositionCovariance(const Eigen::Vector3d& displacement) {
  const double distance = displacement.norm();
  if (distance <= 0.0) return;
  // A heading error swings the displacement about the vertical: dp = (z x d) dpsi.
  StateMatrix F = StateMatrix::Identity();
  F.block<3, 1>(0, kHeading) = Eigen::Vector3d::UnitZ().cross(displacement);
  P_ = F * P_ * F.transpose();

  const Eigen::Vector3d forward = displacement / distance;
  Eigen::Vector3d cross = Eigen::Vector3d::UnitZ().cross(forward);
  if (cross.norm() < 1e-6) cross = T_site_rover_.linear().col(1);
  cross.normalize();
  const Eigen::Vector3d up = forward.cross(cross).normalized();

  // Wheel odometry's own error: sigma along each axis grows by (fraction * distance), so
  // that it stays proportional to the distance driven (slip and wheel radius are mostly
  // systematic): P += ((s + g)^2 - s^2) e e^T with s the current sigma along e.
  const Eigen::Vector3d axes[3] = {forward, cross, up};
  const Eigen::Vector2d fraction = wheel_sigma_fractions();
  const double growth[3] = {fraction.x() * distance, fraction.y() * distance,
                            options_.vertical_sigma_fraction * distance};
  for (int i = 0; i < 3; ++i) GrowPositionSigmaAlong(axes[i], growth[i]);
}

// P += ((s + g)^2 - s^2) e e^T, with s the position's sigma along the unit vector e now.
void PoseEstimator::GrowPositionSigmaAlong(const Eigen::Vector3d& e, double g) {
  auto P_pos = P_.topLeftCorner<3, 3>();
  const double s = std::sqrt(std::max(0.0, e.dot(P_pos * e)));
  P_pos += (2.0 * s * g + g * g) * e * e.transpose();
}

// The mean distance the wheels rolled since the last odometry message (0 when it does not
// carry them, or carries a different number of wheels).
double PoseEstimator::WheelTravelSinceLast(const std::vector<double>& wheel_distance_m) const {
  if (wheel_distance_m.empty() || wheel_distance_m.size() != wheel_distance_m_.size()) return 0.0;
  double sum = 0.0;
  for (std::size_t i = 0; i < wheel_distance_m.size(); ++i) sum += std::abs(wheel_distance_m[i] - wheel_distance_m_[i]);
  return sum / static_cast<double>(wheel_distance_m.size());
}

// A turn in place moves the body too: the wheels scrub and, on a slope, creep downhill. The
// position's sigma grows in both horizontal directions by the cross-track fraction of the
// distance the wheels rolled (the direction of the creep is the slope's, which the
// estimator does not know).
void PoseEstimator::GrowPositionCovarianceInTurn(double wheel_travel_m) {
  if (!(wheel_travel_m > 0.0)) return;
  const double g = wheel_sigma_fractions().y() * wheel_travel_m;
  GrowPositionSigmaAlong(Eigen::Vector3d::UnitX(), g);
  GrowPositionSigmaAlong(Eigen::Vector3d::UnitY(), g);
}

Eigen::Vector2d PoseEstimator::wheel_sigma_fractions() const {
  Eigen::Vector2d f(options_.along_track_sigma_fraction, options_.cross_track_sigma_fraction);
  for (const Eigen::Vector2d& m : measured_slip_) f = f.cwiseMax(m);
  return f;
}

// The wheels' own error over [from, to]: where they put the rover (the history at `to`,
// before this update) against where VO did, along and across the way driven, each as a
// fraction of the wheels' travel. It includes VO's own error (millimetres over a step) and
// the heading's swing of the path, both small beside the slip it is there to catch.
void PoseEstimator::MeasureWheelSlip(const Sample& from, const Sample& to_wheels, const Eigen::Vector3d& t_site_vo) {
  if (options_.slip_memory_updates <= 0) return;
  const double travel = to_wheels.odometer - from.odometer;
  const Eigen::Vector3d wheels = to_wheels.p - from.p;
  Eigen::Vector3d forward(wheels.x(), wheels.y(), 0.0);
  // Too little travel, or travel that went back and forth (or round) with too little net
  // way to tell along from across: no measurement.
  if (!(travel >= options_.slip_min_distance_m) || forward.norm() < 0.5 * options_.slip_min_distance_m) return;
  forward.normalize();
  const Eigen::Vector3d cross = Eigen::Vector3d::UnitZ().cross(forward);
  const Eigen::Vector3d error = t_site_vo - wheels;
  measured_slip_.emplace_back(std::abs(error.dot(forward)) / travel, std::abs(error.dot(cross)) / travel);
  while (static_cast<int>(measured_slip_.size()) > options_.slip_memory_updates) measured_slip_.pop_front();
}

PoseEstimator::Sample PoseEstimator::Current() const {
  Sample s;
  s.utime = utime_;
  s.p = T_site_rover_.translation();
  s.q = Eigen::Quaterniond(T_site_rover_.linear()).normalized();
  s.P = P_;
  s.odometer = odometer_m_;
  s.turned = turned_rad_;
  s.gyro_s = gyro_s_;
  s.at_rest = at_rest_;
  return s;
}

void PoseEstimator::SetCurrent(const Sample& s) {
  T_site_rover_.translation() = s.p;
  T_site_rover_.linear() = s.q.toRotationMatrix();
  P_ = s.P;
  odometer_m_ = s.odometer;
  turned_rad_ = s.turned;
  gyro_s_ = s.gyro_s;
}

void PoseEstimator::Record() {
  const Sample s = Current();
  if (!history_.empty() && history_.back().utime == s.utime) {
    history_.back() = s;
  } else {
    history_.push_back(s);
  }
  // A stretch at rest is kept as its two ends: the pose between them is the same, so an
  // hour or a night parked costs two samples, and a VO update from before it still finds
  // its `from` (a pause is not a reason to refuse a VO update for age). Samples held only
  // provisionally (newer than the last odometry) are kept until odometry confirms them.
  if (s.at_rest && s.utime <= last_odometry_utime_) {
    while (history_.size() >= 3 && history_[history_.size() - 2].at_rest && history_[history_.size() - 3].at_rest) {
      history_.erase(history_.end() - 2);
    }
  }
  while (history_.size() > static_cast<std::size_t>(options_.history_max_samples)) {
    history_.pop_front();
  }
  // Keep one sample at or before the cut-off so that look-ups at the cut-off interpolate.
  // The history spans history_s of time the rover was not at rest (Sample::gyro_s): a
  // pause or a night adds nothing to it, so the capture before it stays in reach.
  const double cutoff = gyro_s_ - options_.history_s;
  while (history_.size() > 2 && history_[1].gyro_s <= cutoff) history_.pop_front();
}

PoseEstimator::Sample PoseEstimator::Interpolate(int64_t utime) const {
  if (utime >= history_.back().utime) {
    Sample s = history_.back();
    s.utime = utime;
    return s;
  }
  const auto it = std::lower_bound(history_.begin(), history_.end(), utime,
                                   [](const Sample& s, int64_t t) { return s.utime < t; });
  if (it->utime == utime || it == history_.begin()) return *it;
  const Sample& a = *(it - 1);
  const Sample& b = *it;
  const double f = static_cast<double>(utime - a.utime) / static_cast<double>(b.utime - a.utime);
  Sample s;
  s.utime = utime;
  s.p = a.p + f * (b.p - a.p);
  s.q = a.q.slerp(f, b.q).normalized();
  s.P = a.P + f * (b.P - a.P);
  s.odometer = a.odometer + f * (b.odometer - a.odometer);
  s.turned = a.turned + f * (b.turned - a.turned);
  s.gyro_s = a.gyro_s + f * (b.gyro_s - a.gyro_s);
  s.at_rest = a.at_rest && b.at_rest;
  return s;
}

std::optional<geometry::Pose> PoseEstimator::PoseAt(int64_t utime) const {
  if (history_.empty() || utime < history_.front().utime || utime > history_.back().utime) {
    return std::nullopt;
  }
  const Sample s = Interpolate(utime);
  geometry::Pose T = geometry::Pose::Identity();
  T.linear() = s.q.toRotationMatrix();
  T.translation() = s.p;
  return T;
}

PoseEstimator::VoCloneModel PoseEstimator::CloneToVoEnd(const Sample& from, const Sample& to,
                                                        const Eigen::Vector3d& t_site,
                                                        const geometry::Matrix6d& vo_covariance) const {
  // Inputs: the errors at `from` [x y z heading bias vo_bias], the gyro's white noise w over
  // the interval, the bias walk v, the VO yaw bias's driving noise u, and VO's noise on its
  // translation (rover frame at `from`) and on its yaw change.
  enum { kW = kStates, kV, kU, kVoT, kVoYaw = kVoT + 3, kInputs };
  // The gyro's bias and noise act on the heading only while it was integrated (not at
  // rest, where it was held); the bias wanders all the time.
  const double dt = std::max(0.0, to.gyro_s - from.gyro_s);
  const double dt_walk = static_cast<double>(to.utime - from.utime) * 1e-6;
  const double distance = t_site.norm();
  const double arw = options_.gyro_random_walk_rad_per_sqrt_s;
  const double scale = options_.gyro_scale_sigma_fraction * std::max(0.0, to.turned - from.turned);
  const double walk = options_.gyro_bias_walk_rad_per_s_per_sqrt_s;
  // VO's yaw bias over the distance: a first-order Gauss-Markov process (its correlation
  // decays as exp(-distance / length) and its variance stays sigma^2), or a constant.
  const double vo_sigma = options_.vo_yaw_bias_sigma_rad_per_m;
  const double vo_keep = VoBiasKept(distance);
  Eigen::Matrix<double, kInputs, kInputs> S = Eigen::Matrix<double, kInputs, kInputs>::Zero();
  S.topLeftCorner<kStates, kStates>() = from.P;
  S(kW, kW) = arw * arw * dt + scale * scale;
  S(kV, kV) = walk * walk * dt_walk;
  S(kU, kU) = vo_sigma * vo_sigma * (1.0 - vo_keep * vo_keep);
  // x y z yaw of VO's x y z roll pitch yaw; VO's yaw weighed at vo_yaw_sigma_factor times
  // its sigma (EstimatorOptions).
  const int vo_index[4] = {0, 1, 2, 5};
  const double vo_scale[4] = {1.0, 1.0, 1.0, options_.vo_yaw_sigma_factor};
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) {
      S(kVoT + i, kVoT + j) = vo_scale[i] * vo_scale[j] * vo_covariance(vo_index[i], vo_index[j]);
    }
  }

  // Outputs: the errors at `to` [x y z heading bias vo_bias] and the gyro check. VO's yaw
  // change has the VO yaw bias learnt so far times its distance taken off; what is left of
  // that bias (the state) errs it by its residue times the distance.
  enum { kCheck = kStates, kOutputs };
  Eigen::Matrix<double, kOutputs, kInputs> A = Eigen::Matrix<double, kOutputs, kInputs>::Zero();
  A.block<3, 3>(0, 0).setIdentity();                                   // p(from)
  A.block<3, 1>(0, kHeading) = Eigen::Vector3d::UnitZ().cross(t_site);  // heading swings t
  A.block<3, 3>(0, kVoT) = from.q.toRotationMatrix();                  // VO's translation
  A(kHeading, kHeading) = 1.0;
  if (options_.vo_heading == VoHeadingMode::kReplace) {
    A(kHeading, kVoYaw) = 1.0;  // heading(to) = heading(from) + VO's yaw change
    A(kHeading, kVoBias) = distance;
  } else {
    A(kHeading, kBias) = dt;    // heading(to) = heading(from) + the gyro's
    A(kHeading, kW) = 1.0;
  }
  A(kBias, kBias) = 1.0;
  A(kBias, kV) = 1.0;
  A(kVoBias, kVoBias) = vo_keep;
  A(kVoBias, kU) = 1.0;
  // check = VO's yaw change - the gyro's = VO's yaw error - (bias * dt + w).
  A(kCheck, kVoYaw) = 1.0;
  A(kCheck, kVoBias) = distance;
  A(kCheck, kBias) = -dt;
  A(kCheck, kW) = -1.0;

  const Eigen::Matrix<double, kOutputs, kOutputs> C = A * S * A.transpose();
  VoCloneModel m;
  m.P_to = C.topLeftCorner<kStates, kStates>();
  m.cov_to_check = C.block<kStates, 1>(0, kCheck);
  m.check_variance = C(kCheck, kCheck);
  return m;
}

PoseEstimator::StateVector PoseEstimator::FuseGyroCheck(const VoCloneModel& m, double check,
                                                     StateMatrix& P_to) const {
  if (!(m.check_variance > 0.0)) {
    // Neither VO nor the gyro claims any error: take the mean of the two yaw changes.
    StateVector e = StateVector::Zero();
    e(kHeading) = -0.5 * check;
    return e;
  }
  // The check corrects the heading and the bias only. The position is a considered state
  // (a Schmidt update: its gain is zero, its covariance with them is updated as such a gain
  // leaves it): the check's bearing on the position runs through the correlations a bias
  // leaves on past headings, and VO's yaw errors that persist over steps, which no one
  // step's covariance holds, moved the position by them: (0.14, 0.26) m over a 516 m drive
  // (README, "Honest over a long day").
  StateVector K = m.cov_to_check / m.check_variance;
  K.head<3>().setZero();
  P_to += -K * m.cov_to_check.transpose() - m.cov_to_check * K.transpose() +
          K * m.check_variance * K.transpose();
  P_to = NearestPsd(StateMatrix(0.5 * (P_to + P_to.transpose())));
  return K * check;
}

VoUpdateResult PoseEstimator::ApplyVoUpdate(const VoUpdate& u) {
  VoUpdateResult result;
  auto refuse = [&](VoUpdateStatus status, const std::string& reason) {
    result.status = status;
    result.reason = reason;
    return result;
  };

  const Eigen::Matrix3d R_vo = u.T_from_to.linear();
  const Eigen::Vector3d t_vo = u.T_from_to.translation();
  if (!R_vo.allFinite() || !t_vo.allFinite()) {
    return refuse(VoUpdateStatus::kNotFinite, "VO delta holds NaN or inf");
  }
  if (!u.covariance.allFinite()) {
    return refuse(VoUpdateStatus::kNotFinite, "VO covariance holds NaN or inf");
  }
  const double ortho_error = (R_vo.transpose() * R_vo - Eigen::Matrix3d::Identity()).norm();
  if (ortho_error > 1e-6 || R_vo.determinant() < 0.0) {
    std::ostringstream os;
    os << "VO rotation is not a rotation (|R^T R - I| = " << ortho_error
       << ", det = " << R_vo.determinant() << ")";
    return refuse(VoUpdateStatus::kBadRotation, os.str());
  }
  const double cov_scale = 1.0 + u.covariance.cwiseAbs().maxCoeff();
  if ((u.covariance.diagonal().array() < 0.0).any() ||
      (u.covariance - u.covariance.transpose()).cwiseAbs().maxCoeff() > 1e-9 * cov_scale) {
    return refuse(VoUpdateStatus::kBadCovariance,
                  "VO covariance has a negative variance or is not symmetric");
  }
  if (u.to_utime <= u.from_utime) {
    return refuse(VoUpdateStatus::kToNotAfterFrom,
                  "to_utime " + std::to_string(u.to_utime) + " is not after from_utime " +
                      std::to_string(u.from_utime));
  }
  if (history_.empty()) {
    return refuse(VoUpdateStatus::kNoHistory, "no IMU or wheel odometry received yet");
  }
  const int64_t oldest = history_.front().utime;
  const int64_t newest = history_.back().utime;
  if (u.from_utime < oldest) {
    return refuse(VoUpdateStatus::kFromTooOld,
                  "from_utime " + std::to_string(u.from_utime) + " is " +
                      Seconds(oldest - u.from_utime) +
                      " older than the pose history (oldest " + std::to_string(oldest) + ")");
  }
  const int64_t tolerance_us = static_cast<int64_t>(options_.vo_future_tolerance_s * 1e6);
  if (u.from_utime > newest + tolerance_us) {
    return refuse(VoUpdateStatus::kFromInFuture,
                  "from_utime " + std::to_string(u.from_utime) + " is " +
                      Seconds(u.from_utime - newest) + " after the latest input (tolerance " +
                      Seconds(tolerance_us) + ")");
  }
  if (u.to_utime > newest + tolerance_us) {
    return refuse(VoUpdateStatus::kToInFuture,
                  "to_utime " + std::to_string(u.to_utime) + " is " +
                      Seconds(u.to_utime - newest) +
                      " after the latest input (tolerance " + Seconds(tolerance_us) + ")");
  }

  // A `to` just after the latest input is taken at the latest input (the rover stands still
  // for a capture). The clock does not jump ahead, so inputs stamped before `to` that are
  // still on their way are accepted, and the history stays ordered.
  const int64_t from_utime = std::min(u.from_utime, newest);
  const int64_t to_utime = std::min(u.to_utime, newest);
  const Sample from = Interpolate(from_utime);
  const Sample to_old = Interpolate(to_utime);
  const Sample now_old = Current();

  const Eigen::Matrix3d R_from = from.q.toRotationMatrix();
  const Eigen::Vector3d t_site = R_from * t_vo;
  MeasureWheelSlip(from, to_old, t_site);

  // The yaw changes over [from, to] as VO and as the gyro (bias already taken off) saw them.
  const double yaw_from = YawOf(R_from);
  const double yaw_to_old = YawOf(to_old.q.toRotationMatrix());
  const double dyaw_gyro = WrapAngle(yaw_to_old - yaw_from);
  // VO's: less the yaw bias learnt for it over the distance it measured.
  const double dyaw_vo = WrapAngle(YawOf(R_from * R_vo) - yaw_from - vo_yaw_bias_ * t_vo.norm());

  // The errors at `to` as a linear map of the errors at `from` and the new noises.
  const VoCloneModel model = CloneToVoEnd(from, to_old, t_site, u.covariance);
  Sample to_new;
  to_new.utime = to_utime;
  to_new.p = from.p + t_site;
  to_new.P = model.P_to;
  to_new.odometer = from.odometer + t_vo.norm();
  to_new.turned = to_old.turned;
  // The gyro's clock runs on through a VO update: the next update's interval is measured
  // from here. (Left at zero, the next `from` made the gyro's noise and bias act over the
  // whole drive so far, at every update: the gyro check then weighed VO's yaw alone and
  // "measured" the bias over hours it had not been integrated.)
  to_new.gyro_s = to_old.gyro_s;
  to_new.at_rest = to_old.at_rest;
  double yaw_to = yaw_from + dyaw_gyro;
  switch (options_.vo_heading) {
    case VoHeadingMode::kReplace:
      yaw_to = yaw_from + dyaw_vo;
      break;
    case VoHeadingMode::kFuse: {
      // VO's yaw change minus the gyro's measures the gyro's error over the interval.
      const StateVector e = FuseGyroCheck(model, WrapAngle(dyaw_vo - dyaw_gyro), to_new.P);
      to_new.p -= e.head<3>();
      yaw_to -= e(kHeading);
      gyro_bias_ += e(kBias);
      vo_yaw_bias_ = vo_yaw_bias_ * VoBiasKept(t_vo.norm()) + e(kVoBias);
      break;
    }
    case VoHeadingMode::kIgnore:
      break;
  }
  const double dpsi = WrapAngle(yaw_to - yaw_to_old);
  const Eigen::Matrix3d Rz_dpsi = Rz(dpsi);
  to_new.q = Eigen::Quaterniond(Rz_dpsi * to_old.q.toRotationMatrix()).normalized();

  auto reapply = [&](const Sample& old) {
    Sample s = old;
    s.p = to_new.p + Rz_dpsi * (old.p - to_old.p);
    s.q = Eigen::Quaterniond(Rz_dpsi * old.q.toRotationMatrix()).normalized();
    s.P = to_new.P + NearestPsd(StateMatrix(old.P - to_old.P));
    s.odometer = to_new.odometer + (old.odometer - to_old.odometer);
    return s;
  };

  std::deque<Sample> rebuilt;
  for (const Sample& s : history_) {
    if (s.utime < from_utime) rebuilt.push_back(s);
  }
  rebuilt.push_back(from);
  if (to_utime > from_utime) {
    rebuilt.push_back(to_new);
  } else {
    rebuilt.back() = to_new;  // both captures after the latest input: one instant in history
  }
  for (const Sample& s : history_) {
    if (s.utime > to_utime) rebuilt.push_back(reapply(s));
  }
  history_.swap(rebuilt);

  SetCurrent(to_utime >= now_old.utime ? to_new : reapply(now_old));
  R_at_last_odometry_ = Rz_dpsi * R_at_last_odometry_;
  yaw_offset_ = WrapAngle(yaw_offset_ + dpsi);
  source_ = PoseSource::kVo;
  last_vo_to_frame_ = u.to_frame_id;
  Record();

  result.position_correction_m = T_site_rover_.translation() - now_old.p;
  result.yaw_correction_rad = dpsi;
  return result;
}

void PoseEstimator::Reset(const geometry::Pose& T_site_rover, int64_t utime) {
  if (!T_site_rover.matrix().allFinite()) {
    throw std::invalid_argument("PoseEstimator::Reset: pose holds NaN or inf");
  }
  T_site_rover_ = T_site_rover;
  const double yaw = YawOf(T_site_rover.linear());
  if (has_imu_) {
    yaw_offset_ = WrapAngle(yaw - YawOf(q_imu_.toRotationMatrix()));
  } else {
    pending_reset_yaw_ = yaw;
  }
  // The gyro's bias belongs to the gyro and VO's yaw bias to VO, not to the pose: their
  // estimates and sigmas are kept.
  const Eigen::Matrix2d bias_covariance = P_.block<2, 2>(kBias, kBias);
  P_ = InitialCovariance();
  P_.block<2, 2>(kBias, kBias) = bias_covariance;
  R_at_last_odometry_ = T_site_rover.linear();
  source_ = PoseSource::kWheelImu;
  utime_ = utime;
  has_time_ = true;
  history_.clear();
  unconfirmed_rest_.clear();
  measured_slip_.clear();
  Record();
}

void PoseEstimator::NewSite(std::optional<int32_t> site_index) {
  const Eigen::Vector3d origin = T_site_rover_.translation();
  const Eigen::Matrix3d P0 = InitialCovariance().topLeftCorner<3, 3>();
  // Past positions relative to the new origin are uncertain by the growth between them and
  // now; that keeps a VO update spanning the new site meaningful. At the origin the position
  // error is P0 and no longer tied to the heading or the bias.
  auto restart = [&](StateMatrix& P, const Eigen::Matrix3d& P_pos) {
    P.topLeftCorner<3, 3>() = P_pos;
    P.topRightCorner<3, kStates - 3>().setZero();
    P.bottomLeftCorner<kStates - 3, 3>().setZero();
  };
  const Eigen::Matrix3d P_now = P_.topLeftCorner<3, 3>();
  for (Sample& s : history_) {
    s.p -= origin;
    restart(s.P, P0 + NearestPsd(Eigen::Matrix3d(P_now - s.P.topLeftCorner<3, 3>())));
  }
  T_site_rover_.translation().setZero();
  restart(P_, P0);
  site_index_ = site_index ? *site_index : site_index_ + 1;
  if (!history_.empty()) {
    history_.back().p.setZero();
    history_.back().P = P_;
  }
}

geometry::Matrix6d PoseEstimator::covariance() const {
  geometry::Matrix6d P = geometry::Matrix6d::Zero();
  P.topLeftCorner<3, 3>() = P_.topLeftCorner<3, 3>();
  P(3, 3) = P(4, 4) = options_.attitude_sigma_rad * options_.attitude_sigma_rad;
  P(5, 5) = P_(kHeading, kHeading);
  // A heading error and the position error it caused are correlated.
  P.block<3, 1>(0, 5) = P_.block<3, 1>(0, kHeading);
  P.block<1, 3>(5, 0) = P_.block<1, 3>(kHeading, 0);
  return P;
}
PoseEstimate PoseEstimator::Estimate() const {
  PoseEstimate e;
  e.utime = utime_;
  e.T_site_rover = T_site_rover_;
  e.covariance = covariance();
  e.source = source_;
  e.site_index = site_index_;
  e.odometer_m = odometer_m_;
  e.last_vo_to_frame = last_vo_to_frame_;
  return e;
}

}  // namespace rover::estimation
