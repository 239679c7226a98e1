// Blocked ways with known answers: a wall with one gap the plan leads through and the
// rover never gets through, and a rover that makes progress.
#include "planner/blocked_ways.hpp"
#include "wall_world.hpp"

#include <gtest/gtest.h>

namespace rover::planner {
namespace {

using rover::avoidance::CellClass;
using rover::avoidance::Grid;

// A wall with one 2.4 m gap at y 0, out to |y| = half_length (the whole grid by default).
avoidance::Grid WallWithAGap(double half_length = 100.0) { return test::WallWithGaps({0.0}, half_length); }
const auto At = test::ToTheGoalFrom;

// The rover stands before the gap step after step: after stall_steps plans without
// progress the gap is blocked, and the next plan finds no way: the goal is reported
// unreachable rather than circled for.
TEST(BlockedWays, AGapTheRoverNeverCrossesIsBlockedAndTheGoalReportedUnreachable) {
  const Grid g = WallWithAGap();
  PlannerOptions po;
  BlockOptions bo;
  bo.stall_steps = 5;
  BlockedWays blocked(bo);
  PlanRequest r = At(3.0, 0.0);
  const GlobalPlan first = PlanOnGrid(g, r, po);
  ASSERT_TRUE(first.reachable()) << first.why_unreachable();
  EXPECT_FALSE(blocked.Update(first));  // the first plan sets the mark to beat
  for (int k = 1; k < bo.stall_steps; ++k) {
    EXPECT_FALSE(blocked.Update(PlanOnGrid(g, r, po))) << k;
    EXPECT_EQ(blocked.stalled_steps(), k);
  }
  ASSERT_TRUE(blocked.Update(PlanOnGrid(g, r, po)));
  ASSERT_EQ(blocked.zones().size(), 1u);
  const hazards::KeepOutZone& z = blocked.zones()[0];
  EXPECT_EQ(z.name, "blocked_way_1");
  EXPECT_NEAR(z.center.x(), 4.5, 0.25);  // 1.5 m down the path: in the gap
  EXPECT_NEAR(z.center.y(), 0.0, 0.25);
  EXPECT_DOUBLE_EQ(z.radius_m, bo.radius_m);
  r.zones = blocked.zones();
  const GlobalPlan after = PlanOnGrid(g, r, po);
  EXPECT_FALSE(after.reachable());
  EXPECT_NE(after.why_unreachable().find("no way from"), std::string::npos) << after.why_unreachable();
  EXPECT_FALSE(blocked.Update(after));  // nothing more to block on an unreachable plan
  blocked.Reset();
  EXPECT_TRUE(blocked.zones().empty());
}

// A rover that gains on the goal step by step never has its way blocked; nor does one whose
// plan grows longer as the map shows more (a new way, counted afresh).
TEST(BlockedWays, ProgressAndANewWayAreNotStalls) {
  const Grid g = WallWithAGap(8.0);
  PlannerOptions po;
  BlockOptions bo;
  bo.stall_steps = 3;
  BlockedWays blocked(bo);
  for (double x = -6.0; x <= 3.0; x += 0.6) EXPECT_FALSE(blocked.Update(PlanOnGrid(g, At(x, 0.0), po))) << x;
  EXPECT_EQ(blocked.stalled_steps(), 0);
  EXPECT_FALSE(blocked.Update(PlanOnGrid(g, At(3.0, 0.0), po)));
  EXPECT_EQ(blocked.stalled_steps(), 1);
  // The same spot, the wall's gap closed by what the map saw: the way round is much longer.
  Grid closed = g;
  for (int i = 0; i < closed.rows; ++i)
    for (int j = 0; j < closed.cols; ++j)
      if (closed.CellCentreX(i) >= 4.0 && closed.CellCentreX(i) <= 4.6 && std::abs(closed.CellCentreY(j)) <= 1.2)
        closed.state[static_cast<std::size_t>(i) * closed.cols + j] = CellClass::kUnsafe;
  const GlobalPlan round = PlanOnGrid(closed, At(3.0, 0.0), po);
  ASSERT_TRUE(round.reachable());
  EXPECT_FALSE(blocked.Update(round));
  EXPECT_EQ(blocked.stalled_steps(), 0);
  EXPECT_TRUE(blocked.zones().empty());
  BlockOptions bad;
  bad.radius_m = 0.0;
  EXPECT_THROW(BlockedWays{bad}, std::invalid_argument);
}

// A way the local check keeps refusing: each refusal makes the way dearer (a costly disc on
// it, 10 per metre as the executor adds), which read as a new way and restarted the count.
// Told of the refusals, the count goes on, and the way is blocked after stall_steps plans.
TEST(BlockedWays, RefusalsOnTheWayDoNotRestartTheCount) {
  const Grid g = WallWithAGap();
  PlannerOptions po;
  BlockOptions bo;
  bo.stall_steps = 5;
  BlockedWays told(bo), untold(bo);
  std::vector<CostlyDisc> refused;
  bool blocked = false;
  double first_cost = 0, last_cost = 0;
  for (int k = 0; k <= bo.stall_steps; ++k) {
    PlanRequest r = At(3.0, 0.0);
    r.costly = refused;
    const GlobalPlan plan = PlanOnGrid(g, r, po);
    ASSERT_TRUE(plan.reachable());
    (k == 0 ? first_cost : last_cost) = plan.cost_at_start();
    blocked = told.Update(plan, refused.size());
    untold.Update(plan);
    if (k < bo.stall_steps) {
      EXPECT_FALSE(blocked) << k;
      EXPECT_EQ(told.stalled_steps(), k) << k;
    }
    refused.push_back({Eigen::Vector2d(4.0, 0.0), 0.6, 10.0});  // refused again, in the gap
  }
  // Each refusal raised the cost by more than new_way_m.
  EXPECT_GT(last_cost - first_cost, bo.stall_steps * bo.new_way_m);
  EXPECT_TRUE(blocked);
  ASSERT_EQ(told.zones().size(), 1u);
  EXPECT_NEAR(told.zones()[0].center.x(), 4.5, 0.25);
  // Untold, every rise read as a new way and restarted the count.
  EXPECT_EQ(untold.stalled_steps(), 0);
  EXPECT_TRUE(untold.zones().empty());
  // A refusal followed by progress along the dearer plan is progress.
  BlockedWays moving(bo);
  EXPECT_FALSE(moving.Update(PlanOnGrid(g, At(3.0, 0.0), po), 0));
  PlanRequest dear = At(3.0, 0.0);
  dear.costly = {{Eigen::Vector2d(4.0, 0.0), 0.6, 10.0}};
  EXPECT_FALSE(moving.Update(PlanOnGrid(g, dear, po), 1));
  EXPECT_EQ(moving.stalled_steps(), 1);
  PlanRequest on = At(6.0, 0.0);  // through the gap now
  on.costly = dear.costly;
  EXPECT_FALSE(moving.Update(PlanOnGrid(g, on, po), 1));
  EXPECT_EQ(moving.stalled_steps(), 0);
}

}  // namespace
}  // namespace rover::planner
