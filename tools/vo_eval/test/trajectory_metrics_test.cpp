// Known-answer tests of the KITTI-style segment metrics and of the NEES summary (VO-13).
#include "vo_eval/trajectory_metrics.hpp"

#include "geometry/pose.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace rover::vo_eval {
namespace {

constexpr double kDeg = M_PI / 180.0;

// A straight drive along camera z (KITTI forward), `step` metres per frame.
PoseList StraightPath(int frames, double step) {
  PoseList poses;
  for (int k = 0; k < frames; ++k) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation() = Eigen::Vector3d(0, 0, step * k);
    poses.push_back(T);
  }
  return poses;
}

// The devkit picks the first frame strictly beyond L, so a segment spans
// ceil-past(L / step) steps; with step 0.25 (exact in binary) that is L + 0.25 m.
double ExpectedMean(int frames, double step, double per_metre_error) {
  double sum = 0.0;
  int n = 0;
  for (double L : {10.0, 20.0, 30.0, 40.0, 50.0}) {
    const int span = static_cast<int>(L / step) + 1;
    for (int first = 0; first + span <= frames - 1; ++first) {
      sum += per_metre_error * (span * step) / L;
      ++n;
    }
  }
  return sum / n;
}

TEST(SegmentMetrics, LastFrameIsFirstStrictlyBeyondTheLength) {
  const std::vector<double> dist = {0, 1, 2, 3, 4, 5};
  EXPECT_EQ(LastFrameOfSegment(dist, 0, 3.0), 4);
  EXPECT_EQ(LastFrameOfSegment(dist, 1, 2.5), 4);
  EXPECT_EQ(LastFrameOfSegment(dist, 2, 3.0), -1);
}

TEST(SegmentMetrics, PerfectEstimateHasZeroError) {
  const PoseList truth = StraightPath(300, 0.25);
  const TrajectoryAccuracy a = EvaluateTrajectory(truth, truth);
  EXPECT_GT(a.num_segments, 0);
  EXPECT_NEAR(a.trans_error_percent, 0.0, 1e-12);
  EXPECT_NEAR(a.rot_error_deg_per_m, 0.0, 1e-12);
  EXPECT_NEAR(a.path_length_m, 299 * 0.25, 1e-9);
}

TEST(SegmentMetrics, OnePercentScaleErrorGivesOnePercent) {
  const PoseList truth = StraightPath(300, 0.25);
  PoseList estimate = truth;
  for (auto& T : estimate) T.translation() *= 1.01;
  const TrajectoryAccuracy a = EvaluateTrajectory(truth, estimate);
  // Each segment is L + 0.25 m long, so its error is 1 % of that over L.
  EXPECT_NEAR(a.trans_error_percent, 100.0 * ExpectedMean(300, 0.25, 0.01), 1e-9);
  EXPECT_NEAR(a.trans_error_percent, 1.0, 0.03);
  EXPECT_NEAR(a.rot_error_deg_per_m, 0.0, 1e-9);
  EXPECT_NEAR(a.final_position_error_percent, 1.0, 1e-9);
  ASSERT_EQ(a.lengths_m.size(), 5u);
  EXPECT_NEAR(a.trans_error_percent_per_length[0], 1.0 * 10.25 / 10.0, 1e-9);
  EXPECT_NEAR(a.trans_error_percent_per_length[4], 1.0 * 50.25 / 50.0, 1e-9);
  // Starts: frames whose segment fits; 300 frames, 41 steps for 10 m.
  EXPECT_EQ(a.segments_per_length[0], 300 - 41);
}

TEST(SegmentMetrics, HeadingDriftGivesItsRateInDegPerMetre) {
  const double drift = 0.05 * kDeg;  // rad per metre travelled
  const PoseList truth = StraightPath(400, 0.25);
  PoseList estimate = truth;
  for (std::size_t k = 0; k < estimate.size(); ++k) {
    estimate[k].linear() = Eigen::AngleAxisd(drift * 0.25 * k, Eigen::Vector3d::UnitY()).toRotationMatrix();
  }
  const TrajectoryAccuracy a = EvaluateTrajectory(truth, estimate);
  EXPECT_NEAR(a.rot_error_deg_per_m, ExpectedMean(400, 0.25, 0.05), 1e-9);
  EXPECT_NEAR(a.rot_error_deg_per_m, 0.05, 0.0015);
}

TEST(SegmentMetrics, TranslationErrorIsMeasuredInTheSegmentStartFrame) {
  // A truth that turns 90 deg; the estimate is the truth moved rigidly (a different
  // start pose): relative poses are identical, so every segment error is zero.
  PoseList truth;
  for (int k = 0; k < 200; ++k) {
    const double yaw = 0.5 * M_PI * k / 199.0;
    truth.push_back(geometry::PoseFromXyzRpy(20 * std::sin(yaw), 20 * (1 - std::cos(yaw)), 0, 0, 0, yaw));
  }
  PoseList estimate;
  const Eigen::Isometry3d offset = geometry::PoseFromXyzRpy(3, -2, 1, 0.1, 0.2, 0.3);
  for (const auto& T : truth) estimate.push_back(offset * T);
  const TrajectoryAccuracy a = EvaluateTrajectory(truth, estimate);
  EXPECT_GT(a.num_segments, 100);
  EXPECT_NEAR(a.trans_error_percent, 0.0, 1e-9);
  EXPECT_NEAR(a.rot_error_deg_per_m, 0.0, 1e-6);
  EXPECT_NEAR(a.final_position_error_m, 0.0, 1e-9);
}

TEST(SegmentMetrics, ShortPathHasNoSegments) {
  const PoseList truth = StraightPath(20, 0.25);  // 4.75 m
  const TrajectoryAccuracy a = EvaluateTrajectory(truth, truth);
  EXPECT_EQ(a.num_segments, 0);
  EXPECT_TRUE(a.lengths_m.empty());
}

TEST(SegmentMetrics, MismatchedSizesThrow) {
  EXPECT_THROW(SegmentErrors(StraightPath(10, 1), StraightPath(9, 1)), std::invalid_argument);
  SegmentOptions bad;
  bad.lengths_m = {0.0};
  EXPECT_THROW(SegmentErrors(StraightPath(10, 1), StraightPath(10, 1), bad), std::invalid_argument);
}

TEST(SegmentMetrics, ComposeMotionsRebuildsTheTrajectory) {
  PoseList truth, motions;
  for (int k = 0; k < 30; ++k) {
    truth.push_back(geometry::PoseFromXyzRpy(0.3 * k, 0.01 * k * k, 0.1 * std::sin(k), 0.01 * k, -0.02 * k,
                                             0.05 * k));
    motions.push_back(k == 0 ? Eigen::Isometry3d::Identity() : Eigen::Isometry3d(truth[k - 1].inverse() * truth[k]));
  }
  const PoseList rebuilt = ComposeMotions(motions, truth[0]);
  for (int k = 0; k < 30; ++k) EXPECT_TRUE(rebuilt[k].isApprox(truth[k], 1e-12)) << k;
}

TEST(Nees, MotionErrorIsTheXyzRpyDifference) {
  const Eigen::Isometry3d truth = geometry::PoseFromXyzRpy(1, 2, 3, 0.1, -0.2, 3.1);
  const Eigen::Isometry3d est = geometry::PoseFromXyzRpy(1.01, 2, 2.98, 0.1, -0.2, 3.1 + 0.1);
  const Eigen::Matrix<double, 6, 1> e = MotionError(truth, est);
  Eigen::Matrix<double, 6, 1> expected;
  expected << 0.01, 0, -0.02, 0, 0, 0.1;  // yaw wraps across +-pi
  EXPECT_TRUE(e.isApprox(expected, 1e-9)) << e.transpose();
}

TEST(Nees, HonestCovarianceGivesSixAndFewFalsePositives) {
  Eigen::Matrix<double, 6, 6> A = Eigen::Matrix<double, 6, 6>::Random();
  const Eigen::Matrix<double, 6, 6> cov = 1e-4 * (A * A.transpose() + Eigen::Matrix<double, 6, 6>::Identity());
  const Eigen::Matrix<double, 6, 6> L = cov.llt().matrixL();
  std::mt19937 rng(7);
  std::normal_distribution<double> n(0.0, 1.0);
  std::vector<double> nees, nees_over;
  std::vector<Eigen::Matrix<double, 6, 1>> z;
  for (int i = 0; i < 4000; ++i) {
    Eigen::Matrix<double, 6, 1> w;
    for (int j = 0; j < 6; ++j) w(j) = n(rng);
    const Eigen::Matrix<double, 6, 1> e = L * w;
    nees.push_back(Nees(e, cov));
    nees_over.push_back(Nees(e, cov / 4.0));  // claims twice the real precision
    z.push_back(e.cwiseQuotient(cov.diagonal().cwiseSqrt()));
  }
  const NeesSummary honest = SummariseNees(nees, z);
  EXPECT_NEAR(honest.mean, 6.0, 0.3);
  EXPECT_LT(honest.false_positives, 30);  // 0.27 % of 4000 = 11 expected
  for (int j = 0; j < 6; ++j) EXPECT_NEAR(honest.within_1sigma(j), 0.683, 0.03);
  const NeesSummary over = SummariseNees(nees_over, {});
  EXPECT_NEAR(over.mean, 24.0, 1.2);
  EXPECT_GT(over.false_positives, 1000);
}

TEST(Nees, SingularCovarianceIsReportedAsInvalid) {
  Eigen::Matrix<double, 6, 6> cov = Eigen::Matrix<double, 6, 6>::Identity();
  cov(5, 5) = 0.0;
  EXPECT_LT(Nees(Eigen::Matrix<double, 6, 1>::Ones(), cov), 0.0);
}

}  // namespace
}  // namespace rover::vo_eval
