// The plan on a perfect map (perfect_map_way.hpp), on worlds built here: a wall of tall
// rocks across a strip of flat ground, with a gap of known width, and the rover's radii from
// the shipped rover config.
#include "navbench/perfect_map_way.hpp"

#include "config/yaml_config.hpp"
#include "terrain/world.hpp"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>

namespace nb = rover::navbench;
using rover::terrain::Rock;
using rover::terrain::World;
using rover::terrain::WorldOptions;

namespace {

rover::config::ConfigNode ShippedRoverConfig() {
  return rover::config::ConfigNode::LoadFile(std::string(ROVER_SOURCE_DIR) + "/configs/rover.yaml");
}

// The shipped config with `key: value` set in the executor section.
rover::config::ConfigNode WithExecutorSetting(const std::string& key, const std::string& value) {
  YAML::Node root = YAML::LoadFile(std::string(ROVER_SOURCE_DIR) + "/configs/rover.yaml");
  root["executor"][key] = YAML::Load(value);
  std::stringstream text;
  text << root;
  return rover::config::ConfigNode::FromString(text.str(), "rover.yaml with executor." + key);
}

// Flat ground 20 m along x (-4..16) and 12 m across (-6..6), and a wall of rocks `height_m`
// tall and `d` across at x = 6 from edge to edge but for a gap `gap_m` wide between the
// rocks' rims, centred on y = 0 (no gap: 0).
World Wall(double gap_m, double height_m, double d = 0.6) {
  WorldOptions o;
  o.map_center = {6.0, 0.0};
  o.map_size_m = {20.0, 12.0};
  o.roughness.amplitude_m = 0.0;
  int n = 0;
  auto place = [&](double y) {
    Rock r;
    r.name = "wall_" + std::to_string(n++);
    r.position = {6.0, y};
    r.diameter_m = d;
    r.height_m = height_m;
    r.placed = true;
    o.placed_rocks.push_back(r);
  };
  // Rims touching, out to the map's edges on both sides of the gap.
  for (double y = 0.5 * gap_m + 0.5 * d; y < 6.0 + d; y += d) place(y), place(-y);
  if (gap_m <= 0) place(0.0);
  return World(o);
}

nb::PerfectWay WayAcross(const World& world, const nb::PerfectWayOptions& o) {
  return nb::PlanPerfectWay(nb::PerfectMap(world, o.map), o.planner, {0.0, 0.0}, {12.0, 0.0}, 0.5);
}

}  // namespace

TEST(PerfectMapWay, TheRadiiAreTheExecutorsPlan) {
  // hazards.footprint 1.6 x 1.4 m, executor.avoid_margin_m 0.1 all round, and half a 0.2 m
  // cell more with planner_vote_clearance (SequenceExecutor::PlanSetUp).
  const nb::PerfectWayOptions o = nb::LoadPerfectWayOptions(ShippedRoverConfig());
  EXPECT_NEAR(o.planner.inscribed_radius_m, 0.7 + 0.1 + 0.1, 1e-9);
  EXPECT_NEAR(o.planner.circumscribed_radius_m, 0.5 * std::hypot(1.8, 1.6) + 0.1, 1e-9);
  EXPECT_NEAR(o.map.max_step_m, 0.25, 1e-9);
  const nb::PerfectWayOptions plain = nb::LoadPerfectWayOptions(WithExecutorSetting("planner_vote_clearance", "false"));
  EXPECT_NEAR(plain.planner.inscribed_radius_m, 0.8, 1e-9);
}

TEST(PerfectMapWay, AGapWideEnoughForThePlanIsAWayAndANarrowOneIsNot) {
  const nb::PerfectWayOptions o = nb::LoadPerfectWayOptions(ShippedRoverConfig());
  // 0.5 m rocks: the cells out to their rims are unsafe (each patch holds the rock's
  // rise), and the plan's centre keeps 0.9 m off those cells' centres: a way needs about
  // 2.3 m between the rims (measured: 2.2 m none, 2.3 m one), where the body is 1.4 m wide.
  const nb::PerfectWay wide = WayAcross(Wall(2.6, 0.5), o);
  ASSERT_TRUE(wide.reachable) << wide.why;
  EXPECT_GT(wide.length_m, 11.0);
  EXPECT_LT(wide.length_m, 13.0);
  // 1.8 m: the body (1.4 m) would pass the rims, but not the cells the map rates unsafe
  // round them with the plan's clearance.
  const nb::PerfectWay narrow = WayAcross(Wall(1.8, 0.5), o);
  EXPECT_FALSE(narrow.reachable);
  EXPECT_NE(narrow.why.find("0.90 m from every obstacle"), std::string::npos) << narrow.why;
}

TEST(PerfectMapWay, NoWayLeavesTheWorldsMap) {
  // A wall from edge to edge: the grid beyond the map would go round it; the map's edge
  // is an obstacle.
  const nb::PerfectWay shut = WayAcross(Wall(0.0, 0.5), nb::LoadPerfectWayOptions(ShippedRoverConfig()));
  EXPECT_FALSE(shut.reachable);
}

TEST(PerfectMapWay, RocksUnderTheStepLimitAreNoObstacle) {
  // The same shut wall of 0.12 m rocks: the map's rating lets the rover over them.
  const nb::PerfectWay low = WayAcross(Wall(0.0, 0.12), nb::LoadPerfectWayOptions(ShippedRoverConfig()));
  ASSERT_TRUE(low.reachable) << low.why;
  EXPECT_LT(low.length_m, 12.5);
}

TEST(PerfectMapWay, ReadAtTheCellsMeanAWallOfRocksOverTheBellyIsCrossed) {
  // Rocks 0.32 m tall and 0.4 m across, rims touching, from edge to edge: over the belly's
  // 0.30 m clearance. At each cell's highest point the map's 0.25 m step limit shuts them;
  // at each cell's mean (what the map's cells measure, even from exact points) a 0.2 m
  // cell on a narrow rock averages its rise away, every cell reads under the limit, and
  // the plan drives the body over them: the map's mean is the collisions' cause, and the
  // limit was set against it.
  const nb::PerfectWayOptions o = nb::LoadPerfectWayOptions(ShippedRoverConfig());
  const World wall = Wall(0.0, 0.32, 0.4);
  EXPECT_FALSE(nb::PlanPerfectWay(nb::PerfectMap(wall, o.map), o.planner, {0.0, 0.0}, {12.0, 0.0}, 0.5).reachable);
  const nb::PerfectWay at_mean =
      nb::PlanPerfectWay(nb::PerfectMap(wall, o.map, true), o.planner, {0.0, 0.0}, {12.0, 0.0}, 0.5);
  ASSERT_TRUE(at_mean.reachable) << at_mean.why;
  EXPECT_LT(at_mean.length_m, 12.5);
}
