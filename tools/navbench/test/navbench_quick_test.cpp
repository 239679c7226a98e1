// A tiny ./rover navbench through the real process set (one run at k = 0.10, a 5 to 6 m goto):
// the table's figures must be those of the run's own log and summary.json. Runs on a
// private bus (./rover test: ctest in a private network namespace).
#include "hazards/hazard_assessor.hpp"
#include "integration/run_support.hpp"
#include "scenario/scenario.hpp"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>

namespace fs = std::filesystem;
using rover::test::Bin;
using rover::test::OutDir;
using rover::test::RunCommand;

TEST(NavbenchQuick, TheTableIsTheLogs) {
  const std::string out = OutDir("navbench_quick");
  const auto result = RunCommand(Bin("navbench") + " --quick --min-goal 5 --max-goal 6 --seed 3 --out " + out);
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("k=0.10"), std::string::npos) << result.output;

  const YAML::Node results = YAML::LoadFile(out + "/results.json");
  ASSERT_EQ(results["groups"].size(), 1u);
  ASSERT_EQ(results["runs"].size(), 1u);
  const YAML::Node group = results["groups"][0];
  const YAML::Node run = results["runs"][0];
  EXPECT_EQ(group["group"].as<std::string>(), "k=0.10");
  EXPECT_EQ(group["runs"].as<int>(), 1);
  ASSERT_TRUE(run["ran"].as<bool>()) << result.output;
  const std::string dir = out + "/runs/" + run["id"].as<std::string>();
  EXPECT_TRUE(fs::exists(dir + "/field.yaml"));
  EXPECT_TRUE(fs::exists(out + "/plots/" + run["id"].as<std::string>() + ".png"));

  // The run's own record: the runner's summary.json and a summary of its log made here.
  const YAML::Node summary = YAML::LoadFile(dir + "/summary.json");
  EXPECT_EQ(run["outcome"].as<std::string>(), summary["outcome"].as<std::string>());
  const auto rover_config = rover::config::ConfigNode::LoadFile(dir + "/rover.yaml");
  const auto footprint = rover::hazards::LoadHazardOptions(rover_config["hazards"], {"publish_hz"}).footprint;
  const auto log = rover::tools::SummarizeLog(dir + "/log.lcm", footprint);
  ASSERT_FALSE(log.truth_track.empty());
  EXPECT_GT(run["driven_m"].as<double>(), 3.0) << "the rover hardly moved";
  // The plane path is at most the 3-D distance, and on this gentle ground within 2 % of it.
  EXPECT_NEAR(run["driven_m"].as<double>(), log.distance_travelled_m, 0.02 * log.distance_travelled_m);
  EXPECT_NEAR(run["path_ratio"].as<double>(), run["driven_m"].as<double>() / run["straight_m"].as<double>(), 1e-4);

  // Collisions: the table's contacts and grazes against the runner's closest true approach
  // to a rock over the collision height (an independent computation over every rock and sample):
  // the footprint overlapped a disc exactly when it met a rock or grazed one.
  ASSERT_TRUE(summary["min_rock_clearance_m"].IsScalar()) << "the field has rocks over the limit";
  const bool touched = summary["min_rock_clearance_m"].as<double>() < 0;
  EXPECT_EQ(run["rock_contacts"].as<int>() + run["rock_grazes"].as<int>() > 0, touched);
  EXPECT_EQ(group["runs_with_collision"].as<int>(), run["rock_contacts"].as<int>() > 0 ? 1 : 0);

  // The goal disc by truth: the log's last truth sample.
  const auto& last = log.truth_track.back();
  const double to_goal = std::hypot(last.x - run["goal_x"].as<double>(), last.y - run["goal_y"].as<double>());
  EXPECT_EQ(run["in_goal_disc"].as<bool>(), to_goal <= run["goal_radius_m"].as<double>()) << to_goal;
  EXPECT_NEAR(run["final_truth"][0].as<double>(), last.x, 1e-4);
  EXPECT_NEAR(run["final_truth"][1].as<double>(), last.y, 1e-4);
  const double straight = run["straight_m"].as<double>();
  EXPECT_GE(straight, 5.0);
  EXPECT_LE(straight, 6.0);
  const bool success = run["success"].as<bool>();
  EXPECT_EQ(group["successes"].as<int>(), success ? 1 : 0);
  if (success) {
    EXPECT_EQ(summary["outcome"].as<std::string>(), "completed");
    EXPECT_FALSE(touched);
    EXPECT_TRUE(run["in_goal_disc"].as<bool>());
    EXPECT_NEAR(group["median_path_ratio"].as<double>(), run["path_ratio"].as<double>(), 1e-9);
    // The shortest safe way on the true world is no longer than what the rover drove into
    // the disc (a lower bound: its legs may pass 0.075 m inside the clearance).
    ASSERT_TRUE(run["shortest_m"].IsScalar()) << result.output;
    EXPECT_LE(run["shortest_m"].as<double>(), run["driven_m"].as<double>() + 0.1);
    EXPECT_GE(run["shortest_m"].as<double>(), straight - run["goal_radius_m"].as<double>() - 1e-6);
    EXPECT_NEAR(group["median_shortest_ratio"].as<double>(), run["shortest_m"].as<double>() / straight, 1e-5);  // JSON: 6 digits
  }

  // The plan on a perfect map of the run's world: checked, and at k = 0.10 over 5 to 6 m
  // there is a way, no shorter than the straight line to the goal disc; counted in the table.
  ASSERT_TRUE(run["perfect_way"].IsScalar()) << result.output;
  EXPECT_TRUE(run["perfect_way"].as<bool>());
  EXPECT_GE(run["perfect_way_m"].as<double>(), straight - run["goal_radius_m"].as<double>() - 0.2);
  EXPECT_EQ(group["runs_way_checked"].as<int>(), 1);
  EXPECT_EQ(group["runs_with_way"].as<int>(), 1);
  EXPECT_NE(result.output.find("the plan on a perfect map"), std::string::npos) << result.output;

  // VO and rover time: the same counts as the summary's.
  EXPECT_EQ(run["vo_updates_accepted"].as<int>(), summary["vo_updates_accepted"].as<int>());
  EXPECT_EQ(run["false_updates"].as<int>(), summary["false_updates"].as<int>());
  EXPECT_GT(run["vo_updates_accepted"].as<int>(), 0);
  const double span = summary["rover_time_breakdown"]["span_s"].as<double>();
  EXPECT_NEAR(run["rover_time_s"].as<double>(), span, 1e-6);
  EXPECT_NEAR(group["drive_rate_m_per_h"].as<double>(), run["driven_m"].as<double>() / span * 3600, 1e-3);
}
