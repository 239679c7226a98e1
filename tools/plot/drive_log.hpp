// What `./rover plot` reads from a run's LCM log (lcm::LogFile), reduced to the series the
// pictures need: the on-board estimate, the wheel-odometry-only path, the truth, the
// keep-out zones, the step reports, the final sequence status and the VO updates.
//
// The wheel-odometry-only path is the paper's "outside path": WHEEL_ODOMETRY integrated
// along the IMU attitude from the first on-board pose, with no VO update. It is computed
// by the estimator's own library (common/estimation) fed the logged IMU and odometry, so
// it is what the rover would have believed with VO off.
#pragma once

#include "hazards/keepout.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <rover_msgs/sequence_status_t.hpp>
#include <rover_msgs/step_report_t.hpp>
#include <rover_msgs/stereo_frame_t.hpp>
#include <rover_msgs/vo_update_t.hpp>

namespace rover::plot {

// One position of a path in the site frame (x north, y east, z down).
struct PathPoint {
  std::int64_t utime = 0;
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
};

struct EstimatePoint : PathPoint {
  double sigma_xy_m = 0.0;  // sqrt of the larger eigenvalue of the x-y covariance
  int source = 0;           // pose_t SOURCE_*
};

struct TruthPoint : PathPoint {
  double yaw = 0.0;         // rad
  double odometer_m = 0.0;  // true path length since the simulator started
};

// A keep-out zone as it was defined, and when it was first in force.
struct ZoneRecord {
  hazards::KeepOutZone zone;
  std::int64_t since_utime = 0;
};

// One submitted sequence and how it ended (a log may hold several, one after another).
struct SequenceRun {
  std::int64_t submission_id = 0;
  std::string name;
  std::optional<rover_msgs::sequence_status_t> final_status;  // none: still running at the log's end
};

// A goto's goal disc, from the submitted sequence text.
struct GoalDisc {
  std::int64_t submission_id = 0;
  int command_index = 0;
  Eigen::Vector2d target = Eigen::Vector2d::Zero();  // site x, y
  double radius_m = 0.0;
};

// A rock of the simulated world (the log does not hold the world: ReadWorldRocks).
struct RockMark {
  std::string name;  // placed rocks' names; "" for random ones
  Eigen::Vector2d position = Eigen::Vector2d::Zero();
  double diameter_m = 0.0;
  double height_m = 0.0;
};

struct DriveLog {
  std::string path;                         // the log file
  std::vector<EstimatePoint> estimate;      // POSE, in log order
  std::vector<PathPoint> wheel_only;        // IMU + WHEEL_ODOMETRY only (see above)
  std::vector<TruthPoint> truth;            // SIM_TRUTH, sorted by time (empty on a rover)
  std::vector<ZoneRecord> zones;            // every zone ever in force, by name (latest shape)
  std::vector<rover_msgs::step_report_t> steps;
  std::vector<rover_msgs::vo_update_t> vo_updates;
  std::optional<rover_msgs::sequence_status_t> final_status;  // the first completed, aborted, rejected
  std::string sequence_name;                                  // the first submitted
  std::vector<SequenceRun> runs;                              // every submitted sequence, in order
  std::vector<GoalDisc> goals;                                // every goto's disc
  std::vector<RockMark> rocks;                                // filled by the caller (ReadWorldRocks)
  // The slip limit in force for each command (command index -> percent), from the
  // submitted sequence's `slip limit` lines; absent where slip checks are off.
  std::map<int, double> slip_limit_pct;
  // Messages that did not decode (by channel): the pictures leave them out.
  std::map<std::string, int> undecodable;
};

// Reads the log. Throws std::runtime_error naming the file when it cannot be read.
DriveLog ReadDriveLog(const std::string& log_path);

// The rocks of a world file taller than `min_height_m` (what the traverse picture draws).
// Throws config::ConfigError naming the file when it cannot be read.
std::vector<RockMark> ReadWorldRocks(const std::string& world_path, double min_height_m);

// The stereo frames with these ids (a second pass over the log: frames are large, so only
// the few a picture needs are kept).
std::map<std::int64_t, rover_msgs::stereo_frame_t> ReadStereoFrames(const std::string& log_path,
                                                                    const std::set<std::int64_t>& ids);

}  // namespace rover::plot
