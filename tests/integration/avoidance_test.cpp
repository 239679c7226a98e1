// Hazard avoidance: the hazard monitor's traversability map from the NAVCAM
// pairs, and `goto ... avoid on` (arc voting, common/avoidance), on worlds of UNDECLARED
// rocks (no keep-out zone anywhere), asserted against truth. Each scenario runs the real
// process set on a private LCM bus (scenario_runner); summary.json carries the truth
// clearance of the rover's footprint to every rock taller than the step limit
// (min_rock_clearance_m, from SIM_TRUTH and the world). ./rover test runs ctest inside a
// private network namespace.
#include "integration/scenario_run.hpp"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <string>

namespace rover::test {
namespace {

YAML::Node RunScenario(const std::string& name) { return RunScenarioSummary("avoidance_", name); }

double Dist(const YAML::Node& pose, double x, double y) {
  return std::hypot(pose["x"].as<double>() - x, pose["y"].as<double>() - y);
}

// (a) Across the field with avoidance: inside the goal disc in truth (0.5 m, plus the
// estimate's error), and the true footprint never on a rock over the step limit.
TEST(Avoidance, RockFieldAvoidReachesTheGoalClearOfEveryTallRock) {
  const YAML::Node s = RunScenario("rock_field_avoid");
  ASSERT_EQ(s["outcome"].as<std::string>(), "completed") << Detail(s);
  ASSERT_GE(s["rocks_over_limit"].as<int>(), 5);
  ASSERT_FALSE(s["min_rock_clearance_m"].IsNull());
  EXPECT_GT(s["min_rock_clearance_m"].as<double>(), 0.0) << s["min_rock_clearance_rock"].as<std::string>("");
  EXPECT_LT(Dist(s["final_estimate"], 8.0, 0.0), 0.5);
  EXPECT_LT(Dist(s["final_truth"], 8.0, 0.0), 0.5 + 0.2);
  // It went round the rock on the line: some steps curved or turned.
  int turned = 0;
  for (const auto& st : s["steps"]) turned += std::abs(st["commanded"]["turn_rad"].as<double>()) > 0.01;
  EXPECT_GT(turned, 0);
}

// (b) The same goto without avoidance: the map stops it before the first tall rock, with
// the hazard named, and the rover never touched it.
TEST(Avoidance, RockFieldNoAvoidStopsBeforeTheFirstTallRock) {
  const YAML::Node s = RunScenario("rock_field_noavoid");
  ASSERT_EQ(s["outcome"].as<std::string>(), "aborted") << Detail(s);
  EXPECT_EQ(s["abort_reason"].as<std::string>(""), "hazard_map") << Detail(s);
  EXPECT_NE(Detail(s).find("hazard_map: step "), std::string::npos) << Detail(s);
  ASSERT_FALSE(s["min_rock_clearance_m"].IsNull());
  EXPECT_GT(s["min_rock_clearance_m"].as<double>(), 0.0);
  EXPECT_EQ(s["min_rock_clearance_rock"].as<std::string>(""), "Block_1");
  // It drove toward the rock first (the stop is the map's, not a refusal to start).
  EXPECT_GT(s["final_truth"]["x"].as<double>(), 0.5);
  EXPECT_LT(s["final_truth"]["x"].as<double>(), 2.8);
}

// (c) The goal behind a wall of rocks with one gap: the goto completes within its 12 m
// distance limit, which leaves no way round an end of the wall, so it went through the gap.
TEST(Avoidance, RockWallGapIsFound) {
  const YAML::Node s = RunScenario("rock_field_gap");
  ASSERT_EQ(s["outcome"].as<std::string>(), "completed") << Detail(s);
  ASSERT_FALSE(s["min_rock_clearance_m"].IsNull());
  EXPECT_GT(s["min_rock_clearance_m"].as<double>(), 0.0) << s["min_rock_clearance_rock"].as<std::string>("");
  EXPECT_LT(Dist(s["final_truth"], 7.5, 0.0), 0.5 + 0.2);
  EXPECT_LT(s["distance_travelled_m"].as<double>(), 12.5);
}

// (d) A keep-out zone across the way of a goto with avoidance: arc voting and the planner
// take it as an obstacle (grown by 3 sigma of the position), so the rover steers round it
// and completes, the hazard monitor never refusing a step and the truth never in the zone.
TEST(Avoidance, KeepOutZoneAcrossTheWayIsSteeredRound) {
  const YAML::Node s = RunScenario("keepout_avoid");
  ASSERT_EQ(s["outcome"].as<std::string>(), "completed") << Detail(s);
  ASSERT_FALSE(s["min_keepout_clearance_m"].IsNull());
  EXPECT_GT(s["min_keepout_clearance_m"].as<double>(), 0.0);
  EXPECT_LT(Dist(s["final_truth"], 7.0, 0.5), 0.5);
  // It says the margin it used for the estimate's uncertainty.
  EXPECT_NE(Detail(s).find("less 3 sigma"), std::string::npos) << Detail(s);
  // The straight line crosses the zone (radius 1 m at 4.2, 0.4): the path left it.
  int turned = 0;
  for (const auto& st : s["steps"]) turned += std::abs(st["commanded"]["turn_rad"].as<double>()) > 0.01;
  EXPECT_GT(turned, 0);
}

// (e) Issue 20: the demo, then a goto back to its start (behind the rover) with avoidance,
// on the same running stack. The second sequence completes, in truth inside its disc.
TEST(Avoidance, GoalBehindTheRoverOnAStackThatHasDrivenIsReached) {
  const YAML::Node s = RunScenario("demo_then_home");
  ASSERT_EQ(s["outcome"].as<std::string>(), "completed") << Detail(s);
  EXPECT_NE(Detail(s).find("goto reached the disc"), std::string::npos) << Detail(s);
  EXPECT_NE(Detail(s).find("sigma"), std::string::npos) << Detail(s);  // the margin it used
  EXPECT_LT(Dist(s["final_truth"], 0.0, 0.0), 0.5);
}

}  // namespace
}  // namespace rover::test
