#include "estimation/pose_estimator.hpp"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include <cmath>
#include <random>

using namespace rover::estimation;
using rover::geometry::Matrix6d;
using rover::geometry::Pose;
using rover::geometry::PoseFromXyzRpy;
using rover::geometry::RotationFromRpy;
using rover::geometry::RpyFromRotation;

namespace {

constexpr int64_t kSecond = 1000000;

Eigen::Quaterniond Q(double roll, double pitch, double yaw) {
  return Eigen::Quaterniond(RotationFromRpy(roll, pitch, yaw));
}

// Options with no drift or scale error, so known answers are exact.
EstimatorOptions Exact() {
  EstimatorOptions o;
  o.gyro_drift_rad_per_s = 0.0;
  o.gyro_random_walk_rad_per_sqrt_s = 0.0;
  o.gyro_bias_walk_rad_per_s_per_sqrt_s = 0.0;
  o.gyro_scale_sigma_fraction = 0.0;
  return o;
}

// Drives `distance` over [t0, t1] at 10 Hz (IMU then odometry each tick) at a fixed attitude.
// `start_distance` is the cumulative odometer reading at t0.
void Drive(PoseEstimator& est, int64_t t0, int64_t t1, double start_distance, double distance,
           const Eigen::Quaterniond& q) {
  const int ticks = static_cast<int>((t1 - t0) / (kSecond / 10));
  for (int i = 0; i <= ticks; ++i) {
    const int64_t t = t0 + (t1 - t0) * i / ticks;
    EXPECT_EQ(est.OnImu(t, q, Eigen::Vector3d::Zero()), InputResult::kAccepted);
    EXPECT_EQ(est.OnWheelOdometry(t, start_distance + distance * i / ticks),
              InputResult::kAccepted);
  }
}

VoUpdate Vo(int64_t from, int64_t to, const Pose& T, double sigma = 0.0) {
  VoUpdate u;
  u.from_utime = from;
  u.to_utime = to;
  u.T_from_to = T;
  u.covariance = Matrix6d::Identity() * sigma * sigma;
  u.from_frame_id = 7;
  u.to_frame_id = 8;
  return u;
}

double Yaw(const Pose& T) { return RpyFromRotation(T.linear()).z(); }

}  // namespace

TEST(PoseEstimator, StraightDriveAtKnownHeading) {
  PoseEstimator est(Exact());
  const double yaw = 30.0 * M_PI / 180.0;
  Drive(est, 0, 5 * kSecond, 0.0, 5.0, Q(0, 0, yaw));
  EXPECT_NEAR(est.pose().translation().x(), 5.0 * std::cos(yaw), 1e-9);
  EXPECT_NEAR(est.pose().translation().y(), 5.0 * std::sin(yaw), 1e-9);
  EXPECT_NEAR(est.pose().translation().z(), 0.0, 1e-9);
  EXPECT_NEAR(est.odometer_m(), 5.0, 1e-9);
  EXPECT_EQ(est.utime(), 5 * kSecond);
  EXPECT_EQ(est.source(), PoseSource::kWheelImu);
}

TEST(PoseEstimator, ClimbGainsElevationUpIsMinusZ) {
  PoseEstimator est(Exact());
  const double pitch = 0.2;  // nose up
  Drive(est, 0, 4 * kSecond, 0.0, 4.0, Q(0, pitch, 0));
  // Z is down: climbing 4 m at pitch p raises the rover by 4 sin p, i.e. z = -4 sin p.
  EXPECT_NEAR(est.pose().translation().z(), -4.0 * std::sin(pitch), 1e-9);
  EXPECT_NEAR(est.pose().translation().x(), 4.0 * std::cos(pitch), 1e-9);
}

TEST(PoseEstimator, ReversingRetracesAndCountsOdometer) {
  PoseEstimator est(Exact());
  Drive(est, 0, 2 * kSecond, 0.0, 2.0, Q(0, 0, 0));
  Drive(est, 2 * kSecond, 3 * kSecond, 2.0, -0.5, Q(0, 0, 0));
  EXPECT_NEAR(est.pose().translation().x(), 1.5, 1e-9);
  EXPECT_NEAR(est.odometer_m(), 2.5, 1e-9);
}

TEST(PoseEstimator, ArcFollowsMidpointHeading) {
  // A quarter circle of radius 2 m: heading turns from 0 to pi/2 over pi m of path.
  PoseEstimator est(Exact());
  const double radius = 2.0, length = M_PI;
  const int n = 400;
  for (int i = 0; i <= n; ++i) {
    const double s = length * i / n;
    const int64_t t = i * kSecond / 10;
    est.OnImu(t, Q(0, 0, s / radius), Eigen::Vector3d::Zero());
    est.OnWheelOdometry(t, s);
  }
  EXPECT_NEAR(est.pose().translation().x(), radius, 1e-4);
  EXPECT_NEAR(est.pose().translation().y(), radius, 1e-4);
}

TEST(PoseEstimator, CovarianceGrowsInProportionToDistance) {
  EstimatorOptions o = Exact();
  o.along_track_sigma_fraction = 0.02;
  o.cross_track_sigma_fraction = 0.03;
  o.vertical_sigma_fraction = 0.01;
  PoseEstimator coarse(o), fine(o);
  // Same 10 m north at two step sizes: sigma must not depend on the step size.
  for (int i = 0; i <= 10; ++i) coarse.OnWheelOdometry(i * kSecond, i * 1.0);
  for (int i = 0; i <= 1000; ++i) fine.OnWheelOdometry(i * kSecond / 100, i * 0.01);
  for (const PoseEstimator* e : {&coarse, &fine}) {
    const Matrix6d P = e->covariance();
    EXPECT_NEAR(std::sqrt(P(0, 0)), 0.2, 1e-9);   // along track (north)
    EXPECT_NEAR(std::sqrt(P(1, 1)), 0.3, 1e-9);   // cross track (east)
    EXPECT_NEAR(std::sqrt(P(2, 2)), 0.1, 1e-9);   // vertical
  }
  // Halfway the sigma is half.
  PoseEstimator half(o);
  for (int i = 0; i <= 5; ++i) half.OnWheelOdometry(i * kSecond, i * 1.0);
  EXPECT_NEAR(std::sqrt(half.covariance()(0, 0)), 0.1, 1e-9);
}

TEST(PoseEstimator, HeadingSigmaGrowsWithGyroDrift) {
  EstimatorOptions o = Exact();
  o.gyro_drift_rad_per_s = 3.0 * M_PI / 180.0 / 3600.0;  // 3 deg/hour
  PoseEstimator est(o);
  for (int i = 0; i <= 3600; ++i) est.OnImu(i * kSecond, Q(0, 0, 0), Eigen::Vector3d::Zero());
  EXPECT_NEAR(std::sqrt(est.covariance()(5, 5)), 3.0 * M_PI / 180.0, 1e-9);
  // Roll/pitch stay at the IMU's levelled sigma.
  EXPECT_NEAR(std::sqrt(est.covariance()(3, 3)), o.attitude_sigma_rad, 1e-12);
}

TEST(PoseEstimator, TurnInPlaceDoesNotMoveThePosition) {
  PoseEstimator est(Exact());
  est.OnImu(0, Q(0, 0, 0), Eigen::Vector3d::Zero());
  est.OnWheelOdometry(0, 0.0, false);
  est.OnImu(kSecond, Q(0, 0, 0.5), Eigen::Vector3d::Zero());
  est.OnWheelOdometry(kSecond, 0.3, true);  // wheels roll while turning
  EXPECT_NEAR(est.pose().translation().norm(), 0.0, 1e-12);
  EXPECT_NEAR(Yaw(est.pose()), 0.5, 1e-12);
  // The reference moved on: the next straight 1 m is 1 m, not 1.3 m.
  est.OnWheelOdometry(2 * kSecond, 1.3, false);
  EXPECT_NEAR(est.pose().translation().norm(), 1.0, 1e-9);
}

// A turn in place scrubs and, on a slope, creeps: the position stays where it was, and its
// sigma grows in both horizontal directions by the cross-track fraction (2 %) of what the
// wheels rolled (six wheels, 0.3 m each, either way).
TEST(PoseEstimator, TurnInPlaceGrowsThePositionSigmaByTheWheelsTravel) {
  PoseEstimator est(Exact());
  WheelOdometrySample odo;
  odo.wheel_distance_m.assign(6, 0.0);
  est.OnImu(0, Q(0, 0, 0), Eigen::Vector3d::Zero());
  ASSERT_EQ(est.OnWheelOdometry(odo), InputResult::kAccepted);
  odo.utime = kSecond;
  odo.turning_in_place = true;
  odo.wheel_distance_m = {-0.3, -0.3, -0.3, 0.3, 0.3, 0.3};
  est.OnImu(kSecond, Q(0, 0, 0.5), Eigen::Vector3d::Zero());
  ASSERT_EQ(est.OnWheelOdometry(odo), InputResult::kAccepted);
  EXPECT_NEAR(est.pose().translation().norm(), 0.0, 1e-12);
  const Matrix6d P = est.covariance();
  EXPECT_NEAR(std::sqrt(P(0, 0)), 0.02 * 0.3, 1e-12);
  EXPECT_NEAR(std::sqrt(P(1, 1)), 0.02 * 0.3, 1e-12);
  EXPECT_NEAR(P(2, 2), 0.0, 1e-15);
}

TEST(PoseEstimator, OutOfOrderAndNonFiniteInputsAreIgnored) {
  PoseEstimator est(Exact());
  est.OnWheelOdometry(2 * kSecond, 0.0);
  EXPECT_EQ(est.OnWheelOdometry(kSecond, 5.0), InputResult::kOutOfOrder);
  EXPECT_EQ(est.OnWheelOdometry(3 * kSecond, NAN), InputResult::kNotFinite);
  EXPECT_EQ(est.OnImu(3 * kSecond, Eigen::Quaterniond(0, 0, 0, 0), Eigen::Vector3d::Zero()),
            InputResult::kNotFinite);
  EXPECT_EQ(est.inputs_rejected(), 3);
  EXPECT_NEAR(est.pose().translation().norm(), 0.0, 1e-12);
}

TEST(PoseEstimator, SlipUpdateMovesThePoseByTheSlip) {
  // The wheels say 2 m, VO says 1.5 m: the estimate ends 0.5 m short of wheel odometry.
  PoseEstimator est(Exact());
  const double yaw = 0.7, pitch = 0.15;
  const Eigen::Quaterniond q = Q(0, pitch, yaw);
  Drive(est, 1 * kSecond, 3 * kSecond, 0.0, 2.0, q);
  const Eigen::Vector3d wheel = est.pose().translation();
  const Pose T_vo = PoseFromXyzRpy(1.5, 0, 0, 0, 0, 0);
  const VoUpdateResult r = est.ApplyVoUpdate(Vo(1 * kSecond, 3 * kSecond, T_vo));
  ASSERT_TRUE(r.applied()) << r.reason;
  const Eigen::Vector3d fwd = q.toRotationMatrix().col(0);
  EXPECT_NEAR((est.pose().translation() - 1.5 * fwd).norm(), 0.0, 1e-9);
  EXPECT_NEAR((r.position_correction_m + 0.5 * fwd).norm(), 0.0, 1e-9);
  EXPECT_NEAR((wheel - est.pose().translation()).norm(), 0.5, 1e-9);
  EXPECT_EQ(est.source(), PoseSource::kVo);
  EXPECT_EQ(est.last_vo_to_frame(), 8);
  EXPECT_NEAR(est.odometer_m(), 1.5, 1e-9);
}

TEST(PoseEstimator, SlipUpdateKeepsTheOdometryThatArrivedAfterTo) {
  PoseEstimator est(Exact());
  const Eigen::Quaterniond q = Q(0.05, -0.1, -2.0);
  Drive(est, 1 * kSecond, 3 * kSecond, 0.0, 2.0, q);
  Drive(est, 3 * kSecond, 4 * kSecond, 2.0, 1.0, q);  // the next step, before VO answers
  const VoUpdateResult r =
      est.ApplyVoUpdate(Vo(1 * kSecond, 3 * kSecond, PoseFromXyzRpy(1.5, 0, 0, 0, 0, 0)));
  ASSERT_TRUE(r.applied()) << r.reason;
  const Eigen::Vector3d fwd = q.toRotationMatrix().col(0);
  EXPECT_NEAR((est.pose().translation() - 2.5 * fwd).norm(), 0.0, 1e-9);
  EXPECT_EQ(est.utime(), 4 * kSecond);
  // History was corrected too: the pose at 3.5 s is 2.0 m along.
  const auto mid = est.PoseAt(3 * kSecond + kSecond / 2);
  ASSERT_TRUE(mid.has_value());
  EXPECT_NEAR((mid->translation() - 2.0 * fwd).norm(), 0.0, 1e-9);
  // Odometry continues from the corrected pose.
  Drive(est, 4 * kSecond, 5 * kSecond, 3.0, 1.0, q);
  EXPECT_NEAR((est.pose().translation() - 3.5 * fwd).norm(), 0.0, 1e-9);
}

TEST(PoseEstimator, ChainedUpdatesEachReplaceTheirInterval) {
  PoseEstimator est(Exact());
  const Eigen::Quaterniond q = Q(0, 0, 0);
  Drive(est, 0, 2 * kSecond, 0.0, 1.0, q);
  ASSERT_TRUE(est.ApplyVoUpdate(Vo(0, 2 * kSecond, PoseFromXyzRpy(0.8, 0, 0, 0, 0, 0))).applied());
  Drive(est, 2 * kSecond, 4 * kSecond, 1.0, 1.0, q);
  ASSERT_TRUE(
      est.ApplyVoUpdate(Vo(2 * kSecond, 4 * kSecond, PoseFromXyzRpy(0.6, 0.1, 0, 0, 0, 0)))
          .applied());
  EXPECT_NEAR(est.pose().translation().x(), 1.4, 1e-9);
  EXPECT_NEAR(est.pose().translation().y(), 0.1, 1e-9);
}

TEST(PoseEstimator, UpdateBetweenSamplesInterpolates) {
  PoseEstimator est(Exact());
  // Samples every 100 ms; `from` and `to` fall between samples.
  Drive(est, 0, 2 * kSecond, 0.0, 2.0, Q(0, 0, 0));
  const int64_t from = 250000, to = 1750000;  // wheel positions 0.25 and 1.75
  ASSERT_TRUE(est.ApplyVoUpdate(Vo(from, to, PoseFromXyzRpy(1.0, 0, 0, 0, 0, 0))).applied());
  // p(to) = 0.25 + 1.0; the 0.25 m driven after `to` is re-applied.
  EXPECT_NEAR(est.pose().translation().x(), 1.5, 1e-9);
}

TEST(PoseEstimator, PoseAtInterpolatesInTime) {
  PoseEstimator est(Exact());
  est.OnImu(0, Q(0, 0, 0.0), Eigen::Vector3d::Zero());
  est.OnWheelOdometry(0, 0.0);
  est.OnImu(kSecond, Q(0, 0, 0.4), Eigen::Vector3d::Zero());
  est.OnWheelOdometry(kSecond, 1.0);
  const auto quarter = est.PoseAt(kSecond / 4);
  ASSERT_TRUE(quarter.has_value());
  const Eigen::Vector3d end = est.pose().translation();
  EXPECT_NEAR((quarter->translation() - 0.25 * end).norm(), 0.0, 1e-12);
  EXPECT_NEAR(Yaw(*quarter), 0.1, 1e-9);
  EXPECT_FALSE(est.PoseAt(-1).has_value());
  EXPECT_FALSE(est.PoseAt(kSecond + 1).has_value());
}

TEST(PoseEstimator, ReplaceModeTakesTheVoHeading) {
  EstimatorOptions o = Exact();
  o.vo_heading = VoHeadingMode::kReplace;
  PoseEstimator est(o);
  Drive(est, 0, 2 * kSecond, 0.0, 1.0, Q(0, 0, 0));
  // VO: 1 m ahead and turned 0.1 rad right; the IMU saw no turn (e.g. a gyro glitch).
  const VoUpdateResult r =
      est.ApplyVoUpdate(Vo(0, 2 * kSecond, PoseFromXyzRpy(1.0, 0, 0, 0, 0, 0.1), 0.01));
  ASSERT_TRUE(r.applied()) << r.reason;
  EXPECT_NEAR(Yaw(est.pose()), 0.1, 1e-9);
  EXPECT_NEAR(r.yaw_correction_rad, 0.1, 1e-9);
  EXPECT_NEAR(est.yaw_offset_rad(), 0.1, 1e-9);
  // The IMU keeps reporting yaw 0; the estimate keeps the correction, and the next metre
  // goes along the corrected heading.
  Drive(est, 2 * kSecond, 3 * kSecond, 1.0, 1.0, Q(0, 0, 0));
  EXPECT_NEAR(Yaw(est.pose()), 0.1, 1e-9);
  EXPECT_NEAR(est.pose().translation().x(), 1.0 + std::cos(0.1), 1e-9);
  EXPECT_NEAR(est.pose().translation().y(), std::sin(0.1), 1e-9);
}

TEST(PoseEstimator, ReplaceModeRotatesTheMotionAfterTo) {
  EstimatorOptions o = Exact();
  o.vo_heading = VoHeadingMode::kReplace;
  PoseEstimator est(o);
  Drive(est, 0, 2 * kSecond, 0.0, 1.0, Q(0, 0, 0));
  Drive(est, 2 * kSecond, 3 * kSecond, 1.0, 1.0, Q(0, 0, 0));
  ASSERT_TRUE(est.ApplyVoUpdate(Vo(0, 2 * kSecond, PoseFromXyzRpy(1.0, 0, 0, 0, 0, -0.2)))
                  .applied());
  EXPECT_NEAR(est.pose().translation().x(), 1.0 + std::cos(-0.2), 1e-9);
  EXPECT_NEAR(est.pose().translation().y(), std::sin(-0.2), 1e-9);
  EXPECT_NEAR(Yaw(est.pose()), -0.2, 1e-9);
}

TEST(PoseEstimator, FuseModeWeightsByVariance) {
  EstimatorOptions o = Exact();
  o.vo_heading = VoHeadingMode::kFuse;
  o.gyro_drift_rad_per_s = 0.01;  // 2 s between captures: gyro sigma 0.02 rad
  PoseEstimator est(o);
  Drive(est, 0, 2 * kSecond, 0.0, 1.0, Q(0, 0, 0));
  VoUpdate u = Vo(0, 2 * kSecond, PoseFromXyzRpy(1.0, 0, 0, 0, 0, 0.1), 0.0);
  u.covariance(5, 5) = 0.02 * 0.02;  // as good as the gyro: the mean
  ASSERT_TRUE(est.ApplyVoUpdate(u).applied());
  EXPECT_NEAR(Yaw(est.pose()), 0.05, 1e-9);
  // Fused heading sigma: sqrt(0.02^2 / 2).
  EXPECT_NEAR(std::sqrt(est.covariance()(5, 5)), 0.02 / std::sqrt(2.0), 1e-9);
}

TEST(PoseEstimator, IgnoreModeKeepsImuHeading) {
  EstimatorOptions o = Exact();
  o.vo_heading = VoHeadingMode::kIgnore;
  PoseEstimator est(o);
  Drive(est, 0, 2 * kSecond, 0.0, 1.0, Q(0, 0, 0.3));
  ASSERT_TRUE(est.ApplyVoUpdate(Vo(0, 2 * kSecond, PoseFromXyzRpy(1.0, 0, 0, 0, 0, 0.1)))
                  .applied());
  EXPECT_NEAR(Yaw(est.pose()), 0.3, 1e-12);
}

TEST(PoseEstimator, CovarianceAfterUpdateReflectsVo) {
  EstimatorOptions o = Exact();
  o.along_track_sigma_fraction = 0.02;
  o.cross_track_sigma_fraction = 0.02;
  o.vertical_sigma_fraction = 0.02;
  // 10 m on the wheels, VO over it (9 m, 1 cm sigma), then one metre more on the wheels;
  // returns the along- and cross-track sigma at the end.
  auto sigma_after_next_metre = [](const EstimatorOptions& options) {
    PoseEstimator est(options);
    Drive(est, 0, 10 * kSecond, 0.0, 10.0, Q(0, 0, 0));
    EXPECT_NEAR(std::sqrt(est.covariance()(0, 0)), 0.2, 1e-9);
    // VO over the whole drive with 1 cm sigma replaces the 20 cm of wheel growth.
    EXPECT_TRUE(est.ApplyVoUpdate(Vo(0, 10 * kSecond, PoseFromXyzRpy(9, 0, 0, 0, 0, 0), 0.01)).applied());
    const Matrix6d P = est.covariance();
    EXPECT_NEAR(std::sqrt(P(0, 0)), 0.01, 1e-9);
    EXPECT_NEAR(std::sqrt(P(1, 1)), 0.01, 1e-9);
    Drive(est, 10 * kSecond, 11 * kSecond, 10.0, 1.0, Q(0, 0, 0));
    return Eigen::Vector2d(std::sqrt(est.covariance()(0, 0)), std::sqrt(est.covariance()(1, 1)));
  };
  // Another metre of wheels grows sigma linearly from there, at the slip VO just measured
  // along track (1 m short in 10: 10 %) and the configured 2 % across it.
  const Eigen::Vector2d slip = sigma_after_next_metre(o);
  EXPECT_NEAR(slip.x(), 0.01 + 0.10, 1e-9);
  EXPECT_NEAR(slip.y(), 0.01 + 0.02, 1e-9);
  // Without the slip memory, at the configured 2 % both ways.
  o.slip_memory_updates = 0;
  const Eigen::Vector2d fixed = sigma_after_next_metre(o);
  EXPECT_NEAR(fixed.x(), 0.01 + 0.02, 1e-9);
  EXPECT_NEAR(fixed.y(), 0.01 + 0.02, 1e-9);
}

// Ground that slipped keeps slipping: the wheels' sigma is the worst error VO measured over
// the last slip_memory_updates steps (along and across track), never under the configured
// one, and it falls back once steps on firm ground have pushed the slip out of memory.
TEST(PoseEstimator, SlipVoMeasuredSetsTheWheelsSigmaForTheNextSteps) {
  EstimatorOptions o = Exact();
  o.along_track_sigma_fraction = 0.02;
  o.cross_track_sigma_fraction = 0.02;
  o.slip_memory_updates = 3;
  PoseEstimator est(o);
  const double yaw = 0.6;
  const Eigen::Quaterniond q = Q(0, 0, yaw);
  int64_t t = 0;
  double odo = 0.0;
  // One metre a step; VO reports each step's motion in the rover frame at `from`.
  auto step = [&](double vo_forward, double vo_left) {
    Drive(est, t, t + kSecond, odo, 1.0, q);
    const VoUpdateResult r = est.ApplyVoUpdate(Vo(t, t + kSecond, PoseFromXyzRpy(vo_forward, vo_left, 0, 0, 0, 0)));
    ASSERT_TRUE(r.applied()) << r.reason;
    t += kSecond;
    odo += 1.0;
  };
  EXPECT_NEAR((est.wheel_sigma_fractions() - Eigen::Vector2d(0.02, 0.02)).norm(), 0.0, 1e-12);
  step(0.80, 0.05);  // 20 % short, 5 % to the left
  EXPECT_NEAR((est.wheel_sigma_fractions() - Eigen::Vector2d(0.20, 0.05)).norm(), 0.0, 1e-9);
  // The next metre on the wheels alone: sigma 0.20 m along the heading, 0.05 m across it.
  Drive(est, t, t + kSecond, odo, 1.0, q);
  const Eigen::Matrix2d P = est.covariance().topLeftCorner<2, 2>();
  const Eigen::Vector2d along(std::cos(yaw), std::sin(yaw)), across(-std::sin(yaw), std::cos(yaw));
  EXPECT_NEAR(std::sqrt(along.dot(P * along)), 0.20, 1e-9);
  EXPECT_NEAR(std::sqrt(across.dot(P * across)), 0.05, 1e-9);
  EXPECT_NEAR(along.dot(P * across), 0.0, 1e-9);
  ASSERT_TRUE(est.ApplyVoUpdate(Vo(t, t + kSecond, PoseFromXyzRpy(1.0, 0, 0, 0, 0, 0))).applied());
  t += kSecond;
  odo += 1.0;
  // Two steps more on firm ground: the slip is still among the last three.
  step(1.0, 0.0);
  EXPECT_NEAR(est.wheel_sigma_fractions().x(), 0.20, 1e-9);
  // The third pushes it out.
  step(1.0, 0.0);
  EXPECT_NEAR((est.wheel_sigma_fractions() - Eigen::Vector2d(0.02, 0.02)).norm(), 0.0, 1e-9);
  // A step shorter than slip_min_distance_m measures nothing.
  o.slip_min_distance_m = 0.5;
  PoseEstimator short_steps(o);
  Drive(short_steps, 0, kSecond, 0.0, 0.3, q);
  ASSERT_TRUE(short_steps.ApplyVoUpdate(Vo(0, kSecond, PoseFromXyzRpy(0.1, 0, 0, 0, 0, 0))).applied());
  EXPECT_NEAR((short_steps.wheel_sigma_fractions() - Eigen::Vector2d(0.02, 0.02)).norm(), 0.0, 1e-12);
  // Reset forgets the ground it measured.
  est.Reset(Pose::Identity(), t);
  step(0.5, 0.0);
  EXPECT_NEAR(est.wheel_sigma_fractions().x(), 0.5, 1e-9);
  est.Reset(Pose::Identity(), t + kSecond);
  EXPECT_NEAR(est.wheel_sigma_fractions().x(), 0.02, 1e-12);
}

TEST(PoseEstimator, CovarianceAfterPastUpdateAddsLaterGrowth) {
  EstimatorOptions o = Exact();
  o.along_track_sigma_fraction = 0.02;
  PoseEstimator est(o);
  Drive(est, 0, 5 * kSecond, 0.0, 5.0, Q(0, 0, 0));
  Drive(est, 5 * kSecond, 6 * kSecond, 5.0, 1.0, Q(0, 0, 0));
  ASSERT_TRUE(est.ApplyVoUpdate(Vo(0, 5 * kSecond, PoseFromXyzRpy(5, 0, 0, 0, 0, 0), 0.01))
                  .applied());
  // Wheel variance growth over the last metre: 0.12^2 - 0.10^2, on top of 0.01^2.
  EXPECT_NEAR(est.covariance()(0, 0), 0.01 * 0.01 + 0.12 * 0.12 - 0.10 * 0.10, 1e-12);
}

TEST(PoseEstimator, BadUpdatesAreRefusedWithAReason) {
  EstimatorOptions o = Exact();
  o.history_s = 10.0;
  o.vo_future_tolerance_s = 0.5;
  PoseEstimator est(o);
  const Pose T = PoseFromXyzRpy(1, 0, 0, 0, 0, 0);
  EXPECT_EQ(est.ApplyVoUpdate(Vo(0, kSecond, T)).status, VoUpdateStatus::kNoHistory);

  Drive(est, 0, 30 * kSecond, 0.0, 3.0, Q(0, 0, 0));
  const Pose before = est.pose();

  VoUpdateResult r = est.ApplyVoUpdate(Vo(kSecond, 25 * kSecond, T));
  EXPECT_EQ(r.status, VoUpdateStatus::kFromTooOld);
  EXPECT_NE(r.reason.find("older than the pose history"), std::string::npos) << r.reason;

  EXPECT_EQ(est.ApplyVoUpdate(Vo(25 * kSecond, 25 * kSecond, T)).status,
            VoUpdateStatus::kToNotAfterFrom);
  EXPECT_EQ(est.ApplyVoUpdate(Vo(26 * kSecond, 25 * kSecond, T)).status,
            VoUpdateStatus::kToNotAfterFrom);
  EXPECT_EQ(est.ApplyVoUpdate(Vo(31 * kSecond, 32 * kSecond, T)).status,
            VoUpdateStatus::kFromInFuture);
  r = est.ApplyVoUpdate(Vo(25 * kSecond, 31 * kSecond, T));
  EXPECT_EQ(r.status, VoUpdateStatus::kToInFuture);
  EXPECT_NE(r.reason.find("after the latest input"), std::string::npos) << r.reason;

  Pose nan_pose = T;
  nan_pose.translation().x() = NAN;
  EXPECT_EQ(est.ApplyVoUpdate(Vo(25 * kSecond, 29 * kSecond, nan_pose)).status,
            VoUpdateStatus::kNotFinite);
  VoUpdate inf_cov = Vo(25 * kSecond, 29 * kSecond, T);
  inf_cov.covariance(2, 2) = INFINITY;
  EXPECT_EQ(est.ApplyVoUpdate(inf_cov).status, VoUpdateStatus::kNotFinite);

  Pose scaled = T;
  scaled.linear() *= 1.1;
  EXPECT_EQ(est.ApplyVoUpdate(Vo(25 * kSecond, 29 * kSecond, scaled)).status,
            VoUpdateStatus::kBadRotation);
  VoUpdate neg = Vo(25 * kSecond, 29 * kSecond, T);
  neg.covariance(0, 0) = -1e-4;
  EXPECT_EQ(est.ApplyVoUpdate(neg).status, VoUpdateStatus::kBadCovariance);
  VoUpdate asym = Vo(25 * kSecond, 29 * kSecond, T, 0.01);
  asym.covariance(0, 1) = 1e-5;
  EXPECT_EQ(est.ApplyVoUpdate(asym).status, VoUpdateStatus::kBadCovariance);

  // Nothing moved, and the source is still wheel+IMU.
  EXPECT_TRUE(est.pose().isApprox(before, 0.0));
  EXPECT_EQ(est.source(), PoseSource::kWheelImu);
  EXPECT_STREQ(ToString(VoUpdateStatus::kFromTooOld), "from_too_old");
}

TEST(PoseEstimator, UpdateSlightlyAfterLatestInputHoldsThePose) {
  PoseEstimator est(Exact());
  Drive(est, 0, 2 * kSecond, 0.0, 2.0, Q(0, 0, 0));
  const int64_t to = 2 * kSecond + 300000;  // capture stamped 0.3 s after the last input
  ASSERT_TRUE(est.ApplyVoUpdate(Vo(0, to, PoseFromXyzRpy(1.8, 0, 0, 0, 0, 0))).applied());
  EXPECT_NEAR(est.pose().translation().x(), 1.8, 1e-9);
  // The clock did not jump: inputs stamped before `to` still count.
  EXPECT_EQ(est.utime(), 2 * kSecond);
  EXPECT_EQ(est.OnWheelOdometry(to - 1, 2.0), InputResult::kAccepted);
  EXPECT_EQ(est.OnWheelOdometry(to + kSecond, 2.5), InputResult::kAccepted);
  EXPECT_NEAR(est.pose().translation().x(), 2.3, 1e-9);
  // Both captures after the latest input (the rover standing): still applied.
  ASSERT_TRUE(est.ApplyVoUpdate(Vo(to + kSecond + 100, to + kSecond + 200,
                                   PoseFromXyzRpy(0.05, 0, 0, 0, 0, 0)))
                  .applied());
  EXPECT_NEAR(est.pose().translation().x(), 2.35, 1e-9);
}

TEST(PoseEstimator, ResetSetsPoseAndHeadingOffset) {
  PoseEstimator est(Exact());
  est.OnImu(0, Q(0, 0, 0.3), Eigen::Vector3d::Zero());
  est.Reset(PoseFromXyzRpy(10, 20, -1, 0, 0, 1.0), kSecond);
  EXPECT_NEAR(est.pose().translation().x(), 10.0, 1e-12);
  est.OnImu(2 * kSecond, Q(0.05, 0.02, 0.4), Eigen::Vector3d::Zero());
  const Eigen::Vector3d rpy = RpyFromRotation(est.pose().linear());
  EXPECT_NEAR(rpy.x(), 0.05, 1e-9);  // roll/pitch from the IMU
  EXPECT_NEAR(rpy.y(), 0.02, 1e-9);
  EXPECT_NEAR(rpy.z(), 1.1, 1e-9);   // IMU yaw + (1.0 - 0.3)
  EXPECT_EQ(est.ApplyVoUpdate(Vo(0, 2 * kSecond, Pose::Identity())).status,
            VoUpdateStatus::kFromTooOld);
}

TEST(PoseEstimator, ResetBeforeTheFirstImuSampleAppliesItsHeading) {
  PoseEstimator est(Exact());
  est.Reset(PoseFromXyzRpy(1, 2, 0, 0, 0, -0.5), 0);
  est.OnImu(kSecond, Q(0, 0, 0.2), Eigen::Vector3d::Zero());
  EXPECT_NEAR(Yaw(est.pose()), -0.5, 1e-9);
}

TEST(PoseEstimator, NewSiteStartsAtTheOriginAndVoStillSpansIt) {
  EstimatorOptions o = Exact();
  o.along_track_sigma_fraction = 0.02;
  PoseEstimator est(o);
  Drive(est, 0, 2 * kSecond, 0.0, 2.0, Q(0, 0, 0.25));
  est.NewSite();
  EXPECT_EQ(est.site_index(), 1);
  EXPECT_NEAR(est.pose().translation().norm(), 0.0, 1e-12);
  EXPECT_NEAR(Yaw(est.pose()), 0.25, 1e-12);
  EXPECT_NEAR(est.covariance()(0, 0), 0.0, 1e-12);
  Drive(est, 2 * kSecond, 3 * kSecond, 2.0, 1.0, Q(0, 0, 0.25));
  const Eigen::Vector3d fwd = Q(0, 0, 0.25).toRotationMatrix().col(0);
  EXPECT_NEAR((est.pose().translation() - fwd).norm(), 0.0, 1e-9);
  // A VO update from before the new site: the old start is at -2 fwd in the new frame.
  ASSERT_TRUE(est.ApplyVoUpdate(Vo(0, 3 * kSecond, PoseFromXyzRpy(2.5, 0, 0, 0, 0, 0)))
                  .applied());
  EXPECT_NEAR((est.pose().translation() - 0.5 * fwd).norm(), 0.0, 1e-9);
  est.NewSite(7);
  EXPECT_EQ(est.site_index(), 7);
  EXPECT_EQ(est.Estimate().site_index, 7);
}

TEST(PoseEstimator, SameInputsGiveIdenticalPoses) {
  auto run = [] {
    EstimatorOptions o;  // defaults, with drift
    PoseEstimator est(o);
    for (int i = 0; i <= 500; ++i) {
      const int64_t t = i * kSecond / 8;
      est.OnImu(t, Q(0.01 * std::sin(i * 0.1), 0.1, 0.002 * i), Eigen::Vector3d(0, 0, 0.016));
      est.OnWheelOdometry(t, 0.005 * i);
      if (i % 100 == 50) {
        est.ApplyVoUpdate(Vo(t - 40 * kSecond / 8, t, PoseFromXyzRpy(0.19, 0.01, 0, 0, 0, 0.07),
                             0.005));
      }
    }
    return est.Estimate();
  };
  const PoseEstimate a = run(), b = run();
  EXPECT_TRUE(a.T_site_rover.matrix() == b.T_site_rover.matrix());
  EXPECT_TRUE(a.covariance == b.covariance);
  EXPECT_EQ(a.odometer_m, b.odometer_m);
}

TEST(PoseEstimator, HistoryIsBounded) {
  EstimatorOptions o = Exact();
  o.history_s = 5.0;
  o.history_max_samples = 1000;
  PoseEstimator est(o);
  Drive(est, 0, 60 * kSecond, 0.0, 6.0, Q(0, 0, 0));
  EXPECT_LE(est.history_size(), 52u);
  EXPECT_FALSE(est.PoseAt(50 * kSecond).has_value());
  EXPECT_TRUE(est.PoseAt(56 * kSecond).has_value());
}

TEST(PoseEstimator, InvalidOptionsThrowNamingTheField) {
  EstimatorOptions o;
  o.along_track_sigma_fraction = -0.1;
  try {
    PoseEstimator est(o);
    FAIL() << "expected a throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("along_track_sigma_fraction"), std::string::npos);
  }
}

namespace {

// The rover parked for `seconds` from `t0` at heading 0: wheels still (odometry at 10 Hz,
// the same reading), the IMU at 10 Hz with its yaw drifting by `bias` (rad/s) plus angle
// random walk `arw` (seeded), and its rate reading the bias. Returns the end time.
int64_t Park(PoseEstimator& est, int64_t t0, double seconds, double distance, double bias, double arw,
             unsigned seed, double* imu_yaw_error) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal;
  const int ticks = static_cast<int>(seconds * 10);
  for (int i = 1; i <= ticks; ++i) {
    const int64_t t = t0 + i * (kSecond / 10);
    *imu_yaw_error += bias * 0.1 + arw * std::sqrt(0.1) * normal(rng);
    est.OnImu(t, Q(0, 0, *imu_yaw_error), Eigen::Vector3d(0, 0, bias));
    est.OnWheelOdometry(t, distance);
  }
  return t0 + ticks * (kSecond / 10);
}

}  // namespace

// A night parked: the wheels stand and the gyro is quiet, so the heading is held against
// the IMU's drift (3 deg/h here, 36 deg over 12 h), its sigma does not grow, the position
// stays, the drift measures the gyro's bias, and the history stays two samples long.
TEST(PoseEstimator, ParkedForANightTheHeadingIsHeldAndTheBiasLearned) {
  EstimatorOptions o;  // the defaults: 3 deg/h drift sigma, zero-velocity updates on
  const double bias = 3.0 * M_PI / 180.0 / 3600.0;
  const double arw = o.gyro_random_walk_rad_per_sqrt_s;
  PoseEstimator est(o);
  double imu_yaw = 0.0;
  Drive(est, 0, 10 * kSecond, 0.0, 1.0, Q(0, 0, 0));
  // The first second parked: at rest once the wheels have stood zupt_settle_s.
  const int64_t settled = Park(est, 10 * kSecond, 1.0, 1.0, bias, arw, 10, &imu_yaw);
  ASSERT_TRUE(est.at_rest());
  const Pose before = est.pose();
  const double heading_sigma_before = std::sqrt(est.covariance()(5, 5));
  const std::size_t history_before = est.history_size();
  const int64_t end = Park(est, settled, 12 * 3600.0, 1.0, bias, arw, 11, &imu_yaw);
  EXPECT_TRUE(est.at_rest());
  EXPECT_GT(imu_yaw * 180 / M_PI, 30.0);  // the IMU turned 36 deg in its own yaw
  EXPECT_NEAR(Yaw(est.pose()), Yaw(before), 1e-9);
  EXPECT_LT((est.pose().translation() - before.translation()).norm(), 1e-12);
  EXPECT_NEAR(std::sqrt(est.covariance()(5, 5)), heading_sigma_before, 1e-9);
  // The bias, measured over 12 h of rest, and honest. Its sigma settles where the bias's
  // own walk and the gyro's noise balance (walk x arw: 0.27 deg/h here), far under the
  // 3 deg/h it started from.
  EXPECT_LT(est.gyro_bias_sigma_rad_per_s(), 0.5 * M_PI / 180.0 / 3600.0);
  EXPECT_LT(std::abs(est.gyro_bias_rad_per_s() - bias), 3.0 * est.gyro_bias_sigma_rad_per_s() + 1e-9);
  EXPECT_LE(est.history_size(), history_before + 3);

  // A VO update from a capture before the night to one after a metre's drive is applied,
  // not refused for age.
  Drive(est, end, end + 10 * kSecond, 1.0, 2.0, Q(0, 0, imu_yaw));
  const auto r = est.ApplyVoUpdate(Vo(settled, end + 10 * kSecond, PoseFromXyzRpy(1.0, 0, 0, 0, 0, 0), 0.01));
  EXPECT_TRUE(r.applied()) << r.reason;
}

// The same night with zero-velocity updates off: the heading follows the IMU's drift, and
// its sigma grows (what the held heading is measured against).
TEST(PoseEstimator, ParkedWithoutZeroVelocityUpdatesTheHeadingDrifts) {
  EstimatorOptions o;
  o.zero_velocity_updates = false;
  const double bias = 3.0 * M_PI / 180.0 / 3600.0;
  PoseEstimator est(o);
  double imu_yaw = 0.0;
  Drive(est, 0, 10 * kSecond, 0.0, 1.0, Q(0, 0, 0));
  const double sigma_before = std::sqrt(est.covariance()(5, 5));
  Park(est, 10 * kSecond, 3600.0, 1.0, bias, 0.0, 11, &imu_yaw);
  EXPECT_FALSE(est.at_rest());
  EXPECT_NEAR(Yaw(est.pose()) * 180 / M_PI, 3.0, 0.01);
  EXPECT_GT(std::sqrt(est.covariance()(5, 5)), sigma_before + 2.0 * M_PI / 180.0);
}

// A rover that turns in place, or whose gyro reads a turn, is not at rest.
TEST(PoseEstimator, AQuietGyroAndStillWheelsAreBothNeededForRest) {
  PoseEstimator est;
  Drive(est, 0, 5 * kSecond, 0.0, 0.5, Q(0, 0, 0));
  for (int i = 1; i <= 20; ++i) {
    const int64_t t = 5 * kSecond + i * (kSecond / 10);
    est.OnImu(t, Q(0, 0, 0.01 * i), Eigen::Vector3d(0, 0, 0.1));  // turning 0.1 rad/s
    est.OnWheelOdometry(t, 0.5);
  }
  EXPECT_FALSE(est.at_rest());
  EXPECT_NEAR(Yaw(est.pose()), 0.2, 1e-9);  // the turn is followed
  for (int i = 21; i <= 40; ++i) {
    const int64_t t = 5 * kSecond + i * (kSecond / 10);
    est.OnImu(t, Q(0, 0, 0.2), Eigen::Vector3d::Zero());
    est.OnWheelOdometry(t, 0.5);
  }
  EXPECT_TRUE(est.at_rest());
}

// The gyro check (VO's yaw change against the gyro's) corrects the heading and the bias,
// never the position: after a drive whose heading error has swung the path (so position,
// heading and bias are correlated), an update whose yaw disagrees with the gyro's puts the
// rover exactly where VO's translation from `from` says, turns the heading, and leaves a
// covariance that is symmetric and positive semi-definite.
TEST(PoseEstimator, TheGyroCheckCorrectsNoPosition) {
  EstimatorOptions o = Exact();
  o.gyro_drift_rad_per_s = 3.0 * M_PI / 180.0 / 3600.0;
  o.gyro_random_walk_rad_per_sqrt_s = 0.15 * M_PI / 180.0 / 60.0;
  o.initial_yaw_sigma_rad = 0.01;
  PoseEstimator est(o);
  Drive(est, 0, 20 * kSecond, 0.0, 1.0, Q(0, 0, 0));
  Drive(est, 20 * kSecond, 40 * kSecond, 1.0, 1.0, Q(0, 0, 0));
  const Matrix6d before = est.covariance();
  ASSERT_GT(std::abs(before(1, 5)), 1e-6);  // the heading's swing of the path
  // VO: 1 m ahead and 0.2 deg of yaw the gyro did not see, over the second step.
  const VoUpdate u =
      Vo(20 * kSecond, 40 * kSecond, PoseFromXyzRpy(1.0, 0.0, 0.0, 0, 0, 0.2 * M_PI / 180.0), 0.001);
  const Pose from = *est.PoseAt(20 * kSecond);
  const VoUpdateResult r = est.ApplyVoUpdate(u);
  ASSERT_TRUE(r.applied()) << r.reason;
  const Eigen::Vector3d expected = from.translation() + from.linear() * Eigen::Vector3d(1.0, 0.0, 0.0);
  EXPECT_NEAR((est.pose().translation() - expected).norm(), 0.0, 1e-12);
  EXPECT_GT(r.yaw_correction_rad, 0.0);  // toward VO's yaw: the gyro's bias took some
  EXPECT_LT(r.yaw_correction_rad, 0.2 * M_PI / 180.0);
  const Matrix6d P = est.covariance();
  EXPECT_NEAR((P - P.transpose()).cwiseAbs().maxCoeff(), 0.0, 1e-15);
  Eigen::SelfAdjointEigenSolver<Matrix6d> es(P);
  EXPECT_GE(es.eigenvalues().minCoeff(), -1e-15);
}

namespace {

// One 10 Hz tick at `t` (the IMU first, then the odometry at half its rate, on even ticks):
// the rover at yaw `yaw` (rate `rate` rad/s) with `distance` on its odometer.
void HalfRateOdometryTick(PoseEstimator& est, int i, double yaw, double rate, double distance) {
  const int64_t t = i * (kSecond / 10);
  ASSERT_EQ(est.OnImu(t, Q(0, 0, yaw), Eigen::Vector3d(0, 0, rate)), InputResult::kAccepted);
  if (i % 2 == 0) {
    ASSERT_EQ(est.OnWheelOdometry(t, distance), InputResult::kAccepted);
  }
}

}  // namespace

// An arc slower than the rest's gyro limit (0.3 deg/s against 0.5) starting from rest: the
// IMU samples after the last odometry look like rest, but the next odometry shows the wheels
// turning, so their yaw is the arc's. The heading ends where the IMU says, to the bit, and the
// history holds the arc's first instants as turned (a VO update may clone from them).
TEST(PoseEstimator, TheStartOfAnArcSlowerThanTheRestLimitIsKept) {
  const double rate = 0.3 * M_PI / 180.0;
  PoseEstimator est(Exact());
  for (int i = 0; i <= 100; ++i) HalfRateOdometryTick(est, i, 0.0, 0.0, 0.0);  // 10 s parked
  ASSERT_TRUE(est.at_rest());
  for (int i = 101; i <= 200; ++i) {  // the arc, from t = 10 s
    const double s = (i - 100) * 0.1;
    HalfRateOdometryTick(est, i, rate * s, rate, 0.04 * s);
  }
  EXPECT_FALSE(est.at_rest());
  EXPECT_NEAR(Yaw(est.pose()), rate * 10.0, 1e-12);
  const auto first = est.PoseAt(10 * kSecond + kSecond / 10);
  ASSERT_TRUE(first.has_value());
  EXPECT_NEAR(Yaw(*first), rate * 0.1, 1e-12);
}

// Parked for an hour with the odometry at half the IMU's rate (half the IMU samples newer than
// the last odometry, held until it confirms them): the heading is still held against a drift
// of 3 deg/h, the drift still measures the bias, and the history stays a few samples long.
TEST(PoseEstimator, ParkedWithOdometryAtHalfTheImuRateTheHeadingIsHeld) {
  EstimatorOptions o;
  const double bias = 3.0 * M_PI / 180.0 / 3600.0;
  PoseEstimator est(o);
  for (int i = 0; i <= 20; ++i) HalfRateOdometryTick(est, i, 0.0, 0.0, 0.0);
  ASSERT_TRUE(est.at_rest());
  const std::size_t history_before = est.history_size();
  const int ticks = 36000;
  for (int i = 21; i <= 20 + ticks; ++i) HalfRateOdometryTick(est, i, bias * (i - 20) * 0.1, bias, 0.0);
  EXPECT_TRUE(est.at_rest());
  EXPECT_NEAR(Yaw(est.pose()), 0.0, 1e-9);
  EXPECT_NEAR(est.gyro_bias_rad_per_s(), bias, 0.05 * bias);
  EXPECT_LE(est.history_size(), history_before + 3);
}
