// The runs navbench draws (navbench_run.hpp): reproducible from the seed, each world kind
// independent of the others, goals in range, and every world, sequence and scenario it
// writes accepted by the loaders the runner and the processes use.
#include "navbench/navbench_run.hpp"

#include "config/yaml_config.hpp"
#include "scenario/scenario.hpp"
#include "sequence/parser.hpp"
#include "terrain/world.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <variant>

namespace nb = rover::navbench;
namespace fs = std::filesystem;

namespace {

nb::BenchOptions Options(const std::string& out) {
  nb::BenchOptions o;
  o.runs = 5;
  o.out_dir = out;
  return o;
}

}  // namespace

TEST(NavbenchPlan, RunsAreDrawnFromTheSeedAlone) {
  const auto a = nb::PlanRuns(Options("/tmp/a"));
  const auto b = nb::PlanRuns(Options("/tmp/b"));
  ASSERT_EQ(a.size(), 6u * 5u);  // 4 densities and 2 fixed worlds
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].id, b[i].id);
    EXPECT_EQ(a[i].world_seed, b[i].world_seed);
    EXPECT_EQ(a[i].goal_x, b[i].goal_x);
    EXPECT_EQ(a[i].goal_y, b[i].goal_y);
  }
  auto other = Options("/tmp/a");
  other.seed = 2;
  EXPECT_NE(nb::PlanRuns(other)[0].world_seed, a[0].world_seed);
}

TEST(NavbenchPlan, OneDensityAloneDrawsTheSameRuns) {
  auto alone = Options("/tmp/a");
  alone.densities = {0.15};
  alone.worlds.clear();
  const auto some = nb::PlanRuns(alone);
  const auto all = nb::PlanRuns(Options("/tmp/a"));
  ASSERT_EQ(some.size(), 5u);
  for (const auto& run : some) {
    bool found = false;
    for (const auto& other : all) {
      if (other.id != run.id) continue;
      found = true;
      EXPECT_EQ(other.world_seed, run.world_seed);
      EXPECT_EQ(other.goal_x, run.goal_x);
      EXPECT_EQ(other.start_yaw_deg, run.start_yaw_deg);
    }
    EXPECT_TRUE(found) << run.id;
  }
}

TEST(NavbenchPlan, GoalsLieInRangeAndFaceTheRover) {
  for (const auto& run : nb::PlanRuns(Options("/tmp/a"))) {
    if (!run.abundance_k) {
      EXPECT_FALSE(run.world_file.empty());
      continue;
    }
    EXPECT_GE(run.straight_m(), 20.0 - 1e-9) << run.id;
    EXPECT_LE(run.straight_m(), 50.0 + 1e-9) << run.id;
    const double bearing_deg = std::atan2(run.goal_y, run.goal_x) * 180 / 3.14159265358979323846;
    const double off = std::remainder(run.start_yaw_deg - bearing_deg, 360.0);
    EXPECT_LE(std::abs(off), 30.0 + 1e-9) << run.id;
  }
}

TEST(NavbenchPlan, WrittenFilesLoad) {
  fs::current_path(ROVER_SOURCE_DIR);  // configs/ are relative to the project, as for ./rover
  const std::string out = (fs::temp_directory_path() / "navbench_plan_test").string();
  fs::remove_all(out);
  auto options = Options(out);
  options.runs = 1;
  for (const auto& run : nb::PlanRuns(options)) {
    nb::WriteRun(run);
    const auto spec = rover::tools::LoadScenario(run.scenario_path());
    EXPECT_EQ(spec.expect_outcome, "completed");
    // Submitted under a name without the output folder: the log (and its digest) is the
    // same wherever --out points.
    EXPECT_EQ(spec.sequence_name, "navbench/" + run.id + "/goto.seq");
    EXPECT_EQ(spec.sequence_name.find(out), std::string::npos) << spec.sequence_name;
    EXPECT_NE(spec.sequence.find(out), std::string::npos) << spec.sequence;
    // The world: the rock field as drawn, with the start and goal kept clear.
    const auto world_options = rover::terrain::WorldOptions::LoadFile(spec.world);
    if (run.abundance_k) {
      EXPECT_DOUBLE_EQ(world_options.random_rocks.abundance_k, *run.abundance_k);
      EXPECT_DOUBLE_EQ(world_options.random_rocks.max_diameter_m, 1.5);
      EXPECT_EQ(world_options.random_rocks.exclude.size(), 2u);
      const Eigen::Vector2d half = 0.5 * world_options.map_size_m;
      EXPECT_LT(std::abs(run.goal_x - world_options.map_center.x()), half.x() - 10);
      EXPECT_LT(std::abs(run.goal_y - world_options.map_center.y()), half.y() - 10);
      EXPECT_LT(std::abs(world_options.map_center.x()), half.x() - 10);
    }
    // The sequence: one goto to the goal with avoidance.
    const auto parsed = rover::sequence::ParseSequence(nb::SequenceText(run), run.id);
    ASSERT_TRUE(parsed.ok()) << nb::SequenceText(run);
    const auto* go = std::get_if<rover::sequence::Goto>(&parsed.sequence.commands.back().action);
    ASSERT_NE(go, nullptr);
    EXPECT_TRUE(go->avoid);
    EXPECT_NEAR(go->target.x(), run.goal_x, 1e-3);
    EXPECT_NEAR(go->target.y(), run.goal_y, 1e-3);
    EXPECT_DOUBLE_EQ(go->tolerance_m, run.goal_radius_m);
    ASSERT_TRUE(go->distance_limit_m);
    EXPECT_GE(*go->distance_limit_m, 3 * run.straight_m());
  }
  fs::remove_all(out);
}

// --set KEY=VALUE: each setting lands in every run's scenario overrides, after the map's own,
// with its YAML type; and a setting of the map's own key replaces it.
TEST(NavbenchPlan, SettingsGoIntoEveryRunsOverrides) {
  fs::current_path(ROVER_SOURCE_DIR);
  const std::string out = (fs::temp_directory_path() / "navbench_set_test").string();
  fs::remove_all(out);
  auto options = Options(out);
  options.runs = 1;
  options.overrides = {nb::ParseSetting("hazards.map.traversability.unframed_unknown=true"),
                       nb::ParseSetting("executor.avoid_margin_m=0.2")};
  const auto runs = nb::PlanRuns(options);
  ASSERT_FALSE(runs.empty());
  for (const auto& run : runs) {
    nb::WriteRun(run, options.overrides);
    const auto spec = rover::tools::LoadScenario(run.scenario_path());
    // Found by key: the scenario's seeds become overrides of their own.
    auto find = [&spec](const std::string& key) -> const rover::tools::ConfigOverride* {
      for (const auto& o : spec.overrides)
        if (o.key == key) return &o;
      return nullptr;
    };
    const auto* map = find("hazards.map.enabled");
    const auto* unframed = find("hazards.map.traversability.unframed_unknown");
    const auto* margin = find("executor.avoid_margin_m");
    ASSERT_TRUE(map && unframed && margin) << run.id;
    EXPECT_TRUE(map->value.as<bool>());
    EXPECT_TRUE(unframed->value.as<bool>());
    EXPECT_DOUBLE_EQ(margin->value.as<double>(), 0.2);
    EXPECT_LT(map, unframed);  // in order: the map's own, then the settings
    EXPECT_LT(unframed, margin);
  }
  const auto off = nb::ParseSetting("hazards.map.enabled=false");
  nb::WriteRun(runs.front(), {off});
  const auto spec = rover::tools::LoadScenario(runs.front().scenario_path());
  int map_keys = 0;
  for (const auto& o : spec.overrides)
    if (o.key == "hazards.map.enabled") {
      ++map_keys;
      EXPECT_FALSE(o.value.as<bool>());
    }
  EXPECT_EQ(map_keys, 1);
  fs::remove_all(out);
}

TEST(NavbenchPlan, ABadSettingIsAOneLineErrorNamingIt) {
  for (const std::string bad : {"executor.avoid_margin_m", "=0.2", "executor..x=1", "executor.x=", "a.b=[1, 2"}) {
    try {
      nb::ParseSetting(bad);
      ADD_FAILURE() << bad << " was accepted";
    } catch (const rover::config::ConfigError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("--set \"" + bad + "\""), std::string::npos) << what;
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    }
  }
  EXPECT_EQ(nb::ParseSetting("a.b=[1, 2]").value.size(), 2u);
}
