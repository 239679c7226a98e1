// Scenario tests (configs/scenarios/README.md): each runs the real process set on
// a private LCM bus through scenario_runner and asserts the outcome against truth.
// ./rover test runs ctest inside a private network namespace.
#include "integration/run_support.hpp"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <fstream>

namespace rover::test {
namespace {

// Runs configs/scenarios/NAME.yaml and returns its summary.json.
YAML::Node RunScenario(const std::string& name) {
  const std::string out = OutDir("scenario_" + name);
  const auto result = RunCommand(Bin("scenario_runner") + " configs/scenarios/" + name +
                                 ".yaml --out " + out + " --quiet");
  EXPECT_EQ(result.exit_code, 0) << result.output;
  EXPECT_TRUE(std::filesystem::exists(out + "/log.lcm")) << "no log written";
  // Every run leaves its pictures (rover_plot, run by scenario_runner).
  for (const char* picture : {"traverse.png", "error.png", "slip.png", "vo_steps/README.txt"}) {
    EXPECT_TRUE(std::filesystem::exists(out + "/" + picture)) << picture << " not drawn:\n" << result.output;
  }
  return YAML::LoadFile(out + "/summary.json");
}

double Horizontal(const YAML::Node& pose, double x, double y) {
  return std::hypot(pose["x"].as<double>() - x, pose["y"].as<double>() - y);
}

TEST(Scenario, DemoCompletesDriveTurnArcGotoInsideTheDisc) {
  const auto s = RunScenario("demo");
  ASSERT_EQ(s["outcome"].as<std::string>(), "completed") << s["detail"].as<std::string>();
  EXPECT_TRUE(s["abort_reason"].IsNull());
  std::string kinds;
  for (const auto& c : s["commands"]) {
    EXPECT_EQ(c["outcome"].as<std::string>(), "completed") << c["text"].as<std::string>();
    kinds += c["text"].as<std::string>().substr(0, 4) + " ";
  }
  for (const char* k : {"driv", "turn", "arc ", "goto"}) EXPECT_NE(kinds.find(k), std::string::npos) << k;
  // Steps never exceed the sequence's 50 cm step length.
  ASSERT_GT(s["steps"].size(), 5u);
  for (const auto& st : s["steps"]) {
    EXPECT_LE(std::abs(st["commanded"]["distance_m"].as<double>()), 0.5 + 1e-9);
  }
  // The goto reached its 0.3 m disc by the VO-corrected estimate; the truth lies within the
  // disc plus the estimate's error, which VO keeps to a few percent of the distance (wheel
  // odometry alone passes 10 % on these cobbles).
  const double distance = s["distance_travelled_m"].as<double>();
  EXPECT_GT(distance, 5.0);
  EXPECT_LT(Horizontal(s["final_estimate"], 5.0, 3.0), 0.3);
  EXPECT_LT(Horizontal(s["final_truth"], 5.0, 3.0), 0.3 + 0.05 * distance);
  EXPECT_LT(s["position_error_pct"].as<double>(), 5.0);
  // VO converges on most driving steps (turns in place may refuse: too little overlap).
  int drive_steps = 0, drive_vo_ok = 0;
  for (const auto& st : s["steps"]) {
    if (std::abs(st["commanded"]["distance_m"].as<double>()) < 1e-6) continue;
    ++drive_steps;
    drive_vo_ok += st["vo_status"].as<int>() == 0;
  }
  EXPECT_GE(2 * drive_vo_ok, drive_steps) << drive_vo_ok << " of " << drive_steps;
}

TEST(Scenario, KeepOutStopsShortOfTheRock) {
  const auto s = RunScenario("keepout_abort");
  ASSERT_EQ(s["outcome"].as<std::string>(), "aborted");
  EXPECT_EQ(s["abort_reason"].as<std::string>(), "keepout") << s["detail"].as<std::string>();
  // Truth: the footprint never touched the zone, and the rover moved toward it first.
  ASSERT_FALSE(s["min_keepout_clearance_m"].IsNull());
  EXPECT_GT(s["min_keepout_clearance_m"].as<double>(), 0.0);
  EXPECT_GT(s["final_truth"]["x"].as<double>(), 1.0);
  EXPECT_EQ(s["commands"][3]["outcome"].as<std::string>(), "aborted");
}

TEST(Scenario, ProgressAbortOnSteepSandWhereTheRoverSlidesBack) {
  const auto s = RunScenario("progress_abort");
  ASSERT_EQ(s["outcome"].as<std::string>(), "aborted") << s["detail"].as<std::string>();
  EXPECT_EQ(s["abort_reason"].as<std::string>(), "progress") << s["detail"].as<std::string>();
  ASSERT_GE(s["steps"].size(), 1u);
  // Sol 206: the truth shows slip beyond 100 % (the rover went backward), and VO, the only
  // sensor that could see it, measured slip over the 40 % limit.
  const auto& last = s["steps"][s["steps"].size() - 1];
  EXPECT_GT(last["slip_pct"].as<double>(), 100.0);
  EXPECT_GT(last["estimated_slip_pct"].as<double>(), 40.0);
  EXPECT_EQ(last["vo_status"].as<int>(), 0);  // an accepted VO update
  EXPECT_LT(s["final_truth"]["x"].as<double>(), 0.0);
  // The VO-corrected estimate followed the slide: error well under the slide itself.
  EXPECT_LT(s["position_error_m"].as<double>(), 0.1);
}

TEST(Scenario, TiltAbortOnASteepBedrockClimb) {
  const auto s = RunScenario("tilt_abort");
  ASSERT_EQ(s["outcome"].as<std::string>(), "aborted");
  EXPECT_EQ(s["abort_reason"].as<std::string>(), "tilt") << s["detail"].as<std::string>();
  // The limit is 15 deg; the slope reaches 26 deg. The truth pitch at the stop is past the
  // limit but far from the slope's full angle (the rover stopped early on the ramp).
  const double pitch_deg = std::abs(s["final_truth"]["pitch"].as<double>()) * 180.0 / M_PI;
  EXPECT_GT(pitch_deg, 14.0);
  EXPECT_LT(pitch_deg, 24.0);
}

TEST(Scenario, ProcessLostStopsTheRover) {
  const auto s = RunScenario("process_lost");
  ASSERT_EQ(s["outcome"].as<std::string>(), "aborted");
  EXPECT_EQ(s["abort_reason"].as<std::string>(), "process_lost") << s["detail"].as<std::string>();
  EXPECT_NE(s["detail"].as<std::string>().find("state_estimator"), std::string::npos);
  // Killed after 2 steps of 5 m: the rover stopped well short of the commanded distance.
  EXPECT_GT(s["distance_travelled_m"].as<double>(), 1.0);
  EXPECT_LT(s["distance_travelled_m"].as<double>(), 3.5);
}

TEST(Scenario, RejectedSequenceNeverMoves) {
  const auto s = RunScenario("rejected");
  ASSERT_EQ(s["outcome"].as<std::string>(), "rejected");
  EXPECT_EQ(s["detail"].as<std::string>(),
            "configs/sequences/bad_units.seq:5:9: wrong unit 'deg' for drive distance (expected m or cm)");
  EXPECT_EQ(s["steps"].size(), 0u);
  EXPECT_LT(s["distance_travelled_m"].as<double>(), 0.01);
  for (const auto& c : s["commands"]) EXPECT_EQ(c["outcome"].as<std::string>(), "not_run");
}

// A process that exits at start (here the executor, on a misspelt key of the scenario's
// overrides) ends the run at once, with that process's one-line error: in virtual time the
// clock could never start, and the runner no longer waits 90 s of wall time to say so.
TEST(Scenario, AProcessThatExitsAtStartEndsTheRunWithItsError) {
  const std::string out = OutDir("scenario_exits_at_start");
  const std::string file = out + "/bad_key.yaml";
  std::ofstream(file) << "name: bad_key\n"
                         "world: configs/worlds/flat_rock_course.yaml\n"
                         "sequence: configs/sequences/demo.seq\n"
                         "deployment: configs/deploy/sim_vo.yaml\n"
                         "start: {x: 0, y: 0, yaw_deg: 0}\n"
                         "sim_rate: 50\n"
                         "timeout_s: 300\n"
                         "overrides:\n"
                         "  executor.avoid_margin_mm: 0.2\n"
                         "expect: {outcome: completed}\n";
  const auto result = RunCommand(Bin("scenario_runner") + " " + file + " --out " + out + "/run --no-plot");
  EXPECT_EQ(result.exit_code, 1) << result.output;
  EXPECT_NE(result.output.find("sequence_executor exited with code 2 at start: "), std::string::npos) << result.output;
  EXPECT_NE(result.output.find("executor.avoid_margin_mm: unknown key"), std::string::npos) << result.output;
  EXPECT_NE(result.output.find("the sequence was not submitted"), std::string::npos) << result.output;
  // Not the 30 s start limit and the 60 s clock-stall limit it used to wait out.
  EXPECT_EQ(result.output.find("the clock did not start"), std::string::npos) << result.output;
  EXPECT_EQ(result.output.find("the clock stood still"), std::string::npos) << result.output;
  EXPECT_EQ(YAML::LoadFile(out + "/run/summary.json")["outcome"].as<std::string>(), "incomplete");
}

}  // namespace
}  // namespace rover::test
