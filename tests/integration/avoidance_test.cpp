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

#include <lcm/lcm-cpp.hpp>
#include <rover_msgs/capture_request_t.hpp>
#include <rover_msgs/hazard_query_t.hpp>
#include <rover_msgs/hazard_reply_t.hpp>
#include <rover_msgs/stereo_frame_t.hpp>
#include <rover_msgs/traversability_map_t.hpp>
#include <rover_msgs/vo_update_t.hpp>

#include <cmath>
#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <vector>

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

  // Thinking while driving: on open ground steps were chosen on the map in hand, and the
  // real hazard monitor judged each at once on that map (its reply before the map holding
  // the pair taken where the step began), so the rover drove while that pair was mapped.
  const int ahead = s["rover_time_breakdown"]["steps_thought_ahead"].as<int>();
  EXPECT_GE(ahead, 3);
  EXPECT_LT(ahead, s["rover_time_breakdown"]["steps"].as<int>()) << "near the rocks some steps must wait";
  lcm::LogFile log(std::string(ROVER_BINARY_DIR) + "/test-out/avoidance_rock_field_avoid/log.lcm", "r");
  ASSERT_TRUE(log.good());
  std::int64_t newest_frame = -1, mapped = -1;
  std::map<std::int64_t, std::int64_t> asked;  // query id -> the pair still being mapped
  int answered_before_map = 0, commanded_before_map = 0;
  std::int64_t waiting_for = -1;  // after an answer ahead: the pair whose map has not come
  for (const lcm::LogEvent* e = log.readNextEvent(); e != nullptr; e = log.readNextEvent()) {
    if (e->channel == "STEREO_FRAME") {
      rover_msgs::stereo_frame_t f;
      if (f.decode(e->data, 0, e->datalen) > 0) newest_frame = f.frame_id;
    } else if (e->channel == "TRAVERSABILITY_MAP") {
      rover_msgs::traversability_map_t m;
      if (m.decode(e->data, 0, e->datalen) > 0) mapped = m.last_frame_id;
      if (mapped >= waiting_for) waiting_for = -1;
    } else if (e->channel == "HAZARD_QUERY") {
      rover_msgs::hazard_query_t q;
      if (q.decode(e->data, 0, e->datalen) <= 0 || q.map_frame_id <= 0) continue;
      EXPECT_LE(q.map_frame_id, mapped) << "chosen on a map the monitor never sent";
      EXPECT_LT(mapped, newest_frame) << "query " << q.query_id << ": the newest pair was already mapped";
      asked[q.query_id] = newest_frame;
    } else if (e->channel == "HAZARD_REPLY") {
      rover_msgs::hazard_reply_t r;
      if (r.decode(e->data, 0, e->datalen) <= 0) continue;
      const auto it = asked.find(r.query_id);
      if (it == asked.end()) continue;
      if (mapped < it->second) {
        ++answered_before_map;
        if (r.verdict == rover_msgs::hazard_reply_t::VERDICT_SAFE) waiting_for = it->second;
      }
    } else if (e->channel == "MOBILITY_COMMAND" && waiting_for >= 0) {
      ++commanded_before_map;
      waiting_for = -1;
    }
  }
  EXPECT_EQ(answered_before_map, static_cast<int>(asked.size()));
  EXPECT_GE(static_cast<int>(asked.size()), ahead);
  EXPECT_EQ(commanded_before_map, ahead);
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

// (f) Looking aside (common/avoidance/README.md): the same wall with its gap, cells no pair
// framed unknown, the mast pointed at the ground beside before the body swings over it. End
// to end on the bus: the executor asks for a pointed pair, camera_capture renders it from
// the pointed rig (its models differ from the mounted ones), the hazard monitor maps it
// before the executor votes again, VO leaves it alone, and the goto completes clear of
// every rock.
TEST(Avoidance, TheMastLooksAsideAndTheMapTakesThePointedPair) {
  const YAML::Node s = RunScenario("rock_field_gap_look");
  ASSERT_EQ(s["outcome"].as<std::string>(), "completed") << Detail(s);
  EXPECT_GT(s["min_rock_clearance_m"].as<double>(), 0.0) << s["min_rock_clearance_rock"].as<std::string>("");

  // (RunScenario ran it in test-out/avoidance_rock_field_gap_look; OutDir would empty it.)
  lcm::LogFile log(std::string(ROVER_BINARY_DIR) + "/test-out/avoidance_rock_field_gap_look/log.lcm", "r");
  ASSERT_TRUE(log.good());
  std::map<std::int64_t, double> looks;  // frame id -> pan
  std::set<std::int64_t> pointed_frames, mapped_looks, vo_on_looks;
  std::vector<double> mounted_model;  // a VO frame's left model
  std::int64_t last_mapped = -1;
  for (const lcm::LogEvent* e = log.readNextEvent(); e != nullptr; e = log.readNextEvent()) {
    if (e->channel == "CAPTURE_REQUEST") {
      rover_msgs::capture_request_t m;
      if (m.decode(e->data, 0, e->datalen) > 0 && m.purpose == "look") looks[m.frame_id] = m.pan_rad;
    } else if (e->channel == "STEREO_FRAME") {
      rover_msgs::stereo_frame_t f;
      if (f.decode(e->data, 0, e->datalen) <= 0) continue;
      if (f.purpose == "vo" && mounted_model.empty()) mounted_model = f.left_model.params;
      if (looks.count(f.frame_id) && f.purpose == "look" && !mounted_model.empty() &&
          f.left_model.params != mounted_model)
        pointed_frames.insert(f.frame_id);
    } else if (e->channel == "TRAVERSABILITY_MAP") {
      rover_msgs::traversability_map_t m;
      if (m.decode(e->data, 0, e->datalen) <= 0) continue;
      for (const auto& [id, pan] : looks)
        if (id > last_mapped && id <= m.last_frame_id) mapped_looks.insert(id);
      last_mapped = m.last_frame_id;
    } else if (e->channel == "VO_UPDATE") {
      rover_msgs::vo_update_t u;
      if (u.decode(e->data, 0, e->datalen) > 0 && looks.count(u.to_frame_id)) vo_on_looks.insert(u.to_frame_id);
    }
  }
  ASSERT_FALSE(looks.empty()) << "the rover never looked aside";
  for (const auto& [id, pan] : looks) {
    EXPECT_NEAR(std::abs(pan), 70.0 * M_PI / 180.0, 1e-9) << "frame " << id;
    EXPECT_TRUE(pointed_frames.count(id)) << "no pointed STEREO_FRAME for look " << id;
    EXPECT_TRUE(mapped_looks.count(id)) << "no map holds look " << id;
  }
  EXPECT_TRUE(vo_on_looks.empty()) << "VO ran on " << vo_on_looks.size() << " look pairs";
}

}  // namespace
}  // namespace rover::test
