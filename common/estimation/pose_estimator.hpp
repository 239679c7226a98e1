// The on-board pose estimate, as on MER (Maimone 2005, sec. 1): attitude from the IMU,
// position from wheel odometry integrated along that 3-D attitude, and VO updates that
// replace the wheel-odometry motion between two stereo captures.
//
// Frames and covariance order are those of geometry/pose.hpp (site X north, Y east, Z down;
// rover X forward, Y right, Z down; covariance x y z roll pitch yaw).
//
// Everything is driven by message time (utime, microseconds of rover time); there is no
// wall clock, so replaying the same inputs gives the same poses bit for bit.
//
// Heading. The estimated attitude is R_est = Rz(yaw_offset) * R_imu: roll and pitch always
// come from the IMU (it levels on gravity), and yaw is the IMU yaw plus an offset. A VO
// update changes only that offset (EstimatorOptions::vo_heading), so VO never tilts the
// rover, and the gyro keeps integrating heading change between updates.
//
// VO update (ApplyVoUpdate). With T_from_to from VO, the estimator
//   1. looks up the estimated pose at from_utime and at to_utime (interpolated in time),
//   2. sets p(to) = p(from) + R_est(from) * t_from_to, and yaw(to) per vo_heading,
//   3. re-applies the motion accumulated after to_utime on top, rotated by the heading
//      correction: p(t) = p_new(to) + Rz(dyaw) * (p_old(t) - p_old(to)),
//   4. drops the history samples strictly between from and to (the VO motion replaced
//      them; later look-ups there interpolate between the corrected ends).
// Covariance. The estimator carries one covariance over the errors of
// [x, y, z, heading, gyro bias, VO yaw bias] (site frame), so a heading error and the position error it
// causes stay correlated, and a gyro bias makes the heading error grow in proportion to time,
// not to its square root:
//   - IMU: the heading error grows by bias error * dt, plus angle random walk and the
//     gyro's scale-factor error on each yaw change; the bias wanders (bias walk).
//   - Wheel odometry: the position error grows by the heading error swinging each
//     displacement about the vertical (the Jacobian), plus the along/cross/vertical growth.
//   - VO update: the state at `from` is cloned to `to` twice, along the VO motion (position)
//     and along the gyro (heading, bias). The VO yaw change minus the gyro's is then a
//     measurement of the gyro's error over [from, to] (its bias times the interval plus its
//     noise); with vo_heading: fuse, one Kalman update on it corrects the heading at `to`
//     and the gyro bias estimate, which the IMU path subtracts from then on (the position
//     is a considered state: the check does not move it).
//     The wheel growth over [from, to] is gone; the growth added after `to` is added back on
//     top (an approximation: the later growth keeps its earlier correlations).
//
// New site (NewSite). The pose becomes the origin of a new site frame: x = y = z = 0,
// attitude kept (a site frame is still north-east-down), site_index + 1, position
// covariance back to the initial value. The history is moved into the new frame, so a VO
// update whose `from` precedes the new site still applies.
#pragma once

#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <vector>

#include "estimation/estimator_options.hpp"
#include "geometry/pose.hpp"

namespace rover::estimation {

// Mirrors pose_t.SOURCE_*: what last corrected the position.
enum class PoseSource : int8_t { kWheelImu = 0, kVo = 1 };

// Why an input message was or was not used. Inputs never throw: a process callback must
// not throw, so bad data is reported and counted instead.
enum class InputResult {
  kAccepted,
  kOutOfOrder,  // utime older than the latest input: ignored
  kNotFinite,   // NaN/inf, or a zero quaternion: ignored
};

enum class VoUpdateStatus {
  kApplied,
  kNoHistory,      // no IMU or odometry received yet
  kFromTooOld,     // from_utime precedes the pose history
  kFromInFuture,   // from_utime after the latest input
  kToInFuture,     // to_utime after the latest input by more than vo_future_tolerance_s
  kToNotAfterFrom, // to_utime <= from_utime
  kNotFinite,      // NaN/inf in the delta or the covariance
  kBadRotation,    // the delta's rotation is not orthonormal
  kBadCovariance,  // negative variance or asymmetric covariance
};
const char* ToString(VoUpdateStatus status);

struct ImuSample {
  int64_t utime = 0;
  Eigen::Quaterniond q_site_rover = Eigen::Quaterniond::Identity();  // yaw drifts
  Eigen::Vector3d angular_rate = Eigen::Vector3d::Zero();            // rad/s, rover frame
};

struct WheelOdometrySample {
  int64_t utime = 0;
  double distance_m = 0.0;  // cumulative, signed path length of the body
  // Optional, cumulative per wheel: kept, and in a turn in place the distance they rolled
  // grows the position's sigma (the body scrubs and creeps).
  std::vector<double> wheel_distance_m;
  double curvature_per_m = 0.0;
  bool turning_in_place = false;
};

struct VoUpdate {
  int64_t from_utime = 0;
  int64_t to_utime = 0;
  // inverse(T_site_rover(from)) * T_site_rover(to), in the rover frame at `from`.
  geometry::Pose T_from_to = geometry::Pose::Identity();
  geometry::Matrix6d covariance = geometry::Matrix6d::Zero();  // x y z roll pitch yaw
  int64_t from_frame_id = -1;
  int64_t to_frame_id = -1;
};

struct VoUpdateResult {
  VoUpdateStatus status = VoUpdateStatus::kApplied;
  std::string reason;  // empty when applied
  // How much the update moved the current pose (site frame) and turned its heading.
  Eigen::Vector3d position_correction_m = Eigen::Vector3d::Zero();
  double yaw_correction_rad = 0.0;
  bool applied() const { return status == VoUpdateStatus::kApplied; }
};

// Everything pose_t carries.
struct PoseEstimate {
  int64_t utime = 0;
  geometry::Pose T_site_rover = geometry::Pose::Identity();
  geometry::Matrix6d covariance = geometry::Matrix6d::Zero();
  PoseSource source = PoseSource::kWheelImu;
  int32_t site_index = 0;
  double odometer_m = 0.0;
  int64_t last_vo_to_frame = -1;
};

class PoseEstimator {
 public:
  // Throws std::invalid_argument if the options are out of range.
  explicit PoseEstimator(const EstimatorOptions& options = {});

  // Attitude from the IMU. The first sample sets the attitude; yaw follows the IMU plus
  // the current heading offset. Heading sigma grows with gyro drift over time.
  InputResult OnImu(const ImuSample& imu);
  InputResult OnImu(int64_t utime, const Eigen::Quaterniond& q_site_rover,
                    const Eigen::Vector3d& angular_rate);

  // Position: the increment of the cumulative body distance since the previous sample,
  // along the rover's forward axis (mean of the axes at the previous and this sample), so
  // a climb changes z. The first sample only sets the reference distance.
  InputResult OnWheelOdometry(const WheelOdometrySample& odometry);
  InputResult OnWheelOdometry(int64_t utime, double distance_m, bool turning_in_place = false);

  VoUpdateResult ApplyVoUpdate(const VoUpdate& update);

  // Sets the pose (the IMU's roll and pitch take over again at the next IMU sample) and
  // the covariance to the initial one; clears the history. Source back to wheel+IMU.
  void Reset(const geometry::Pose& T_site_rover, int64_t utime);
  // Starts a new site frame at the current pose (see the file comment). With no index,
  // the site index increments.
  void NewSite(std::optional<int32_t> site_index = std::nullopt);

  // The estimated pose at a past time, interpolated between history samples (position
  // linear, rotation slerp). Empty outside the history.
  std::optional<geometry::Pose> PoseAt(int64_t utime) const;

  const geometry::Pose& pose() const { return T_site_rover_; }
  geometry::Matrix6d covariance() const;
  int64_t utime() const { return utime_; }
  double odometer_m() const { return odometer_m_; }
  PoseSource source() const { return source_; }
  int32_t site_index() const { return site_index_; }
  int64_t last_vo_to_frame() const { return last_vo_to_frame_; }
  double yaw_offset_rad() const { return yaw_offset_; }
  // The gyro's bias about the vertical as VO has measured it (rad/s, subtracted from the
  // IMU's heading), and its 1-sigma.
  double gyro_bias_rad_per_s() const { return gyro_bias_; }
  double gyro_bias_sigma_rad_per_s() const;
  // VO's yaw bias as learnt against the gyro (rad per metre VO measured, taken off VO's yaw
  // change; EstimatorOptions::vo_yaw_bias_sigma_rad_per_m), and its 1-sigma.
  double vo_yaw_bias_rad_per_m() const { return vo_yaw_bias_; }
  double vo_yaw_bias_sigma_rad_per_m() const;
  bool has_attitude() const { return has_imu_; }
  // Has any input been received (is pose() meaningful)?
  bool initialized() const { return has_imu_ || has_odometry_; }
  PoseEstimate Estimate() const;
  std::size_t history_size() const { return history_.size(); }
  int64_t inputs_rejected() const { return inputs_rejected_; }
  const std::vector<double>& last_wheel_distances_m() const { return wheel_distance_m_; }
  // Standing still now (EstimatorOptions::zero_velocity_updates): the heading is held and
  // the gyro's drift measures its bias.
  bool at_rest() const { return at_rest_; }
  // The wheels' 1-sigma fractions now in use, along and across track: the configured ones,
  // or the worst error VO measured on the last updates where that is more.
  Eigen::Vector2d wheel_sigma_fractions() const;
  const Eigen::Vector3d& last_angular_rate() const { return angular_rate_; }
  const EstimatorOptions& options() const { return options_; }

 private:
  // Error covariance over [x, y, z, heading, gyro bias, VO yaw bias].
  static constexpr int kStates = 6;
  using StateMatrix = Eigen::Matrix<double, kStates, kStates>;
  static constexpr int kHeading = 3;
  static constexpr int kBias = 4;
  static constexpr int kVoBias = 5;

  struct Sample {
    int64_t utime = 0;
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
    StateMatrix P = StateMatrix::Zero();
    double odometer = 0.0;
    double turned = 0.0;  // cumulative |yaw change| the gyro measured (rad)
    // Cumulative seconds the gyro's heading was integrated (not at rest): its bias acts on
    // the heading over these only.
    double gyro_s = 0.0;
    bool at_rest = false;
  };

  Sample Current() const;
  Sample Interpolate(int64_t utime) const;  // requires utime within the history
  void SetCurrent(const Sample& s);
  void Record();  // appends the current state and prunes
  using StateVector = Eigen::Matrix<double, kStates, 1>;
  // The errors at a VO update's `to`, cloned from `from` along the VO motion and the gyro
  // (see the file comment): their covariance, and how they covary with the gyro check (the
  // VO yaw change minus the gyro's), whose variance is check_variance.
  struct VoCloneModel {
    StateMatrix P_to = StateMatrix::Zero();
    StateVector cov_to_check = StateVector::Zero();
    double check_variance = 0.0;
  };
  VoCloneModel CloneToVoEnd(const Sample& from, const Sample& to, const Eigen::Vector3d& t_site,
                            const geometry::Matrix6d& vo_covariance) const;
  // The Kalman update on the gyro check `check` of the heading and the bias (the position
  // is considered, not corrected): returns the estimated errors at `to` (estimate minus
  // truth; the bias entry is the bias still left in the gyro; position entries zero) and
  // lowers P_to.
  StateVector FuseGyroCheck(const VoCloneModel& model, double check, StateMatrix& P_to) const;
  void PropagateHeading(double dt, double abs_dyaw);
  // At rest: holds the heading against the IMU's yaw change `dyaw` over `dt`, and feeds the
  // rest segment's bias measurement (FuseRestBias), provisionally while the sample is newer
  // than the last odometry (ConfirmRest, ResumeHeldMotion).
  void HoldHeadingAtRest(int64_t utime, double dt, double dyaw);
  void AddToRestSegment(double dt, double dyaw);
  void ConfirmRest();
  void ResumeHeldMotion();
  void FuseRestBias(double segment_s, double segment_dyaw);
  void ConsiderRestBias(double R, StateMatrix& P) const;
  // How much of VO's yaw bias is still correlated after `distance_m` of VO's travel.
  double VoBiasKept(double distance_m) const;
  void EndRest();
  bool StandingStill(int64_t utime, const Eigen::Vector3d& angular_rate) const;
  void GrowPositionCovariance(const Eigen::Vector3d& displacement);
  void GrowPositionCovarianceInTurn(double wheel_travel_m);
  void GrowPositionSigmaAlong(const Eigen::Vector3d& e, double g);
  double WheelTravelSinceLast(const std::vector<double>& wheel_distance_m) const;
  // The wheels' error VO measured over [from, to] (EstimatorOptions::slip_memory_updates).
  void MeasureWheelSlip(const Sample& from, const Sample& to_wheels, const Eigen::Vector3d& t_site_vo);
  StateMatrix InitialCovariance() const;
  bool AdvanceTime(int64_t utime);

  EstimatorOptions options_;

  int64_t utime_ = 0;
  bool has_time_ = false;
  geometry::Pose T_site_rover_ = geometry::Pose::Identity();
  StateMatrix P_ = StateMatrix::Zero();
  double odometer_m_ = 0.0;
  double turned_rad_ = 0.0;
  double yaw_offset_ = 0.0;
  double gyro_bias_ = 0.0;
  double vo_yaw_bias_ = 0.0;
  double gyro_s_ = 0.0;  // seconds the gyro's heading was integrated (Sample::gyro_s)
  bool at_rest_ = false;
  double rest_segment_s_ = 0.0, rest_segment_dyaw_ = 0.0;  // the rest segment so far
  // IMU samples held at rest that are newer than the last odometry message: the next one
  // says whether the wheels stood through them.
  struct HeldSample {
    int64_t utime = 0;
    double dt = 0.0, dyaw = 0.0;
  };
  std::vector<HeldSample> unconfirmed_rest_;
  int64_t last_odometry_utime_ = 0, last_wheel_motion_utime_ = 0;
  std::optional<double> pending_reset_yaw_;  // Reset() before the first IMU sample

  bool has_imu_ = false;
  int64_t last_imu_utime_ = 0;
  Eigen::Quaterniond q_imu_ = Eigen::Quaterniond::Identity();
  Eigen::Vector3d angular_rate_ = Eigen::Vector3d::Zero();

  bool has_odometry_ = false;
  double last_distance_m_ = 0.0;
  Eigen::Matrix3d R_at_last_odometry_ = Eigen::Matrix3d::Identity();
  std::vector<double> wheel_distance_m_;
  // The wheels' along- and cross-track errors VO measured (fractions of the distance), the
  // newest last, at most slip_memory_updates of them.
  std::deque<Eigen::Vector2d> measured_slip_;

  PoseSource source_ = PoseSource::kWheelImu;
  int32_t site_index_ = 0;
  int64_t last_vo_to_frame_ = -1;
  int64_t inputs_rejected_ = 0;

  std::deque<Sample> history_;
};

}  // namespace rover::estimation
