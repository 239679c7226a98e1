// The gyro bias: heading sigma that grows in proportion to time until VO measures the bias,
// a heading error that swings every later step the same way, and a bias learnt from VO.
#include "estimation/pose_estimator.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <numeric>
#include <random>
#include <vector>

using namespace rover::estimation;
using rover::geometry::Matrix6d;
using rover::geometry::Pose;
using rover::geometry::PoseFromXyzRpy;
using rover::geometry::RotationFromRpy;
using rover::geometry::RpyFromRotation;

namespace {

constexpr int64_t kSecond = 1000000;
constexpr double kDegPerHour = M_PI / 180.0 / 3600.0;

Eigen::Quaterniond YawQ(double yaw) { return Eigen::Quaterniond(RotationFromRpy(0, 0, yaw)); }

double Yaw(const Pose& T) { return RpyFromRotation(T.linear()).z(); }

// Only what a test names: no wheel error, no gyro noise, no bias walk.
EstimatorOptions Quiet() {
  EstimatorOptions o;
  o.along_track_sigma_fraction = 0.0;
  o.cross_track_sigma_fraction = 0.0;
  o.vertical_sigma_fraction = 0.0;
  o.gyro_drift_rad_per_s = 0.0;
  o.gyro_random_walk_rad_per_sqrt_s = 0.0;
  o.gyro_bias_walk_rad_per_s_per_sqrt_s = 0.0;
  o.gyro_scale_sigma_fraction = 0.0;
  return o;
}

VoUpdate Vo(int64_t from, int64_t to, const Pose& T, double xyz_sigma, double yaw_sigma) {
  VoUpdate u;
  u.from_utime = from;
  u.to_utime = to;
  u.T_from_to = T;
  u.covariance = Matrix6d::Identity() * xyz_sigma * xyz_sigma;
  u.covariance(3, 3) = u.covariance(4, 4) = yaw_sigma * yaw_sigma;
  u.covariance(5, 5) = yaw_sigma * yaw_sigma;
  return u;
}

// A rover driving north at 0.05 m/s whose gyro drifts by `bias` (plus white noise of
// `arw`): the IMU's yaw is bias * t off the truth. Every `step_s` VO reports the true
// motion with its yaw change off by N(0, vo_yaw_sigma).
struct DriftingDrive {
  double bias = 0.0;
  double arw = 0.0;
  double vo_yaw_sigma = 0.0;
  double claimed_yaw_factor = 1.0;  // VO claims this times vo_yaw_sigma
  double step_s = 20.0;
  double vo_yaw_bias_per_m = 0.0;  // VO's yaw change off by this much a metre too
  double vo_xy_sigma = 0.0;        // VO's translation off by N(0, this) along x and y (claimed: 0.001)
  double tick_s = 0.1;             // the IMU's and the odometer's period
  std::mt19937 rng{1};
  double imu_yaw_error = 0.0;
  int64_t t = 0;
  int64_t last_capture = 0;

  void Start(PoseEstimator& est) {
    est.OnImu(0, YawQ(0.0), Eigen::Vector3d::Zero());
    est.OnWheelOdometry(0, 0.0);
  }
  // Drives one step at 10 Hz, then applies VO over it.
  void Step(PoseEstimator& est) {
    std::normal_distribution<double> normal;
    const int ticks = static_cast<int>(std::lround(step_s / tick_s));
    for (int i = 0; i < ticks; ++i) Tick(est, 0.05 * static_cast<double>(t + TickUs()) * 1e-6 - parked_m, normal);
    const double yaw_noise = vo_yaw_sigma * normal(rng) + vo_yaw_bias_per_m * 0.05 * step_s;
    double dx = 0.0, dy = 0.0;
    if (vo_xy_sigma > 0.0) {
      dx = vo_xy_sigma * normal(rng);
      dy = vo_xy_sigma * normal(rng);
    }
    const Pose T = PoseFromXyzRpy(0.05 * step_s + dx, dy, 0, 0, 0, yaw_noise);
    const double claimed = std::max(claimed_yaw_factor * vo_yaw_sigma, 1e-9);
    const VoUpdateResult r = est.ApplyVoUpdate(Vo(last_capture, t, T, 0.001, claimed));
    ASSERT_TRUE(r.applied()) << r.reason;
    last_capture = t;
  }
  // Parks for `seconds` at 10 Hz: the wheels still, the gyro drifting.
  void Park(PoseEstimator& est, double seconds) {
    std::normal_distribution<double> normal;
    const double distance = 0.05 * static_cast<double>(t) * 1e-6 - parked_m;
    for (int i = 0; i < static_cast<int>(std::lround(seconds / tick_s)); ++i) Tick(est, distance, normal);
    parked_m += 0.05 * seconds;
  }
  int64_t TickUs() const { return std::llround(tick_s * kSecond); }
  // One tick: the gyro drifts on, the odometer reads `distance_m`.
  void Tick(PoseEstimator& est, double distance_m, std::normal_distribution<double>& normal) {
    t += TickUs();
    imu_yaw_error += bias * tick_s + arw * std::sqrt(tick_s) * normal(rng);
    ASSERT_EQ(est.OnImu(t, YawQ(imu_yaw_error), Eigen::Vector3d::Zero()), InputResult::kAccepted);
    ASSERT_EQ(est.OnWheelOdometry(t, distance_m), InputResult::kAccepted);
  }
  double parked_m = 0.0;  // what the odometer did not run while parked
  double HeadingError(const PoseEstimator& est) const { return Yaw(est.pose()); }
};

// The gyro of the simulated rover (3 deg/h of bias, 0.15 deg/sqrt(h) of white noise) and
// nothing else, and a drive with that bias whose VO errs its yaw by 0.0005 rad a step.
EstimatorOptions MerGyro() {
  EstimatorOptions o = Quiet();
  o.gyro_drift_rad_per_s = 3.0 * kDegPerHour;
  o.gyro_random_walk_rad_per_sqrt_s = 0.15 * M_PI / 180.0 / 60.0;
  return o;
}
DriftingDrive MerGyroDrive() {
  DriftingDrive drive;
  drive.bias = 3.0 * kDegPerHour;
  drive.arw = MerGyro().gyro_random_walk_rad_per_sqrt_s;
  drive.vo_yaw_sigma = 0.0005;
  return drive;
}

}  // namespace

// The defect this model mends: with fuse, each VO update used to add the gyro's error over
// its step in quadrature, so the heading sigma grew as the square root of the steps while a
// bias grows in proportion to time. With VO blind to yaw, the heading sigma must be exactly
// the bias sigma times the time.
TEST(GyroBias, HeadingSigmaGrowsInProportionToTimeAcrossVoUpdates) {
  EstimatorOptions o = Quiet();
  o.gyro_drift_rad_per_s = 3.0 * kDegPerHour;
  PoseEstimator est(o);
  DriftingDrive drive;
  drive.vo_yaw_sigma = 1.0;  // VO says nothing useful about yaw
  drive.Start(est);
  for (int i = 0; i < 10; ++i) drive.Step(est);  // 200 s
  EXPECT_NEAR(std::sqrt(est.covariance()(5, 5)), 3.0 * kDegPerHour * 200.0,
              1e-3 * 3.0 * kDegPerHour * 200.0);
}

// The same when each update arrives while the rover drives on (thinking while driving: VO
// measures the last step during the next). The sample at each update's `to` then carries the
// gyro's clock on, so the next update's interval is its own 20 s, not the drive so far: with
// that clock left at zero the heading sigma after 205 s was 5.5 times too large here, and on
// a rock-field drive the gyro check weighed VO's yaw alone.
TEST(GyroBias, HeadingSigmaGrowsInProportionToTimeWhenUpdatesArriveLate) {
  EstimatorOptions o = Quiet();
  o.gyro_drift_rad_per_s = 3.0 * kDegPerHour;
  PoseEstimator est(o);
  est.OnImu(0, YawQ(0.0), Eigen::Vector3d::Zero());
  est.OnWheelOdometry(0, 0.0);
  int64_t t = 0, last_capture = 0;
  auto drive = [&](double seconds) {
    for (int i = 0; i < static_cast<int>(seconds * 10); ++i) {
      t += kSecond / 10;
      est.OnImu(t, YawQ(0.0), Eigen::Vector3d::Zero());
      est.OnWheelOdometry(t, 0.05 * static_cast<double>(t) * 1e-6);
    }
  };
  drive(20.0);
  for (int i = 0; i < 10; ++i) {
    const int64_t capture = t;
    drive(i < 9 ? 20.0 : 5.0);  // the next step starts before VO has measured this one
    const Pose T = PoseFromXyzRpy(0.05 * 20.0, 0, 0, 0, 0, 0);
    ASSERT_TRUE(est.ApplyVoUpdate(Vo(last_capture, capture, T, 0.001, 1.0)).applied());
    last_capture = capture;
  }
  // 205 s of gyro time, VO blind to yaw: the bias's sigma times the time (within 1 %: the
  // growth after each `to` is added back as the difference of the old covariances, which
  // a projection onto the PSD cone raises by 0.5 % here; with the clock at zero: 5.5 times).
  EXPECT_NEAR(std::sqrt(est.covariance()(5, 5)), 3.0 * kDegPerHour * 205.0, 1e-2 * 3.0 * kDegPerHour * 205.0);
}

// vo_yaw_sigma_factor weighs VO's yaw at that multiple of its own sigma: a drive whose VO
// claims 0.0005 rad with the factor 2 is estimated exactly as one whose VO claims 0.001 rad,
// and the heading then leans less on VO (its sigma after the drive is larger).
TEST(GyroBias, VoYawSigmaFactorWeighsVoYawAsAWiderSigma) {
  const EstimatorOptions o = MerGyro();
  auto run = [&](double factor, double claimed_factor) {
    EstimatorOptions oo = o;
    oo.vo_yaw_sigma_factor = factor;
    auto est = std::make_unique<PoseEstimator>(oo);
    DriftingDrive drive = MerGyroDrive();
    drive.claimed_yaw_factor = claimed_factor;
    drive.Start(*est);
    for (int i = 0; i < 30; ++i) drive.Step(*est);
    return est;
  };
  const auto scaled = run(2.0, 1.0), wide = run(1.0, 2.0), own = run(1.0, 1.0);
  EXPECT_NEAR(Yaw(scaled->pose()), Yaw(wide->pose()), 1e-12);
  EXPECT_NEAR(scaled->covariance()(5, 5), wide->covariance()(5, 5), 1e-15);
  EXPECT_NEAR(scaled->gyro_bias_rad_per_s(), wide->gyro_bias_rad_per_s(), 1e-15);
  EXPECT_GT(scaled->covariance()(5, 5), 1.2 * own->covariance()(5, 5));
}

// A heading error at the start swings every later step the same way, so the cross-track
// sigma after D metres is sigma_heading * D, whether wheel odometry or VO steps carried the
// rover (not sigma * D / sqrt(steps)).
TEST(GyroBias, AHeadingErrorSwingsChainedStepsCoherently) {
  EstimatorOptions o = Quiet();
  o.initial_yaw_sigma_rad = 0.01;
  o.vo_heading = VoHeadingMode::kIgnore;
  for (bool with_vo : {false, true}) {
    PoseEstimator est(o);
    DriftingDrive drive;
    drive.Start(est);
    for (int i = 0; i < 20; ++i) {
      if (with_vo) {
        drive.Step(est);
      } else {
        drive.vo_yaw_sigma = 0.0;
        const int64_t t = (i + 1) * 20 * kSecond;
        est.OnImu(t, YawQ(0.0), Eigen::Vector3d::Zero());
        est.OnWheelOdometry(t, 0.05 * 20.0 * (i + 1));
      }
    }
    const Matrix6d P = est.covariance();
    EXPECT_NEAR(std::sqrt(P(1, 1)), 0.01 * 20.0, with_vo ? 0.002 : 1e-9) << "with_vo " << with_vo;
    // Heading and the east error it caused are fully correlated.
    EXPECT_NEAR(P(1, 5) / std::sqrt(P(1, 1) * P(5, 5)), 1.0, 0.02) << "with_vo " << with_vo;
  }
}

// VO's yaw changes measure the gyro's drift; the estimator learns the bias and takes it off
// the IMU's heading, so the heading error stops growing with it.
TEST(GyroBias, VoTeachesTheBiasAndTheHeadingStopsDrifting) {
  EstimatorOptions o = Quiet();
  o.gyro_drift_rad_per_s = 3.0 * kDegPerHour;
  o.gyro_random_walk_rad_per_sqrt_s = 0.15 * M_PI / 180.0 / 60.0;
  PoseEstimator est(o);
  DriftingDrive drive;
  drive.bias = 3.0 * kDegPerHour;
  drive.arw = o.gyro_random_walk_rad_per_sqrt_s;
  drive.vo_yaw_sigma = 0.0005;  // about 0.03 deg per step
  drive.Start(est);
  for (int i = 0; i < 180; ++i) drive.Step(est);  // one hour
  const double bias_sigma = est.gyro_bias_sigma_rad_per_s();
  EXPECT_LT(bias_sigma, 0.5 * kDegPerHour);
  EXPECT_NEAR(est.gyro_bias_rad_per_s(), drive.bias, 3.0 * bias_sigma);
  // Uncorrected, the bias alone would put the heading 3 deg off after an hour; what is left
  // is VO's yaw noise summed over 180 steps (0.0005 rad * sqrt(180) = 0.4 deg, 1 sigma).
  EXPECT_LT(std::abs(drive.HeadingError(est)), 1.0 * M_PI / 180.0);
  EXPECT_LT(std::abs(drive.HeadingError(est)), 3.0 * std::sqrt(est.covariance()(5, 5)));
}

// The claimed sigma is honest: over many seeded drives with a bias drawn from its prior,
// the heading error's normalized squared error averages about 1, at the end and midway.
TEST(GyroBias, HeadingSigmaIsConsistentOverSeededDrives) {
  EstimatorOptions o = Quiet();
  o.gyro_drift_rad_per_s = 3.0 * kDegPerHour;
  o.gyro_random_walk_rad_per_sqrt_s = 0.15 * M_PI / 180.0 / 60.0;
  std::mt19937 bias_rng(7);
  std::normal_distribution<double> normal;
  const int kDrives = 200;
  double nees_mid = 0.0, nees_end = 0.0;
  for (int k = 0; k < kDrives; ++k) {
    PoseEstimator est(o);
    DriftingDrive drive;
    drive.rng.seed(100 + k);
    drive.bias = o.gyro_drift_rad_per_s * normal(bias_rng);
    drive.arw = o.gyro_random_walk_rad_per_sqrt_s;
    drive.vo_yaw_sigma = 0.002;
    drive.Start(est);
    for (int i = 0; i < 60; ++i) {
      drive.Step(est);
      if (i == 29 || i == 59) {
        const double e = drive.HeadingError(est);
        (i == 29 ? nees_mid : nees_end) += e * e / est.covariance()(5, 5);
      }
    }
  }
  nees_mid /= kDrives;
  nees_end /= kDrives;
  std::printf("heading NEES over %d drives: %.3f after 10 min, %.3f after 20 min\n", kDrives,
              nees_mid, nees_end);
  // The mean of 200 chi-square(1) draws lies within 0.6 and 1.4 with odds far beyond 99 %.
  EXPECT_GT(nees_mid, 0.6);
  EXPECT_LT(nees_mid, 1.4);
  EXPECT_GT(nees_end, 0.6);
  EXPECT_LT(nees_end, 1.4);
}

// Reset moves the pose, not the gyro: the bias learnt so far is kept.
TEST(GyroBias, ResetKeepsTheBiasLearnt) {
  EstimatorOptions o = Quiet();
  o.gyro_drift_rad_per_s = 3.0 * kDegPerHour;
  PoseEstimator est(o);
  DriftingDrive drive;
  drive.bias = 2.0 * kDegPerHour;
  drive.vo_yaw_sigma = 0.0005;
  drive.Start(est);
  for (int i = 0; i < 60; ++i) drive.Step(est);
  const double bias = est.gyro_bias_rad_per_s();
  const double sigma = est.gyro_bias_sigma_rad_per_s();
  EXPECT_GT(bias, 1.0 * kDegPerHour);
  est.Reset(Pose::Identity(), drive.t);
  EXPECT_EQ(est.gyro_bias_rad_per_s(), bias);
  EXPECT_EQ(est.gyro_bias_sigma_rad_per_s(), sigma);
  EXPECT_EQ(est.covariance()(5, 5), 0.0);
}

// VO's yaw bias (EstimatorOptions::vo_yaw_bias_sigma_rad_per_m). VO errs its yaw change by
// 0.02 deg a metre on every step; the gyro drifts 3 deg/h, and parks of 60 s every five
// steps let the rest segments measure the gyro's bias apart from VO's. Without the state
// the check takes VO's drift for the gyro's and the heading follows it, claiming a sigma far
// under its error; with it the bias is learnt and the heading stays within its sigma.
TEST(VoYawBias, VosDriftIsLearntApartFromTheGyrosAndTheHeadingStaysHonest) {
  const double vo_bias = 0.02 * M_PI / 180.0;  // rad per metre
  auto run = [&](double prior_sigma, double* heading_z) {
    EstimatorOptions oo = MerGyro();
    oo.vo_yaw_bias_sigma_rad_per_m = prior_sigma;
    auto est = std::make_unique<PoseEstimator>(oo);
    DriftingDrive drive = MerGyroDrive();
    drive.vo_yaw_bias_per_m = vo_bias;
    drive.Start(*est);
    for (int i = 0; i < 180; ++i) {  // 180 m
      drive.Step(*est);
      if (i % 5 == 4) drive.Park(*est, 60.0);
    }
    *heading_z = drive.HeadingError(*est) / std::sqrt(est->covariance()(5, 5));
    std::printf("VO yaw bias prior %.4f deg/m: learnt %.5f +- %.5f deg/m, heading error %.3f deg, z %.2f\n",
                prior_sigma * 180.0 / M_PI, est->vo_yaw_bias_rad_per_m() * 180.0 / M_PI,
                est->vo_yaw_bias_sigma_rad_per_m() * 180.0 / M_PI, drive.HeadingError(*est) * 180.0 / M_PI,
                *heading_z);
    return est;
  };
  double z_off = 0.0, z_on = 0.0;
  const auto off = run(0.0, &z_off);
  const auto on = run(0.03 * M_PI / 180.0, &z_on);
  EXPECT_EQ(off->vo_yaw_bias_rad_per_m(), 0.0);
  EXPECT_GT(std::abs(z_off), 3.0);
  EXPECT_LT(std::abs(z_on), 3.0);
  EXPECT_NEAR(on->vo_yaw_bias_rad_per_m(), vo_bias, 3.0 * on->vo_yaw_bias_sigma_rad_per_m());
  EXPECT_LT(on->vo_yaw_bias_sigma_rad_per_m(), 0.5 * vo_bias);
}

// Honest over seeded drives whose VO yaw bias and gyro bias are drawn from their priors,
// with no parks: the two biases are then told apart by nothing (VO's distance runs with the
// gyro's time), so the heading's sigma must hold what neither can tell.
TEST(VoYawBias, HeadingSigmaIsConsistentWhenTheBiasesCannotBeToldApart) {
  EstimatorOptions o = MerGyro();
  o.vo_yaw_bias_sigma_rad_per_m = 0.01 * M_PI / 180.0;
  std::mt19937 bias_rng(11);
  std::normal_distribution<double> normal;
  const int kDrives = 200;
  double nees = 0.0;
  for (int k = 0; k < kDrives; ++k) {
    PoseEstimator est(o);
    DriftingDrive drive = MerGyroDrive();
    drive.rng.seed(500 + k);
    drive.bias = o.gyro_drift_rad_per_s * normal(bias_rng);
    drive.vo_yaw_bias_per_m = o.vo_yaw_bias_sigma_rad_per_m * normal(bias_rng);
    drive.Start(est);
    for (int i = 0; i < 60; ++i) drive.Step(est);
    const double e = drive.HeadingError(est);
    nees += e * e / est.covariance()(5, 5);
  }
  nees /= kDrives;
  std::printf("heading NEES over %d drives with a VO yaw bias: %.3f\n", kDrives, nees);
  EXPECT_GT(nees, 0.6);
  EXPECT_LT(nees, 1.4);
}

// What one drive's mean NEES can show. Over a long day the heading's error is one path of a
// random walk (the gyro's bias and VO's persistent yaw, each a few draws for the whole day),
// so the mean of e^2 / sigma^2 over one drive's poses is not a chi-square mean of many
// independent draws: it spreads widely about 1 even when the model is the truth. Here the
// truth is drawn from the estimator's own model, 500 m at a time: the gyro's bias from its
// prior, VO's yaw bias a Gauss-Markov process of the same sigma and length, VO's own yaw and
// translation noise at the sigmas it claims. The estimate is honest over the drives, and yet
// a share of single drives falls outside the bounds a drive is held to (0.5-1.5 for the
// heading, 1-3 for the position): those bounds test a campaign's mean, not one drive.
TEST(VoYawBias, OneDrivesMeanNeesSpreadsWideWhenTheModelIsTheTruth) {
  EstimatorOptions o = MerGyro();
  o.vo_yaw_bias_sigma_rad_per_m = 0.003 * M_PI / 180.0;
  o.vo_yaw_bias_length_m = 20.0;
  std::mt19937 draw(13);
  std::normal_distribution<double> normal;
  const int kDrives = 100, kSteps = 834;  // 0.6 m steps: 500 m
  std::vector<double> heading, horizontal;
  for (int k = 0; k < kDrives; ++k) {
    PoseEstimator est(o);
    DriftingDrive drive = MerGyroDrive();
    drive.rng.seed(900 + k);
    drive.step_s = 12.0;
    drive.tick_s = 1.0;
    drive.vo_xy_sigma = 0.001;
    drive.bias = o.gyro_drift_rad_per_s * normal(draw);
    const double keep = std::exp(-0.05 * drive.step_s / o.vo_yaw_bias_length_m);
    double vo_bias = o.vo_yaw_bias_sigma_rad_per_m * normal(draw);
    double sum_heading = 0.0, sum_horizontal = 0.0;
    drive.Start(est);
    for (int i = 0; i < kSteps; ++i) {
      drive.vo_yaw_bias_per_m = vo_bias;
      drive.Step(est);
      vo_bias = keep * vo_bias + o.vo_yaw_bias_sigma_rad_per_m * std::sqrt(1.0 - keep * keep) * normal(draw);
      const double e = drive.HeadingError(est);
      sum_heading += e * e / est.covariance()(5, 5);
      const Eigen::Vector2d exy =
          est.pose().translation().head<2>() - Eigen::Vector2d(0.05 * static_cast<double>(drive.t) * 1e-6, 0.0);
      sum_horizontal += exy.dot(est.covariance().topLeftCorner<2, 2>().ldlt().solve(exy));
    }
    heading.push_back(sum_heading / kSteps);
    horizontal.push_back(sum_horizontal / kSteps);
  }
  auto mean = [](const std::vector<double>& v) { return std::accumulate(v.begin(), v.end(), 0.0) / v.size(); };
  auto share = [](const std::vector<double>& v, double lo, double hi) {
    return static_cast<double>(std::count_if(v.begin(), v.end(), [&](double x) { return x >= lo && x <= hi; })) /
           v.size();
  };
  int both = 0;
  for (int k = 0; k < kDrives; ++k) {
    both += heading[k] >= 0.5 && heading[k] <= 1.5 && horizontal[k] >= 1.0 && horizontal[k] <= 3.0;
  }
  std::vector<double> h = heading, z = horizontal;
  std::sort(h.begin(), h.end());
  std::sort(z.begin(), z.end());
  std::printf("%d drives of 500 m, the truth drawn from the model: heading NEES mean %.2f (per drive %.2f to %.2f, "
              "10th-90th percentile %.2f-%.2f, %.0f %% in 0.5-1.5); horizontal mean %.2f (%.2f to %.2f, %.2f-%.2f, "
              "%.0f %% in 1-3); %d %% within both\n",
              kDrives, mean(heading), h.front(), h.back(), h[kDrives / 10], h[kDrives * 9 / 10],
              100.0 * share(heading, 0.5, 1.5), mean(horizontal), z.front(), z.back(), z[kDrives / 10],
              z[kDrives * 9 / 10], 100.0 * share(horizontal, 1.0, 3.0), 100 * both / kDrives);
  // Honest over the drives: the heading's mean of means near 1, the position's near 2 (its
  // per-drive means are heavier-tailed: 2.45 over these 100 drives, 2.29 over 300).
  EXPECT_GT(mean(heading), 0.7);
  EXPECT_LT(mean(heading), 1.3);
  EXPECT_GT(mean(horizontal), 1.4);
  EXPECT_LT(mean(horizontal), 3.0);
  // And one drive is no verdict: a fifth of them or more fall outside either bound.
  EXPECT_LT(share(heading, 0.5, 1.5), 0.8);
  EXPECT_LT(share(horizontal, 1.0, 3.0), 0.8);
}

// A rest's bias measurement survives the next VO update that spans the rest. The update
// clones its `from`, taken before the rest; the rest's measurement now reaches the history
// too (before, the update restored the bias sigma of `from`: 3 deg/h here, the prior).
TEST(GyroBias, ARestsBiasMeasurementSurvivesTheVoUpdateThatSpansIt) {
  PoseEstimator est(MerGyro());
  DriftingDrive drive = MerGyroDrive();
  drive.vo_yaw_sigma = 1.0;  // VO says nothing about yaw: only the rest measures the bias
  drive.Start(est);
  drive.Step(est);
  drive.Park(est, 600.0);
  const double after_rest = est.gyro_bias_sigma_rad_per_s();
  EXPECT_LT(after_rest, 0.5 * kDegPerHour);
  drive.Step(est);  // its VO update's `from` is the capture before the rest
  EXPECT_LT(est.gyro_bias_sigma_rad_per_s(), 1.01 * after_rest);
}
