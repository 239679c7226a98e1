// The simulated rover: arcs and turns in place on the terrain height field, with slip
// that depends on soil and slope, and the IMU and wheel encoders it carries.
//
// It knows nothing of LCM: the rover_sim process turns mobility_command_t into
// MotionCommand, calls Step() to advance rover time, and publishes what Step() returns
// (IMU, wheel odometry, status changes) plus status() and Truth() at its own rates.
//
// As on MER, a command ends when the WHEELS have rolled the commanded distance (or turned
// the commanded angle): the rover believes it is done. Slip makes the true motion differ;
// only Truth() shows it.
//
// Frames (geometry/pose.hpp): site X north, Y east, Z down; rover X forward, Y right,
// Z down; yaw 0 = north, + = clockwise from above.
#pragma once

#include <Eigen/Geometry>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "geometry/pose.hpp"
#include "mobility/mobility_options.hpp"
#include "terrain/random.hpp"
#include "terrain/world.hpp"

namespace rover::mobility {

struct MotionCommand {
  enum class Type { kArc, kTurn, kStop };
  std::int64_t id = 0;
  Type type = Type::kStop;
  double distance_m = 0.0;       // arc: signed (- = backward)
  double curvature_per_m = 0.0;  // arc: 0 = straight, + = toward the right
  double turn_rad = 0.0;         // turn: signed, + = clockwise from above (north to east)
  double speed_mps = 0.0;        // 0 = geometry.speed_mps
  double turn_rate_rps = 0.0;    // 0 = geometry.turn_rate_rps

  static MotionCommand Arc(std::int64_t id, double distance_m, double curvature_per_m = 0.0);
  static MotionCommand Turn(std::int64_t id, double turn_rad);
  static MotionCommand Stop(std::int64_t id);
};

// Same numbering as mobility_status_t STATE_*.
enum class MobilityState : std::int8_t { kIdle = 0, kMoving = 1, kDone = 2, kStopped = 3, kFault = 4 };
const char* MobilityStateName(MobilityState s);  // "idle", "moving", ...

struct MobilityStatus {
  std::int64_t utime = 0;
  std::int64_t command_id = -1;  // -1 = no command yet
  MobilityState state = MobilityState::kIdle;
  double wheel_distance_m = 0.0;  // rolled by the wheels in this command (signed)
  double wheel_turn_rad = 0.0;    // turned through the wheels in this command (signed)
  std::string detail;
};

struct ImuSample {
  std::int64_t utime = 0;
  Eigen::Quaterniond q_site_rover = Eigen::Quaterniond::Identity();  // yaw drifts
  Eigen::Vector3d angular_rate_rps = Eigen::Vector3d::Zero();       // rover frame
  Eigen::Vector3d accel_mps2 = Eigen::Vector3d::Zero();  // specific force, rover frame
};

struct WheelOdometrySample {
  std::int64_t utime = 0;
  std::array<double, kNumWheels> wheel_distance_m{};  // cumulative, signed, per Wheel
  // Cumulative body path length from the encoders: for arcs, the mean over the wheels of
  // each wheel's distance divided by its arc factor. A dragged wheel that reads zero pulls
  // this below the truth (Spirit's right front wheel).
  double distance_m = 0.0;
  double curvature_per_m = 0.0;
  bool turning_in_place = false;
};

struct RoverTruth {
  std::int64_t utime = 0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // site frame, rover frame origin
  Eigen::Quaterniond q_site_rover = Eigen::Quaterniond::Identity();
  Eigen::Vector3d rpy = Eigen::Vector3d::Zero();  // roll, pitch, yaw (rad)
  double odometer_m = 0.0;  // true 3-D path length
  double slip = 0.0;        // longitudinal slip fraction in use (model value, with noise)
  double lateral_slip = 0.0;  // sideways drift per metre rolled, + = toward the right
  terrain::Soil soil = terrain::Soil::kBedrock;  // under the rover's centre
  std::int64_t command_id = -1;
  geometry::Pose T_site_rover() const;
};

// What one Step() produced. Vectors keep their capacity between steps.
struct StepOutput {
  std::vector<ImuSample> imu;
  std::vector<WheelOdometrySample> odometry;
  // Status changes since the previous Step() (including those caused by Command()).
  std::vector<MobilityStatus> status;
};

class RoverSimulator {
 public:
  // `world` must outlive the simulator. The rover is placed on the ground at (x, y) with
  // heading yaw_rad; its clock starts at start_utime. Throws std::invalid_argument if the
  // start is off the map or an option is out of range (e.g. a sample rate <= 0).
  RoverSimulator(const terrain::World& world, MobilityOptions options, double x, double y,
                 double yaw_rad, std::int64_t start_utime = 0);
  // Starts at the world's suggested start pose.
  RoverSimulator(const terrain::World& world, MobilityOptions options,
                 std::int64_t start_utime = 0);

  // Starts a command now. A running command is replaced (its status becomes stopped,
  // "preempted by <id>"). Stop halts at once. Throws std::invalid_argument on a non-finite
  // value, a curvature beyond geometry.max_curvature_per_m, or a negative speed or rate.
  void Command(const MotionCommand& command);
  // Stops the motion in progress by the rover's own decision (the dead-man,
  // deadman.hpp): its status becomes stopped with `detail`, keeping its command id.
  // Does nothing when no motion is in progress.
  void Halt(const std::string& detail);

  // Advances rover time by dt_s (> 0; any length: it integrates in substeps and emits
  // each IMU and encoder sample exactly at its scheduled time). Allocation-free once the
  // output vectors have grown. The reference stays valid until the next Step().
  const StepOutput& Step(double dt_s);

  // Steps until the current command is no longer moving, or max_s of rover time pass.
  // Samples are discarded. Returns the final status. For tests and tools.
  MobilityStatus RunUntilIdle(double max_s = 3600.0, double dt_s = 0.1);

  std::int64_t utime() const { return utime_; }
  const MobilityStatus& status() const { return status_; }
  bool moving() const { return status_.state == MobilityState::kMoving; }
  RoverTruth Truth() const;
  // Latest samples (also valid before the first scheduled one).
  ImuSample Imu() const { return last_imu_; }  // the last IMU sample taken
  WheelOdometrySample Odometry() const;          // the encoders now
  const MobilityOptions& options() const { return options_; }
  const terrain::World& world() const { return world_; }

 private:
  void SetStatus(MobilityState state, const std::string& detail);
  void Advance(double dt);
  bool FollowTerrain();  // false if a wheel is off the map
  void Fault(const std::string& detail);
  void CheckRocks(const Eigen::Vector3d& p_prev);
  ImuSample MakeImuSample();
  void AddWheelMotion(double amount, bool turning);
  double SoilSlipAt(double pitch_travel_deg) const;  // mean of the wheels' soil tables
  double LongitudinalSlip(double pitch_travel_deg) const;  // soil, slope and rocks
  // Rise of the rocks over one wheel radius ahead of (x, y) along the travel direction,
  // per metre (0 when level or descending).
  double ClimbGrade(double x, double y, double travel_x, double travel_y) const;

  const terrain::World& world_;
  MobilityOptions options_;
  std::array<Eigen::Vector2d, kNumWheels> wheel_xy_;
  double mean_wheel_arm_ = 0;  // mean wheel distance from the centre (turn in place)

  // True state: horizontal position and yaw are integrated; elevation, roll and pitch
  // come from the terrain under the wheels (FollowTerrain).
  double x_ = 0, y_ = 0, yaw_ = 0;
  double z_ = 0, roll_ = 0, pitch_ = 0;
  Eigen::Matrix3d R_ = Eigen::Matrix3d::Identity();
  double plane_slope_fwd_ = 0, plane_slope_right_ = 0;  // d elevation / d(fwd, right)
  std::array<terrain::Soil, kNumWheels> wheel_soil_{};
  std::array<double, kNumWheels> wheel_climb_grade_{};  // ClimbGrade under each wheel
  double odometer_ = 0;
  double slip_ = 0, lateral_slip_ = 0;
  Eigen::Vector3d body_rate_ = Eigen::Vector3d::Zero();

  // Command in progress.
  MotionCommand command_;
  double target_ = 0;     // |distance| or |angle|
  double progress_ = 0;   // rolled so far, >= 0
  double rate_ = 0;       // m/s or rad/s
  MobilityStatus status_;
  std::vector<MobilityStatus> pending_status_;
  std::vector<const terrain::Rock*> tall_rocks_;

  // Sensors.
  std::int64_t utime_ = 0;
  std::int64_t imu_period_us_ = 0, encoder_period_us_ = 0;
  std::int64_t next_imu_us_ = 0, next_encoder_us_ = 0;
  double yaw_error_ = 0;  // integrated gyro bias + random walk
  std::array<double, kNumWheels> wheel_true_{};  // cumulative rolled distance per wheel
  double odometry_distance_ = 0;
  ImuSample last_imu_;
  double slip_noise_ = 0, drift_noise_ = 0;  // unit Ornstein-Uhlenbeck processes
  terrain::Random slip_rng_;
  terrain::Random imu_rng_;
  StepOutput out_;
};

}  // namespace rover::mobility
