#include "sequence/stepping.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

using namespace rover::sequence;
using rover::geometry::PoseFromXyzRpy;

namespace {
constexpr double kDeg = std::numbers::pi / 180.0;
}

TEST(Stepping, DrivesSplitIntoEqualStepsNoLongerThanTheStepLength) {
  auto steps = SplitArc(2.34, 0.0, 0.60, 18 * kDeg);
  ASSERT_EQ(steps.size(), 4u);
  for (const auto& s : steps) EXPECT_NEAR(s.distance_m, 0.585, 1e-12);
  EXPECT_EQ(SplitArc(1.2, 0.0, 0.6, 18 * kDeg).size(), 2u);  // exact multiple: no extra step
  auto back = SplitArc(-1.0, 0.0, 0.35, 18 * kDeg);
  ASSERT_EQ(back.size(), 3u);
  EXPECT_NEAR(back[0].distance_m, -1.0 / 3.0, 1e-12);
  EXPECT_TRUE(SplitArc(0.0, 0.0, 0.6, 1.0).empty());
  EXPECT_THROW(SplitArc(1.0, 0.0, 0.0, 1.0), std::invalid_argument);
}

TEST(Stepping, ArcStepsAlsoRespectTheMaxTurnPerStep) {
  // 1.5 m on a 1 m radius turns 85.9 deg: 5 steps of 18 deg or less, not 3 of 0.5 m.
  auto steps = SplitArc(1.5, 1.0, 0.6, 18 * kDeg);
  ASSERT_EQ(steps.size(), 5u);
  for (const auto& s : steps) EXPECT_LE(std::abs(s.HeadingChange()), 18 * kDeg + 1e-12);
  auto turns = SplitTurn(-40 * kDeg, 18 * kDeg);
  ASSERT_EQ(turns.size(), 3u);
  EXPECT_NEAR(turns[0].turn_rad, -40.0 / 3.0 * kDeg, 1e-12);
}

TEST(Stepping, TurnToTakesTheShortestWay) {
  EXPECT_NEAR(ShortestTurn(170 * kDeg, -170 * kDeg), 20 * kDeg, 1e-12);
  EXPECT_NEAR(ShortestTurn(-20.4 * kDeg, 90 * kDeg), 110.4 * kDeg, 1e-12);
  EXPECT_NEAR(ShortestTurn(0, -100 * kDeg), -100 * kDeg, 1e-12);
}

TEST(Stepping, EndOfStepFollowsTheFrameConventions) {
  // Facing east (yaw +90 deg), 2 m forward goes +Y (east).
  PlanePose p = EndOfStep({1, 1, 90 * kDeg}, {PlannedStep::Kind::kArc, 2.0, 0.0, 0.0});
  EXPECT_NEAR(p.x, 1.0, 1e-12);
  EXPECT_NEAR(p.y, 3.0, 1e-12);
  // A quarter circle to the right (radius 2) from north ends 2 m north, 2 m east, facing east.
  p = EndOfStep({0, 0, 0}, {PlannedStep::Kind::kArc, std::numbers::pi, 0.5, 0.0});
  EXPECT_NEAR(p.x, 2.0, 1e-12);
  EXPECT_NEAR(p.y, 2.0, 1e-12);
  EXPECT_NEAR(p.yaw, 90 * kDeg, 1e-12);
  // Negative radius curves left.
  p = EndOfStep({0, 0, 0}, {PlannedStep::Kind::kArc, std::numbers::pi, -0.5, 0.0});
  EXPECT_NEAR(p.y, -2.0, 1e-12);
}

TEST(Stepping, MeasureStepGivesSlipAndIgnoresSlopeGeometry) {
  const PlannedStep step{PlannedStep::Kind::kArc, 0.6, 0.0, 0.0};
  // Flat, heading east, moved 0.33 m of 0.6 m: 45 % slip.
  auto m = MeasureStep(PoseFromXyzRpy(0, 0, 0, 0, 0, 90 * kDeg), PoseFromXyzRpy(0, 0.33, 0, 0, 0, 90 * kDeg), step);
  EXPECT_NEAR(m.estimated_distance_m, 0.33, 1e-12);
  EXPECT_NEAR(m.slip_pct, 45.0, 1e-9);
  // Up a 25 deg slope (nose up, Z down): the full 0.6 m along the ground is no slip, although
  // the horizontal motion is only 0.544 m.
  const double pitch = 25 * kDeg;
  m = MeasureStep(PoseFromXyzRpy(0, 0, 0, 0, pitch, 0),
                  PoseFromXyzRpy(0.6 * std::cos(pitch), 0, -0.6 * std::sin(pitch), 0, pitch, 0), step);
  EXPECT_NEAR(m.slip_pct, 0.0, 1e-9);
  // Sliding back: past 100 %.
  m = MeasureStep(PoseFromXyzRpy(0, 0, 0, 0, 0, 0), PoseFromXyzRpy(-0.1, 0, 0, 0, 0, 0), step);
  EXPECT_NEAR(m.slip_pct, 100.0 * (1 + 0.1 / 0.6), 1e-9);
  // An arc measured along its chord.
  const PlannedStep arc{PlannedStep::Kind::kArc, 0.5, 1.0 / 3.0, 0.0};
  const PlanePose end = EndOfStep({0, 0, 0}, arc);
  m = MeasureStep(PoseFromXyzRpy(0, 0, 0, 0, 0, 0), PoseFromXyzRpy(end.x, end.y, 0, 0, 0, end.yaw), arc);
  EXPECT_NEAR(m.estimated_distance_m, 0.5, 1e-9);
  EXPECT_NEAR(m.estimated_turn_rad, 0.5 / 3.0, 1e-9);
}

TEST(Stepping, SteerTowardTurnsThenDrivesAndStopsInsideTheDisc) {
  const Eigen::Vector2d goal(0, 5);  // due east
  auto d = SteerToward({0, 0, 0}, goal, 0.3, 0.6, 18 * kDeg, 10 * kDeg);
  ASSERT_FALSE(d.arrived);
  EXPECT_EQ(d.step.kind, PlannedStep::Kind::kTurn);
  EXPECT_NEAR(d.step.turn_rad, 18 * kDeg, 1e-12);
  d = SteerToward({0, 0, 85 * kDeg}, goal, 0.3, 0.6, 18 * kDeg, 10 * kDeg);
  EXPECT_EQ(d.step.kind, PlannedStep::Kind::kArc);
  EXPECT_NEAR(d.step.distance_m, 0.6, 1e-12);
  d = SteerToward({0, 4.6, 90 * kDeg}, goal, 0.3, 0.6, 18 * kDeg, 10 * kDeg);
  EXPECT_NEAR(d.step.distance_m, 0.4, 1e-9);  // min(step, remaining)
  EXPECT_TRUE(SteerToward({0.1, 4.8, 0}, goal, 0.3, 0.6, 18 * kDeg, 10 * kDeg).arrived);
}

TEST(Stepping, DriftOfAStepIsItsErrorPerMetreAgainstTheCommandedEnd) {
  // 25 cm north commanded; the rover went 20 cm north and 5 cm east, turning 1 deg right.
  const PlannedStep step{PlannedStep::Kind::kArc, 0.25, 0.0, 0.0};
  const StepDrift d = DriftOfStep({1, 2, 0}, {1.20, 2.05, 1 * kDeg}, step);
  EXPECT_NEAR(d.error_per_m.x(), -0.2, 1e-12);
  EXPECT_NEAR(d.error_per_m.y(), 0.2, 1e-12);
  EXPECT_NEAR(d.yaw_error_per_m, 4 * kDeg, 1e-12);
  EXPECT_NEAR(d.along_pct, 20.0, 1e-9);
  EXPECT_NEAR(d.cross_pct, 20.0, 1e-9);
  // Facing east: 5 cm short and 5 cm to the left (north).
  const StepDrift e = DriftOfStep({0, 0, 90 * kDeg}, {0.05, 0.20, 90 * kDeg}, step);
  EXPECT_NEAR(e.along_pct, 20.0, 1e-9);
  EXPECT_NEAR(e.cross_pct, 20.0, 1e-9);
  // A turn has no drift.
  EXPECT_EQ(DriftOfStep({0, 0, 0}, {1, 1, 0}, {PlannedStep::Kind::kTurn, 0, 0, 0.3}).error_per_m.norm(), 0.0);
}

TEST(Stepping, PredictedDriftShiftsAndOutlinesTheSweptPath) {
  // Three steps drifting 5 cm per 25 cm toward +y, one of them 2 cm more.
  std::vector<StepDrift> recent(3);
  recent[0].error_per_m = {0.0, 0.20};
  recent[1].error_per_m = {0.0, 0.20};
  recent[2].error_per_m = {0.0, 0.32};
  const DriftPrediction p = PredictDrift(recent, -0.5);  // a 50 cm step (backward)
  EXPECT_NEAR(p.shift.x(), 0.0, 1e-12);
  EXPECT_NEAR(p.shift.y(), 0.24 * 0.5, 1e-12);
  EXPECT_NEAR(p.spread_m, 0.08 * 0.5, 1e-12);
  EXPECT_TRUE(p.Any());
  EXPECT_FALSE(PredictDrift({}, 0.5).Any());

  const std::vector<PlanePose> commanded = {{0, 0, 0}, {0.25, 0, 0}, {0.5, 0, 0}};
  const std::vector<PlanePose> path = PathWithDrift(commanded, p);
  ASSERT_EQ(path.size(), 6u);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(path[i].y, 0.0);
  EXPECT_NEAR(path[3].x, 0.5, 1e-12);   // the drifted end ...
  EXPECT_NEAR(path[3].y, 0.12, 1e-12);
  EXPECT_NEAR(path[4].y, 0.06, 1e-12);  // ... half-way ...
  EXPECT_NEAR(path[5].y, 0.0, 1e-12);   // ... back to the start
  EXPECT_EQ(PathWithDrift(commanded, DriftPrediction{}).size(), 3u);
}

TEST(Stepping, StepSigmaGrowthAndTilt) {
  EXPECT_NEAR(StepSigmaGrowth(0.0, 0.6, 0.02), 0.012, 1e-12);
  EXPECT_NEAR(StepSigmaGrowth(0.05, -0.6, 0.02), std::sqrt(0.05 * 0.05 + 0.012 * 0.012) - 0.05, 1e-12);
  EXPECT_NEAR(TiltAngle(rover::geometry::RotationFromRpy(0, 20 * kDeg, 1.0)), 20 * kDeg, 1e-12);
  EXPECT_NEAR(TiltAngle(rover::geometry::RotationFromRpy(-20 * kDeg, 0, -2.0)), 20 * kDeg, 1e-12);
  EXPECT_NEAR(TiltAngle(rover::geometry::RotationFromRpy(0.3, 0.4, 0)), std::acos(std::cos(0.3) * std::cos(0.4)), 1e-12);
}

TEST(ArrivalRadius, TheDiscLessTheMarginOrAFractionOfIt) {
  using rover::sequence::ArrivalRadius;
  const auto fits = ArrivalRadius(0.5, 0.05, 3.0, 0.25);
  EXPECT_TRUE(fits.fits);
  EXPECT_NEAR(fits.radius_m, 0.35, 1e-12);
  EXPECT_NEAR(fits.margin_m, 0.15, 1e-12);
  EXPECT_EQ(fits.Describe(), "inside the 0.50 m disc less 3 sigma (0.15 m)");
  const auto tight = ArrivalRadius(0.3, 0.1, 3.0, 0.25);
  EXPECT_FALSE(tight.fits);
  EXPECT_NEAR(tight.radius_m, 0.075, 1e-12);
  EXPECT_NE(tight.Describe().find("does not fit in the 0.30 m disc: stopped within 0.07"), std::string::npos)
      << tight.Describe();
  EXPECT_FALSE(ArrivalRadius(0.3, std::nan(""), 3.0, 0.25).fits);  // an unknown sigma never fits
  EXPECT_NEAR(ArrivalRadius(0.3, 0.0, 3.0, 0.25).radius_m, 0.3, 1e-12);
}
