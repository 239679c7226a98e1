// VO-13: the motion covariance against Monte Carlo truth. Stereo matches of known 3-D
// points are drawn with known pixel noise, triangulated (VO-4, VO-5) and fitted (VO-8);
// the reported covariance must agree with the spread of the estimates.
#include "geometry/pose.hpp"
#include "test_rig.hpp"
#include "vo/motion_estimation.hpp"
#include "vo/triangulation.hpp"
#include "vo/vo_state.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

namespace rover::vo {
namespace {

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;

const Eigen::Isometry3d kMotion = geometry::PoseFromXyzRpy(0.05, -0.02, 0.6, 0.01, -0.03, 0.02);

// What is injected into the pixel observations of one trial.
struct Noise {
  double sigma_px = 0.2;        // independent, per pixel coordinate of every match
  double model_sigma_px = 0.2;  // what the matcher reports (the match covariance)
  double cell_sigma_px = 0;     // one offset per image cell, shared by its features
  double shift_sigma_px = 0;    // one shift of every current match (left and right)
  double disparity_sigma_px = 0;  // one right-image x offset for both pairs
};

struct Trial {
  std::vector<Correspondence> c;
  std::vector<int> all, cluster;
};

constexpr int kGrid = 4;

// Points on the ground ahead of a 640x480 rig (f 500, baseline 0.3 m) seen from both
// poses; each observed in left and right with the noise, triangulated, its covariance
// from the reported match covariance.
Trial MakeTrial(const geometry::StereoRig& rig, const Noise& n, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0, 1);
  std::normal_distribution<double> g(0, 1);
  const Eigen::Isometry3d T_curr_prev = kMotion.inverse();
  const Eigen::Matrix2d S = n.model_sigma_px * n.model_sigma_px * Eigen::Matrix2d::Identity();
  TriangulationLimits limits;
  limits.max_gap_rad = 1.0;  // the noise is the test's; do not gate it
  std::vector<Eigen::Vector2d> cell_offset(kGrid * kGrid);
  for (auto& o : cell_offset) o = n.cell_sigma_px * Eigen::Vector2d(g(rng), g(rng));
  const Eigen::Vector2d shift = n.shift_sigma_px * Eigen::Vector2d(g(rng), g(rng));
  const double disparity = n.disparity_sigma_px * g(rng);
  Trial t;
  while (t.c.size() < 120) {
    const double z = 3 + 12 * u(rng);
    const Eigen::Vector3d P(z * (u(rng) - 0.5) * 1.1, 1.2 + 0.3 * g(rng), z);
    const Eigen::Vector3d Pc = T_curr_prev * P;
    Eigen::Vector2d pl = Eigen::Vector2d::Zero(), pr = pl, cl = pl, cr = pl;
    if (!rig.left->Project(P, &pl) || !rig.right->Project(P, &pr) ||
        !rig.left->Project(Pc, &cl) || !rig.right->Project(Pc, &cr)) {
      continue;
    }
    auto inside = [&](const Eigen::Vector2d& p) {
      return p.x() > 5 && p.y() > 5 && p.x() < rig.left->width() - 6 && p.y() < rig.left->height() - 6;
    };
    if (!inside(pl) || !inside(pr) || !inside(cl) || !inside(cr)) continue;
    const int cell = std::min(kGrid - 1, static_cast<int>(cl.x() * kGrid / rig.left->width())) +
                     kGrid * std::min(kGrid - 1, static_cast<int>(cl.y() * kGrid / rig.left->height()));
    auto noisy = [&](const Eigen::Vector2d& p) -> Eigen::Vector2d {
      return p + n.sigma_px * Eigen::Vector2d(g(rng), g(rng));
    };
    // Previous pair: the left feature defines the point; its right match carries noise.
    const Eigen::Vector2d pl_obs = noisy(pl), pr_obs = noisy(pr) + Eigen::Vector2d(disparity, 0);
    // Current pair: the tracked left match and the right match follow the shared field.
    const Eigen::Vector2d common = shift + cell_offset[cell];
    const Eigen::Vector2d cl_obs = noisy(cl) + common;
    const Eigen::Vector2d cr_obs = noisy(cr) + common + Eigen::Vector2d(disparity, 0);
    StereoPoint sp, sc;
    Eigen::Matrix<double, 3, 4> Jp, Jc;
    if (!TriangulateStereo(rig, pl_obs, S, pr_obs, S, limits, &sp, &Jp) ||
        !TriangulateStereo(rig, cl_obs, S, cr_obs, S, limits, &sc, &Jc)) {
      continue;
    }
    Correspondence x;
    x.P_prev = sp.P;
    x.Sigma_prev = sp.Sigma;
    x.P_curr = sc.P;
    x.Sigma_curr = sc.Sigma;
    x.left = cl_obs;
    x.right = cr_obs;
    x.dPcurr_dshift.col(0) = Jc.col(0) + Jc.col(2);
    x.dPcurr_dshift.col(1) = Jc.col(1) + Jc.col(3);
    x.dPcurr_ddisparity = Jc.col(2);
    x.dPprev_ddisparity = Jp.col(2);
    t.all.push_back(static_cast<int>(t.c.size()));
    t.cluster.push_back(cell);
    t.c.push_back(x);
  }
  return t;
}

Vector6d Error(const Eigen::Isometry3d& estimate) {
  Vector6d e;
  e.head<3>() = estimate.translation() - kMotion.translation();
  e.tail<3>() = geometry::RpyFromRotation(estimate.linear()) - geometry::RpyFromRotation(kMotion.linear());
  return e;
}

struct MonteCarlo {
  double nees_mean = 0;             // with the covariance EstimateMotionUncertainty reports
  double nees_unscaled_mean = 0;    // with H^-1 alone (no variance factor, no shared errors)
  double variance_factor = 0;       // mean s0^2
  double cluster_factor = 0;        // mean k
  Matrix6d empirical = Matrix6d::Zero();  // covariance of the estimates about the truth
  Matrix6d reported = Matrix6d::Zero();   // mean reported covariance
  int beyond = 0;                   // NEES over 20.06 (the 99.73 % bound)
};

// The estimator told of no shared error at all (SharedErrors' defaults carry the cell
// errors VisualOdometry assumes).
SharedErrors Untold() {
  SharedErrors m;
  m.cell_shift_sigma_px = 0;
  m.cell_disparity_sigma_px = 0;
  return m;
}

// `model` says what the estimator is told about the shared errors. `one_cell`: every
// feature counts as one image cell (a lone textured patch).
MonteCarlo RunMonteCarlo(const Noise& noise, const SharedErrors& model, int trials, unsigned seed,
                         bool one_cell = false) {
  const geometry::StereoRig rig = test::MakeRig(640, 480, 500, 319.5, 239.5, 0.3);
  std::mt19937 rng(seed);
  MonteCarlo mc;
  for (int k = 0; k < trials; ++k) {
    Trial t = MakeTrial(rig, noise, rng);
    if (one_cell) t.cluster.assign(t.cluster.size(), 0);
    const MlOutcome ml = MaximumLikelihoodMotion(t.c, t.all, kMotion, 20, 1e-10);
    EXPECT_TRUE(ml.converged);
    SharedErrors m = model;
    m.centre_px = Eigen::Vector2d(319.5, 239.5);
    m.half_size_px = 320;
    const MotionUncertainty u =
        EstimateMotionUncertainty(t.c, t.all, ml.T_prev_curr, t.cluster, kGrid * kGrid, m);
    EXPECT_TRUE(u.ok);
    const Vector6d e = Error(ml.T_prev_curr);
    const double nees = e.dot(u.covariance.ldlt().solve(e));
    mc.nees_mean += nees / trials;
    mc.nees_unscaled_mean += e.dot(u.inverse_normal.ldlt().solve(e)) / trials;
    mc.variance_factor += u.variance_factor / trials;
    mc.cluster_factor += u.cluster_factor / trials;
    mc.empirical += e * e.transpose() / trials;
    mc.reported += u.covariance / trials;
    mc.beyond += nees > 20.06;
  }
  std::printf("NEES %.2f (H^-1 alone %.2f), s0^2 %.3f, k %.3f, %d/%d beyond 20.06\n", mc.nees_mean,
              mc.nees_unscaled_mean, mc.variance_factor, mc.cluster_factor, mc.beyond, trials);
  return mc;
}

TEST(MotionUncertainty, VO13_ReportedCovarianceMatchesTheSpreadOfEstimates) {
  Noise noise;  // 0.2 px, reported as 0.2 px
  const MonteCarlo mc = RunMonteCarlo(noise, Untold(), 300, 1);
  // chi-square(6) has mean 6; 300 trials put the mean within about +-0.4 of it.
  EXPECT_GT(mc.nees_mean, 5.0);
  EXPECT_LT(mc.nees_mean, 7.0);
  EXPECT_NEAR(mc.variance_factor, 1.0, 0.1);
  EXPECT_NEAR(mc.cluster_factor, 1.0, 0.2);
  EXPECT_LE(mc.beyond, 5);  // 0.27 % expected: 0.8 of 300
  // Component by component: the empirical variance within 25 % of the reported one.
  for (int i = 0; i < 6; ++i) {
    EXPECT_NEAR(mc.empirical(i, i) / mc.reported(i, i), 1.0, 0.25) << "component " << i;
  }
}

TEST(MotionUncertainty, VO13_VarianceFactorGrowsWithInjectedNoise) {
  // The matcher keeps reporting 0.2 px while the real noise is half, equal, double.
  double previous = 0;
  for (const double sigma : {0.1, 0.2, 0.4}) {
    Noise noise;
    noise.sigma_px = sigma;
    const MonteCarlo mc = RunMonteCarlo(noise, Untold(), 120, 2);
    const double expected = (sigma / noise.model_sigma_px) * (sigma / noise.model_sigma_px);
    EXPECT_NEAR(mc.variance_factor / expected, 1.0, 0.15) << "sigma " << sigma;
    EXPECT_GT(mc.variance_factor, 2.5 * previous);
    previous = mc.variance_factor;
    // Scaled by it, the covariance stays honest; H^-1 alone is off by the factor.
    EXPECT_GT(mc.nees_mean, 4.5) << "sigma " << sigma;
    EXPECT_LT(mc.nees_mean, 7.5) << "sigma " << sigma;
    EXPECT_NEAR(mc.nees_unscaled_mean / mc.nees_mean, expected, 0.3 * expected);
  }
}

TEST(MotionUncertainty, VO13_ClusterFactorSeesErrorsThatNeighboursShare) {
  // Every feature of an image cell shares an offset as large as its own noise: the
  // residuals within a cell agree, so s0^2 barely moves, but the motion errs more.
  Noise noise;
  noise.cell_sigma_px = 0.2;
  const MonteCarlo mc = RunMonteCarlo(noise, Untold(), 200, 3);
  EXPECT_GT(mc.cluster_factor, 1.8 * mc.variance_factor);
  EXPECT_GT(mc.nees_unscaled_mean, 2.0 * mc.nees_mean);
  EXPECT_GT(mc.nees_mean, 4.0);
  EXPECT_LT(mc.nees_mean, 9.0);
}

TEST(MotionUncertainty, VO13_SharedErrorsNoResidualShowsArePropagated) {
  // A shift of every current match and one disparity offset for both pairs, as large as
  // the model says: the fit absorbs them (s0^2 stays 1), and only their propagation
  // through the normal equations accounts for the extra error.
  Noise noise;
  noise.sigma_px = 0.1;
  noise.model_sigma_px = 0.1;
  noise.shift_sigma_px = 0.1;
  noise.disparity_sigma_px = 0.2;
  SharedErrors told = Untold();
  told.field_sigma_px = 0.1;
  told.disparity_sigma_px = 0.2;
  const MonteCarlo with = RunMonteCarlo(noise, told, 300, 4);
  EXPECT_NEAR(with.variance_factor, 1.0, 0.1);
  EXPECT_GT(with.nees_mean, 3.0);  // the rotation and scale modes were not injected
  EXPECT_LT(with.nees_mean, 7.0);
  EXPECT_LE(with.beyond, 6);
  const MonteCarlo without = RunMonteCarlo(noise, Untold(), 300, 4);
  EXPECT_GT(without.nees_mean, 3.0 * with.nees_mean);
}

TEST(MotionUncertainty, VO13_CellErrorsCountWhenTheFeaturesShareOneCell) {
  // Every current match shifted alike (a lone textured patch whose matches share their
  // sub-pixel bias), all features in one cell: no cluster factor, s0^2 stays 1, and only
  // the cell term, told the shift's size, accounts for it.
  Noise noise;
  noise.sigma_px = 0.1;
  noise.model_sigma_px = 0.1;
  noise.shift_sigma_px = 0.1;
  SharedErrors told = Untold();
  told.cell_shift_sigma_px = 0.1;
  const MonteCarlo with = RunMonteCarlo(noise, told, 300, 5, true);
  EXPECT_NEAR(with.variance_factor, 1.0, 0.1);
  EXPECT_EQ(with.cluster_factor, 0.0);
  EXPECT_GT(with.nees_mean, 4.5);
  EXPECT_LT(with.nees_mean, 7.5);
  EXPECT_LE(with.beyond, 6);
  const MonteCarlo without = RunMonteCarlo(noise, Untold(), 300, 5, true);
  EXPECT_GT(without.nees_mean, 2.0 * with.nees_mean);
}

TEST(MotionUncertainty, VO13_DefaultCellErrorsStayModestForSpreadFeatures) {
  // Independent errors only, 0.2 px (more than VO's matches show), the estimator told of
  // the cell errors VisualOdometry assumes (SharedErrors' defaults): spread over 16 cells
  // they average out, so the covariance grows by a third at most (NEES 5.7 -> 3.8 here),
  // not beyond use.
  Noise noise;  // 0.2 px, reported as 0.2 px
  const MonteCarlo cells = RunMonteCarlo(noise, SharedErrors{}, 200, 6);
  const MonteCarlo none = RunMonteCarlo(noise, Untold(), 200, 6);
  EXPECT_GT(cells.nees_mean, 0.6 * none.nees_mean);
  EXPECT_LT(cells.nees_mean, none.nees_mean);
}


// VO-13, the window's consistency test (NestedDifferenceChi2): two estimates of one
// motion, `a` using all of `b`'s data and more (a = x + e_a, b = a + n with n independent
// of a, so Cov(a, b) = Sigma_a). Drawn with honest covariances, the statistic of a - b is
// chi-square with 6 degrees of freedom; an `a` that claims a larger gain over `b` than it
// has fails it far more often.
namespace nested {

struct Draws {
  double mean = 0;
  double beyond = 0;  // fraction beyond 20.06, the 99.7 % bound
};

Draws DrawNested(std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  std::uniform_real_distribution<double> gain(0.15, 0.9);
  // A covariance of b with correlated translation and rotation, millimetres and
  // milliradians as VO reports them.
  Matrix6d A;
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) A(r, c) = (r < 3 ? 1e-3 : 3e-4) * (r == c ? 1.0 : 0.3 * g(rng));
  }
  const Matrix6d Sigma_b = A * A.transpose();
  // a's covariance: b's, shrunk per direction of b's whitened frame by a gain in
  // [0.15, 0.9] (what a's extra data buy).
  const Eigen::LLT<Matrix6d> llt(Sigma_b);
  const Matrix6d L = llt.matrixL();
  Vector6d f;
  for (int i = 0; i < 6; ++i) f(i) = gain(rng);
  const Matrix6d Sigma_a = L * f.asDiagonal() * L.transpose();
  const Matrix6d L_a = Eigen::LLT<Matrix6d>(Sigma_a).matrixL();
  const Matrix6d L_n = Eigen::LLT<Matrix6d>(Sigma_b - Sigma_a).matrixL();
  const int trials = 20000;
  Draws out;
  for (int t = 0; t < trials; ++t) {
    Vector6d za, zn;
    for (int i = 0; i < 6; ++i) {
      za(i) = g(rng);
      zn(i) = g(rng);
    }
    const Vector6d e_a = L_a * za;
    const Vector6d e_b = e_a + L_n * zn;
    const double chi2 = NestedDifferenceChi2(e_a - e_b, Sigma_a, Sigma_b, 0.05);
    out.mean += chi2 / trials;
    out.beyond += (chi2 > 20.06) / double(trials);
  }
  return out;
}

}  // namespace nested

TEST(MotionUncertainty, VO13_NestedDifferenceIsChiSquareWhenBothAreHonest) {
  for (std::uint32_t seed : {1u, 2u, 3u}) {
    const nested::Draws d = nested::DrawNested(seed);
    // Gains up to 0.9 leave eigenvalues of 0.1 above the 0.05 floor: the statistic is exact.
    EXPECT_NEAR(d.mean, 6.0, 0.25) << "seed " << seed;
    EXPECT_LT(d.beyond, 0.006) << "seed " << seed;
    EXPECT_GT(d.beyond, 0.0005) << "seed " << seed;  // 0.27 % expected
  }
}

TEST(MotionUncertainty, VO13_NestedDifferenceRejectsAnOverconfidentRefinement) {
  // The difference between the two does not depend on a's own error, only on what b
  // adds; so an a that is honest about its own error but claims a larger gain over b
  // than it has (here: the noise b adds is twice what Sigma_b - Sigma_a says) is what
  // the statistic sees. Drawn as b = a + n with n at twice the variance.
  std::mt19937 rng(7);
  std::normal_distribution<double> g(0.0, 1.0);
  Matrix6d Sigma_b = Matrix6d::Zero();
  Sigma_b.diagonal() << 4e-6, 1e-6, 2e-6, 1e-7, 1e-7, 5e-8;
  const Matrix6d Sigma_a = 0.5 * Sigma_b;  // claims half b's variance
  int beyond = 0, trials = 5000;
  for (int t = 0; t < trials; ++t) {
    Vector6d n;
    // Real Cov(n) = 0.9 Sigma_b (a really gains almost nothing), claimed 0.5 Sigma_b.
    for (int i = 0; i < 6; ++i) n(i) = std::sqrt(0.9 * Sigma_b(i, i)) * g(rng);
    beyond += NestedDifferenceChi2(n, Sigma_a, Sigma_b, 0.05) > 20.06;
  }
  // chi2 = 1.8 x chi-square(6): beyond 20.06 when chi-square(6) > 11.1, 8.5 % of draws.
  EXPECT_GT(beyond, trials * 6 / 100);
  // Judged under b's covariance alone (the old test), the same differences pass: 0.9 x chi2(6).
  int beyond_b = 0;
  std::mt19937 rng2(7);
  for (int t = 0; t < trials; ++t) {
    Vector6d n;
    for (int i = 0; i < 6; ++i) n(i) = std::sqrt(0.9 * Sigma_b(i, i)) * g(rng2);
    beyond_b += n.dot(Sigma_b.ldlt().solve(n)) > 20.06;
  }
  EXPECT_LT(beyond_b, trials / 100);
}

TEST(MotionUncertainty, VO13_NestedDifferenceFloorsDirectionsWithoutGainAndRefusesBadInput) {
  Matrix6d Sigma_b = Matrix6d::Zero();
  Sigma_b.diagonal() << 4e-6, 1e-6, 2e-6, 1e-7, 1e-7, 5e-8;
  // a claims no gain at all: every direction is floored at 5 % of b's variance.
  Vector6d d = Vector6d::Zero();
  d(0) = std::sqrt(4e-6);  // one sigma of b in x
  EXPECT_NEAR(NestedDifferenceChi2(d, Sigma_b, Sigma_b, 0.05), 1.0 / 0.05, 1e-9);
  // Half b's variance in x: d of one b-sigma is 2 in chi-square.
  Matrix6d Sigma_a = Sigma_b;
  Sigma_a(0, 0) = 2e-6;
  EXPECT_NEAR(NestedDifferenceChi2(d, Sigma_a, Sigma_b, 0.05), 2.0, 1e-9);
  Matrix6d bad = Sigma_b;
  bad(2, 2) = -1e-6;
  EXPECT_TRUE(std::isinf(NestedDifferenceChi2(d, Sigma_a, bad, 0.05)));
  d(1) = std::nan("");
  EXPECT_TRUE(std::isinf(NestedDifferenceChi2(d, Sigma_a, Sigma_b, 0.05)));
}

// A tracked pair under the carried errors VO-6 makes (README "Carried track errors"): the
// current left match is found with a template cut at the previous one, so it repeats the
// previous left error (track carry 1), and each right match repeats its own left match's
// error (stereo carry 1). Both pairs then see one displaced point X', the previous left
// match exactly; the errors are the previous right match's own, and the current left
// match's own, which its right match repeats.
struct CarriedMonteCarlo {
  double nees_carried = 0;      // VO-8 with the carries (MakeFeature, TriangulateStereo)
  double nees_independent = 0;  // VO-8 with the paper's independent matches
};

CarriedMonteCarlo RunCarriedMonteCarlo(int trials, unsigned seed) {
  const geometry::StereoRig rig = test::MakeRig(640, 480, 500, 319.5, 239.5, 0.3);
  const Eigen::Isometry3d T_curr_prev = kMotion.inverse();
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::normal_distribution<double> g(0, 1);
  const double sigma = 0.2;
  const Eigen::Matrix2d S = sigma * sigma * Eigen::Matrix2d::Identity();
  TriangulationLimits limits;
  limits.max_gap_rad = 1.0;
  auto noise = [&]() -> Eigen::Vector2d { return sigma * Eigen::Vector2d(g(rng), g(rng)); };
  CarriedMonteCarlo mc;
  for (int k = 0; k < trials; ++k) {
    std::vector<Correspondence> carried, independent;
    while (carried.size() < 120) {
      const double z = 3 + 12 * u(rng);
      const Eigen::Vector3d X(z * (u(rng) - 0.5) * 1.1, 1.2 + 0.3 * g(rng), z);
      Eigen::Vector2d pl;
      if (!rig.left->Project(X, &pl)) continue;
      // The point the track follows: on the ray through the previous left match.
      const Eigen::Vector2d pl_obs = pl + noise();
      Eigen::Vector3d C, ray;
      rig.left->BackProject(pl_obs, &C, &ray);
      const Eigen::Vector3d Xd = C + ray * ((X.z() - C.z()) / ray.z());
      const Eigen::Vector3d Xc = T_curr_prev * Xd;
      Eigen::Vector2d pr, cl, cr;
      if (!rig.right->Project(Xd, &pr) || !rig.left->Project(Xc, &cl) || !rig.right->Project(Xc, &cr)) continue;
      const Eigen::Vector2d pr_obs = pr + noise();
      const Eigen::Vector2d w = noise();
      const Eigen::Vector2d cl_obs = cl + w, cr_obs = cr + w + noise();
      for (const double carry : {1.0, 0.0}) {
        StereoPoint sp, sc;
        Eigen::Matrix<double, 3, 4> Jp, Jc;
        if (!TriangulateStereo(rig, pl_obs, S, pr_obs, S, limits, &sp, &Jp, carry) ||
            !TriangulateStereo(rig, cl_obs, S, cr_obs, S, limits, &sc, &Jc, carry)) {
          continue;
        }
        const Feature f = MakeFeature(pl_obs, S, pr_obs, S, sp, Jp, carry, carry);
        Correspondence x;
        x.P_prev = f.P;
        x.Sigma_prev = f.Sigma_uncarried;
        x.P_curr = sc.P;
        x.Sigma_curr = sc.Sigma;
        (carry > 0 ? carried : independent).push_back(x);
      }
      if (carried.size() != independent.size()) {
        carried.resize(std::min(carried.size(), independent.size()));
        independent.resize(carried.size());
      }
    }
    std::vector<int> all(carried.size());
    for (std::size_t i = 0; i < all.size(); ++i) all[i] = static_cast<int>(i);
    for (const bool with_carry : {true, false}) {
      const MlOutcome ml = MaximumLikelihoodMotion(with_carry ? carried : independent, all, kMotion, 20, 1e-10);
      EXPECT_TRUE(ml.converged);
      const Vector6d e = Error(ml.T_prev_curr);
      (with_carry ? mc.nees_carried : mc.nees_independent) += e.dot(ml.covariance.ldlt().solve(e)) / trials;
    }
  }
  std::printf("carried errors: NEES with the carries %.2f, as independent %.2f\n", mc.nees_carried,
              mc.nees_independent);
  return mc;
}

TEST(MotionUncertainty, VO8_CarriedMatchErrorsAreWeighedByWhatTheResidualSees) {
  // The fit's own covariance (J^T W J)^-1, no variance factor: with the carries the
  // matches' errors are modelled as they were made, and chi-square(6) has mean 6. Taken
  // as independent, the two matches of a pair are taken for two looks at the bearing
  // (the right one repeats the left one's error) and the fit claims more than it has
  // (7.4 here; 200 trials put the mean within about +-0.5 of 6).
  const CarriedMonteCarlo mc = RunCarriedMonteCarlo(200, 21);
  EXPECT_GT(mc.nees_carried, 5.0);
  EXPECT_LT(mc.nees_carried, 7.0);
  EXPECT_GT(mc.nees_independent, mc.nees_carried + 0.8);
}

// The window's published covariance is scaled by the larger of the pair's two factors,
// the window's own under a carried covariance model, and the floor
// (window_covariance_min_variance_factor): a factor below the floor no longer shrinks it.
TEST(MotionUncertainty, VO13_PublishedWindowFactorIsFlooredAtTheMinimum) {
  MotionUncertainty pair;
  pair.variance_factor = 0.36;
  pair.cluster_factor = 0.48;
  WindowSolution window;
  window.covariance_variance_factor = 0.44;
  EXPECT_DOUBLE_EQ(PublishedWindowFactor(pair, window, false, 0.0, 0.0), 0.48);  // no floor: as before
  EXPECT_DOUBLE_EQ(PublishedWindowFactor(pair, window, true, 0.0, 0.0), 0.48);
  window.covariance_variance_factor = 0.7;
  EXPECT_DOUBLE_EQ(PublishedWindowFactor(pair, window, true, 0.0, 0.0), 0.7);   // the sandwich's own
  EXPECT_DOUBLE_EQ(PublishedWindowFactor(pair, window, false, 0.0, 0.0), 0.48);  // ignored under S^-1
  EXPECT_DOUBLE_EQ(PublishedWindowFactor(pair, window, true, 0.9, 0.0), 0.9);    // the floor
  pair.variance_factor = 1.3;
  EXPECT_DOUBLE_EQ(PublishedWindowFactor(pair, window, true, 0.9, 0.0), 1.3);    // a larger factor stands
}

// The chi-square quantiles against the tables' (lower 5 % at 10, 30 and 100 dof, lower 1 %
// at 100), and the factor's upper bound s0^2 r / chi^2_alpha(r): with the pair's s0^2 from
// 12 inliers (r = 30) at alpha 0.05 the window is scaled by 0.36 * 30 / 18.493, not by the
// cluster factor 0.48; alpha 0 leaves the point estimate.
TEST(MotionUncertainty, VO13_PublishedWindowFactorIsTheUpperBoundOfS0Squared) {
  EXPECT_NEAR(ChiSquareLowerQuantile(10, 0.05), 3.940, 0.02);
  EXPECT_NEAR(ChiSquareLowerQuantile(30, 0.05), 18.493, 0.03);
  EXPECT_NEAR(ChiSquareLowerQuantile(100, 0.05), 77.929, 0.05);
  EXPECT_NEAR(ChiSquareLowerQuantile(100, 0.01), 70.065, 0.05);
  EXPECT_EQ(ChiSquareLowerQuantile(0, 0.05), 0.0);
  EXPECT_DOUBLE_EQ(VarianceFactorUpperBound(0.4, 30, 0.0), 0.4);
  EXPECT_NEAR(VarianceFactorUpperBound(0.4, 30, 0.05), 0.4 * 30 / 18.493, 1e-3);
  // Many residuals: the bound is barely above the estimate (r = 504, 170 inliers).
  EXPECT_LT(VarianceFactorUpperBound(0.11, 504, 0.05), 0.11 * 1.12);
  MotionUncertainty pair;
  pair.variance_factor = 0.36;
  pair.cluster_factor = 0.48;
  pair.redundancy = 30;
  WindowSolution window;
  window.covariance_variance_factor = 0.44;
  EXPECT_DOUBLE_EQ(PublishedWindowFactor(pair, window, false, 0.0, 0.0), 0.48);
  EXPECT_NEAR(PublishedWindowFactor(pair, window, false, 0.0, 0.05), 0.36 * 30 / 18.493, 1e-3);
}

}  // namespace
}  // namespace rover::vo
