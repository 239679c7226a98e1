// The distance-to-goal field on synthetic grids with known answers.
#include "avoidance/arc_voting.hpp"
#include "avoidance/goal_field.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace rover::avoidance {
namespace {

Grid Open() { return Grid::Filled(-6.0, -6.0, 0.2, 60, 60, CellClass::kSafe, 0.9f); }

void Wall(Grid* g, double wall_x, double y0, double y1) {
  for (double y = y0; y <= y1; y += 0.1) g->Paint(wall_x, y, 0.25, CellClass::kUnsafe, 0.0f, 0.4f);
}

TEST(GoalField, OpenGroundIsNearlyTheStraightLine) {
  const Grid g = Open();
  const GoalField f(g, 4.0, 3.0, 0.7);
  // 8-connected steps: at most 8 % over the straight line, never under it (less a cell).
  const double d = f.DistanceAt(0.0, 0.0);
  EXPECT_GE(d, 5.0 - 0.2);
  EXPECT_LE(d, 5.0 * 1.08 + 0.2);
  // Off the grid: the straight line.
  EXPECT_DOUBLE_EQ(f.DistanceAt(10.0, 3.0), 6.0);
}

TEST(GoalField, AWallIsGoneRoundThroughItsGapAndItsNeighbourhoodIsDear) {
  // A wall across x = 3 from y = -6 to 1, gap from 1 to 3, wall again to 6; the goal
  // beyond the grid straight ahead, at (9, 0).
  Grid g = Open();
  Wall(&g, 3.0, -6.0, 1.0);
  Wall(&g, 3.0, 3.0, 6.0);
  const GoalField f(g, 9.0, 0.0, 0.7);
  const double from_start = f.DistanceAt(0.0, 0.0);
  ASSERT_TRUE(std::isfinite(from_start));
  EXPECT_GT(from_start, 9.0 + 0.5);                 // longer than the straight line
  EXPECT_LT(f.DistanceAt(0.0, 2.0), from_start);    // toward the gap is progress
  EXPECT_GT(f.DistanceAt(0.0, -2.0), from_start);   // away from it is not
  // Through the gap's middle costs its length; on the wall, or within 0.7 m of its end,
  // every cell costs kNearHazardCost times as much, so leaving there is the way on.
  const double gap = f.DistanceAt(3.0, 2.0);
  EXPECT_NEAR(gap, std::hypot(6.0, 2.0), 0.5);
  EXPECT_GT(f.DistanceAt(3.0, -2.0), gap + 1.0);
  EXPECT_GT(f.DistanceAt(3.0, 1.5), f.DistanceAt(3.0, 2.0));
  EXPECT_TRUE(std::isfinite(f.DistanceAt(3.0, -2.0)));
}

TEST(GoalField, AWallTheMapRatesCautionIsGoneRoundThroughClearGround) {
  // A band of caution cells 0.8 m thick across x = 3.5..4.3 (a wall of rocks seen from
  // afar), clear between y = 1 and 3: the gap is the cheaper way; straight through the band
  // costs kCautionCost times its thickness.
  Grid g = Open();
  for (double y = -6.0; y <= 6.0; y += 0.1)
    if (y < 1.0 || y > 3.0)
      for (double x = 3.5; x <= 4.3; x += 0.1) g.Paint(x, y, 0.05, CellClass::kCaution, 0.3f, 0.2f);
  const GoalField f(g, 7.5, 0.0, 0.7);
  EXPECT_LT(f.DistanceAt(2.0, 1.5), f.DistanceAt(2.0, -0.5));   // toward the gap is downhill
  EXPECT_NEAR(f.DistanceAt(3.2, 0.0) - f.DistanceAt(4.6, 0.0), 1.4 + 2 * 0.8, 0.9);
}

TEST(GoalField, AGoalBesideARockIsStillReached) {
  // A rock 0.4 m from the goal: the goal lies in the rock's neighbourhood, yet the field
  // leads to it from every side (nothing is cut off), dearer across the neighbourhood.
  Grid g = Open();
  g.Paint(2.4, 0.0, 0.3, CellClass::kUnsafe, 0.0f, 0.4f);
  const GoalField f(g, 2.0, 0.0, 0.7);
  EXPECT_NEAR(f.DistanceAt(2.0, 0.0), 0.0, 1e-9);
  for (double y : {-3.0, 0.0, 3.0}) {
    EXPECT_TRUE(std::isfinite(f.DistanceAt(-1.0, y)));
    EXPECT_TRUE(std::isfinite(f.DistanceAt(5.0, y)));
  }
  EXPECT_LT(f.DistanceAt(0.0, 0.0), f.DistanceAt(-1.0, 0.0));  // nearer on the way in is less
}

TEST(ArcVoting, ALongWallIsGoneRoundAtTheEndThatLeadsToTheGoal) {
  // The goal straight ahead beyond a wall whose gap is to the right (east, +y) of the line,
  // the wall's far end to the left is farther: the first step must turn right.
  Grid g = Open();
  Wall(&g, 4.0, -6.0, 0.9);
  Wall(&g, 4.0, 3.9, 6.0);
  VoteOptions o;
  const Choice c = VoteArcs(g, {0, 0, 0}, 7.5, 0.0, o);
  ASSERT_TRUE(c.found);
  const double heading_change = c.best.kind == Candidate::Kind::kTurn ? c.best.turn_rad
                                                                      : c.best.curvature_per_m * c.best.distance_m;
  EXPECT_GT(heading_change, 0.0) << ToString(c.best.kind) << " k " << c.best.curvature_per_m;
}

// Issue 20: after a drive, a goto back to the start. The ground ahead is known and good;
// behind the rover it was never seen. A straight arc away from the goal makes no progress
// at any point, so it is a loss, not a draw: the rover turns toward the goal.
TEST(ArcVoting, GoalBehindTheRoverOnSeenGroundTurnsRatherThanDrivesAway) {
  Grid g = Grid::Filled(-6.0, -6.0, 0.2, 60, 60, CellClass::kUnknown, 0.0f);
  for (int i = 0; i < g.rows; ++i)
    for (int j = 0; j < g.cols; ++j)
      if (g.CellCentreX(i) > -0.8) {
        g.state[static_cast<std::size_t>(i) * g.cols + j] = CellClass::kSafe;
        g.goodness[static_cast<std::size_t>(i) * g.cols + j] = 1.0f;
      }
  // 150 deg off the heading, as (0, 0) from the demo's end at (5, 3) facing 60 deg.
  const double gx = -5.0 * std::cos(30 * M_PI / 180), gy = -5.0 * std::sin(30 * M_PI / 180);
  const Choice c = VoteArcs(g, {0, 0, 0}, gx, gy, VoteOptions{});
  ASSERT_TRUE(c.found);
  // The short way round, to the left (west): a turn in place or a hard left arc.
  const double heading_change = c.best.kind == Candidate::Kind::kTurn ? c.best.turn_rad
                                                                      : c.best.curvature_per_m * c.best.distance_m;
  EXPECT_LT(heading_change, -5 * M_PI / 180) << ToString(c.best.kind) << " " << c.best.distance_m << " m k "
                                             << c.best.curvature_per_m;
}

// A plan's cost-to-go (common/planner) that says the way lies behind, south, though the goal
// itself lies north beyond the end of a pocket the rover stands in.
struct SouthIsTheWay final : GoalDistance {
  double DistanceAt(double x, double) const override { return 30.0 + x; }
};

// The pocket: open ground ahead for a while, its end at x = 3.5, sides at +-half_width.
Grid Pocket(double half_width) {
  Grid g = Open();
  Wall(&g, 3.5, -half_width, half_width);
  for (double x = -4.0; x <= 3.5; x += 0.1) {
    g.Paint(x, -half_width, 0.25, CellClass::kUnsafe, 0.0f, 0.4f);
    g.Paint(x, half_width, 0.25, CellClass::kUnsafe, 0.0f, 0.4f);
  }
  return g;
}

TEST(ArcVoting, FollowingAPlanOutOfAPocketTurnsRoundWhereItCan) {
  const Grid g = Pocket(1.4);  // room to turn in place
  VoteOptions o;
  o.footprint.width_m = 1.2;
  // Without the plan, the goal ahead draws the rover deeper in.
  const Choice local = VoteArcs(g, {0, 0, 0}, 8.0, 0.0, o);
  ASSERT_TRUE(local.found);
  EXPECT_EQ(local.best.kind, Candidate::Kind::kArc);
  EXPECT_GT(local.best.distance_m, 0.0);
  const SouthIsTheWay plan;
  o.goal_distance = &plan;
  o.way_heading_rad = M_PI;
  const Choice c = VoteArcs(g, {0, 0, 0}, 8.0, 0.0, o);
  ASSERT_TRUE(c.found);
  ASSERT_EQ(c.best.kind, Candidate::Kind::kTurn) << ToString(c.best.kind) << " " << c.best.distance_m;
  EXPECT_GT(std::abs(c.best.planned_turn_rad), 0.5 * M_PI);  // round toward the way out
}

TEST(ArcVoting, FollowingAPlanOutOfAPocketTooNarrowToTurnInBacksUp) {
  const Grid g = Pocket(1.15);
  VoteOptions o;
  o.footprint.width_m = 1.2;
  const Choice local = VoteArcs(g, {0, 0, 0}, 8.0, 0.0, o);
  ASSERT_TRUE(local.found);
  EXPECT_EQ(local.best.kind, Candidate::Kind::kArc);
  const SouthIsTheWay plan;
  o.goal_distance = &plan;
  o.way_heading_rad = M_PI;
  const Choice c = VoteArcs(g, {0, 0, 0}, 8.0, 0.0, o);
  ASSERT_TRUE(c.found);
  EXPECT_EQ(c.best.kind, Candidate::Kind::kBackup) << ToString(c.best.kind) << " " << c.best.distance_m << " "
                                                   << c.best.planned_turn_rad;
  EXPECT_LT(c.best.distance_m, 0.0);
}

}  // namespace
}  // namespace rover::avoidance
