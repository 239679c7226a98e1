// VO-4 (ray intersection, gap test) and VO-5 (covariance from the Jacobian).
#include "test_rig.hpp"
#include "vo/triangulation.hpp"

#include <gtest/gtest.h>

#include <random>

namespace rover::vo {
namespace {

TEST(Triangulation, VO4_SatisfiesThePapersEquations) {
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0, 1);
  for (int trial = 0; trial < 100; ++trial) {
    const Eigen::Vector3d C1(n(rng), n(rng), n(rng));
    const Eigen::Vector3d C2 = C1 + Eigen::Vector3d(0.3 + 0.1 * n(rng), 0.05 * n(rng), 0.05 * n(rng));
    const Eigen::Vector3d X = C1 + Eigen::Vector3d(n(rng), n(rng), 5 + std::abs(n(rng)));
    // Skew the rays a little so that they do not meet.
    const Eigen::Vector3d r1 = (X - C1).normalized();
    const Eigen::Vector3d r2 = (X + 0.01 * Eigen::Vector3d(n(rng), n(rng), n(rng)) - C2).normalized();
    RayIntersection x;
    ASSERT_TRUE(IntersectRays(C1, r1, C2, r2, &x));
    const Eigen::Vector3d P1 = C1 + r1 * x.m1, P2 = C2 + r2 * x.m2;  // eqs. (1), (2)
    // eqs. (3), (4): the shortest segment is perpendicular to both rays.
    EXPECT_NEAR((P2 - P1).dot(r1), 0, 1e-9);
    EXPECT_NEAR((P2 - P1).dot(r2), 0, 1e-9);
    // eq. (7) and the gap.
    EXPECT_LT((x.P - 0.5 * (P1 + P2)).norm(), 1e-12);
    EXPECT_NEAR(x.gap, (P1 - P2).norm(), 1e-12);
    // No other pair of points on the rays is closer.
    for (double d1 : {-0.01, 0.01}) {
      for (double d2 : {-0.01, 0.01}) {
        EXPECT_GE(((C1 + r1 * (x.m1 + d1)) - (C2 + r2 * (x.m2 + d2))).norm(), x.gap);
      }
    }
  }
}

TEST(Triangulation, VO4_ExactRaysGiveThePointAndTheGapTestRejects) {
  const geometry::StereoRig rig = test::MakeRig(640, 480, 500, 319.5, 239.5, 0.3);
  const Eigen::Vector3d X(0.7, -0.4, 6.0);
  Eigen::Vector2d l, r;
  ASSERT_TRUE(rig.left->Project(X, &l, nullptr));
  ASSERT_TRUE(rig.right->Project(X, &r, nullptr));
  const Eigen::Matrix2d S = 0.01 * Eigen::Matrix2d::Identity();
  TriangulationLimits limits;
  limits.max_gap_rad = 1.5 / 500.0;
  StereoPoint p;
  ASSERT_TRUE(TriangulateStereo(rig, l, S, r, S, limits, &p));
  EXPECT_LT((p.P - X).norm(), 1e-9);
  EXPECT_LT(p.gap, 1e-9);
  // 3 px off the epipolar line: the rays miss each other by more than 1.5 px of angle.
  EXPECT_FALSE(TriangulateStereo(rig, l, S, r + Eigen::Vector2d(0, 3), S, limits, &p));
  EXPECT_EQ(p.failure, TriangulationFailure::kGap);
  // Negative disparity: the rays diverge.
  EXPECT_FALSE(TriangulateStereo(rig, l, S, l + Eigen::Vector2d(2, 0), S, limits, &p));
  EXPECT_NE(p.failure, TriangulationFailure::kNone);
}

TEST(Triangulation, VO5_JacobianMatchesNumericDerivative) {
  const geometry::StereoRig rig = test::MakeRig(640, 480, 500, 319.5, 239.5, 0.3);
  const Eigen::Vector2d l(400.3, 200.7), r(380.1, 201.2);  // 1.2 px off the line: a gap
  const Eigen::Matrix2d S = Eigen::Matrix2d::Identity();
  TriangulationLimits limits;
  limits.max_gap_rad = 1.0;
  StereoPoint p;
  Eigen::Matrix<double, 3, 4> J;
  ASSERT_TRUE(TriangulateStereo(rig, l, S, r, S, limits, &p, &J));
  const double h = 1e-5;
  for (int i = 0; i < 4; ++i) {
    Eigen::Vector4d d = Eigen::Vector4d::Zero();
    d[i] = h;
    StereoPoint a, b;
    ASSERT_TRUE(TriangulateStereo(rig, l + d.head<2>(), S, r + d.tail<2>(), S, limits, &a));
    ASSERT_TRUE(TriangulateStereo(rig, l - d.head<2>(), S, r - d.tail<2>(), S, limits, &b));
    const Eigen::Vector3d numeric = (a.P - b.P) / (2 * h);
    EXPECT_LT((numeric - J.col(i)).norm(), 1e-5 * (1 + numeric.norm())) << "column " << i;
  }
}

// The Monte Carlo tests' point: 8 m ahead of a 0.3 m rig, with unequal, correlated match
// covariances on the two sides.
struct MonteCarloPoint {
  geometry::StereoRig rig = test::MakeRig(640, 480, 500, 319.5, 239.5, 0.3);
  Eigen::Vector3d X{-1.0, 0.5, 8.0};
  Eigen::Vector2d l, r;
  Eigen::Matrix2d Sl, Sr;
  TriangulationLimits limits;
  MonteCarloPoint() {
    rig.left->Project(X, &l, nullptr);
    rig.right->Project(X, &r, nullptr);
    Sl << 0.04, 0.01, 0.01, 0.02;
    Sr << 0.03, -0.005, -0.005, 0.05;
    limits.max_gap_rad = 1.0;
  }
};

// The sample covariance of `samples` (N - 1 in the denominator).
Eigen::Matrix3d SampleCovariance(const std::vector<Eigen::Vector3d>& samples) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& s : samples) mean += s;
  mean /= static_cast<double>(samples.size());
  Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
  for (const auto& s : samples) C += (s - mean) * (s - mean).transpose();
  return C / static_cast<double>(samples.size() - 1);
}

TEST(Triangulation, VO5_CovarianceAgreesWithMonteCarlo) {
  MonteCarloPoint m;
  const auto& [rig, X, l0, r0, Sl, Sr, limits] = m;
  Eigen::Vector2d l = l0, r = r0;
  StereoPoint p;
  ASSERT_TRUE(TriangulateStereo(rig, l, Sl, r, Sr, limits, &p));
  std::mt19937 rng(11);
  std::normal_distribution<double> n(0, 1);
  const Eigen::Matrix2d Ll = Sl.llt().matrixL(), Lr = Sr.llt().matrixL();
  const int N = 20000;
  std::vector<Eigen::Vector3d> samples;
  for (int k = 0; k < N; ++k) {
    StereoPoint q;
    ASSERT_TRUE(TriangulateStereo(rig, l + Ll * Eigen::Vector2d(n(rng), n(rng)), Sl,
                                  r + Lr * Eigen::Vector2d(n(rng), n(rng)), Sr, limits, &q));
    samples.push_back(q.P);
  }
  const Eigen::Matrix3d C = SampleCovariance(samples);
  // First-order propagation vs sampling: within 10 % (range noise is slightly skewed).
  EXPECT_LT((C - p.Sigma).norm() / p.Sigma.norm(), 0.1) << "MC\n" << C << "\nJ S J^T\n" << p.Sigma;
  // And the covariance reflects range: a point twice as far is ~4x less certain in depth.
  StereoPoint far;
  rig.left->Project(2 * X, &l, nullptr);
  rig.right->Project(2 * X, &r, nullptr);
  ASSERT_TRUE(TriangulateStereo(rig, l, Sl, r, Sr, limits, &far));
  EXPECT_GT(far.Sigma(2, 2), 12 * p.Sigma(2, 2));
}

TEST(Triangulation, VO5_CarriedStereoErrorCovarianceAgreesWithMonteCarlo) {
  // The right match repeats the left match's error (its template is cut there): e_r =
  // c e_l + e_s. The point then moves across the line of sight with e_l and in range with
  // e_s alone, which the covariance with the carry must say and the paper's must not.
  const MonteCarloPoint m;
  const auto& [rig, X, l, r, Sl, Sr, limits] = m;
  std::mt19937 rng(12);
  std::normal_distribution<double> n(0, 1);
  const Eigen::Matrix2d Ll = Sl.llt().matrixL(), Lr = Sr.llt().matrixL();
  for (const double carry : {1.0, 0.5}) {
    StereoPoint p, independent;
    ASSERT_TRUE(TriangulateStereo(rig, l, Sl, r, Sr, limits, &p, nullptr, carry));
    ASSERT_TRUE(TriangulateStereo(rig, l, Sl, r, Sr, limits, &independent));
    const int N = 20000;
    std::vector<Eigen::Vector3d> samples;
    for (int k = 0; k < N; ++k) {
      const Eigen::Vector2d el = Ll * Eigen::Vector2d(n(rng), n(rng));
      const Eigen::Vector2d es = Lr * Eigen::Vector2d(n(rng), n(rng));
      StereoPoint q;
      ASSERT_TRUE(TriangulateStereo(rig, l + el, Sl, r + carry * el + es, Sr, limits, &q));
      samples.push_back(q.P);
    }
    const Eigen::Matrix3d C = SampleCovariance(samples);
    EXPECT_LT((C - p.Sigma).norm() / p.Sigma.norm(), 0.1) << "carry " << carry << " MC\n" << C << "\nmodel\n" << p.Sigma;
    EXPECT_GT((C - independent.Sigma).norm() / independent.Sigma.norm(), 0.2) << "carry " << carry;
  }
}

}  // namespace
}  // namespace rover::vo
