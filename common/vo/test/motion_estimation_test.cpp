// VO-7 (weighted least squares in RANSAC) and VO-8 (maximum likelihood) on synthetic
// 3-D points with a known motion.
#include "geometry/pose.hpp"
#include "test_rig.hpp"
#include "vo/motion_estimation.hpp"
#include "vo/triangulation.hpp"

#include <gtest/gtest.h>

#include <random>

namespace rover::vo {
namespace {

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;

// Stereo-like point covariance: elongated along the viewing ray, growing with range^2.
Eigen::Matrix3d StereoCovariance(const Eigen::Vector3d& P, double lateral, double depth_per_m2) {
  const Eigen::Vector3d ray = P.normalized();
  const double r2 = P.squaredNorm();
  const double along = depth_per_m2 * r2;
  const double across = lateral * std::sqrt(r2);
  return across * across * (Eigen::Matrix3d::Identity() - ray * ray.transpose()) +
         along * along * ray * ray.transpose();
}

struct Scene {
  std::vector<Correspondence> c;
  std::vector<bool> outlier;
};

// Points 3-20 m ahead of a rig; P_curr = T_curr_prev * P_prev, observed with noise drawn
// from each covariance when `noise`; a fraction of correspondences replaced by outliers.
Scene MakeScene(const geometry::StereoRig& rig, const Eigen::Isometry3d& T_prev_curr, int n,
                double outlier_fraction, bool noise, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0, 1);
  std::normal_distribution<double> g(0, 1);
  const Eigen::Isometry3d T_curr_prev = T_prev_curr.inverse();
  Scene s;
  while (static_cast<int>(s.c.size()) < n) {
    const double z = 3 + 17 * u(rng);
    const Eigen::Vector3d P(z * (u(rng) - 0.5), z * (0.6 * u(rng) - 0.3), z);
    Correspondence x;
    x.P_prev = P;
    x.P_curr = T_curr_prev * P;
    if (x.P_curr.z() < 1) continue;
    x.Sigma_prev = StereoCovariance(x.P_prev, 3e-4, 2e-3);
    x.Sigma_curr = StereoCovariance(x.P_curr, 3e-4, 2e-3);
    const bool out = u(rng) < outlier_fraction;
    if (out) {
      x.P_curr += Eigen::Vector3d(g(rng), g(rng), g(rng)) * 0.5 + Eigen::Vector3d(0.3, 0, 0);
    } else if (noise) {
      const Eigen::Matrix3d Lp = x.Sigma_prev.llt().matrixL(), Lc = x.Sigma_curr.llt().matrixL();
      x.P_prev += Lp * Eigen::Vector3d(g(rng), g(rng), g(rng));
      x.P_curr += Lc * Eigen::Vector3d(g(rng), g(rng), g(rng));
    }
    Eigen::Vector2d l, r;
    if (!rig.left->Project(x.P_curr, &l, nullptr) || !rig.right->Project(x.P_curr, &r, nullptr)) continue;
    // The observed pixels are those of the true point (observations of P_curr).
    rig.left->Project(T_curr_prev * P, &x.left, nullptr);
    rig.right->Project(T_curr_prev * P, &x.right, nullptr);
    if (out) x.left += Eigen::Vector2d(15 + 20 * u(rng), 5 * g(rng));
    s.c.push_back(x);
    s.outlier.push_back(out);
  }
  return s;
}

Vector6d PoseError(const Eigen::Isometry3d& estimate, const Eigen::Isometry3d& truth) {
  Vector6d e;
  e.head<3>() = estimate.translation() - truth.translation();
  e.tail<3>() = geometry::RpyFromRotation(estimate.linear()) - geometry::RpyFromRotation(truth.linear());
  return e;
}

const Eigen::Isometry3d kMotion = geometry::PoseFromXyzRpy(0.12, -0.03, 0.9, 0.01, -0.04, 0.02);

TEST(MotionEstimation, VO7_VO8_RecoverExactMotionWith30PercentOutliers) {
  const geometry::StereoRig rig = test::MakeRig(800, 600, 600, 399.5, 299.5, 0.5);
  std::mt19937 rng(5);
  const Scene s = MakeScene(rig, kMotion, 150, 0.3, false, rng);
  RansacOptions ro;
  ro.iterations = 200;
  ro.seed = 1;
  const RansacOutcome rs = RansacMotion(s.c, rig, ro);
  // Every inlier is a true correspondence and every true correspondence is an inlier.
  int true_inliers = 0;
  for (bool o : s.outlier) true_inliers += !o;
  EXPECT_EQ(static_cast<int>(rs.inliers.size()), true_inliers);
  for (int k : rs.inliers) EXPECT_FALSE(s.outlier[k]);
  EXPECT_LT(PoseError(rs.T_curr_prev.inverse(), kMotion).norm(), 1e-6);
  const MlOutcome ml = MaximumLikelihoodMotion(s.c, rs.inliers, rs.T_curr_prev.inverse(), 20, 1e-12);
  ASSERT_TRUE(ml.converged);
  EXPECT_LT(PoseError(ml.T_prev_curr, kMotion).norm(), 1e-6);
  // Deterministic: the same seed gives the same inliers.
  EXPECT_EQ(RansacMotion(s.c, rig, ro).inliers, rs.inliers);
}

TEST(MotionEstimation, VO8_NoisyMotionLiesWithinReportedCovariance) {
  const geometry::StereoRig rig = test::MakeRig(800, 600, 600, 399.5, 299.5, 0.5);
  std::mt19937 rng(8);
  RansacOptions ro;
  ro.iterations = 150;
  ro.inlier_px = 5.0;
  const int trials = 200;
  double nees_sum = 0;
  int within = 0;
  for (int t = 0; t < trials; ++t) {
    const Scene s = MakeScene(rig, kMotion, 120, 0.3, true, rng);
    ro.seed = t;
    const RansacOutcome rs = RansacMotion(s.c, rig, ro);
    std::vector<int> truth;
    for (int k = 0; k < static_cast<int>(s.c.size()); ++k) if (!s.outlier[k]) truth.push_back(k);
    int outliers_in = 0;
    for (int k : rs.inliers) outliers_in += s.outlier[k];
    EXPECT_EQ(outliers_in, 0);
    const MlOutcome ml = MaximumLikelihoodMotion(s.c, rs.inliers, rs.T_curr_prev.inverse(), 20, 1e-10);
    ASSERT_TRUE(ml.converged);
    const Vector6d e = PoseError(ml.T_prev_curr, kMotion);
    const double nees = e.dot(ml.covariance.ldlt().solve(e));
    nees_sum += nees;
    within += nees < 16.81;  // chi-square, 6 dof, 99 %
  }
  const double mean_nees = nees_sum / trials;
  std::printf("mean NEES %.2f (6 expected), %d/%d within the 99 %% bound\n", mean_nees, within, trials);
  EXPECT_GT(mean_nees, 4.0);
  EXPECT_LT(mean_nees, 8.5);
  EXPECT_GE(within, trials * 95 / 100);
}

TEST(MotionEstimation, VO8_MaximumLikelihoodBeatsLeastSquaresOnAnisotropicNoise) {
  const geometry::StereoRig rig = test::MakeRig(800, 600, 600, 399.5, 299.5, 0.5);
  std::mt19937 rng(21);
  double ls_sq = 0, ml_sq = 0;
  for (int t = 0; t < 100; ++t) {
    const Scene s = MakeScene(rig, kMotion, 100, 0.0, true, rng);
    const Eigen::Isometry3d ls = WeightedLeastSquaresMotion(s.c).inverse();
    std::vector<int> all(s.c.size());
    for (int k = 0; k < static_cast<int>(all.size()); ++k) all[k] = k;
    const MlOutcome ml = MaximumLikelihoodMotion(s.c, all, ls, 20, 1e-10);
    ASSERT_TRUE(ml.converged);
    ls_sq += PoseError(ls, kMotion).head<3>().squaredNorm();
    ml_sq += PoseError(ml.T_prev_curr, kMotion).head<3>().squaredNorm();
  }
  std::printf("translation RMS: least squares %.4f m, ML %.4f m\n", std::sqrt(ls_sq / 100),
              std::sqrt(ml_sq / 100));
  EXPECT_LT(ml_sq, 0.5 * ls_sq);
}

}  // namespace
}  // namespace rover::vo
