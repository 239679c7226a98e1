// The series each picture of `./rover plot` shows, computed from a DriveLog. Nothing here
// draws: gnuplot does (plots.hpp).
#pragma once

#include "plot/drive_log.hpp"

#include <algorithm>
#include <optional>
#include <vector>

namespace rover::plot {

// How a stretch of the on-board path was measured. A step is VO-corrected when its
// STEP_REPORT says VO measured it (vo_status OK); otherwise it was driven blind on wheel
// odometry and IMU. (pose_t.source alone cannot tell: it stays "VO" after the first
// update.) Poses between steps keep the mode of the step before them; before the first
// step, blind.
enum class Mode { kBlind = 0, kVo = 1 };

struct Segment {
  Mode mode = Mode::kBlind;
  std::vector<Eigen::Vector3d> points;  // consecutive segments share their end point
};

std::vector<Segment> EstimateSegments(const DriveLog& log);

// Position error (3-D, like summary.json) against the true distance travelled, one sample
// per 2 cm of true travel. Empty without truth.
struct ErrorSample {
  double distance_m = 0;
  double wheel_only_error_m = 0;
  double estimate_error_m = 0;
};
std::vector<ErrorSample> ErrorSeries(const DriveLog& log);

// One row per STEP_REPORT: commanded against measured progress along the commanded
// direction; slip where a distance was commanded.
struct SlipRow {
  int number = 0;  // 1-based, in order
  int command_index = 0, step_index = 0;
  double commanded_m = 0, measured_m = 0;
  std::optional<double> true_m;
  std::optional<double> measured_slip_pct, true_slip_pct, limit_pct;
  bool vo = false;  // measured by VO
};
std::vector<SlipRow> SlipRows(const DriveLog& log);

// A step VO measured, and the pair of frames the update related.
struct VoStepChoice {
  int number = 0;  // as SlipRow::number
  rover_msgs::step_report_t step;
  rover_msgs::vo_update_t update;
};
// Up to `max_steps` steps measured by VO, evenly spaced over the drive.
std::vector<VoStepChoice> ChooseVoSteps(const DriveLog& log, int max_steps);

// The position of a path at `utime`, linear between samples (clamped at the ends).
template <typename Point>
std::optional<Eigen::Vector3d> PositionAt(const std::vector<Point>& path, std::int64_t utime) {
  if (path.empty()) return std::nullopt;
  auto after = std::lower_bound(path.begin(), path.end(), utime,
                                [](const Point& p, std::int64_t u) { return p.utime < u; });
  if (after == path.begin()) return path.front().p;
  if (after == path.end()) return path.back().p;
  const auto before = after - 1;
  const double span = static_cast<double>(after->utime - before->utime);
  const double f = span > 0 ? static_cast<double>(utime - before->utime) / span : 1.0;
  return Eigen::Vector3d(before->p + f * (after->p - before->p));
}

}  // namespace rover::plot
