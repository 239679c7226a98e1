// VO-7 (weighted least squares inside RANSAC) and VO-8 (maximum likelihood).
//
// A correspondence is the same feature triangulated in the previous pair (P_p, in the
// previous reference frame) and the current pair (P_c, current frame). The motion maps
// P_c = R P_p + T, i.e. (R, T) = T_curr_prev; results are reported as T_prev_curr.
#pragma once

#include "geometry/camera_model.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <vector>

namespace rover::vo {

struct Correspondence {
  Eigen::Vector3d P_prev = Eigen::Vector3d::Zero();
  Eigen::Matrix3d Sigma_prev = Eigen::Matrix3d::Identity();
  Eigen::Vector3d P_curr = Eigen::Vector3d::Zero();
  Eigen::Matrix3d Sigma_curr = Eigen::Matrix3d::Identity();
  // Where the feature was observed in the current pair (for the RANSAC image gap).
  Eigen::Vector2d left = Eigen::Vector2d::Zero(), right = Eigen::Vector2d::Zero();
};

// Closed-form weighted least squares (eq. 12-14), weights w_j = 1/(det Sp_j + det Sc_j):
// minimises sum w_j |P_c - R P_p - T|^2 by the weighted SVD (Arun/Umeyama) solution.
// Returns T_curr_prev. `indices` selects the correspondences (all if empty).
Eigen::Isometry3d WeightedLeastSquaresMotion(const std::vector<Correspondence>& c,
                                             const std::vector<int>& indices = {});

struct RansacOptions {
  int iterations = 100;
  int sample_size = 6;
  double inlier_px = 1.0;
  std::uint64_t seed = 42;
};

struct RansacOutcome {
  Eigen::Isometry3d T_curr_prev = Eigen::Isometry3d::Identity();
  std::vector<int> inliers;
};

// VO-7: fixed iterations; a feature counts when its reprojection into the current left
// and right images (through the rig) is within inlier_px of where it was observed. The
// best hypothesis is refitted once on its inliers. `subset` limits the features used
// (all if empty).
RansacOutcome RansacMotion(const std::vector<Correspondence>& c, const geometry::StereoRig& rig,
                           const RansacOptions& options, const std::vector<int>& subset = {});

// Image gap of one feature under T_curr_prev (largest of left and right; +inf if it does
// not project).
double ReprojectionGap(const Correspondence& c, const geometry::StereoRig& rig,
                       const Eigen::Isometry3d& T_curr_prev);

struct MlOutcome {
  bool converged = false;
  int iterations = 0;
  Eigen::Isometry3d T_prev_curr = Eigen::Isometry3d::Identity();
  // x y z roll pitch yaw of T_prev_curr.
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Zero();
  double cost = 0;  // sum r^T W r at the solution
};

// VO-8: Gauss-Newton on (x, y, z, roll, pitch, yaw) of T_prev_curr, minimising
// sum r_j^T W_j r_j with r_j = P_c - R P_p - T and W_j = (Sigma_c + R Sigma_p R^T)^-1
// (eq. 15-17), W re-evaluated at each iteration. Covariance = (J^T W J)^-1.
MlOutcome MaximumLikelihoodMotion(const std::vector<Correspondence>& c,
                                  const std::vector<int>& indices,
                                  const Eigen::Isometry3d& initial_T_prev_curr,
                                  int max_iterations, double tolerance);

// r_j^T W_j r_j of one correspondence under T_prev_curr.
double MahalanobisSquared(const Correspondence& c, const Eigen::Isometry3d& T_prev_curr);

}  // namespace rover::vo
