// VO-7 (weighted least squares inside RANSAC) and VO-8 (maximum likelihood).
//
// A correspondence is the same feature triangulated in the previous pair (P_p, in the
// previous reference frame) and the current pair (P_c, current frame). The motion maps
// P_c = R P_p + T, i.e. (R, T) = T_curr_prev; results are reported as T_prev_curr.
#pragma once

#include "geometry/camera_model.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
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
  // Sensitivities to the errors every feature shares (VO-13, SharedErrorCovariance):
  // dP_curr / d(shift of the current pair's match in x, in y), dP_curr / d(disparity
  // offset) and dP_prev / d(disparity offset). Zero: the feature carries no shared error.
  Eigen::Matrix<double, 3, 2> dPcurr_dshift = Eigen::Matrix<double, 3, 2>::Zero();
  Eigen::Vector3d dPcurr_ddisparity = Eigen::Vector3d::Zero();
  Eigen::Vector3d dPprev_ddisparity = Eigen::Vector3d::Zero();
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
  // Degrees of freedom of the residuals: 3 per correspondence minus the 6 estimated.
  int redundancy = 0;
  // A-posteriori variance factor sigma0^2 = cost / redundancy: how large the residuals
  // are against the covariances that weighted them (1 when those covariances are right).
  // `covariance` is NOT scaled by it; the caller decides (VisualOdometry does).
  double variance_factor = 0;
};

// VO-8: Gauss-Newton on (x, y, z, roll, pitch, yaw) of T_prev_curr, minimising
// sum r_j^T W_j r_j with r_j = P_c - R P_p - T and W_j = (Sigma_c + R Sigma_p R^T)^-1
// (eq. 15-17), W re-evaluated at each iteration. Covariance = (J^T W J)^-1.
MlOutcome MaximumLikelihoodMotion(const std::vector<Correspondence>& c,
                                  const std::vector<int>& indices,
                                  const Eigen::Isometry3d& initial_T_prev_curr,
                                  int max_iterations, double tolerance);

// VO-13: errors that every feature of a pair shares. The ML fit absorbs them into the
// motion, so its residuals cannot show them.
struct SharedErrors {
  // A smooth error field over the current pair's matches (sub-pixel peak bias, which
  // depends on the sub-pixel phase that features moving alike share; residual lens
  // distortion; templates matched across a change of viewpoint), by its first-order
  // modes: a shift in x and in y, a rotation and a scale about the image centre, each
  // with this one-sigma in pixels (the rotation and the scale at `half_size_px` from the
  // centre). The matched point moves in both images: its bearing changes, not its range.
  double field_sigma_px = 0;
  Eigen::Vector2d centre_px = Eigen::Vector2d::Zero();
  double half_size_px = 1;
  // One disparity offset for both pairs (the rig's calibration), pixels.
  double disparity_sigma_px = 0;
  // Errors that the features of one image cell share (the cells of `cluster` below; all
  // features form one cell without clusters): neighbours see the same texture, the same
  // sub-pixel phase (they moved alike, and lie at about the same range) and the same
  // template deformation, so the peak-fit bias of their matches agrees. Per cell, independent
  // between cells: a shift of the current pair's matches in x and in y
  // (`cell_shift_sigma_px` each), and a disparity error in each of the two pairs
  // (`cell_disparity_sigma_px` each, independent between the pairs: their sub-pixel phases
  // differ). With features over many cells these average out like independent errors;
  // with the features in one or two cells (a lone textured patch) they move the whole
  // cloud, and no residual shows them. The cluster factor sees only the part of them that
  // differs between cells. VoOptions carries them (covariance_cell_shift_sigma_px,
  // covariance_cell_disparity_sigma_px in configs/vo.yaml). They were chosen on rendered truth: vo_eval --world drives (0.5-0.6 m steps on
  // columbia_hills_traverse and outcrop_slope, turns up to 26 deg on flat_rock_course, the
  // clustered_features patch), the synthetic terrain and catalogue runs (sol304_approach,
  // sol188_191, large_turn, clustered_features): over those 243 updates the mean NEES went
  // from 6.25 to 5.23 and the updates beyond 20.06 from 4 to 1; synthetic 4.43 -> 3.37.
  double cell_shift_sigma_px = 0.04;
  double cell_disparity_sigma_px = 0.04;
};

// VO-13: the covariance of an ML motion from what the data shows. At the solution, with
// J_j = dr_j / d(x y z roll pitch yaw), W_j the weight and H = sum J_j^T W_j J_j:
//   - the a-posteriori variance factor s0^2 = sum r_j^T W_j r_j / (3n - 6): the residuals
//     against the covariances that weighted them;
//   - the cluster variance factor: the same, but from the scores s_g = sum_{j in g}
//     J_j^T W_j r_j summed over clusters g of neighbouring features (cells of a grid over
//     the image), k = tr(H^-1 sum_g s_g s_g^T) / (6 - sum_g tr((H^-1 H_g)^2)). Both have
//     expectation 1 when the features' errors are independent and their covariances
//     right; the cluster factor also grows when neighbours share their errors;
//   - the shared errors (SharedErrors), which the fit absorbs and no residual shows:
//     d theta = H^-1 sum_j J_j^T W_j D_j dc with D_j = dr_j / dc, so their covariance is
//     G diag(sigma^2) G^T with G = H^-1 sum_j J_j^T W_j D_j; the cell errors the same per
//     cell g (G_g = H^-1 sum_{j in g} J_j^T W_j D_j), summed over the cells.
// covariance = max(s0^2, k) H^-1 + G diag(sigma^2) G^T + sum_g G_g diag(sigma_cell^2) G_g^T.
struct MotionUncertainty {
  bool ok = false;                 // H invertible
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 6> inverse_normal = Eigen::Matrix<double, 6, 6>::Zero();  // H^-1
  Eigen::Matrix<double, 6, 6> shared = Eigen::Matrix<double, 6, 6>::Zero();  // G diag G^T + cells
  double variance_factor = 0;      // s0^2
  double cluster_factor = 0;       // k (0 with fewer than two clusters)
  int redundancy = 0;              // 3n - 6
  int clusters = 0;                // clusters holding features
  // The motion's response to one pixel of disparity offset common to both pairs (the
  // disparity column of G), for comparing this fit with one that holds an offset.
  Eigen::Matrix<double, 6, 1> disparity_sensitivity = Eigen::Matrix<double, 6, 1>::Zero();

  // VO-13's covariance of a fit whose inverse normal matrix is `fit`: scaled by the larger
  // factor, plus the shared errors (`covariance` is Scaled(inverse_normal); the sliding
  // window's refined delta is Scaled of the window's own).
  Eigen::Matrix<double, 6, 6> Scaled(const Eigen::Matrix<double, 6, 6>& fit) const {
    return std::max(variance_factor, cluster_factor) * fit + shared;
  }
};

// `cluster` gives each correspondence's cluster, in [0, num_clusters) (indexed like `c`);
// empty or num_clusters < 2: no cluster factor, and all features form one cell.
MotionUncertainty EstimateMotionUncertainty(const std::vector<Correspondence>& c,
                                            const std::vector<int>& indices,
                                            const Eigen::Isometry3d& T_prev_curr,
                                            const std::vector<int>& cluster, int num_clusters,
                                            const SharedErrors& shared);

// The lower alpha-quantile of the chi-square distribution with `dof` degrees of freedom
// (Wilson-Hilferty's cube-root normal approximation: within 1.5 % of the exact value for
// dof >= 30 and alpha >= 1e-4; below that it errs low, so the bound below errs large, e.g.
// 7 % at 10 dof and alpha 0.001). dof < 1 or alpha outside (0, 1): 0.
double ChiSquareLowerQuantile(int dof, double alpha);

// An upper confidence bound on a variance factor estimated as cost / dof: with chi-square
// errors cost ~ sigma^2 chi^2(dof), so sigma^2 <= factor * dof / chi^2_alpha(dof) at
// confidence 1 - alpha. A factor from few residuals is uncertain (and RANSAC's inlier
// selection truncates them), so the bound inflates it much at 20 inliers and barely at 170.
// alpha <= 0 or dof < 1: the factor as it is.
double VarianceFactorUpperBound(double factor, int dof, double alpha);

// VO-13: the chi-square (6 dof) of the difference d = a - b between two estimates of one
// motion where `a` (covariance Sigma_a) uses all the data of `b` (Sigma_b) and more, as
// the sliding window's delta uses its newest pair's. If both covariances are honest,
// Cov(a, b) = Sigma_a and so Cov(d) = Sigma_b - Sigma_a (Hausman's test of an efficient
// against a consistent estimator); an `a` that claims more than its data give differs
// from `b` by more than that. The difference's covariance is taken in the frame whitened
// by Sigma_b, each eigenvalue floored at `min_fraction` of b's own variance there: the
// two estimates are never exactly nested (the window re-triangulates its points and
// weights its observations by a Huber loss), and a direction where `a` claims no gain
// over `b` must not make a tiny difference look huge. +inf when Sigma_b is not positive
// definite or anything is not finite.
double NestedDifferenceChi2(const Eigen::Matrix<double, 6, 1>& d, const Eigen::Matrix<double, 6, 6>& Sigma_a,
                            const Eigen::Matrix<double, 6, 6>& Sigma_b, double min_fraction);

// r_j^T W_j r_j of one correspondence under T_prev_curr.
double MahalanobisSquared(const Correspondence& c, const Eigen::Isometry3d& T_prev_curr);

}  // namespace rover::vo
