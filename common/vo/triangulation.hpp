// VO-4 and VO-5: ray intersection with the gap test, and the feature's covariance.
#pragma once

#include "geometry/camera_model.hpp"

#include <Eigen/Core>

namespace rover::vo {

// The paper's equations (1)-(7). r1, r2 are unit rays from C1, C2.
//   m1 = (B.r1 - (B.r2)(r1.r2)) / (1 - (r1.r2)^2),  m2 = (r1.r2) m1 - B.r2,  B = C2 - C1
//   P1 = C1 + r1 m1, P2 = C2 + r2 m2, P = (P1 + P2) / 2.
struct RayIntersection {
  Eigen::Vector3d P = Eigen::Vector3d::Zero();
  double m1 = 0, m2 = 0;
  double gap = 0;  // |P1 - P2|
  // dP/dr1, dP/dr2 (3x3 each).
  Eigen::Matrix3d dP_dr1 = Eigen::Matrix3d::Zero(), dP_dr2 = Eigen::Matrix3d::Zero();
};

// Returns false for parallel rays (no intersection).
bool IntersectRays(const Eigen::Vector3d& C1, const Eigen::Vector3d& r1,
                   const Eigen::Vector3d& C2, const Eigen::Vector3d& r2,
                   RayIntersection* out);

enum class TriangulationFailure { kNone, kParallel, kDiverging, kBehind, kGap, kRange };

struct StereoPoint {
  Eigen::Vector3d P = Eigen::Vector3d::Zero();
  Eigen::Matrix3d Sigma = Eigen::Matrix3d::Zero();  // VO-5
  double range = 0;                                // m1
  double gap = 0;
  TriangulationFailure failure = TriangulationFailure::kNone;
};

struct TriangulationLimits {
  // Largest gap, as an angle at the left range (radians).
  double max_gap_rad = 1e-3;
  // Smallest parallax between the rays (radians): rays closer to parallel carry no range.
  double min_parallax_rad = 0;
  double max_range_m = 0;  // 0 = none
};

// Triangulates a left/right pixel pair with covariances Sigma_left, Sigma_right:
// Sigma_P = J S J^T, J = dP/d(xl, yl, xr, yr) (VO-5, eq. 11), S the covariance of the two
// matches' errors. The right match is found with a template cut at the left match, so it
// repeats `stereo_carry` of the left match's error e_l on top of its own e_s:
// e_r = stereo_carry e_l + e_s, and
//   S = [Sigma_left, c Sigma_left; c Sigma_left, c^2 Sigma_left + Sigma_right] (c = stereo_carry).
// 0 is the paper's diag(Sigma_left, Sigma_right); at 1 the left error moves the point
// across the line of sight only (both rays alike), and the disparity carries the right
// match's own error alone (common/vo/README.md, "Carried track errors").
// Returns false (and out->failure) when the gap test or geometry rejects the feature.
bool TriangulateStereo(const geometry::StereoRig& rig, const Eigen::Vector2d& left,
                       const Eigen::Matrix2d& Sigma_left, const Eigen::Vector2d& right,
                       const Eigen::Matrix2d& Sigma_right, const TriangulationLimits& limits,
                       StereoPoint* out, Eigen::Matrix<double, 3, 4>* J = nullptr,
                       double stereo_carry = 0.0);

// VO-5's covariance of a triangulated point: J S J^T with S as TriangulateStereo builds it.
Eigen::Matrix3d StereoPointCovariance(const Eigen::Matrix<double, 3, 4>& J, const Eigen::Matrix2d& Sigma_left,
                                      const Eigen::Matrix2d& Sigma_right, double stereo_carry);

}  // namespace rover::vo
