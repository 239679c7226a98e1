// Known answers for ACE-style clearance: flat ground, a rock under each wheel, under the
// belly and between the wheels, a slope, and unknown or uncertain ground, on a synthetic
// height map. The expected angles follow from the suspension's geometry by hand: a rock h
// under one wheel turns that wheel's bogie or rocker about the other end.
#include "clearance/clearance.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace rover::clearance {
namespace {

constexpr double kCell = 0.05;

// A level, fully known map round the origin, cell centres on multiples of kCell.
struct TestMap {
  int n = 81;
  std::vector<float> elevation = std::vector<float>(81 * 81, 0.0f);
  std::vector<float> sigma = std::vector<float>(81 * 81, 0.0f);
  HeightMap View() const {
    HeightMap m;
    m.origin_x = m.origin_y = -(n / 2) * kCell - 0.5 * kCell;
    m.cell_m = kCell;
    m.rows = m.cols = n;
    m.elevation_m = elevation.data();
    m.sigma_m = sigma.data();
    return m;
  }
  std::size_t At(double x, double y) const {
    const HeightMap m = View();
    const long i = std::lround((x - m.origin_x) / kCell - 0.5), j = std::lround((y - m.origin_y) / kCell - 0.5);
    return static_cast<std::size_t>(i) * n + j;
  }
  void Set(double x, double y, float h) { elevation[At(x, y)] = h; }
  void Unknown(double x, double y) { sigma[At(x, y)] = -1.0f; }
};

Bounds At(const Suspension& s, const TestMap& map, const Excused* excused = nullptr) {
  return Evaluate(s, SampleTerrain(s, map.View(), Pose{}, excused));
}

double Deg(double rad) { return rad * 180.0 / M_PI; }

TEST(AceClearance, FlatGroundGivesTheNominalClearanceAndNoAngles) {
  const Suspension s;
  const Bounds b = At(s, TestMap{});
  ASSERT_TRUE(b.Safe()) << b.violation;
  EXPECT_NEAR(b.min_clearance_m, s.belly_height_m, 1e-9);
  EXPECT_NEAR(b.max_rocker_rad, 0.0, 1e-12);
  EXPECT_NEAR(b.max_bogie_rad, 0.0, 1e-12);
  EXPECT_NEAR(b.max_roll_rad, 0.0, 1e-12);
  EXPECT_NEAR(b.max_pitch_rad, 0.0, 1e-12);
  EXPECT_NEAR(b.margin, 1.0, 1e-9);
}

// A rock h under one wheel, the others on level ground: the angles it causes.
struct WheelRockCase {
  double x;            // the wheel's x in the rover frame
  double bogie_deg;    // |bogie - rocker|
  double rocker_deg;   // |rocker - body|
};

TEST(AceClearance, ARockUnderEachWheelTurnsItsBogieAndRocker) {
  const Suspension s;
  const double h = 0.15;
  const double bogie_len = s.middle_wheel_x_m - s.rear_wheel_x_m;            // middle to rear
  const double rocker_len = s.front_wheel_x_m - s.bogie_pivot_x_m;           // bogie pivot to front
  const double u_b = (s.middle_wheel_x_m - s.bogie_pivot_x_m) / bogie_len;   // the pivot's share of the rear
  // Front: the rocker turns about the bogie pivot by atan(h / rocker_len); the bogie stays level.
  const double front = std::atan(h / rocker_len);
  // Middle: the bogie turns by atan(h / bogie_len) and lifts its pivot by (1 - u_b) h, which
  // turns the rocker the other way.
  const double middle_rocker = std::atan((1.0 - u_b) * h / rocker_len);
  const double middle_bogie = std::atan(h / bogie_len) + middle_rocker;
  // Rear: the bogie pitches nose down and lifts the pivot by u_b h, which pitches the rocker
  // nose down too: the bogie turns against the rocker by the difference.
  const double rear_rocker = std::atan(u_b * h / rocker_len);
  const double rear_bogie = std::atan(h / bogie_len) - rear_rocker;
  const WheelRockCase cases[] = {{s.front_wheel_x_m, Deg(front), Deg(front) / 2},
                                 {s.middle_wheel_x_m, Deg(middle_bogie), Deg(middle_rocker) / 2},
                                 {s.rear_wheel_x_m, Deg(rear_bogie), Deg(rear_rocker) / 2}};
  for (const double side : {-1.0, 1.0}) {
    for (const WheelRockCase& c : cases) {
      TestMap map;
      map.Set(c.x, side * 0.5 * s.track_m, static_cast<float>(h));
      const Bounds b = At(s, map);
      SCOPED_TRACE("wheel at x " + std::to_string(c.x) + ", side " + std::to_string(side));
      EXPECT_TRUE(b.decided);
      EXPECT_NEAR(Deg(b.max_bogie_rad), c.bogie_deg, 1e-6);
      // The differential: each rocker turns against the body by half their difference.
      EXPECT_NEAR(Deg(b.max_rocker_rad), c.rocker_deg, 1e-6);
      EXPECT_GT(b.max_roll_rad, 0.0);  // one side lifted
      // The belly does not come down on level ground: the wheels lift it or tilt it.
      EXPECT_GT(b.min_clearance_m, s.belly_height_m - 0.5 * h);
    }
  }
}

TEST(AceClearance, ATallRockUnderTheMiddleWheelExceedsTheBogieLimit) {
  Suspension s;
  TestMap map;
  // The bogie angle a rock h under the middle wheel causes grows with h; find it over the limit.
  map.Set(s.middle_wheel_x_m, -0.5 * s.track_m, 0.35f);
  const Bounds b = At(s, map);
  EXPECT_FALSE(b.Safe());
  EXPECT_GT(Deg(b.max_bogie_rad), s.max_bogie_deg);
  EXPECT_NE(b.violation.find("bogie"), std::string::npos) << b.violation;
}

TEST(AceClearance, ARockUnderTheBellyReducesTheClearanceByItsHeight) {
  const Suspension s;
  for (const double h : {0.05, 0.12}) {
    TestMap map;
    map.Set(0.0, 0.0, static_cast<float>(h));
    const Bounds b = At(s, map);
    EXPECT_NEAR(b.min_clearance_m, s.belly_height_m - h, 1e-6);
    EXPECT_NEAR(b.max_bogie_rad, 0.0, 1e-12);  // the wheels never touch it
  }
}

TEST(AceClearance, ARockBetweenTheWheelsIsSafeUnderTheBellyAndUnsafeOverIt) {
  const Suspension s;
  const double lower = s.belly_height_m - s.min_belly_clearance_m - 0.05;  // leaves more than the minimum
  const double higher = s.belly_height_m + 0.05;                           // taller than the belly is high
  TestMap low, high;
  // Between the left and right middle wheels, under the belly's front half.
  low.Set(0.3, 0.1, static_cast<float>(lower));
  high.Set(0.3, 0.1, static_cast<float>(higher));
  const Bounds bl = At(s, low), bh = At(s, high);
  EXPECT_TRUE(bl.Safe()) << bl.violation;
  EXPECT_NEAR(bl.min_clearance_m, s.belly_height_m - lower, 1e-6);
  EXPECT_FALSE(bh.Safe());
  EXPECT_LT(bh.min_clearance_m, 0.0);
  EXPECT_NE(bh.violation.find("belly clearance"), std::string::npos) << bh.violation;
  // Moved out beside the rover (outside the wheels), the tall rock touches nothing.
  TestMap beside;
  beside.Set(0.3, 0.8, static_cast<float>(higher));
  EXPECT_TRUE(At(s, beside).Safe());
}

TEST(AceClearance, AUniformSlopePitchesTheBodyAndLeavesTheSuspensionStraight) {
  const Suspension s;
  const double grade = std::tan(12.0 * M_PI / 180.0);
  TestMap map;
  const HeightMap v = map.View();
  for (int i = 0; i < map.n; ++i)
    for (int j = 0; j < map.n; ++j)
      map.elevation[static_cast<std::size_t>(i) * map.n + j] = static_cast<float>(grade * (v.origin_x + (i + 0.5) * kCell));
  const Bounds b = At(s, map);
  ASSERT_TRUE(b.Safe()) << b.violation;
  EXPECT_NEAR(Deg(b.max_pitch_rad), 12.0, 1e-3);
  EXPECT_NEAR(b.max_roll_rad, 0.0, 1e-9);
  EXPECT_NEAR(b.max_rocker_rad, 0.0, 1e-9);
  EXPECT_NEAR(b.max_bogie_rad, 0.0, 1e-9);
}

TEST(AceClearance, UncertaintyOnlyWidensTheBounds) {
  Suspension s;
  TestMap map;
  map.Set(s.middle_wheel_x_m, -0.5 * s.track_m, 0.1f);
  map.Set(0.2, 0.0, 0.08f);
  const Bounds sure = At(s, map);
  double previous_clearance = sure.min_clearance_m, previous_bogie = sure.max_bogie_rad;
  for (const float sigma : {0.01f, 0.03f}) {
    std::fill(map.sigma.begin(), map.sigma.end(), sigma);
    const Bounds b = At(s, map);
    EXPECT_LT(b.min_clearance_m, previous_clearance);
    EXPECT_GT(b.max_bogie_rad, previous_bogie);
    previous_clearance = b.min_clearance_m;
    previous_bogie = b.max_bogie_rad;
  }
}

TEST(AceClearance, AnUnknownCellUnderTheBellyCanHideARock) {
  Suspension s;
  TestMap map;
  const Bounds known = At(s, map);
  map.Unknown(0.1, 0.0);
  const Bounds b = At(s, map);
  EXPECT_NEAR(b.min_clearance_m, s.belly_height_m - s.unknown_rise_m, 1e-6);
  EXPECT_LT(b.min_clearance_m, known.min_clearance_m);
  EXPECT_FALSE(b.Safe());  // 0.30 - 0.25 leaves less than 0.10 m
  // A rover that cannot hide such a rock there is not stopped by the cell.
  s.unknown_rise_m = 0.1;
  EXPECT_TRUE(At(s, map).Safe());
}

TEST(AceClearance, AnUnknownCellUnderAWheelMakesItsBoundWorse) {
  const Suspension s;
  TestMap map;
  map.Unknown(s.middle_wheel_x_m + kCell, 0.5 * s.track_m);  // one cell of the right middle wheel's patch
  const Bounds b = At(s, map);
  ASSERT_TRUE(b.decided);
  EXPECT_GT(b.max_bogie_rad, 0.0);
  EXPECT_GT(b.max_roll_rad, 0.0);
  // The bound is the one a rock unknown_rise_m tall under that wheel would give.
  TestMap rock;
  rock.Set(s.middle_wheel_x_m, 0.5 * s.track_m, static_cast<float>(s.unknown_rise_m));
  EXPECT_NEAR(b.max_bogie_rad, At(s, rock).max_bogie_rad, 1e-9);
  EXPECT_FALSE(b.Safe()) << "a 0.25 m rock under a middle wheel exceeds the bogie limit";
}

TEST(AceClearance, AWheelOnUnknownGroundStandsOnTheWorstItCouldHide) {
  const Suspension s;
  TestMap map;
  for (double dx = -0.15; dx <= 0.15 + 1e-9; dx += kCell)
    for (double dy = -0.15; dy <= 0.15 + 1e-9; dy += kCell) map.Unknown(s.middle_wheel_x_m + dx, -0.5 * s.track_m + dy);
  const Bounds b = At(s, map);
  EXPECT_TRUE(b.decided);
  // As bad as a rock unknown_rise_m tall under the left middle wheel, or worse.
  TestMap rock;
  rock.Set(s.middle_wheel_x_m, -0.5 * s.track_m, static_cast<float>(s.unknown_rise_m));
  EXPECT_GE(b.max_bogie_rad, At(s, rock).max_bogie_rad - 1e-9);
  EXPECT_FALSE(b.Safe());
  // With nothing known under the rover at all, it cannot be decided.
  TestMap blank;
  std::fill(blank.sigma.begin(), blank.sigma.end(), -1.0f);
  const Bounds u = At(s, blank);
  EXPECT_FALSE(u.decided);
  EXPECT_FALSE(u.Safe());
  EXPECT_NE(u.undecided_why.find("wheel at"), std::string::npos) << u.undecided_why;
  // The same ground where the rover stands (excused: the mast cannot see it) rests the wheel
  // within the heights the other wheels rest on.
  Excused here;
  here.length_m = 1.6;
  here.width_m = 1.4;
  here.margin_m = 0.5;
  const Bounds e = At(s, map, &here);
  EXPECT_TRUE(e.Safe()) << e.violation;
}

TEST(AceClearance, ASpeckOfUnknownGroundHidesOnlyASmallRock) {
  Suspension s;
  s.rock_width_per_height = 2.5;
  TestMap map;
  map.Unknown(0.1, 0.0);  // one cell, 5 cm across: a rock 2 cm tall at most
  for (double x = -1.0; x <= 1.0 + 1e-9; x += kCell) map.Unknown(x, 0.9);  // a band 5 cm wide, 2 m long
  HeightMap v = map.View();
  const std::vector<float> hidden = HiddenRockHeights(s, v);
  EXPECT_NEAR(hidden[map.At(0.1, 0.0)], kCell / 2.5, 1e-6);
  EXPECT_NEAR(hidden[map.At(0.0, 0.9)], kCell / 2.5, 1e-6);
  EXPECT_EQ(hidden[map.At(0.0, 0.0)], 0.0f);  // known
  v.hidden_rock_m = hidden.data();
  const Bounds b = Evaluate(s, SampleTerrain(s, v, Pose{}, nullptr));
  EXPECT_NEAR(b.min_clearance_m, s.belly_height_m - kCell / 2.5, 1e-6);
  EXPECT_TRUE(b.Safe()) << b.violation;
  // Unknown ground wide enough for a rock over the limit keeps the full rise.
  TestMap wide;
  for (double x = -0.2; x <= 0.4 + 1e-9; x += kCell)
    for (double y = -0.3; y <= 0.3 + 1e-9; y += kCell) wide.Unknown(x, y);
  const std::vector<float> h2 = HiddenRockHeights(s, wide.View());
  EXPECT_NEAR(h2[wide.At(0.1, 0.0)], s.unknown_rise_m, 1e-6);
}

TEST(AceClearance, TheGroundTheRoverStandsOnIsNotHeldAgainstTheBelly) {
  const Suspension s;
  TestMap map;
  map.Set(0.0, 0.0, static_cast<float>(s.belly_height_m));  // a false height under the rover
  Excused here;
  here.length_m = 1.6;
  here.width_m = 1.4;
  here.margin_m = 0.5;
  EXPECT_FALSE(At(s, map).Safe());
  EXPECT_TRUE(At(s, map, &here).Safe());
  // Elsewhere it is: 0.6 m ahead, the rover's belly would reach a rock there.
  TestMap ahead;
  ahead.Set(1.0, 0.0, static_cast<float>(s.belly_height_m));
  EXPECT_FALSE(Evaluate(s, SampleTerrain(s, ahead.View(), Pose{0.6, 0.0, 0.0}, &here)).Safe());
}

TEST(AceClearance, APathStopsAtItsFirstUnsafePose) {
  const Suspension s;
  TestMap map;
  map.Set(1.0, 0.0, static_cast<float>(s.belly_height_m));  // under the belly once the rover is 0.5 m on
  std::vector<Pose> path;
  for (int k = 0; k <= 10; ++k) path.push_back({0.1 * k, 0.0, 0.0});
  const PathBounds p = EvaluatePath(s, map.View(), path, nullptr);
  // The belly's front edge (belly_max_x_m, grown by half a cell) reaches the rock at x 1.0.
  const int expected = static_cast<int>(std::ceil((1.0 - s.belly_max_x_m - 0.5 * kCell) / 0.1 - 1e-9));
  EXPECT_EQ(p.first_unsafe_pose, expected);
  EXPECT_FALSE(p.first_unsafe.Safe());
  EXPECT_NEAR(p.min_margin, 1.0, 1e-9);
}

TEST(AceClearance, ConfigErrorsNameTheKey) {
  auto load = [](const std::string& yaml) {
    return LoadSuspension(config::ConfigNode::FromString(yaml, "rover.yaml")["clearance"]);
  };
  EXPECT_NO_THROW(load("clearance: {belly_height_m: 0.35}"));
  auto message = [&](const std::string& yaml) {
    try {
      load(yaml);
    } catch (const config::ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("clearance: {wheel_radius_m: -1}").find("wheel_radius_m"), std::string::npos);
  EXPECT_NE(message("clearance: {bogie_pivot_x_m: 0.3}").find("bogie_pivot_x_m"), std::string::npos);
  EXPECT_NE(message("clearance: {min_belly_clearance_m: 0.4}").find("min_belly_clearance_m"), std::string::npos);
  EXPECT_NE(message("clearance: {belly_hieght_m: 0.3}").find("belly_hieght_m"), std::string::npos);
  EXPECT_NE(message("clearance: {max_bogie_deg: 95}").find("max_bogie_deg"), std::string::npos);
}

}  // namespace
}  // namespace rover::clearance
