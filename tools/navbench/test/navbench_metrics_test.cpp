// Known answers for navbench's judge against truth and for its table (navbench_metrics.hpp).
#include "navbench/navbench_metrics.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

namespace nb = rover::navbench;
using rover::hazards::Footprint;
using rover::hazards::KeepOutZone;
using rover::hazards::Pose2;

namespace {

constexpr double kPi = 3.14159265358979323846;

Footprint MerFootprint() {
  Footprint f;
  f.length_m = 1.6;
  f.width_m = 1.4;
  return f;
}

// x from x0 to x1 in steps of 0.1 m at y, heading north.
std::vector<Pose2> StraightNorth(double x0, double x1, double y) {
  std::vector<Pose2> track;
  for (int i = 0; x0 + 0.1 * i <= x1 + 1e-9; ++i) track.push_back({x0 + 0.1 * i, y, 0.0});
  return track;
}

}  // namespace

TEST(NavbenchJudge, DrivingThroughARockIsOneContact) {
  // The footprint's front edge is 0.8 m ahead of the origin; the rock's edge at 1.5 m.
  const auto report = nb::JudgeCollisions(StraightNorth(0, 3, 0), MerFootprint(), {KeepOutZone::Circle("boulder", 2, 0, 0.5)});
  EXPECT_EQ(report.contacts, 1);
  // The first pose whose front edge passes 1.5 m: x = 0.8 m (0.7 m just touches).
  ASSERT_EQ(report.contact_samples.size(), 1u);
  EXPECT_NEAR(0.1 * static_cast<double>(report.contact_samples[0]), 0.75, 0.051);
  ASSERT_EQ(report.touched.size(), 1u);
  EXPECT_EQ(report.touched[0], "boulder");
  ASSERT_TRUE(report.min_clearance_m);
  EXPECT_LT(*report.min_clearance_m, 0.0);
}

TEST(NavbenchJudge, PassingBesideARockKeepsItsExactGap) {
  // Abeam at y = 1.5: the gap is 1.5 - 0.7 (half the width) - 0.5 (the radius) = 0.3 m.
  const auto report = nb::JudgeCollisions(StraightNorth(0, 4, 1.5), MerFootprint(), {KeepOutZone::Circle("boulder", 2, 0, 0.5)});
  EXPECT_EQ(report.contacts, 0);
  EXPECT_TRUE(report.touched.empty());
  ASSERT_TRUE(report.min_clearance_m);
  EXPECT_NEAR(*report.min_clearance_m, 0.3, 1e-9);
  EXPECT_EQ(report.closest, "boulder");
}

// Rocks as the simulator judges them: a contact only where the surface under the footprint
// rises over the 0.3 m clearance. Rocks 0.31 m tall and 0.39 m in radius (half-ellipsoids)
// beside a drive north along y = 0, the footprint's side at y = -0.7: one whose centre lies
// 0.35 m beyond the side is grazed (0.14 m of rim under it), one 0.05 m beyond is hit
// (0.307 m); any overlap counts for JudgeCollisions.
TEST(NavbenchJudge, ARocksRimUnderTheFootprintIsAGrazeNotAContact) {
  const std::vector<KeepOutZone> rocks = {KeepOutZone::Circle("rim", 2, -1.05, 0.39),
                                          KeepOutZone::Circle("side", 5, -0.75, 0.39),
                                          KeepOutZone::Circle("far", 8, -1.3, 0.39)};
  const nb::SurfaceHeight dome = [](std::size_t, double gap_m) {
    const double u = gap_m * gap_m / (0.39 * 0.39);
    return u < 1 ? 0.31 * std::sqrt(1 - u) : 0.0;
  };
  const auto track = StraightNorth(0, 9, 0);
  const auto report = nb::JudgeRockCollisions(track, MerFootprint(), rocks, dome, 0.3);
  EXPECT_EQ(report.contacts, 1);
  ASSERT_EQ(report.touched.size(), 1u);
  EXPECT_EQ(report.touched[0], "side");
  ASSERT_EQ(report.grazed.size(), 1u);
  EXPECT_EQ(report.grazed[0], "rim");
  // The side rock is hit from where the front edge comes within 0.085 m of its centre's x
  // (its surface 0.098 m from the centre is 0.3 m high): the pose at x = 4.2.
  ASSERT_EQ(report.contact_samples.size(), 1u);
  EXPECT_NEAR(track[report.contact_samples[0]].x, 4.2, 0.051);
  // Any overlap: both rims and the side rock are contacts.
  EXPECT_EQ(nb::JudgeCollisions(track, MerFootprint(), rocks).contacts, 2);
  // A lower rock under the same corner: no contact, a graze.
  const nb::SurfaceHeight low = [&](std::size_t i, double gap_m) { return 0.9 * dome(i, gap_m); };
  const auto lower = nb::JudgeRockCollisions(track, MerFootprint(), rocks, low, 0.3);
  EXPECT_EQ(lower.contacts, 0);
  EXPECT_EQ(lower.grazed.size(), 2u);
  // In the run's figures the graze is no collision, and the table names the runs with one.
  nb::RunFigures r;
  r.group = "k=0.30";
  r.ran = true;
  r.outcome = "completed";
  r.in_goal_disc = true;
  r.rock_grazes = static_cast<int>(report.grazed.size());
  EXPECT_EQ(r.Verdict(), "success");
  const nb::GroupFigures g = nb::Aggregate("k=0.30", {r});
  EXPECT_EQ(g.runs_with_collision, 0);
  EXPECT_EQ(g.runs_with_graze, 1);
  EXPECT_NE(nb::TableText({g}).find("grazed a rock over the collision height"), std::string::npos);
  EXPECT_NE(nb::ResultsJson({g}, {r}, "navbench").find("\"rock_grazes\": 1"), std::string::npos);
}

TEST(NavbenchJudge, EachEntryIsAContactAndZonesCount) {
  // North through the rock, back south out of it, north into it again: two contacts. A
  // square zone beside the start, overlapped at the first pose (one contact), is left at
  // x = 1.8 m and entered again on the way back, where the rover stays in it: two.
  std::vector<Pose2> track = StraightNorth(0, 3, 0);
  const auto back = StraightNorth(0, 3, 0);
  track.insert(track.end(), back.rbegin(), back.rend());
  track.insert(track.end(), back.begin(), back.end());
  const KeepOutZone zone = KeepOutZone::Polygon("square", {{-1, -1.2}, {1, -1.2}, {1, -0.5}, {-1, -0.5}});
  const auto report = nb::JudgeCollisions(track, MerFootprint(), {KeepOutZone::Circle("boulder", 2, 0, 0.5), zone});
  EXPECT_EQ(report.contacts, 2 + 2);
  ASSERT_EQ(report.touched.size(), 2u);
  EXPECT_EQ(report.touched[0], "square");
  EXPECT_EQ(report.touched[1], "boulder");
}

TEST(NavbenchJudge, FarObstaclesAreNotMeasured) {
  const auto report = nb::JudgeCollisions(StraightNorth(0, 3, 0), MerFootprint(), {KeepOutZone::Circle("far", 100, 100, 1)});
  EXPECT_EQ(report.contacts, 0);
  EXPECT_FALSE(report.min_clearance_m);
}

TEST(NavbenchJudge, TheGridFindsWhatEveryPairFinds) {
  // Random rocks and a wandering track: the judge's smallest clearance equals the one over
  // every pose and rock, wherever that is within the footprint's reach.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> pos(-10, 10), rad(0.05, 0.75), step(-0.3, 0.3), turn(-0.3, 0.3);
  std::vector<KeepOutZone> rocks;
  for (int i = 0; i < 300; ++i) {
    std::string name = std::to_string(i);
    name.insert(0, 1, 'r');
    const double x = pos(rng), y = pos(rng);
    rocks.push_back(KeepOutZone::Circle(name, x, y, rad(rng)));
  }
  std::vector<Pose2> track = {{0, 0, 0}};
  for (int i = 0; i < 400; ++i) {
    const Pose2& p = track.back();
    const double yaw = p.yaw + turn(rng), d = std::abs(step(rng));
    track.push_back({p.x + d * std::cos(yaw), p.y + d * std::sin(yaw), yaw});
  }
  const Footprint f = MerFootprint();
  double brute = std::numeric_limits<double>::infinity();
  int overlapping_pairs = 0;
  for (const auto& p : track) {
    for (const auto& r : rocks) {
      const double c = rover::hazards::Clearance(r, f, p);
      brute = std::min(brute, c);
      overlapping_pairs += c < 0;
    }
  }
  const auto report = nb::JudgeCollisions(track, f, rocks);
  ASSERT_TRUE(report.min_clearance_m);
  EXPECT_DOUBLE_EQ(*report.min_clearance_m, brute);
  EXPECT_EQ(report.contacts > 0, overlapping_pairs > 0);
}

TEST(NavbenchWheels, AWheelOverTheEdgeIsOffTheMap) {
  const nb::MapBounds map{-5, 5, -5, 5};
  const auto wheels = nb::SixWheels(1.1, 1.0);
  ASSERT_EQ(wheels.size(), 6u);
  // Front wheels at x + 0.55: inside at 4.4, outside at 4.5.
  EXPECT_EQ(nb::WheelsOffMap({{4.4, 0, 0}}, wheels, map).samples, 0);
  const auto off = nb::WheelsOffMap({{4.4, 0, 0}, {4.5, 0, 0}, {4.6, 0, 0}}, wheels, map);
  EXPECT_EQ(off.samples, 2);
  ASSERT_TRUE(off.first);
  EXPECT_NEAR(off.first->x(), 5.05, 1e-9);
  // Heading east (yaw 90 deg): the side wheels stick out 0.5 m north and south; the front
  // ones 0.55 m east.
  EXPECT_EQ(nb::WheelsOffMap({{4.45, 4.4, kPi / 2}}, wheels, map).samples, 0);
  EXPECT_EQ(nb::WheelsOffMap({{4.55, 4.4, kPi / 2}}, wheels, map).samples, 1);
  EXPECT_EQ(nb::WheelsOffMap({{0, 4.5, kPi / 2}}, wheels, map).samples, 1);
}

TEST(NavbenchPath, LengthRatioAndMedian) {
  EXPECT_NEAR(nb::PathLength({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 0}}), 4.0, 1e-12);
  EXPECT_NEAR(*nb::PathRatio(12.0, {0, 0}, {6, 8}), 1.2, 1e-12);
  EXPECT_FALSE(nb::PathRatio(3.0, {1, 1}, {1, 1}));
  EXPECT_EQ(*nb::Median({3, 1, 2}), 2.0);
  EXPECT_EQ(*nb::Median({4, 1, 3, 2}), 2.5);
  EXPECT_FALSE(nb::Median({}));
}

// Round one rock from (0, 0) to (10, 0): the centre keeps 0.5 m off a 1 m disc at (5, 0),
// so the shortest way is the two tangents to the 1.5 m circle and the arc between them,
// less the last 0.3 m (the goal disc): 2 sqrt(5^2 - 1.5^2) + 1.5 (pi - 2 acos(1.5 / 5)) - 0.3.
TEST(NavbenchShortest, RoundOneRockIsTangentsAndArc) {
  const std::vector<KeepOutZone> rocks = {KeepOutZone::Circle("rock", 5.0, 0.0, 1.0)};
  const nb::MapBounds map{-3, 13, -6, 6};
  const double expected = 2 * std::sqrt(25.0 - 2.25) + 1.5 * (kPi - 2 * std::acos(0.3)) - 0.3;
  const nb::ShortestPath best = nb::ShortestSafePath(rocks, 0.5, {0, 0}, {10, 0}, 0.3, map);
  ASSERT_TRUE(best.length_m);
  EXPECT_NEAR(*best.length_m, expected, 0.05);  // 10.15 m: the grid's 8-connected way is longer
  EXPECT_GT(*best.length_m, 9.7 + 0.3);
  // Every leg keeps (nearly: a cell's allowance) 0.5 m off the rock.
  for (std::size_t k = 1; k < best.path.size(); ++k) {
    const Eigen::Vector2d a = best.path[k - 1], b = best.path[k], c(5, 0);
    const double t = std::clamp((c - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
    EXPECT_GT((a + t * (b - a) - c).norm(), 1.5 - 0.08);
  }
  // No rock: the straight line, to the disc's edge.
  const nb::ShortestPath open = nb::ShortestSafePath({}, 0.5, {0, 0}, {10, 0}, 0.3, map);
  ASSERT_TRUE(open.length_m);
  EXPECT_NEAR(*open.length_m, 9.7, 0.02);
  // A wall of rocks from edge to edge of the map: no way.
  std::vector<KeepOutZone> wall;
  for (double y = -6; y <= 6; y += 0.5) wall.push_back(KeepOutZone::Circle("w", 5.0, y, 0.4));
  EXPECT_FALSE(nb::ShortestSafePath(wall, 0.5, {0, 0}, {10, 0}, 0.3, map).length_m);
  // A 1.2 m gap in it (between the rocks at y 1 and 3): a centre kept 0.5 m off passes
  // 1.9 to 2.1 m east, by the nearer edge; one kept 0.7 m off cannot.
  std::vector<KeepOutZone> gap;
  for (const auto& z : wall)
    if (std::abs(z.center.y() - 2.0) > 0.9) gap.push_back(z);
  const nb::ShortestPath through = nb::ShortestSafePath(gap, 0.5, {0, 0}, {10, 0}, 0.3, map);
  ASSERT_TRUE(through.length_m);
  EXPECT_NEAR(*through.length_m, 2 * std::hypot(5.0, 1.9) - 0.3, 0.1);
  EXPECT_FALSE(nb::ShortestSafePath(gap, 0.7, {0, 0}, {10, 0}, 0.3, map).length_m);
}

TEST(NavbenchTable, RowsCountWhatTheRunsSay) {
  auto run = [](const std::string& outcome, const std::string& reason, bool in_disc, int rocks, int off_map,
                double driven, double ratio, double time_s) {
    nb::RunFigures r;
    r.group = "k=0.15";
    r.ran = outcome != "incomplete";
    r.outcome = outcome;
    r.abort_reason = reason;
    r.in_goal_disc = in_disc;
    r.rock_contacts = rocks;
    r.off_map_samples = off_map;
    r.driven_m = driven;
    r.path_ratio = ratio;
    r.rover_time_s = time_s;
    r.driving_s = 0.5 * time_s;
    r.planning_s = 0.125 * time_s;
    r.vo_accepted = 10;
    r.vo_false = 1;
    r.horizontal_poses = r.ran ? 100 : 0;
    r.horizontal_nees_mean = driven > 25 ? 4.0 : 1.0;
    r.horizontal_beyond_pct = driven > 25 ? 2.0 : 0.0;
    return r;
  };
  std::vector<nb::RunFigures> runs = {
      run("completed", "", true, 0, 0, 22, 1.1, 1000),         // success
      run("completed", "", true, 0, 0, 26, 1.3, 1000),         // success
      run("completed", "", true, 1, 0, 30, 1.5, 1000),         // touched a rock: no success, no safe abort
      run("completed", "", false, 0, 0, 20, 1.0, 1000),        // ended outside the disc by truth
      run("aborted", "goto_distance_limit", false, 0, 0, 60, 3.0, 3000),
      run("aborted", "hazard_map", false, 0, 0, 5, 0.25, 400),
      run("aborted", "hazard_map", false, 0, 2, 5, 0.25, 400),  // a wheel off the map: not safe
      run("incomplete", "", false, 0, 0, 0, 0, 0),
  };
  nb::RunFigures other = runs[0];
  other.group = "k=0.05";
  runs.push_back(other);
  const nb::GroupFigures g = nb::Aggregate("k=0.15", runs);
  EXPECT_EQ(g.runs, 8);
  EXPECT_EQ(g.successes, 2);
  EXPECT_EQ(g.completed, 4);
  EXPECT_EQ(g.runs_with_collision, 1);
  EXPECT_EQ(g.runs_off_map, 1);
  EXPECT_EQ(g.runs_left_map, 1);  // off the map without a collision: apart from navigation
  EXPECT_EQ(g.navigation_runs(), 7);
  EXPECT_NEAR(g.success_pct(), 100.0 * 2 / 7, 1e-12);
  EXPECT_EQ(g.safe_aborts.size(), 3u);
  EXPECT_EQ(g.safe_aborts.at("goto_distance_limit"), 1);
  EXPECT_EQ(g.safe_aborts.at("hazard_map"), 1);
  EXPECT_EQ(g.safe_aborts.at("incomplete"), 1);
  ASSERT_TRUE(g.median_path_ratio);
  EXPECT_NEAR(*g.median_path_ratio, 1.2, 1e-12);  // the two successes: 1.1 and 1.3
  ASSERT_TRUE(g.drive_rate_m_per_h);
  EXPECT_NEAR(g.driven_m, 168.0, 1e-9);
  EXPECT_NEAR(g.rover_time_s, 7800.0, 1e-9);
  EXPECT_NEAR(*g.drive_rate_m_per_h, 168.0 / 7800.0 * 3600.0, 1e-9);
  EXPECT_NEAR(g.driving_s, 3900.0, 1e-9);
  EXPECT_NEAR(g.planning_s, 975.0, 1e-9);
  EXPECT_EQ(g.vo_accepted, 70);
  EXPECT_EQ(g.vo_false, 7);
  // Pose honesty pooled by poses: 7 runs ran, 3 of them (26, 30 and 60 m) at NEES 4 and
  // 2 % beyond the bound, 4 at NEES 1 and none beyond.
  EXPECT_EQ(g.horizontal_poses, 700);
  ASSERT_TRUE(g.horizontal_nees_mean && g.horizontal_beyond_pct);
  EXPECT_NEAR(*g.horizontal_nees_mean, (3 * 4.0 + 4 * 1.0) / 7, 1e-12);
  EXPECT_NEAR(*g.horizontal_beyond_pct, 3 * 2.0 / 7, 1e-12);
  const std::string text = nb::TableText({g});
  EXPECT_NE(text.find("2 of 7 (28.6 %)"), std::string::npos) << text;
  EXPECT_NE(text.find("hazard_map 1"), std::string::npos) << text;
  EXPECT_NE(text.find("77.5"), std::string::npos) << text;  // 168 m in 7800 s: 77.5 m/h
  EXPECT_NE(text.find("50.0 %"), std::string::npos) << text;  // driving share
  EXPECT_NE(text.find("12.5 %"), std::string::npos) << text;  // planning share
  EXPECT_NE(text.find("pose honesty"), std::string::npos) << text;
  EXPECT_NE(text.find("2.29"), std::string::npos) << text;    // the pooled NEES, 16 / 7
}

// The plan on a perfect map (RunFigures::perfect_way): worlds with a way counted among those
// checked, and success counted among the navigation runs in worlds with one; no line when no
// run was checked.
TEST(NavbenchTable, WorldsWithAWayOnAPerfectMapAreCountedApart) {
  auto run = [](bool success, std::optional<bool> way, int off_map) {
    nb::RunFigures r;
    r.group = "k=0.30";
    r.ran = true;
    r.outcome = success ? "completed" : "aborted";
    r.abort_reason = success ? "" : "goal_unreachable";
    r.in_goal_disc = success;
    r.off_map_samples = off_map;
    r.perfect_way = way;
    r.perfect_way_m = way && *way ? 30.0 : 0.0;
    return r;
  };
  const std::vector<nb::RunFigures> runs = {
      run(true, true, 0),  run(false, true, 0), run(false, true, 3),  // one left the map
      run(false, false, 0), run(false, false, 0), run(true, std::nullopt, 0),
  };
  const nb::GroupFigures g = nb::Aggregate("k=0.30", runs);
  EXPECT_EQ(g.runs_way_checked, 5);
  EXPECT_EQ(g.runs_with_way, 3);
  EXPECT_EQ(g.successes_with_way, 1);
  EXPECT_EQ(g.navigation_runs_with_way, 2);
  const std::string text = nb::TableText({g});
  EXPECT_NE(text.find("the plan on a perfect map"), std::string::npos) << text;
  EXPECT_NE(text.find("3 of 5"), std::string::npos) << text;
  EXPECT_NE(text.find("1 of 2 (50.0 %)"), std::string::npos) << text;
  const std::string json = nb::ResultsJson({g}, runs, "navbench");
  EXPECT_NE(json.find("\"runs_with_way\": 3"), std::string::npos) << json;
  EXPECT_NE(json.find("\"perfect_way\": false"), std::string::npos) << json;
  EXPECT_NE(json.find("\"perfect_way_m\": 30"), std::string::npos) << json;
  nb::GroupFigures unchecked = nb::Aggregate("k=0.30", {run(true, std::nullopt, 0)});
  EXPECT_EQ(nb::TableText({unchecked}).find("the plan on a perfect map"), std::string::npos);
}

// The verdict of a run judged from synthetic truth tracks on a 20 x 10 m map (x -2 to 18,
// y -5 to 5) from (0, 0) to (15, 0): a detour that swings its wheels past the map's east
// edge and comes back to the goal left the map (not a navigation failure, and not in the
// success figure's runs); a track that also drives through a rock over the limit is a
// collision, whatever the map; a straight drive is a success.
TEST(NavbenchVerdict, LeavingTheMapIsApartFromNavigation) {
  const nb::MapBounds map{-2, 18, -5, 5};
  const auto wheels = nb::SixWheels(1.1, 1.0);
  const std::vector<KeepOutZone> rocks = {KeepOutZone::Circle("rock", 7.5, 4.0, 0.3)};
  auto judge = [&](const std::vector<Pose2>& track) {
    nb::RunFigures r;
    r.group = "k=0.30";
    r.ran = true;
    r.outcome = "completed";
    r.in_goal_disc = std::hypot(track.back().x - 15, track.back().y) <= 0.5;
    r.rock_contacts = nb::JudgeCollisions(track, MerFootprint(), rocks).contacts;
    r.off_map_samples = nb::WheelsOffMap(track, wheels, map).samples;
    return r;
  };
  // Straight: 2.2 m clear of the rock's edge (3.7 m minus the footprint's half width 0.7 and
  // the rock's 0.3 m), on the map.
  const nb::RunFigures straight = judge(StraightNorth(0, 15, 0));
  EXPECT_EQ(straight.Verdict(), "success");
  // A detour out to y = 4.8 (wheels 0.5 m further, past 5) between x 9 and 12, then back.
  std::vector<Pose2> detour;
  for (const auto& p : StraightNorth(0, 15, 0)) detour.push_back({p.x, (p.x >= 9 && p.x <= 12) ? 4.8 : 0.0, 0.0});
  const nb::RunFigures off = judge(detour);
  EXPECT_GT(off.off_map_samples, 0);
  EXPECT_EQ(off.rock_contacts, 0);
  EXPECT_TRUE(off.left_map());
  EXPECT_FALSE(off.success());
  EXPECT_EQ(off.Verdict(), "left the map");
  // The same detour begun at x 7 (through the rock at (7.5, 4)): a collision first.
  std::vector<Pose2> through;
  for (const auto& p : StraightNorth(0, 15, 0)) through.push_back({p.x, (p.x >= 7 && p.x <= 12) ? 4.8 : 0.0, 0.0});
  const nb::RunFigures hit = judge(through);
  EXPECT_GT(hit.rock_contacts, 0);
  EXPECT_FALSE(hit.left_map());
  EXPECT_EQ(hit.Verdict(), "collision");
  // The group: three runs, one left the map, so success is 1 of the 2 that stayed on it.
  const nb::GroupFigures g = nb::Aggregate("k=0.30", {straight, off, hit});
  EXPECT_EQ(g.runs, 3);
  EXPECT_EQ(g.runs_left_map, 1);
  EXPECT_EQ(g.runs_off_map, 2);
  EXPECT_EQ(g.navigation_runs(), 2);
  EXPECT_EQ(g.successes, 1);
  EXPECT_EQ(g.runs_with_collision, 1);
  EXPECT_NEAR(g.success_pct(), 50.0, 1e-12);
  EXPECT_NE(nb::TableText({g}).find("1 of 2 (50.0 %)"), std::string::npos) << nb::TableText({g});
  // In results.json: each run's verdict, and the group's left-map and navigation runs.
  const std::string json = nb::ResultsJson({g}, {straight, off, hit}, "navbench");
  EXPECT_NE(json.find("\"verdict\": \"left the map\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"runs_left_map\": 1"), std::string::npos) << json;
  EXPECT_NE(json.find("\"navigation_runs\": 2"), std::string::npos) << json;
}

// The verdicts of runs that neither collided nor left the map.
TEST(NavbenchVerdict, OtherOutcomes) {
  nb::RunFigures r;
  r.outcome = "completed";
  EXPECT_EQ(r.Verdict(), "missed the goal");  // completed outside the goal disc by truth
  r.outcome = "aborted";
  r.abort_reason = "hazard_map";
  EXPECT_EQ(r.Verdict(), "aborted (hazard_map)");
  r.outcome = "incomplete";
  EXPECT_EQ(r.Verdict(), "incomplete");
}
