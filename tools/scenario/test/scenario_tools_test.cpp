// Scenario tooling without a bus: scenario files with seeds and overrides, the overridden
// config copies, VO updates against interpolated truth (NEES, false updates), and the
// expectation check the runner's exit status comes from.
#include "scenario/scenario.hpp"

#include "config/yaml_config.hpp"
#include "geometry/pose.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>

namespace fs = std::filesystem;
using namespace rover::tools;
using rover::config::ConfigError;

namespace {

std::string TempDir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("scenario_tools_test_" + name + "_" + std::to_string(getpid()));
  fs::create_directories(dir);
  return dir.string();
}

std::string Write(const std::string& dir, const std::string& name, const std::string& text) {
  const std::string path = dir + "/" + name;
  std::ofstream(path) << text;
  return path;
}

rover_msgs::sim_truth_t Truth(std::int64_t utime, double x, double y, double yaw) {
  rover_msgs::sim_truth_t t{};
  t.utime = utime;
  t.position[0] = x;
  t.position[1] = y;
  const Eigen::Quaterniond q(rover::geometry::RotationFromRpy(0, 0, yaw));
  t.orientation[0] = q.w();
  t.orientation[1] = q.x();
  t.orientation[2] = q.y();
  t.orientation[3] = q.z();
  t.rpy[2] = yaw;
  return t;
}

}  // namespace

TEST(ScenarioOverrides, DottedKeysSetMapsAndListsAndCreateMissingSections) {
  YAML::Node root = YAML::Load("mobility: {seed: 1, slip: {dragged_wheel: {wheel: none}}}\n"
                               "slopes: [{angle_deg: 28}, {angle_deg: 2}]\ncapture: {rig: a.yaml}\n");
  ApplyOverrides(root,
                 {{"mobility.seed", YAML::Node(7)},
                  {"mobility.slip.dragged_wheel.wheel", YAML::Node("right_front")},
                  {"slopes.1.angle_deg", YAML::Node(3.5)},
                  {"capture.render.noise_seed", YAML::Node(11)}},
                 "rover.yaml");
  EXPECT_EQ(root["mobility"]["seed"].as<int>(), 7);
  EXPECT_EQ(root["mobility"]["slip"]["dragged_wheel"]["wheel"].as<std::string>(), "right_front");
  EXPECT_DOUBLE_EQ(root["slopes"][1]["angle_deg"].as<double>(), 3.5);
  EXPECT_DOUBLE_EQ(root["slopes"][0]["angle_deg"].as<double>(), 28.0);
  EXPECT_EQ(root["capture"]["render"]["noise_seed"].as<int>(), 11);
  EXPECT_EQ(root["capture"]["rig"].as<std::string>(), "a.yaml");
  try {
    ApplyOverrides(root, {{"slopes.2.angle_deg", YAML::Node(1)}}, "w.yaml");
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("w.yaml: slopes.2.angle_deg: '2' is not an index of the list of 2"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(ApplyOverrides(root, {{"mobility.seed.x", YAML::Node(1)}}, "r.yaml"), ConfigError);
}

TEST(ScenarioOverrides, ScenarioSeedsDraggedWheelAndOverridesBecomeCopies) {
  const std::string dir = TempDir("copies");
  const std::string scenario = Write(dir, "s.yaml",
                                     "name: t\nworld: configs/worlds/steep_sand_slope.yaml\n"
                                     "sequence: configs/sequences/slope_climb.seq\ndeployment: configs/deploy/sim_vo.yaml\n"
                                     "seeds: {world: 5, mobility: 6, render: 7}\ndragged_wheel: right_front\n"
                                     "overrides: {mobility.slip.soils.sand.noise_std: 0.05,"
                                     " capture.hazcam.rig: cameras/hazcam_front.yaml}\n"
                                     "world_overrides: {slopes.0.angle_deg: 29}\n"
                                     "campaign: {slope_jitter_deg: 1}\n"
                                     "expect: {outcome: aborted, abort_reason: [progress, vo_lost], min_clearance_m: 0}\n");
  const ScenarioSpec spec = LoadScenario(scenario);
  ASSERT_EQ(spec.overrides.size(), 5u);
  EXPECT_EQ(spec.overrides[0].key, "mobility.seed");
  EXPECT_EQ(spec.overrides[1].key, "capture.render.noise_seed");
  EXPECT_EQ(spec.overrides[2].key, "mobility.slip.dragged_wheel.wheel");
  ASSERT_EQ(spec.world_overrides.size(), 2u);
  EXPECT_EQ(spec.world_overrides[0].key, "seed");
  EXPECT_EQ(spec.expect_abort_reason, "progress|vo_lost");
  EXPECT_DOUBLE_EQ(spec.campaign_slope_jitter_deg, 1.0);

  const std::string source = ROVER_SOURCE_DIR;
  const RunConfigs c = PrepareRunConfigs(source + "/configs/rover.yaml", spec.overrides,
                                         source + "/configs/worlds/steep_sand_slope.yaml", spec.world_overrides, dir);
  EXPECT_EQ(c.rover_config, dir + "/rover.yaml");
  EXPECT_EQ(c.world, dir + "/world.yaml");
  const auto rover = rover::config::ConfigNode::LoadFile(c.rover_config);
  std::string wheel, rig;
  rover["mobility"]["slip"]["dragged_wheel"].Get("wheel", wheel);
  EXPECT_EQ(wheel, "right_front");
  rover["capture"].Get("rig", rig);
  EXPECT_TRUE(fs::path(rig).is_absolute()) << rig;
  EXPECT_TRUE(fs::exists(rig)) << rig;
  // The HAZCAM turned on by an override, relative to configs/ like the shipped rig.
  std::string hazcam_rig;
  rover["capture"]["hazcam"].Get("rig", hazcam_rig);
  EXPECT_TRUE(fs::path(hazcam_rig).is_absolute()) << hazcam_rig;
  EXPECT_TRUE(fs::exists(hazcam_rig)) << hazcam_rig;
  const YAML::Node world = YAML::LoadFile(c.world);
  EXPECT_EQ(world["seed"].as<int>(), 5);
  EXPECT_DOUBLE_EQ(world["slopes"][0]["angle_deg"].as<double>(), 29.0);
  // Nothing overridden: the originals are used as they are.
  const RunConfigs plain = PrepareRunConfigs("a.yaml", {}, "w.yaml", {}, dir);
  EXPECT_EQ(plain.rover_config, "a.yaml");
  EXPECT_EQ(plain.world, "w.yaml");

  const std::string bad = Write(dir, "bad.yaml",
                                "world: w\nsequence: s\ndeployment: d\nseeds: {wrold: 5}\n");
  EXPECT_THROW(LoadScenario(bad), ConfigError);
  fs::remove_all(dir);
}

// The sequence is submitted under `sequence_name` when the scenario gives one (navbench
// names its runs so that their logs do not carry the output folder), else under its path.
TEST(ScenarioFile, TheSequenceIsSubmittedUnderItsNameOrItsPath) {
  const std::string dir = TempDir("names");
  const std::string base = "world: w.yaml\nsequence: /any/folder/goto.seq\ndeployment: d.yaml\n";
  EXPECT_EQ(LoadScenario(Write(dir, "plain.yaml", base)).sequence_name, "/any/folder/goto.seq");
  const ScenarioSpec named = LoadScenario(Write(dir, "named.yaml", base + "sequence_name: navbench/r01/goto.seq\n"));
  EXPECT_EQ(named.sequence, "/any/folder/goto.seq");
  EXPECT_EQ(named.sequence_name, "navbench/r01/goto.seq");
  try {
    LoadScenario(Write(dir, "empty.yaml", base + "sequence_name: \"\"\n"));
    ADD_FAILURE() << "an empty sequence_name was accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("sequence_name"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("expected a name"), std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}

TEST(VoTruth, TruthIsInterpolatedBetweenSamples) {
  const std::vector<rover_msgs::sim_truth_t> truth = {Truth(1000, 0, 0, 0), Truth(2000, 1, 2, 0.2)};
  const auto mid = TruthPoseAt(truth, 1250);
  ASSERT_TRUE(mid);
  EXPECT_NEAR(mid->translation().x(), 0.25, 1e-12);
  EXPECT_NEAR(mid->translation().y(), 0.5, 1e-12);
  EXPECT_NEAR(rover::geometry::XyzRpyFromPose(*mid)(5), 0.05, 1e-12);
  EXPECT_FALSE(TruthPoseAt(truth, 999));
  EXPECT_FALSE(TruthPoseAt(truth, 2001));
  EXPECT_TRUE(TruthPoseAt(truth, 2000));
}

TEST(VoTruth, NeesOfAKnownErrorAndTheFalseUpdateBound) {
  // Truth: 0.5 m forward between the two captures. VO says 0.503 m, with 1 mm sigmas:
  // NEES = 3^2 = 9 (an honest 3 sigma in one axis, not a false update); 0.506 m gives 36.
  const std::vector<rover_msgs::sim_truth_t> truth = {Truth(0, 0, 0, 0), Truth(1'000'000, 0, 0, 0),
                                                      Truth(2'000'000, 0.5, 0, 0), Truth(3'000'000, 0.5, 0, 0)};
  rover_msgs::vo_update_t u{};
  u.status = rover_msgs::vo_update_t::STATUS_OK;
  u.from_utime = 500'000;
  u.to_utime = 2'500'000;
  u.delta_orientation[0] = 1.0;
  u.delta_position[0] = 0.503;
  for (int i = 0; i < 6; ++i) u.covariance[i][i] = 1e-6;
  VoCheck c = CheckVoUpdate(u, truth);
  ASSERT_TRUE(c.accepted);
  ASSERT_TRUE(c.true_delta);
  EXPECT_NEAR((*c.true_delta)(0), 0.5, 1e-12);
  EXPECT_NEAR(c.delta(0), 0.503, 1e-12);
  ASSERT_TRUE(c.nees);
  EXPECT_NEAR(*c.nees, 9.0, 1e-6);
  EXPECT_FALSE(c.false_update());
  u.delta_position[0] = 0.506;
  c = CheckVoUpdate(u, truth);
  EXPECT_NEAR(*c.nees, 36.0, 1e-6);
  EXPECT_TRUE(c.false_update());
  // A failure has no delta; a covariance that is not positive definite has no NEES.
  u.covariance[0][0] = 0.0;
  EXPECT_FALSE(CheckVoUpdate(u, truth).nees);
  u.status = rover_msgs::vo_update_t::STATUS_TOO_FEW_FEATURES;
  EXPECT_FALSE(CheckVoUpdate(u, truth).accepted);
}

// expect: horizontal_nees and heading_nees as [min, max], max_final_3sigma_m: read from the
// file, checked against summary.json's pose_honesty, and a bad range is one line.
TEST(ScenarioExpectation, PoseHonestyIsChecked) {
  const std::string dir = TempDir("honesty");
  const std::string base = "name: t\nworld: w.yaml\nsequence: s.seq\ndeployment: d.yaml\n";
  const ScenarioSpec spec = LoadScenario(Write(
      dir, "h.yaml",
      base + "expect: {outcome: completed, horizontal_nees: [1, 3], heading_nees: [0.5, 1.5], max_final_3sigma_m: 2}\n"));
  ASSERT_TRUE(spec.expect_horizontal_nees && spec.expect_heading_nees && spec.expect_max_final_3sigma_m);
  EXPECT_EQ(spec.expect_heading_nees->first, 0.5);
  EXPECT_EQ(spec.expect_heading_nees->second, 1.5);
  for (const char* bad : {"horizontal_nees: 2", "horizontal_nees: [3, 1]", "heading_nees: [1]"}) {
    try {
      LoadScenario(Write(dir, "bad.yaml", base + "expect: {" + std::string(bad) + "}\n"));
      ADD_FAILURE() << bad << " was accepted";
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("expect"), std::string::npos) << e.what();
    }
  }
  ScenarioSummary s;
  s.outcome = "completed";
  std::string why;
  EXPECT_FALSE(AsExpected(spec, s, &why));  // no pose judged: unknown is not honest
  EXPECT_NE(why.find("horizontal NEES unknown"), std::string::npos) << why;
  PoseHonesty h;
  h.horizontal_nees_mean = 2.1;
  h.heading_nees_mean = 0.9;
  h.final_horizontal_3sigma_m = 1.2;
  s.pose_honesty = h;
  EXPECT_TRUE(AsExpected(spec, s, &why)) << why;
  s.pose_honesty->horizontal_nees_mean = 0.30;
  s.pose_honesty->heading_nees_mean = 1.72;
  s.pose_honesty->final_horizontal_3sigma_m = 6.94;
  EXPECT_FALSE(AsExpected(spec, s, &why));
  EXPECT_NE(why.find("horizontal NEES mean 0.3, expected in [1, 3]"), std::string::npos) << why;
  EXPECT_NE(why.find("heading NEES mean 1.72, expected in [0.5, 1.5]"), std::string::npos) << why;
  EXPECT_NE(why.find("final 3-sigma 6.94 m, expected <= 2 m"), std::string::npos) << why;
  fs::remove_all(dir);
}

TEST(ScenarioExpectation, EveryExpectEntryIsChecked) {
  ScenarioSpec spec;
  spec.expect_outcome = "aborted";
  spec.expect_abort_reasons = {"progress", "vo_lost"};
  spec.expect_abort_reason = "progress|vo_lost";
  spec.expect_min_clearance_m = 0.0;
  spec.expect_max_false_updates = 0;
  ScenarioSummary s;
  s.outcome = "aborted";
  s.abort_reason = "vo_lost";
  s.min_keepout_clearance_m = 0.02;
  std::string why;
  EXPECT_TRUE(AsExpected(spec, s, &why)) << why;
  s.abort_reason = "keepout";
  s.min_keepout_clearance_m = -0.034;
  s.false_updates = 2;
  EXPECT_FALSE(AsExpected(spec, s, &why));
  EXPECT_NE(why.find("abort reason keepout, expected progress|vo_lost"), std::string::npos) << why;
  EXPECT_NE(why.find("truth clearance -0.034 m, expected >= 0 m"), std::string::npos) << why;
  EXPECT_NE(why.find("2 false VO updates"), std::string::npos) << why;
  s.outcome = "completed";
  EXPECT_FALSE(AsExpected(spec, s, &why));
  EXPECT_EQ(why.rfind("outcome completed, expected aborted", 0), 0u) << why;
}
