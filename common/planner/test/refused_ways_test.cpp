// Refused ways with known answers: a plan through the near gap of a wall that the local
// check refuses twice goes through the far gap; a refusal of the only way costs but never
// shuts it; a costly disc never makes ground cheaper.
#include "planner/refused_ways.hpp"
#include "wall_world.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace rover::planner {
namespace {

using rover::avoidance::CellClass;
using rover::avoidance::Grid;

using test::WallWithGaps;
const auto From = test::ToTheGoalFrom;

// Where the path crosses the wall's middle (x = 4.3): its y.
double CrossingY(const GlobalPlan& plan) {
  const auto& p = plan.path();
  for (std::size_t i = 1; i < p.size(); ++i)
    if (p[i - 1].x() < 4.3 && p[i].x() >= 4.3) return p[i].y();
  ADD_FAILURE() << "the path never crosses the wall";
  return NAN;
}

// The rover at (3, 0) before the near gap (y 0); the far gap is at y 5. The plan leads
// through the near one. The local check refuses it twice (the rover backed up from it
// twice): then the plan goes through the far gap, and stays reachable.
TEST(RefusedWays, APlanRefusedLocallyTwiceRoutesRound) {
  const Grid g = WallWithGaps({0.0, 5.0});
  PlannerOptions po;
  RefusedWays refused;
  PlanRequest r = From(3.0, 0.0);
  const GlobalPlan first = PlanOnGrid(g, r, po);
  ASSERT_TRUE(first.reachable()) << first.why_unreachable();
  EXPECT_NEAR(CrossingY(first), 0.0, 0.5);
  for (int k = 0; k < 2; ++k) {
    const GlobalPlan plan = PlanOnGrid(g, r, po);
    const auto disc = refused.Refuse(plan);
    ASSERT_TRUE(disc.has_value()) << k;
    // 1 m down the path: at the near gap's mouth.
    EXPECT_NEAR((disc->center - Eigen::Vector2d(3.0, 0.0)).norm(), 1.0, 0.25) << k;
    r.costly = refused.discs();
  }
  ASSERT_EQ(refused.discs().size(), 2u);
  const GlobalPlan after = PlanOnGrid(g, r, po);
  ASSERT_TRUE(after.reachable()) << after.why_unreachable();
  EXPECT_NEAR(CrossingY(after), 5.0, 0.6);
  EXPECT_GT(after.cost_at_start(), first.cost_at_start() + 2.0);  // the way round is longer
  refused.Reset();
  EXPECT_TRUE(refused.discs().empty());
}

// One gap only: however often it is refused, it stays the way (costlier), never shut, so
// refusals cannot make a reachable goal unreachable.
TEST(RefusedWays, RefusingTheOnlyWayCostsButNeverShutsIt) {
  const Grid g = WallWithGaps({0.0});
  PlannerOptions po;
  RefusalOptions ro;
  ro.max_refusals = 3;
  RefusedWays refused(ro);
  PlanRequest r = From(3.0, 0.0);
  const double before = PlanOnGrid(g, r, po).cost_at_start();
  for (int k = 0; k < 5; ++k) {
    const GlobalPlan plan = PlanOnGrid(g, r, po);
    ASSERT_TRUE(plan.reachable()) << k << ": " << plan.why_unreachable();
    EXPECT_NEAR(CrossingY(plan), 0.0, 0.5) << k;
    EXPECT_EQ(refused.Refuse(plan).has_value(), k < ro.max_refusals) << k;
    r.costly = refused.discs();
  }
  EXPECT_EQ(refused.discs().size(), 3u);
  EXPECT_GT(PlanOnGrid(g, r, po).cost_at_start(), before + 3.0 * ro.cost_per_m * 0.5);
}

// Costs only add: with a disc over unknown ground, no cell's cost to go is lower than
// without it, and cells far from the disc are as they were.
TEST(RefusedWays, ACostlyDiscNeverMakesGroundCheaper) {
  Grid g = WallWithGaps({0.0, 5.0});
  for (int i = 0; i < g.rows; ++i)
    for (int j = 0; j < g.cols; ++j)
      if (g.CellCentreX(i) > 2.0 && g.CellCentreX(i) < 4.0) g.state[static_cast<std::size_t>(i) * g.cols + j] = CellClass::kUnknown;
  PlannerOptions po;
  PlanRequest r = From(0.0, 0.0);
  const GlobalPlan plain = PlanOnGrid(g, r, po);
  r.costly.push_back({Eigen::Vector2d(3.0, 0.0), 0.6, 10.0});
  const GlobalPlan costly = PlanOnGrid(g, r, po);
  for (double x = -8.0; x < 12.0; x += 0.5)
    for (double y = -12.0; y < 12.0; y += 0.5) {
      const double a = plain.DistanceAt(x, y), b = costly.DistanceAt(x, y);
      if (std::isinf(a)) {
        EXPECT_TRUE(std::isinf(b)) << x << "," << y;
        continue;
      }
      EXPECT_GE(b, a - 1e-9) << x << "," << y;
    }
  EXPECT_DOUBLE_EQ(costly.DistanceAt(8.0, 0.0), plain.DistanceAt(8.0, 0.0));  // beyond the wall: untouched
  EXPECT_GT(costly.DistanceAt(3.0, 0.0), plain.DistanceAt(3.0, 0.0));
}

TEST(RefusedWays, BadOptionsAndDiscsAreRefusedByName) {
  RefusalOptions o;
  o.radius_m = 0.0;
  try {
    o.Validate();
    FAIL() << "radius 0 accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("radius_m"), std::string::npos) << e.what();
  }
  PlanRequest r = From(0.0, 0.0);
  r.costly.push_back({Eigen::Vector2d(NAN, 0.0), 0.6, 10.0});
  EXPECT_THROW(PlanOnGrid(WallWithGaps({0.0}), r, PlannerOptions{}), std::invalid_argument);
  // Off: nothing remembered.
  RefusalOptions off;
  off.cost_per_m = 0.0;
  RefusedWays none(off);
  EXPECT_FALSE(none.Refuse(PlanOnGrid(WallWithGaps({0.0}), From(3.0, 0.0), PlannerOptions{})).has_value());
}

}  // namespace
}  // namespace rover::planner
