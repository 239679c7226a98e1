// The hazard monitor's judgement: keep-out zones against the footprint grown by the
// position uncertainty, and tilt limits (MER's reactive tilt check), from the latest pose.
//
// A safety check that cannot decide must stop the rover: with no pose, or a pose older than
// max_pose_age_s, the state is UNKNOWN, which callers treat as unsafe. The age is read on
// the clock every guard reads (bus::Process::guard_seconds): rover seconds in virtual time,
// wall seconds on a real clock (set_clock_rate).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "config/yaml_config.hpp"
#include "geometry/pose.hpp"
#include "hazards/keepout.hpp"

namespace rover::hazards {

struct TiltLimits {
  double roll_limit_rad = 30.0 * 3.14159265358979323846 / 180.0;
  double pitch_limit_rad = 30.0 * 3.14159265358979323846 / 180.0;
};

struct TiltCheck {
  bool violated = false;
  std::string detail;  // which angle exceeded which limit, or empty
};

// Violated when |roll| > roll limit or |pitch| > pitch limit (a limit equal is not a
// violation). Non-finite angles count as violated.
TiltCheck CheckTilt(double roll_rad, double pitch_rad, const TiltLimits& limits);

// The horizontal position sigma for keep-out checks: the square root of the largest
// eigenvalue of the x-y block of a pose covariance (the worst direction).
double HorizontalSigma(const geometry::Matrix6d& covariance);

struct HazardOptions {
  Footprint footprint;
  // Keep-out uses the footprint grown by sigma_multiplier * horizontal position sigma.
  double sigma_multiplier = 3.0;
  TiltLimits tilt;
  // A pose older than this (against the `now` passed to Assess, in guard seconds: see
  // HazardAssessor::set_clock_rate) is stale.
  double max_pose_age_s = 2.0;
  // Zones in force from the start (e.g. rocks of a world marked keep-out).
  std::vector<KeepOutZone> zones;

  // Throws std::invalid_argument naming the field or the zone.
  void Validate() const;
};

// Reads the `hazards:` section:
//   footprint: {length_m, width_m, margin_m, center_forward_m}
//   sigma_multiplier, roll_limit_deg, pitch_limit_deg, max_pose_age_s
//   map: the traversability map (read by LoadMapCheckOptions, map_check.hpp)
//   zones: list of {name, circle: {center: [x, y], radius_m}} or
//                  {name, polygon: [[x, y], [x, y], [x, y], ...]}
// `extra_keys` are keys the process shell reads itself. Throws config::ConfigError naming
// the file and key (also for an invalid zone or a duplicate zone name).
HazardOptions LoadHazardOptions(const config::ConfigNode& section,
                                const std::vector<std::string>& extra_keys = {});
// One zone entry as above, and a list of them (duplicate names rejected).
KeepOutZone LoadKeepOutZone(const config::ConfigNode& node);
std::vector<KeepOutZone> LoadKeepOutZones(const config::ConfigNode& list);

// What the assessor needs of a pose estimate.
struct PoseSnapshot {
  int64_t utime = 0;
  double x = 0.0, y = 0.0, yaw = 0.0;
  double roll = 0.0, pitch = 0.0;
  double position_sigma_m = 0.0;  // e.g. HorizontalSigma(covariance)
};

// A snapshot from a full pose estimate: x, y and roll, pitch, yaw of T_site_rover, and
// HorizontalSigma of its covariance.
PoseSnapshot SnapshotFromPose(int64_t utime, const geometry::Pose& T_site_rover,
                              const geometry::Matrix6d& covariance);

// Mirrors hazard_status_t.STATE_*.
enum class HazardState { kSafe = 0, kViolation = 1, kUnknown = 2 };
const char* ToString(HazardState state);

// Mirrors hazard_status_t.
struct HazardStatus {
  int64_t utime = 0;
  HazardState state = HazardState::kUnknown;
  bool keepout_violated = false;
  std::string zone_name;  // nearest zone, or the violated one
  // Footprint to the nearest zone, less sigma_multiplier * position sigma; +inf if no zones.
  double min_clearance_m = std::numeric_limits<double>::infinity();
  bool tilt_violated = false;
  double roll_rad = 0.0;
  double pitch_rad = 0.0;
  double roll_limit_rad = 0.0;
  double pitch_limit_rad = 0.0;
  std::string detail;
  bool safe() const { return state == HazardState::kSafe; }
};

class HazardAssessor {
 public:
  // Throws std::invalid_argument if the options (or their zones) are invalid.
  explicit HazardAssessor(const HazardOptions& options = {});

  // Replaces the zones in force (keepout_zones_t replaces the previous set). Throws
  // std::invalid_argument naming the zone when any is invalid; the previous set stays.
  void SetZones(const std::vector<KeepOutZone>& zones);
  // Limits from a sequence's `tilt` command. Throws if not finite and > 0.
  void SetTiltLimits(const TiltLimits& limits);

  void OnPose(const PoseSnapshot& pose);
  // Fresher roll and pitch (e.g. from the IMU) for the tilt check between poses.
  void OnAttitude(int64_t utime, double roll_rad, double pitch_rad);

  // Rover seconds per second of the guards' clock: 1 in virtual time (the guards read
  // rover time) and on a rover (rate 1); a real clock running a simulation at rate r reads
  // its guards in wall seconds, so a pose r * max_pose_age_s of rover time old is stale
  // there, as the executor's heartbeat and dead-man limits are wall seconds. Throws
  // std::invalid_argument unless finite and > 0.
  void set_clock_rate(double rover_s_per_guard_s);

  // The status at rover time `now_utime`.
  HazardStatus Assess(int64_t now_utime) const;

  // "Would this step's swept footprint enter a zone?" with the latest pose's sigma and
  // the asker's extra margin (hazard_query_t.margin_m). Unknown when there is no pose or
  // it is stale at `now_utime`, or the margin is not a finite value >= 0.
  SweptCheck CheckStep(const std::vector<Pose2>& path, int64_t now_utime,
                       double margin_m = 0.0) const;

  const std::vector<KeepOutZone>& zones() const { return zones_; }
  const HazardOptions& options() const { return options_; }
  const std::optional<PoseSnapshot>& latest_pose() const { return pose_; }

 private:
  // Empty when the pose is fresh; otherwise why the assessor cannot decide.
  std::string Staleness(int64_t now_utime) const;

  HazardOptions options_;
  double clock_rate_ = 1.0;  // set_clock_rate
  std::vector<KeepOutZone> zones_;
  std::optional<PoseSnapshot> pose_;
  int64_t attitude_utime_ = 0;
  bool has_attitude_ = false;
  double roll_ = 0.0, pitch_ = 0.0;
};

}  // namespace rover::hazards
