#include "vo_eval/trajectory_metrics.hpp"

#include "geometry/pose.hpp"

#include <Eigen/Cholesky>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace rover::vo_eval {

std::vector<double> PathDistances(const PoseList& poses) {
  std::vector<double> dist(poses.size(), 0.0);
  for (std::size_t i = 1; i < poses.size(); ++i) {
    dist[i] = dist[i - 1] + (poses[i].translation() - poses[i - 1].translation()).norm();
  }
  return dist;
}

int LastFrameOfSegment(const std::vector<double>& dist, int first, double length) {
  for (std::size_t i = static_cast<std::size_t>(first); i < dist.size(); ++i) {
    if (dist[i] > dist[static_cast<std::size_t>(first)] + length) return static_cast<int>(i);
  }
  return -1;
}

double RotationAngle(const Eigen::Matrix3d& R) {
  const double d = 0.5 * (R(0, 0) + R(1, 1) + R(2, 2) - 1.0);
  return std::acos(std::clamp(d, -1.0, 1.0));
}

std::vector<SegmentError> SegmentErrors(const PoseList& truth, const PoseList& estimate,
                                        const SegmentOptions& options) {
  if (truth.size() != estimate.size()) {
    throw std::invalid_argument("SegmentErrors: " + std::to_string(truth.size()) +
                                " truth poses but " + std::to_string(estimate.size()) +
                                " estimated poses");
  }
  if (options.start_step < 1) {
    throw std::invalid_argument("SegmentErrors: start_step must be >= 1, got " +
                                std::to_string(options.start_step));
  }
  const std::vector<double> dist = PathDistances(truth);
  std::vector<SegmentError> errors;
  for (int first = 0; first < static_cast<int>(truth.size()); first += options.start_step) {
    for (double length : options.lengths_m) {
      if (!(length > 0.0)) {
        throw std::invalid_argument("SegmentErrors: segment length must be > 0, got " +
                                    std::to_string(length));
      }
      const int last = LastFrameOfSegment(dist, first, length);
      if (last < 0) continue;
      const Eigen::Isometry3d delta_truth = truth[first].inverse() * truth[last];
      const Eigen::Isometry3d delta_est = estimate[first].inverse() * estimate[last];
      const Eigen::Isometry3d E = delta_est.inverse() * delta_truth;
      SegmentError s;
      s.first_frame = first;
      s.last_frame = last;
      s.length_m = length;
      s.trans_error = E.translation().norm() / length;
      s.rot_error = RotationAngle(E.linear()) / length;
      errors.push_back(s);
    }
  }
  return errors;
}

TrajectoryAccuracy EvaluateTrajectory(const PoseList& truth, const PoseList& estimate,
                                      const SegmentOptions& options) {
  const std::vector<SegmentError> segments = SegmentErrors(truth, estimate, options);
  TrajectoryAccuracy acc;
  acc.num_segments = static_cast<int>(segments.size());
  for (const SegmentError& s : segments) {
    acc.trans_error_percent += 100.0 * s.trans_error;
    acc.rot_error_deg_per_m += s.rot_error * 180.0 / M_PI;
  }
  if (!segments.empty()) {
    acc.trans_error_percent /= static_cast<double>(segments.size());
    acc.rot_error_deg_per_m /= static_cast<double>(segments.size());
  }
  for (double length : options.lengths_m) {
    int n = 0;
    double t = 0.0, r = 0.0;
    for (const SegmentError& s : segments) {
      if (s.length_m != length) continue;
      ++n;
      t += 100.0 * s.trans_error;
      r += s.rot_error * 180.0 / M_PI;
    }
    if (n == 0) continue;
    acc.lengths_m.push_back(length);
    acc.segments_per_length.push_back(n);
    acc.trans_error_percent_per_length.push_back(t / n);
    acc.rot_error_deg_per_m_per_length.push_back(r / n);
  }
  const std::vector<double> dist = PathDistances(truth);
  if (!truth.empty()) {
    acc.path_length_m = dist.back();
    // Both trajectories start at their first pose; compare the end in the truth's frame
    // after aligning the starts, so that an estimate that begins at identity still counts.
    const Eigen::Isometry3d end_truth = truth.front().inverse() * truth.back();
    const Eigen::Isometry3d end_est = estimate.front().inverse() * estimate.back();
    acc.final_position_error_m = (end_truth.translation() - end_est.translation()).norm();
    if (acc.path_length_m > 0.0) {
      acc.final_position_error_percent = 100.0 * acc.final_position_error_m / acc.path_length_m;
    }
  }
  return acc;
}

PoseList ComposeMotions(const PoseList& motions_prev_curr, const Eigen::Isometry3d& start) {
  PoseList poses;
  poses.reserve(motions_prev_curr.size());
  for (std::size_t k = 0; k < motions_prev_curr.size(); ++k) {
    poses.push_back(k == 0 ? start : Eigen::Isometry3d(poses.back() * motions_prev_curr[k]));
  }
  return poses;
}

Eigen::Matrix<double, 6, 1> MotionError(const Eigen::Isometry3d& truth,
                                        const Eigen::Isometry3d& estimate) {
  const geometry::Vector6d a = geometry::XyzRpyFromPose(estimate);
  const geometry::Vector6d b = geometry::XyzRpyFromPose(truth);
  Eigen::Matrix<double, 6, 1> e = a - b;
  for (int i = 3; i < 6; ++i) e(i) = geometry::WrapAngle(e(i));
  return e;
}

double Nees(const Eigen::Matrix<double, 6, 1>& error, const Eigen::Matrix<double, 6, 6>& cov) {
  const Eigen::LDLT<Eigen::Matrix<double, 6, 6>> ldlt(cov);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive() ||
      (ldlt.vectorD().array() <= 0.0).any()) {
    return -1.0;
  }
  return error.dot(ldlt.solve(error));
}

NeesSummary SummariseNees(const std::vector<double>& nees,
                          const std::vector<Eigen::Matrix<double, 6, 1>>& normalised_errors) {
  NeesSummary s;
  s.count = static_cast<int>(nees.size());
  if (nees.empty()) return s;
  std::vector<double> sorted = nees;
  std::sort(sorted.begin(), sorted.end());
  for (double v : nees) {
    s.mean += v;
    if (v > kChi2Dof6ThreeSigma) ++s.false_positives;
  }
  s.mean /= static_cast<double>(nees.size());
  const std::size_t n = sorted.size();
  s.median = n % 2 == 1 ? sorted[n / 2] : 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]);
  s.max = sorted.back();
  if (!normalised_errors.empty()) {
    for (const auto& z : normalised_errors) {
      for (int i = 0; i < 6; ++i) {
        if (std::abs(z(i)) <= 1.0) s.within_1sigma(i) += 1.0;
      }
    }
    s.within_1sigma /= static_cast<double>(normalised_errors.size());
  }
  return s;
}

}  // namespace rover::vo_eval
