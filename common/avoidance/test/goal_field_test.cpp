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

}  // namespace
}  // namespace rover::avoidance
