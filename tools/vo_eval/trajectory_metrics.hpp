// Accuracy of an estimated trajectory against ground truth, the KITTI odometry way.
//
// The segment errors follow the KITTI devkit (evaluate_odometry.cpp): for every start
// frame and every segment length L, the end is the first frame whose path distance along
// the ground truth exceeds dist[start] + L; the error is the relative pose
// E = (T_est_start^-1 T_est_end)^-1 (T_gt_start^-1 T_gt_end), translational error
// |t(E)| / L and rotational error angle(E) / L. The devkit samples every 10th start and
// 100..800 m segments; we take every frame as a start and shorter segments by default,
// because our sequences are short (a rover drive, or 51 KITTI frames).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <string>
#include <vector>

namespace rover::vo_eval {

using PoseList = std::vector<Eigen::Isometry3d, Eigen::aligned_allocator<Eigen::Isometry3d>>;

struct SegmentOptions {
  // Segment lengths in metres. Default: 10..50 m.
  std::vector<double> lengths_m = {10.0, 20.0, 30.0, 40.0, 50.0};
  // Every `start_step`-th frame starts segments (the devkit uses 10; we use all).
  int start_step = 1;
};

struct SegmentError {
  int first_frame = 0;
  int last_frame = 0;
  double length_m = 0.0;       // nominal L
  double trans_error = 0.0;    // |t(E)| / L, a fraction (0.01 = 1 %)
  double rot_error = 0.0;      // angle(E) / L, rad/m
};

struct TrajectoryAccuracy {
  int num_segments = 0;                  // 0 when the path is shorter than every length
  double trans_error_percent = 0.0;      // mean over segments
  double rot_error_deg_per_m = 0.0;      // mean over segments
  std::vector<double> lengths_m;         // per length present:
  std::vector<int> segments_per_length;
  std::vector<double> trans_error_percent_per_length;
  std::vector<double> rot_error_deg_per_m_per_length;
  double path_length_m = 0.0;            // along the ground truth
  double final_position_error_m = 0.0;
  double final_position_error_percent = 0.0;  // of path_length_m
};

// Cumulative distance along the positions of `poses` (devkit trajectoryDistances).
std::vector<double> PathDistances(const PoseList& poses);

// The devkit's lastFrameFromSegmentLength: the first frame i >= first with
// dist[i] > dist[first] + length, or -1.
int LastFrameOfSegment(const std::vector<double>& dist, int first, double length);

// Angle of a rotation from its trace, clamped like the devkit's rotationError.
double RotationAngle(const Eigen::Matrix3d& R);

// All segment errors. Throws std::invalid_argument when the lists differ in size.
std::vector<SegmentError> SegmentErrors(const PoseList& truth, const PoseList& estimate,
                                        const SegmentOptions& options = {});

// Segment averages plus the final position error.
TrajectoryAccuracy EvaluateTrajectory(const PoseList& truth, const PoseList& estimate,
                                      const SegmentOptions& options = {});

// Composes per-frame motions into poses: pose[0] = start, pose[k] = pose[k-1] * motion[k]
// (motion[0] is ignored), so T_world_curr = T_world_prev * T_prev_curr.
PoseList ComposeMotions(const PoseList& motions_prev_curr,
                        const Eigen::Isometry3d& start = Eigen::Isometry3d::Identity());

// Statistics of the normalised estimation error squared (VO-13).
struct NeesSummary {
  int count = 0;
  double mean = 0.0;           // ~6 for an honest 6-DOF covariance
  double median = 0.0;
  double max = 0.0;
  // Accepted updates beyond the 6-DOF equivalent of 3 sigma: chi2(6) > 20.06, the
  // 99.73 % quantile, i.e. the same tail mass as |x| > 3 sigma in one dimension.
  int false_positives = 0;
  // Per component: fraction of updates whose error is within 1 sigma (0.683 expected).
  Eigen::Matrix<double, 6, 1> within_1sigma = Eigen::Matrix<double, 6, 1>::Zero();
};

constexpr double kChi2Dof6ThreeSigma = 20.062;

// The error vector of an estimated motion against the truth, in the covariance's order
// (x y z roll pitch yaw): difference of translations and of wrapped roll-pitch-yaw angles.
Eigen::Matrix<double, 6, 1> MotionError(const Eigen::Isometry3d& truth,
                                        const Eigen::Isometry3d& estimate);

// eᵀ Σ⁻¹ e; returns a negative number when Σ is not positive definite.
double Nees(const Eigen::Matrix<double, 6, 1>& error, const Eigen::Matrix<double, 6, 6>& cov);

NeesSummary SummariseNees(const std::vector<double>& nees,
                          const std::vector<Eigen::Matrix<double, 6, 1>>& normalised_errors);

}  // namespace rover::vo_eval
