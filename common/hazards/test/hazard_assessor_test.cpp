#include "hazards/hazard_assessor.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace rover::hazards;
using rover::config::ConfigError;
using rover::config::ConfigNode;

namespace {

constexpr int64_t kSecond = 1000000;
constexpr double kDeg = M_PI / 180.0;

// MER footprint (1.6 x 2.3 m), k = 3, a rock 3 m north: clearance 3 - 0.8 - 0.5 = 1.7 m.
HazardOptions RockAhead() {
  HazardOptions o;
  o.zones = {KeepOutZone::Circle("rock", 3.0, 0.0, 0.5)};
  return o;
}

PoseSnapshot At(int64_t utime, double sigma = 0.0, double roll = 0.0, double pitch = 0.0) {
  PoseSnapshot p;
  p.utime = utime;
  p.position_sigma_m = sigma;
  p.roll = roll;
  p.pitch = pitch;
  return p;
}

}  // namespace

TEST(Tilt, LimitsAreStrict) {
  TiltLimits limits;
  limits.roll_limit_rad = 20 * kDeg;
  limits.pitch_limit_rad = 25 * kDeg;
  EXPECT_FALSE(CheckTilt(19.9 * kDeg, -24.9 * kDeg, limits).violated);
  EXPECT_FALSE(CheckTilt(20 * kDeg, 25 * kDeg, limits).violated);
  const TiltCheck roll = CheckTilt(-20.5 * kDeg, 0.0, limits);
  EXPECT_TRUE(roll.violated);
  EXPECT_NE(roll.detail.find("roll -20.500 deg"), std::string::npos) << roll.detail;
  const TiltCheck pitch = CheckTilt(0.0, 26 * kDeg, limits);
  EXPECT_TRUE(pitch.violated);
  EXPECT_NE(pitch.detail.find("pitch"), std::string::npos);
  EXPECT_TRUE(CheckTilt(NAN, 0.0, limits).violated);
}

TEST(HorizontalSigma, WorstDirection) {
  rover::geometry::Matrix6d P = rover::geometry::Matrix6d::Zero();
  P(0, 0) = 0.04;
  P(1, 1) = 0.01;
  EXPECT_NEAR(HorizontalSigma(P), 0.2, 1e-12);
  // [[2, 1], [1, 2]] has eigenvalues 1 and 3.
  P(0, 0) = 2;
  P(1, 1) = 2;
  P(0, 1) = P(1, 0) = 1;
  EXPECT_NEAR(HorizontalSigma(P), std::sqrt(3.0), 1e-12);
}

TEST(HazardAssessor, UnknownWithoutAPose) {
  const HazardAssessor a(RockAhead());
  const HazardStatus s = a.Assess(5 * kSecond);
  EXPECT_EQ(s.state, HazardState::kUnknown);
  EXPECT_FALSE(s.safe());
  EXPECT_NE(s.detail.find("no pose"), std::string::npos) << s.detail;
  EXPECT_EQ(a.CheckStep({{0, 0, 0}}, 5 * kSecond).verdict, Verdict::kUnknown);
}

TEST(HazardAssessor, UnknownWhenThePoseIsStale) {
  HazardAssessor a(RockAhead());  // max age 2 s
  a.OnPose(At(10 * kSecond));
  EXPECT_EQ(a.Assess(11 * kSecond + kSecond / 2).state, HazardState::kSafe);
  const HazardStatus s = a.Assess(12 * kSecond + 1);
  EXPECT_EQ(s.state, HazardState::kUnknown);
  EXPECT_NE(s.detail.find("old"), std::string::npos) << s.detail;
  EXPECT_EQ(a.CheckStep({{0, 0, 0}}, 13 * kSecond).verdict, Verdict::kUnknown);
}

// A real clock running a simulation at 50x reads its guards in wall seconds: 2 s of wall
// time is 100 s of rover time. Virtual time and a rover (rate 1) read rover seconds.
TEST(HazardAssessor, PoseAgeIsReadOnTheGuardsClock) {
  HazardAssessor a(RockAhead());  // max age 2 s
  a.OnPose(At(10 * kSecond));
  a.set_clock_rate(50.0);
  EXPECT_EQ(a.Assess(13 * kSecond).state, HazardState::kSafe);    // 3 s of rover time, 0.06 s of wall
  EXPECT_EQ(a.Assess(109 * kSecond).state, HazardState::kSafe);   // 1.98 s of wall
  const HazardStatus s = a.Assess(111 * kSecond);                  // 2.02 s of wall
  EXPECT_EQ(s.state, HazardState::kUnknown);
  EXPECT_NE(s.detail.find("in wall time (101 s of rover time at 50x)"), std::string::npos) << s.detail;
  a.set_clock_rate(1.0);
  EXPECT_EQ(a.Assess(13 * kSecond).state, HazardState::kUnknown);
  EXPECT_THROW(a.set_clock_rate(0.0), std::invalid_argument);
  EXPECT_THROW(a.set_clock_rate(NAN), std::invalid_argument);
}

TEST(HazardAssessor, SafeReportsNearestZoneAndClearance) {
  HazardAssessor a(RockAhead());
  a.OnPose(At(0, 0.1));
  const HazardStatus s = a.Assess(0);
  EXPECT_EQ(s.state, HazardState::kSafe);
  EXPECT_EQ(s.zone_name, "rock");
  EXPECT_NEAR(s.min_clearance_m, 1.7 - 0.3, 1e-12);
  EXPECT_FALSE(s.keepout_violated);
  EXPECT_FALSE(s.tilt_violated);
  EXPECT_NEAR(s.roll_limit_rad, 30 * kDeg, 1e-12);
  EXPECT_STREQ(ToString(s.state), "SAFE");
}

TEST(HazardAssessor, UncertaintyAloneCanViolateKeepOut) {
  HazardAssessor a(RockAhead());
  a.OnPose(At(0, 0.55));  // 3 x 0.55 = 1.65 < 1.7: still clear
  EXPECT_EQ(a.Assess(0).state, HazardState::kSafe);
  a.OnPose(At(0, 0.6));   // 1.8 > 1.7
  const HazardStatus s = a.Assess(0);
  EXPECT_EQ(s.state, HazardState::kViolation);
  EXPECT_TRUE(s.keepout_violated);
  EXPECT_EQ(s.zone_name, "rock");
  EXPECT_NEAR(s.min_clearance_m, -0.1, 1e-12);
  EXPECT_NE(s.detail.find("keep-out"), std::string::npos) << s.detail;
}

TEST(HazardAssessor, TiltViolation) {
  HazardOptions o = RockAhead();
  o.tilt.pitch_limit_rad = 20 * kDeg;
  HazardAssessor a(o);
  a.OnPose(At(0, 0.0, 0.0, 22 * kDeg));
  HazardStatus s = a.Assess(0);
  EXPECT_EQ(s.state, HazardState::kViolation);
  EXPECT_TRUE(s.tilt_violated);
  EXPECT_FALSE(s.keepout_violated);
  EXPECT_NEAR(s.pitch_rad, 22 * kDeg, 1e-12);
  // A fresher IMU attitude takes over between poses.
  a.OnAttitude(kSecond / 2, 0.0, 5 * kDeg);
  s = a.Assess(kSecond / 2);
  EXPECT_EQ(s.state, HazardState::kSafe);
  // Sequences may tighten the limits.
  a.SetTiltLimits({3 * kDeg, 3 * kDeg});
  EXPECT_TRUE(a.Assess(kSecond / 2).tilt_violated);
  EXPECT_THROW(a.SetTiltLimits({-1.0, 0.1}), std::invalid_argument);
}

TEST(HazardAssessor, KnownTiltViolationWinsOverStalePose) {
  HazardAssessor a(RockAhead());
  a.OnPose(At(0));
  a.OnAttitude(10 * kSecond, 40 * kDeg, 0.0);  // IMU alive, estimator silent
  const HazardStatus s = a.Assess(10 * kSecond);
  EXPECT_EQ(s.state, HazardState::kViolation);
  EXPECT_TRUE(s.tilt_violated);
  EXPECT_NE(s.detail.find("old"), std::string::npos) << s.detail;
}

TEST(HazardAssessor, StepCheckUsesTheLatestSigma) {
  HazardAssessor a(RockAhead());
  const auto path = SampleStepPath({0, 0, 0}, 1.0, 0.0, 0.0, 0.05, 0.05);
  a.OnPose(At(0, 0.1));
  const SweptCheck ok = a.CheckStep(path, 0);  // ends 0.7 m from the rock, less 0.3
  EXPECT_TRUE(ok.safe());
  EXPECT_NEAR(ok.min_clearance_m, 0.4, 1e-9);
  a.OnPose(At(0, 0.3));
  EXPECT_EQ(a.CheckStep(path, 0).verdict, Verdict::kUnsafe);
}

TEST(HazardAssessor, StepCheckAddsTheQueryMargin) {
  HazardAssessor a(RockAhead());
  const auto path = SampleStepPath({0, 0, 0}, 1.0, 0.0, 0.0, 0.05, 0.05);
  a.OnPose(At(0, 0.1));
  const SweptCheck ok = a.CheckStep(path, 0, 0.35);
  EXPECT_TRUE(ok.safe());
  EXPECT_NEAR(ok.min_clearance_m, 0.05, 1e-9);  // 0.7 - 0.3 - 0.35
  EXPECT_EQ(a.CheckStep(path, 0, 0.45).verdict, Verdict::kUnsafe);
  EXPECT_EQ(a.CheckStep(path, 0, NAN).verdict, Verdict::kUnknown);
}

TEST(HazardAssessor, InvalidZonesAreRejectedAndThePreviousSetStays) {
  HazardAssessor a(RockAhead());
  KeepOutZone bad;
  bad.name = "sliver";
  bad.shape = KeepOutZone::Shape::kPolygon;
  bad.vertices = {{0, 0}, {1, 1}};
  try {
    a.SetZones({bad});
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("zone 'sliver'"), std::string::npos) << e.what();
  }
  ASSERT_EQ(a.zones().size(), 1u);
  EXPECT_EQ(a.zones()[0].name, "rock");
  a.SetZones({});
  a.OnPose(At(0));
  const HazardStatus s = a.Assess(0);
  EXPECT_EQ(s.state, HazardState::kSafe);
  EXPECT_TRUE(std::isinf(s.min_clearance_m));
  EXPECT_NE(s.detail.find("no keep-out zones"), std::string::npos);
}

TEST(HazardOptions, ExampleFileLoads) {
  const ConfigNode root =
      ConfigNode::LoadFile(std::string(ROVER_SOURCE_DIR) + "/common/hazards/hazards_example.yaml");
  const HazardOptions o = LoadHazardOptions(root["hazards"]);
  EXPECT_NEAR(o.footprint.length_m, 1.6, 1e-12);
  EXPECT_NEAR(o.footprint.width_m, 2.3, 1e-12);
  EXPECT_NEAR(o.tilt.roll_limit_rad, 30 * kDeg, 1e-12);
  EXPECT_NEAR(o.max_pose_age_s, 2.0, 1e-12);
  ASSERT_EQ(o.zones.size(), 2u);
  EXPECT_EQ(o.zones[0].name, "rock_a");
  EXPECT_EQ(o.zones[0].shape, KeepOutZone::Shape::kCircle);
  EXPECT_NEAR(o.zones[0].radius_m, 0.6, 1e-12);
  EXPECT_EQ(o.zones[1].shape, KeepOutZone::Shape::kPolygon);
  EXPECT_EQ(o.zones[1].vertices.size(), 4u);
  EXPECT_NO_THROW(HazardAssessor{o});
}

TEST(HazardOptions, ErrorsNameFileAndKey) {
  auto message = [](const std::string& text) {
    try {
      LoadHazardOptions(ConfigNode::FromString(text, "rover.yaml")["hazards"], {"rate_hz"});
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message("hazards:\n  rate_hz: 5\n"), "no error");
  const std::string typo = message("hazards:\n  footprint:\n    lenght_m: 2\n");
  EXPECT_NE(typo.find("rover.yaml: hazards.footprint.lenght_m: unknown key"), std::string::npos)
      << typo;
  const std::string two = message(
      "hazards:\n  zones:\n    - name: z\n      polygon: [[0, 0], [1, 1]]\n");
  EXPECT_NE(two.find("rover.yaml"), std::string::npos) << two;
  EXPECT_NE(two.find("hazards.zones"), std::string::npos) << two;
  EXPECT_NE(two.find("at least 3"), std::string::npos) << two;
  const std::string dup = message(
      "hazards:\n  zones:\n    - {name: a, circle: {center: [0, 0], radius_m: 1}}\n"
      "    - {name: a, circle: {center: [5, 0], radius_m: 1}}\n");
  EXPECT_NE(dup.find("duplicate zone name 'a'"), std::string::npos) << dup;
  const std::string both = message(
      "hazards:\n  zones:\n    - {name: a, circle: {center: [0, 0], radius_m: 1}, "
      "polygon: [[0, 0], [1, 0], [0, 1]]}\n");
  EXPECT_NE(both.find("exactly one"), std::string::npos) << both;
  const std::string radius = message(
      "hazards:\n  zones:\n    - {name: a, circle: {center: [0, 0], radius_m: 0}}\n");
  EXPECT_NE(radius.find("radius"), std::string::npos) << radius;
  const std::string tilt = message("hazards:\n  roll_limit_deg: 120\n");
  EXPECT_NE(tilt.find("hazards.roll_limit_deg"), std::string::npos) << tilt;
}

TEST(HazardAssessor, SnapshotFromAFullPose) {
  rover::geometry::Matrix6d P = rover::geometry::Matrix6d::Identity() * 0.01;
  P(1, 1) = 0.09;
  const PoseSnapshot s =
      SnapshotFromPose(42, rover::geometry::PoseFromXyzRpy(1, 2, 3, 0.1, -0.2, 0.3), P);
  EXPECT_EQ(s.utime, 42);
  EXPECT_NEAR(s.x, 1.0, 1e-12);
  EXPECT_NEAR(s.y, 2.0, 1e-12);
  EXPECT_NEAR(s.roll, 0.1, 1e-12);
  EXPECT_NEAR(s.pitch, -0.2, 1e-12);
  EXPECT_NEAR(s.yaw, 0.3, 1e-12);
  EXPECT_NEAR(s.position_sigma_m, 0.3, 1e-12);
}
