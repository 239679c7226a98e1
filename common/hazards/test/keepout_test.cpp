#include "hazards/keepout.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace rover::hazards;
using Vec = Eigen::Vector2d;

namespace {

// 2 m long, 1 m wide: x in [-1, 1], y in [-0.5, 0.5] at the origin facing north.
Footprint Box() {
  Footprint f;
  f.length_m = 2.0;
  f.width_m = 1.0;
  return f;
}

// A rover-frame point (forward, right) in the site plane at pose p.
Vec SitePoint(const Pose2& p, double fwd, double right) {
  return Vec(p.x, p.y) + fwd * Vec(std::cos(p.yaw), std::sin(p.yaw)) +
         right * Vec(-std::sin(p.yaw), std::cos(p.yaw));
}

std::string Problem(const KeepOutZone& z) { return ZoneProblem(z); }

KeepOutZone RawPolygon(const std::string& name, std::vector<Vec> v) {
  KeepOutZone z;
  z.name = name;
  z.shape = KeepOutZone::Shape::kPolygon;
  z.vertices = std::move(v);
  return z;
}

}  // namespace

TEST(Clearance, CircleAheadBesideAndAtTheCorner) {
  const Footprint f = Box();
  EXPECT_NEAR(Clearance(KeepOutZone::Circle("a", 3, 0, 0.5), f, 0, 0, 0), 1.5, 1e-12);
  EXPECT_NEAR(Clearance(KeepOutZone::Circle("b", 0, 2, 0.5), f, 0, 0, 0), 1.0, 1e-12);
  EXPECT_NEAR(Clearance(KeepOutZone::Circle("c", 0, -2, 0.5), f, 0, 0, 0), 1.0, 1e-12);
  // Nearest point is the corner (1, 0.5): the gap is |(0.3, 0.4)| - 0.1.
  EXPECT_NEAR(Clearance(KeepOutZone::Circle("d", 1.3, 0.9, 0.1), f, 0, 0, 0), 0.4, 1e-12);
}

TEST(Clearance, CircleOverlapIsNegativeDepth) {
  const Footprint f = Box();
  // Centre 0.2 m inside the front edge: depth 0.2 + r.
  EXPECT_NEAR(Clearance(KeepOutZone::Circle("a", 0.8, 0, 0.5), f, 0, 0, 0), -0.7, 1e-12);
  // Touching.
  EXPECT_NEAR(Clearance(KeepOutZone::Circle("b", 1.5, 0, 0.5), f, 0, 0, 0), 0.0, 1e-12);
}

TEST(Clearance, RotatedFootprint) {
  const Footprint f = Box();
  // Facing east, the 2 m length lies along y.
  const double east = M_PI / 2;
  EXPECT_NEAR(Clearance(KeepOutZone::Circle("a", 0, 3, 0.5), f, 0, 0, east), 1.5, 1e-12);
  EXPECT_NEAR(Clearance(KeepOutZone::Circle("b", 3, 0, 0.5), f, 0, 0, east), 2.0, 1e-12);
  // Any pose: a circle placed at a known rover-frame offset from the front-right corner.
  for (double yaw : {-2.5, -0.7, 0.3, 1.9}) {
    const Pose2 p{2.0, -1.0, yaw};
    const Vec c = SitePoint(p, 1.3, 0.9);
    EXPECT_NEAR(Clearance(KeepOutZone::Circle("c", c.x(), c.y(), 0.1), f, p), 0.4, 1e-12);
    const Vec behind = SitePoint(p, -2.0, 0.0);
    EXPECT_NEAR(Clearance(KeepOutZone::Circle("d", behind.x(), behind.y(), 0.25), f, p), 0.75,
                1e-12);
  }
}

TEST(Clearance, MarginAndCentreOffset) {
  Footprint f = Box();
  f.margin_m = 0.2;
  f.center_forward_m = 0.5;  // rectangle x in [-0.5, 1.5]
  EXPECT_NEAR(Clearance(KeepOutZone::Circle("a", 3, 0, 0.5), f, 0, 0, 0), 3 - 1.5 - 0.5 - 0.2,
              1e-12);
  EXPECT_NEAR(Clearance(KeepOutZone::Circle("b", -3, 0, 0.5), f, 0, 0, 0), 3 - 0.5 - 0.5 - 0.2,
              1e-12);
}

TEST(Clearance, PolygonGapIsExact) {
  const Footprint f = Box();
  const KeepOutZone sq = KeepOutZone::Polygon("sq", {{3, -1}, {5, -1}, {5, 1}, {3, 1}});
  EXPECT_NEAR(Clearance(sq, f, 0, 0, 0), 2.0, 1e-12);
  EXPECT_NEAR(Clearance(sq, f, 0, 0, M_PI / 2), 2.5, 1e-12);
  // Corner to corner.
  const KeepOutZone diag = KeepOutZone::Polygon("diag", {{2, 1.5}, {3, 1.5}, {3, 2.5}, {2, 2.5}});
  EXPECT_NEAR(Clearance(diag, f, 0, 0, 0), std::sqrt(2.0), 1e-12);
  // A polygon vertex nearest to a footprint edge (a triangle pointing at the rover).
  const KeepOutZone tri = KeepOutZone::Polygon("tri", {{2.5, 0.1}, {4, -1}, {4, 1}});
  EXPECT_NEAR(Clearance(tri, f, 0, 0, 0), 1.5, 1e-12);
}

TEST(Clearance, PolygonOverlapAndContainment) {
  const Footprint f = Box();
  // Partial overlap: the shortest way out is 0.5 m backward.
  const KeepOutZone part = KeepOutZone::Polygon("p", {{0.5, -1}, {3, -1}, {3, 1}, {0.5, 1}});
  EXPECT_NEAR(Clearance(part, f, 0, 0, 0), -0.5, 1e-12);
  // The rover entirely inside a 20 m square: 10.5 m to get out sideways.
  const KeepOutZone big =
      KeepOutZone::Polygon("big", {{-10, -10}, {10, -10}, {10, 10}, {-10, 10}});
  EXPECT_NEAR(Clearance(big, f, 0, 0, 0), -10.5, 1e-12);
  // A small zone entirely under the rover.
  const KeepOutZone small =
      KeepOutZone::Polygon("small", {{-0.1, -0.1}, {0.1, -0.1}, {0.1, 0.1}, {-0.1, 0.1}});
  EXPECT_LT(Clearance(small, f, 0, 0, 0), -0.5);
}

TEST(Clearance, ConcavePolygon) {
  // A U open to the south (small x): the notch is x in [0, 4], y in [2, 4].
  const KeepOutZone u = KeepOutZone::Polygon(
      "u", {{0, 0}, {6, 0}, {6, 6}, {0, 6}, {0, 4}, {4, 4}, {4, 2}, {0, 2}});
  Footprint f;
  f.length_m = 1.0;
  f.width_m = 1.0;
  // In the notch at (2, 3): 0.5 m to both arms, 1.5 m to the bottom of the U.
  EXPECT_NEAR(Clearance(u, f, 2, 3, 0), 0.5, 1e-12);
  EXPECT_NEAR(Clearance(u, f, 2.5, 3, 0), 0.5, 1e-12);
  EXPECT_NEAR(Clearance(u, f, 3.0, 3, 0), 0.5, 1e-12);
  // Pushed 0.3 m into the east arm: overlap, at most 0.3 m deep.
  const double c = Clearance(u, f, 2, 3.8, 0);
  EXPECT_LT(c, 0.0);
  EXPECT_GE(c, -0.3 - 1e-12);
  // Outside the U entirely, west of it.
  EXPECT_NEAR(Clearance(u, f, 3, -2, 0), 1.5, 1e-12);
}

TEST(ZoneValidation, InvalidZonesAreRejectedWithAClearMessage) {
  EXPECT_EQ(Problem(KeepOutZone::Circle("ok", 1, 2, 0.5)), "");
  EXPECT_THROW(KeepOutZone::Circle("r", 0, 0, 0.0), std::invalid_argument);
  try {
    KeepOutZone::Circle("rock7", 0, 0, -1.0);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("zone 'rock7'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("radius -1"), std::string::npos) << e.what();
  }
  EXPECT_NE(Problem(RawPolygon("two", {{0, 0}, {1, 0}})).find("at least 3"), std::string::npos);
  EXPECT_NE(Problem(RawPolygon("bow", {{0, 0}, {3, 3}, {3, 0}, {0, 1}})).find("cross"),
            std::string::npos);
  EXPECT_NE(Problem(RawPolygon("nan", {{0, 0}, {NAN, 1}, {1, 0}})).find("not finite"),
            std::string::npos);
  EXPECT_NE(Problem(RawPolygon("flat", {{0, 0}, {1, 0}, {2, 0}})).find("zero area"),
            std::string::npos);
  EXPECT_NE(Problem(RawPolygon("dup", {{0, 0}, {1, 0}, {1, 0}, {0, 1}})).find("coincide"),
            std::string::npos);
  EXPECT_NE(Problem(RawPolygon("spike", {{0, 0}, {2, 0}, {3, 0}, {2.5, 0}, {1, 1}})).find("folds"),
            std::string::npos);
  EXPECT_NE(Problem(RawPolygon("", {{0, 0}, {1, 0}, {0, 1}})).find("without a name"),
            std::string::npos);
  const std::vector<KeepOutZone> twice = {KeepOutZone::Circle("a", 0, 0, 1),
                                          KeepOutZone::Circle("a", 5, 5, 1)};
  EXPECT_NE(ZoneSetProblem(twice).find("duplicate"), std::string::npos);
  EXPECT_THROW(ValidateZones(twice), std::invalid_argument);
}

TEST(SweptPath, StraightPathBesideACircleHasTheKnownClearance) {
  const Footprint f = Box();
  const std::vector<KeepOutZone> zones = {KeepOutZone::Circle("rock", 5, 2, 0.5)};
  const auto path = SampleStepPath({0, 0, 0}, 10.0, 0.0, 0.0, 0.05, 0.05);
  const SweptCheck ok = CheckSweptPath(zones, f, path, 0.0, 3.0);
  EXPECT_EQ(ok.verdict, Verdict::kSafe);
  EXPECT_EQ(ok.zone_name, "rock");
  EXPECT_NEAR(ok.min_clearance_m, 1.0, 1e-9);  // 2 - 0.5 (half width) - 0.5 (radius)
  EXPECT_NEAR(path[ok.worst_pose_index].x, 5.0, 1.0 + 1e-9);  // beside the rock
}

TEST(SweptPath, UncertaintyShrinksClearanceByKSigma) {
  const Footprint f = Box();
  const std::vector<KeepOutZone> zones = {KeepOutZone::Circle("rock", 5, 2, 0.5)};
  const auto path = SampleStepPath({0, 0, 0}, 10.0, 0.0, 0.0, 0.05, 0.05);
  const SweptCheck small = CheckSweptPath(zones, f, path, 0.1, 3.0);
  EXPECT_TRUE(small.safe());
  EXPECT_NEAR(small.min_clearance_m, 0.7, 1e-9);
  const SweptCheck large = CheckSweptPath(zones, f, path, 0.4, 3.0);
  EXPECT_EQ(large.verdict, Verdict::kUnsafe);
  EXPECT_NEAR(large.min_clearance_m, -0.2, 1e-9);
  EXPECT_NE(large.detail.find("rock"), std::string::npos) << large.detail;
}

TEST(SweptPath, TheAskersMarginShrinksClearanceOnTopOfKSigma) {
  const Footprint f = Box();
  const std::vector<KeepOutZone> zones = {KeepOutZone::Circle("rock", 5, 2, 0.5)};
  const auto path = SampleStepPath({0, 0, 0}, 10.0, 0.0, 0.0, 0.05, 0.05);
  const SweptCheck ok = CheckSweptPath(zones, f, path, 0.1, 3.0, 0.65);
  EXPECT_TRUE(ok.safe());
  EXPECT_NEAR(ok.min_clearance_m, 0.05, 1e-9);  // 1.0 - 0.3 - 0.65
  EXPECT_NE(ok.detail.find("margin of 0.65 m"), std::string::npos) << ok.detail;
  const SweptCheck over = CheckSweptPath(zones, f, path, 0.1, 3.0, 0.75);
  EXPECT_EQ(over.verdict, Verdict::kUnsafe);
  EXPECT_NEAR(over.min_clearance_m, -0.05, 1e-9);
  // A margin that cannot be trusted is no answer.
  EXPECT_EQ(CheckSweptPath(zones, f, path, 0.1, 3.0, -0.01).verdict, Verdict::kUnknown);
  EXPECT_EQ(CheckSweptPath(zones, f, path, 0.1, 3.0, NAN).verdict, Verdict::kUnknown);
  EXPECT_EQ(CheckSweptPath(zones, f, path, 0.1, 3.0, INFINITY).verdict, Verdict::kUnknown);
}

TEST(SweptPath, APathIntoAZoneIsUnsafeAndNamesIt) {
  const Footprint f = Box();
  const std::vector<KeepOutZone> zones = {
      KeepOutZone::Circle("far", -20, 0, 1),
      KeepOutZone::Polygon("ridge", {{4, -3}, {4.5, -3}, {4.5, 3}, {4, 3}})};
  const auto path = SampleStepPath({0, 0, 0}, 6.0, 0.0, 0.0, 0.1, 0.1);
  const SweptCheck check = CheckSweptPath(zones, f, path, 0.0, 3.0);
  EXPECT_EQ(check.verdict, Verdict::kUnsafe);
  EXPECT_EQ(check.zone_name, "ridge");
  // The same step stopping short is safe, with 0.5 m to spare.
  const auto short_path = SampleStepPath({0, 0, 0}, 2.5, 0.0, 0.0, 0.1, 0.1);
  const SweptCheck ok = CheckSweptPath(zones, f, short_path, 0.0, 3.0);
  EXPECT_TRUE(ok.safe());
  EXPECT_NEAR(ok.min_clearance_m, 0.5, 1e-9);
}

TEST(SweptPath, TurnInPlaceSweepsTheCorners) {
  // A rock 0.05 m inside the front-left corner's circle: facing north it is clear, but a
  // turn sweeps the corner (radius |(1, 0.5)|) over it.
  const Footprint f = Box();
  const double corner = std::hypot(1.0, 0.5);
  const std::vector<KeepOutZone> zones = {KeepOutZone::Circle("rock", 0, -(corner + 0.1), 0.15)};
  EXPECT_GT(Clearance(zones[0], f, 0, 0, 0), 0.0);
  const auto turn = SampleStepPath({0, 0, 0}, 0.0, 0.0, -M_PI / 2, 0.1, 0.02);
  const SweptCheck check = CheckSweptPath(zones, f, turn, 0.0, 3.0);
  EXPECT_EQ(check.verdict, Verdict::kUnsafe);
}

TEST(SweptPath, DegenerateInputsAreUnknownAndNoZonesIsSafe) {
  const Footprint f = Box();
  const std::vector<KeepOutZone> zones = {KeepOutZone::Circle("rock", 5, 2, 0.5)};
  EXPECT_EQ(CheckSweptPath(zones, f, {}, 0.0, 3.0).verdict, Verdict::kUnknown);
  EXPECT_EQ(CheckSweptPath(zones, f, {{0, NAN, 0}}, 0.0, 3.0).verdict, Verdict::kUnknown);
  EXPECT_EQ(CheckSweptPath(zones, f, {{0, 0, 0}}, -1.0, 3.0).verdict, Verdict::kUnknown);
  const SweptCheck none = CheckSweptPath({}, f, {{0, 0, 0}}, 0.0, 3.0);
  EXPECT_TRUE(none.safe());
  EXPECT_TRUE(std::isinf(none.min_clearance_m));
  EXPECT_STREQ(ToString(Verdict::kUnknown), "unknown");
}

TEST(StepPath, StraightArcTurnAndBackward) {
  const auto straight = SampleStepPath({1, 2, 0}, 1.0, 0.0, 0.0, 0.1, 0.1);
  ASSERT_EQ(straight.size(), 11u);
  EXPECT_NEAR(straight.back().x, 2.0, 1e-12);
  EXPECT_NEAR(straight.back().y, 2.0, 1e-12);

  // Quarter circle of radius 2 turning right from north: ends 2 m north, 2 m east, facing east.
  const auto arc = SampleStepPath({0, 0, 0}, M_PI, 0.5, 0.0, 0.05, 0.05);
  EXPECT_NEAR(arc.back().x, 2.0, 1e-12);
  EXPECT_NEAR(arc.back().y, 2.0, 1e-12);
  EXPECT_NEAR(arc.back().yaw, M_PI / 2, 1e-12);
  for (std::size_t i = 1; i < arc.size(); ++i) {
    EXPECT_LE(std::hypot(arc[i].x - arc[i - 1].x, arc[i].y - arc[i - 1].y), 0.05 + 1e-12);
    EXPECT_NEAR(std::hypot(arc[i].x, arc[i].y - 2.0), 2.0, 1e-12);  // on the circle
  }

  // Turn in place +0.5 rad (clockwise from above: toward east) in 0.1 rad steps.
  const auto turn = SampleStepPath({3, 4, 0.2}, 0.0, 0.0, 0.5, 0.1, 0.1);
  ASSERT_EQ(turn.size(), 6u);
  EXPECT_NEAR(turn.back().yaw, 0.7, 1e-12);
  EXPECT_EQ(turn.back().x, 3.0);
  EXPECT_EQ(turn.back().y, 4.0);

  const auto back = SampleStepPath({0, 0, M_PI / 2}, -1.0, 0.0, 0.0, 0.5, 0.1);
  EXPECT_NEAR(back.back().y, -1.0, 1e-12);
  EXPECT_NEAR(back.back().yaw, M_PI / 2, 1e-12);

  // Turn, then drive along the new heading.
  const auto both = SampleStepPath({0, 0, 0}, 1.0, 0.0, M_PI / 2, 0.1, 0.1);
  EXPECT_NEAR(both.back().y, 1.0, 1e-12);

  EXPECT_THROW(SampleStepPath({0, 0, 0}, 1.0, 0.0, 0.0, 0.0, 0.1), std::invalid_argument);
  EXPECT_THROW(SampleStepPath({0, 0, 0}, NAN, 0.0, 0.0, 0.1, 0.1), std::invalid_argument);
}

TEST(SweptPath, CoarseSamplesCannotStepOverASmallRock) {
  // Only the two ends of a 6 m drive: both are clear of a 10 cm rock in the middle.
  const Footprint f = Box();
  const std::vector<KeepOutZone> zones = {KeepOutZone::Circle("pebble", 3, 0, 0.1)};
  const std::vector<Pose2> ends = {{0, 0, 0}, {6, 0, 0}};
  EXPECT_GT(Clearance(zones[0], f, ends[0]), 0.0);
  EXPECT_GT(Clearance(zones[0], f, ends[1]), 0.0);
  const SweptCheck check = CheckSweptPath(zones, f, ends, 0.0, 3.0);
  EXPECT_EQ(check.verdict, Verdict::kUnsafe);
  EXPECT_EQ(check.worst_pose_index, 0u);
  // Deepest overlap: the rock under the rover's middle, 0.5 m from either side, plus r.
  EXPECT_NEAR(check.min_clearance_m, -0.6, 1e-9);
  EXPECT_GE(check.worst_pose.x, 2.5 - 1e-9);
  EXPECT_LE(check.worst_pose.x, 3.5 + 1e-9);
}
