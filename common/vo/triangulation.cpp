#include "vo/triangulation.hpp"

#include <algorithm>
#include <cmath>

namespace rover::vo {

bool IntersectRays(const Eigen::Vector3d& C1, const Eigen::Vector3d& r1,
                   const Eigen::Vector3d& C2, const Eigen::Vector3d& r2,
                   RayIntersection* out) {
  const Eigen::Vector3d B = C2 - C1;
  const double a = r1.dot(r2);
  const double den = 1.0 - a * a;
  if (!(den > 1e-15)) return false;
  const double b1 = B.dot(r1), b2 = B.dot(r2);
  const double num = b1 - b2 * a;
  const double m1 = num / den;                 // eq. (5)
  const double m2 = a * m1 - b2;               // eq. (6)
  const Eigen::Vector3d P1 = C1 + r1 * m1;     // eq. (1)
  const Eigen::Vector3d P2 = C2 + r2 * m2;     // eq. (2)
  out->P = 0.5 * (P1 + P2);                    // eq. (7)
  out->m1 = m1;
  out->m2 = m2;
  out->gap = (P1 - P2).norm();
  // Partial derivatives of m1, m2 (the paper's eqs. 8-10, written for unit rays).
  const Eigen::RowVector3d dm1_dr1 =
      (B.transpose() - b2 * r2.transpose()) / den + num * 2.0 * a * r2.transpose() / (den * den);
  const Eigen::RowVector3d dm1_dr2 =
      (-a * B.transpose() - b2 * r1.transpose()) / den + num * 2.0 * a * r1.transpose() / (den * den);
  const Eigen::RowVector3d dm2_dr1 = m1 * r2.transpose() + a * dm1_dr1;
  const Eigen::RowVector3d dm2_dr2 = m1 * r1.transpose() + a * dm1_dr2 - B.transpose();
  out->dP_dr1 = 0.5 * (m1 * Eigen::Matrix3d::Identity() + r1 * dm1_dr1 + r2 * dm2_dr1);
  out->dP_dr2 = 0.5 * (r1 * dm1_dr2 + m2 * Eigen::Matrix3d::Identity() + r2 * dm2_dr2);
  return true;
}

Eigen::Matrix3d StereoPointCovariance(const Eigen::Matrix<double, 3, 4>& J, const Eigen::Matrix2d& Sigma_left,
                                      const Eigen::Matrix2d& Sigma_right, double stereo_carry) {
  Eigen::Matrix4d S;
  S.topLeftCorner<2, 2>() = Sigma_left;
  S.topRightCorner<2, 2>() = stereo_carry * Sigma_left;
  S.bottomLeftCorner<2, 2>() = stereo_carry * Sigma_left;
  S.bottomRightCorner<2, 2>() = stereo_carry * stereo_carry * Sigma_left + Sigma_right;
  return J * S * J.transpose();
}

bool TriangulateStereo(const geometry::StereoRig& rig, const Eigen::Vector2d& left,
                       const Eigen::Matrix2d& Sigma_left, const Eigen::Vector2d& right,
                       const Eigen::Matrix2d& Sigma_right, const TriangulationLimits& limits,
                       StereoPoint* out, Eigen::Matrix<double, 3, 4>* J_out, double stereo_carry) {
  Eigen::Vector3d C1, r1, C2, r2;
  Eigen::Matrix<double, 3, 2> Jd1, Jd2;
  rig.left->BackProject(left, &C1, &r1, &Jd1);
  rig.right->BackProject(right, &C2, &r2, &Jd2);
  RayIntersection x;
  if (!IntersectRays(C1, r1, C2, r2, &x)) {
    out->failure = TriangulationFailure::kParallel;
    return false;
  }
  out->range = x.m1;
  out->gap = x.gap;
  if (x.m1 <= 0 || x.m2 <= 0) {
    out->failure = TriangulationFailure::kBehind;
    return false;
  }
  // Rays that meet behind the point where they are closest diverge: the right ray must
  // cross the left one from the baseline side, i.e. the parallax is positive.
  const double parallax = std::acos(std::clamp(r1.dot(r2), -1.0, 1.0));
  const Eigen::Vector3d B = C2 - C1;
  if (B.dot(r1) - B.dot(r2) <= 0 || parallax < limits.min_parallax_rad) {
    out->failure = TriangulationFailure::kDiverging;
    return false;
  }
  if (x.gap > limits.max_gap_rad * x.m1) {
    out->failure = TriangulationFailure::kGap;
    return false;
  }
  if (limits.max_range_m > 0 && x.m1 > limits.max_range_m) {
    out->failure = TriangulationFailure::kRange;
    return false;
  }
  Eigen::Matrix<double, 3, 4> J;
  J.leftCols<2>() = x.dP_dr1 * Jd1;
  J.rightCols<2>() = x.dP_dr2 * Jd2;
  out->P = x.P;
  out->Sigma = StereoPointCovariance(J, Sigma_left, Sigma_right, stereo_carry);  // eq. (11)
  out->failure = TriangulationFailure::kNone;
  if (J_out) *J_out = J;
  return true;
}

}  // namespace rover::vo
