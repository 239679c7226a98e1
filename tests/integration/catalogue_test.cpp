// The scenario catalogue (configs/scenarios/README.md): the ten Mars episodes, each run
// through the real process set on a private LCM bus by scenario_runner, and asserted
// against truth: outcome, errors, clearance, and no false VO update (summary.json counts
// an accepted update whose error against truth lies beyond the 99.7 % NEES bound).
// ./rover test runs ctest inside a private network namespace.
#include "integration/scenario_run.hpp"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>

namespace rover::test {
namespace {

constexpr double kDeg = M_PI / 180.0;

// VO statuses in summary.json (vo_update_t STATUS_*).
constexpr int kVoOk = 0;
constexpr int kVoTooFewFeatures = 2;
constexpr int kVoMotionTooLarge = 7;
constexpr int kVoDegenerate = 9;

YAML::Node RunScenario(const std::string& name) { return RunScenarioSummary("catalogue_", name); }

double Get(const YAML::Node& pose, const char* key) { return pose[key].as<double>(); }

double Horizontal(const YAML::Node& a, const YAML::Node& b) {
  return std::hypot(Get(a, "x") - Get(b, "x"), Get(a, "y") - Get(b, "y"));
}

// Steps that drove (not turns in place).
bool IsDrive(const YAML::Node& step) {
  return std::abs(step["commanded"]["distance_m"].as<double>()) > 1e-6;
}

double MaxTrueSlipPct(const YAML::Node& s) {
  double m = -1e9;
  for (const auto& st : s["steps"]) {
    if (IsDrive(st)) m = std::max(m, st["slip_pct"].as<double>());
  }
  return m;
}

int CountVoStatus(const YAML::Node& s, int status) {
  int n = 0;
  for (const auto& st : s["steps"]) n += st["vo_status"].as<int>() == status;
  return n;
}

// The most updates beyond the 99.7 % NEES bound that an honest VO shows, among n correct
// ones, with probability over 99 %: each lands beyond it with p = 0.0027, so a count of 1
// in 40 is chance (10 %), while the false updates Mars showed (the rover's shadow,
// features clustered on one patch) come many at once.
int FalseUpdatesAllowed(int n) {
  const double p = 0.0027;
  double tail = 1.0, term = std::pow(1.0 - p, n);  // P(X > k) with X ~ Binomial(n, p)
  for (int k = 0; k <= n; ++k) {
    tail -= term;
    if (tail < 0.01) return k;
    term *= p / (1.0 - p) * (n - k) / (k + 1.0);
  }
  return n;
}

// `extra`: on the long slope drives (Sol 304, Sols 188-191) VO's covariance is still a
// little overconfident (5-variant campaigns: 6 of 311 updates beyond the bound, then 3 of
// 311 after the cell terms of VO-13, where an honest one gives 0.27 %), so a run can show
// one more than chance allows. There
// the test allows one more: it still catches the false updates Mars showed, which come
// many at once; the calibration itself is measured by `./rover campaign`.
void ExpectNoFalseUpdate(const YAML::Node& s, int extra = 0) {
  const int accepted = s["vo_updates_accepted"].as<int>();
  EXPECT_LE(s["false_updates"].as<int>(), FalseUpdatesAllowed(accepted) + extra)
      << s["false_updates"].as<int>() << " of " << accepted << " accepted VO updates beyond the 99.7 % NEES bound";
}

TEST(Catalogue, FalseUpdateAllowanceIsWhatChanceGivesAnHonestVo) {
  EXPECT_EQ(FalseUpdatesAllowed(0), 0);
  EXPECT_EQ(FalseUpdatesAllowed(3), 0);   // P(any) = 0.8 %
  EXPECT_EQ(FalseUpdatesAllowed(40), 1);  // P(> 1) = 0.5 %
  EXPECT_EQ(FalseUpdatesAllowed(200), 3);
}

// Rock course: 2.45 m in 35 cm steps over cobbles on sand. Slip reaches 85 %;
// VO measures every step and keeps the error under 1 % of the distance.
TEST(Catalogue, RockCourseVoKeepsTheErrorUnderOnePercentWhileSlipReaches85Percent) {
  const auto s = RunScenario("rock_course");
  ASSERT_EQ(s["outcome"].as<std::string>(), "completed") << Detail(s);
  ASSERT_EQ(s["steps"].size(), 7u);
  EXPECT_GT(MaxTrueSlipPct(s), 75.0);
  for (const auto& st : s["steps"]) {
    EXPECT_EQ(st["vo_status"].as<int>(), kVoOk);
    // VO saw each step's slip as it was.
    EXPECT_NEAR(st["estimated_slip_pct"].as<double>(), st["slip_pct"].as<double>(), 5.0);
  }
  EXPECT_LT(s["position_error_pct"].as<double>(), 1.0);
  ExpectNoFalseUpdate(s);
}

// The same course blind: wheel odometry passes 10 % error within 1.4 m (4 steps).
TEST(Catalogue, RockCourseBlindWheelOdometryPassesTenPercentWithinOnePointFourMetres) {
  const auto s = RunScenario("rock_course_blind");
  ASSERT_EQ(s["outcome"].as<std::string>(), "completed") << Detail(s);
  ASSERT_EQ(s["steps"].size(), 7u);
  double estimated = 0, truth = 0;
  for (std::size_t i = 0; i < 4; ++i) {
    estimated += s["steps"][i]["estimated"]["distance_m"].as<double>();
    truth += s["steps"][i]["true"]["distance_m"].as<double>();
  }
  EXPECT_GT((estimated - truth) / estimated, 0.10) << estimated << " m estimated, " << truth << " m true";
  EXPECT_GT(MaxTrueSlipPct(s), 75.0);
  EXPECT_GT(s["position_error_pct"].as<double>(), 10.0);
}

// Sol 304: 8.7 m across, then up, a 20 to 24 deg outcrop slope, ending in one sequence
// within the arm's reach of the target (the stand-off point at x 3, y 5.7).
TEST(Catalogue, Sol304ApproachEndsWithinReachOfTheTarget) {
  const auto s = RunScenario("sol304_approach");
  ASSERT_EQ(s["outcome"].as<std::string>(), "completed") << Detail(s);
  for (const auto& c : s["commands"]) EXPECT_EQ(c["outcome"].as<std::string>(), "completed");
  const double to_target = std::hypot(Get(s["final_truth"], "x") - 3.0, Get(s["final_truth"], "y") - 5.7);
  EXPECT_LT(to_target, 0.5);                                       // the arm reaches it
  EXPECT_GT(std::abs(Get(s["final_truth"], "pitch")), 18.0 * kDeg);  // on the slope, facing up
  EXPECT_GT(s["distance_travelled_m"].as<double>(), 8.0);
  EXPECT_LT(s["position_error_pct"].as<double>(), 2.0);
  ExpectNoFalseUpdate(s, /*extra=*/1);
}

// Wopmay with VO: the rover slides downslope toward the rock at every step; VO measures
// it and the predictive keep-out check stops the drive before the zone.
TEST(Catalogue, WopmayVoStopsBeforeTheZone) {
  const auto s = RunScenario("wopmay");
  ASSERT_EQ(s["outcome"].as<std::string>(), "aborted") << Detail(s);
  EXPECT_EQ(s["abort_reason"].as<std::string>(), "keepout") << Detail(s);
  ASSERT_FALSE(s["min_keepout_clearance_m"].IsNull());
  EXPECT_GT(s["min_keepout_clearance_m"].as<double>(), 0.0);
  // It did drive, and it did slide: north (downslope), off its line x = 2.6.
  EXPECT_GT(s["distance_travelled_m"].as<double>(), 1.0);
  EXPECT_GT(Get(s["final_truth"], "x") - 2.6, 0.3);
  // VO followed the slide (blind, the estimate ends over 0.5 m off: below). The stop may
  // come mid-step, after the last VO update: the monitor's footprint grows by 3 sigma, and
  // the wheels' sigma grows at the slip VO measured on the last steps.
  EXPECT_LT(s["position_error_m"].as<double>(), 0.10);
  EXPECT_EQ(CountVoStatus(s, kVoOk), static_cast<int>(s["steps"].size()));
  ExpectNoFalseUpdate(s);
}

// Wopmay blind: wheel odometry keeps the rover on its line, clear of the zone; in truth
// it slides into the zone (and onto the rock).
TEST(Catalogue, WopmayBlindEntersTheZone) {
  const auto s = RunScenario("wopmay_blind");
  ASSERT_FALSE(s["min_keepout_clearance_m"].IsNull());
  EXPECT_LT(s["min_keepout_clearance_m"].as<double>(), 0.0) << Detail(s);
  EXPECT_NEAR(Get(s["final_estimate"], "x"), 2.6, 0.1);  // it believes it held its line
  EXPECT_GT(Get(s["final_truth"], "x") - 2.6, 0.5);
  EXPECT_NE(s["abort_reason"].as<std::string>(""), "keepout");  // nothing saw it coming
}

// Sol 206: up a 28 deg loose-sand slope. Slip passes 100 %: the rover slides back, VO
// measures it, and the progress check aborts.
TEST(Catalogue, Sol206VoSeesTheSlideAndTheProgressCheckAborts) {
  const auto s = RunScenario("progress_abort");
  ASSERT_EQ(s["outcome"].as<std::string>(), "aborted") << Detail(s);
  EXPECT_EQ(s["abort_reason"].as<std::string>(), "progress") << Detail(s);
  ASSERT_GE(s["steps"].size(), 1u);
  const auto& last = s["steps"][s["steps"].size() - 1];
  EXPECT_GT(last["slip_pct"].as<double>(), 100.0);
  EXPECT_GT(last["estimated_slip_pct"].as<double>(), 100.0);
  EXPECT_EQ(last["vo_status"].as<int>(), kVoOk);
  EXPECT_LT(Get(s["final_truth"], "x"), 0.0);  // it went backward
  EXPECT_LT(s["position_error_m"].as<double>(), 0.05);
  ExpectNoFalseUpdate(s);
}

// Sols 188 to 191 with VO: 19.2 m up and across a 20 to 22 deg hillside; the rover slides
// down and across the slope by metres, and VO follows it.
TEST(Catalogue, Sol188To191VoFollowsTheSlideDownAndAcrossTheSlope) {
  const auto s = RunScenario("sol188_191");
  ASSERT_EQ(s["outcome"].as<std::string>(), "completed") << Detail(s);
  EXPECT_GT(s["distance_travelled_m"].as<double>(), 19.2);  // further than the wheels rolled
  EXPECT_LT(s["position_error_pct"].as<double>(), 2.0);
  EXPECT_LT(std::abs(Get(s["final_estimate"], "z") - Get(s["final_truth"], "z")), 0.2);
  const int ok = CountVoStatus(s, kVoOk);
  EXPECT_GE(ok, static_cast<int>(s["steps"].size()) - 2);
  ExpectNoFalseUpdate(s, /*extra=*/1);
}

// Sols 188 to 191 blind: wheel odometry underestimates the distance (the rover slid down
// and across the slope, so it travelled further than its wheels said), misses the
// slip-induced descent, and ends metres from the truth.
TEST(Catalogue, Sol188To191BlindUnderestimatesTheDistanceAndMissesTheDescent) {
  const auto s = RunScenario("sol188_191_blind");
  ASSERT_EQ(s["outcome"].as<std::string>(), "completed") << Detail(s);
  double wheels = 0;
  for (const auto& st : s["steps"]) wheels += st["estimated"]["distance_m"].as<double>();
  const double truth = s["distance_travelled_m"].as<double>();
  EXPECT_NEAR(wheels, 19.2, 0.1);
  EXPECT_GT(truth - wheels, 0.8) << truth << " m true, " << wheels << " m by the wheels";  // Mars: 1.6 m
  EXPECT_GT(Horizontal(s["final_estimate"], s["final_truth"]), 3.0);  // Mars: nearly 5 m
  // Z down: wheel odometry says it climbed; in truth it slid down the slope.
  EXPECT_LT(Get(s["final_estimate"], "z"), -0.3);
  EXPECT_GT(Get(s["final_truth"], "z") - Get(s["final_estimate"], "z"), 1.0);
}

// Featureless sand: VO reports too few features at every pair; the prior (wheel
// odometry) is kept and no update is made.
TEST(Catalogue, FeaturelessSandVoReportsTooFewFeaturesAndKeepsThePrior) {
  const auto s = RunScenario("featureless_sand");
  ASSERT_EQ(s["outcome"].as<std::string>(), "completed") << Detail(s);
  ASSERT_EQ(s["steps"].size(), 6u);
  EXPECT_EQ(CountVoStatus(s, kVoTooFewFeatures), 6);
  EXPECT_EQ(s["vo_updates_accepted"].as<int>(), 0);
  ExpectNoFalseUpdate(s);
  // The estimate is wheel odometry's: the 3 m the wheels rolled, a sand slip short in truth.
  EXPECT_NEAR(Get(s["final_estimate"], "x"), 3.0, 0.05);
  EXPECT_LT(s["position_error_pct"].as<double>(), 10.0);
}

// Rover shadow: the rover's own long shadow in view on bland sand moves with it; VO must
// not take it for the scene.
TEST(Catalogue, RoverShadowMakesNoFalseUpdate) {
  const auto s = RunScenario("rover_shadow");
  ASSERT_EQ(s["outcome"].as<std::string>(), "completed") << Detail(s);
  ExpectNoFalseUpdate(s);
  EXPECT_GT(Get(s["final_truth"], "x"), 2.5);  // it drove (a shadow-locked VO would say it stood still)
  EXPECT_LT(s["position_error_pct"].as<double>(), 10.0);
}

// Clustered features: every corner lies on one small textured patch; the degenerate-
// geometry check refuses the clustered inliers until the patch fills more of the view.
TEST(Catalogue, ClusteredFeaturesMakeNoFalseUpdate) {
  const auto s = RunScenario("clustered_features");
  ASSERT_EQ(s["outcome"].as<std::string>(), "completed") << Detail(s);
  EXPECT_GE(CountVoStatus(s, kVoDegenerate), 1);
  ExpectNoFalseUpdate(s);
  EXPECT_LT(s["position_error_pct"].as<double>(), 10.0);
}

// Large turn: 40 deg in place in one step with VO on. Too little overlap: VO re-initialises
// tracking on the new pair (no update across the turn) and measures the next drive.
TEST(Catalogue, LargeTurnReinitialisesTrackingWithoutAFalseUpdate) {
  const auto s = RunScenario("large_turn");
  ASSERT_EQ(s["outcome"].as<std::string>(), "completed") << Detail(s);
  int turn = -1;
  for (std::size_t i = 0; i < s["steps"].size(); ++i) {
    if (std::abs(s["steps"][i]["commanded"]["turn_rad"].as<double>()) > 30.0 * kDeg) turn = static_cast<int>(i);
  }
  ASSERT_GE(turn, 0) << "no step turned 40 deg at once";
  EXPECT_NEAR(s["steps"][turn]["commanded"]["turn_rad"].as<double>(), 40.0 * kDeg, 1e-6);
  EXPECT_EQ(s["steps"][turn]["vo_status"].as<int>(), kVoMotionTooLarge);
  ASSERT_GT(s["steps"].size(), static_cast<std::size_t>(turn + 1));
  EXPECT_EQ(s["steps"][turn + 1]["vo_status"].as<int>(), kVoOk);  // tracking re-initialised
  ExpectNoFalseUpdate(s);
  EXPECT_NEAR(Get(s["final_truth"], "yaw"), 40.0 * kDeg, 4.0 * kDeg);
  EXPECT_LT(s["position_error_pct"].as<double>(), 2.0);
}

// Wheel dragging: the right front wheel is dragged, so the wheels under-read and the
// rover yaws toward it; VO keeps the position error bounded.
TEST(Catalogue, WheelDraggingVoKeepsThePositionErrorBounded) {
  const auto s = RunScenario("wheel_dragging");
  ASSERT_EQ(s["outcome"].as<std::string>(), "completed") << Detail(s);
  EXPECT_GT(Get(s["final_truth"], "yaw"), 3.0 * kDeg);  // pulled toward the dragged (right) side
  double commanded = 0, truth = 0;
  for (const auto& st : s["steps"]) {
    commanded += st["commanded"]["distance_m"].as<double>();
    truth += st["true"]["distance_m"].as<double>();
    EXPECT_NEAR(st["estimated_slip_pct"].as<double>(), st["slip_pct"].as<double>(), 3.0);
  }
  EXPECT_LT(truth, 0.95 * commanded);  // the drag costs distance the wheels do not see
  EXPECT_LT(s["position_error_pct"].as<double>(), 2.0);
  ExpectNoFalseUpdate(s);
}

}  // namespace
}  // namespace rover::test
