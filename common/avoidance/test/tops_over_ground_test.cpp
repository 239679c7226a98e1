// The vote's reading of rock tops over the ground round them, on synthetic grids with known
// heights.
#include "avoidance/tops_over_ground.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace rover::avoidance {
namespace {

constexpr double kRadius = 1.0, kRise = 0.25;

// A 10 m x 10 m grid of safe cells centred on the origin, 0.2 m cells, on the plane
// z = slope x (level at 0) with a fixed +-0.01 m ripple, every height known (sigma 0.01).
Grid Ground(double slope = 0.0) {
  Grid g = Grid::Filled(-5.0, -5.0, 0.2, 50, 50, CellClass::kSafe, 0.9f);
  g.SetHeights(0.0f, 0.01f);
  for (int i = 0; i < g.rows; ++i)
    for (int j = 0; j < g.cols; ++j)
      g.elevation_m[i * g.cols + j] =
          static_cast<float>(slope * g.CellCentreX(i) + 0.01 * (((i * 7 + j * 3) % 3) - 1));
  return g;
}

// A round rock at (x, y): every cell whose centre lies within radius_m tops out at `top`
// over the ground there (a dome: its rim at half that), rated as the map rated the 0.31 m
// rock of navbench seed 41 k0.25_r16: caution, its step read under the limit.
void Rock(Grid* g, double x, double y, double radius_m, double top, float step_read) {
  for (int i = 0; i < g->rows; ++i)
    for (int j = 0; j < g->cols; ++j) {
      const double r = std::hypot(g->CellCentreX(i) - x, g->CellCentreY(j) - y);
      if (r > radius_m) continue;
      const std::size_t k = static_cast<std::size_t>(i) * g->cols + j;
      g->elevation_m[k] += static_cast<float>(top * (1.0 - 0.5 * (r / radius_m) * (r / radius_m)));
      g->state[k] = CellClass::kCaution;
      g->step_m[k] = step_read;
      g->goodness[k] = 1.0f - step_read / 0.25f;
    }
}

CellClass At(const Grid& g, double x, double y) { return g.state[g.IndexAt(x, y)]; }

// The rock of seed 41's collision: tops 0.27 m over level ground, steps read 0.20 to 0.25 m
// (caution). Its top cells become unsafe; its rim (under the limit) and the ground stay as
// they were; a body sweep that was clear of unsafe cells now meets them.
TEST(TopsOverGround, ARockReadCautionWhoseTopsStandOverTheLimitIsUnsafe) {
  Grid g = Ground();
  Rock(&g, 1.3, 0.7, 0.35, 0.27, 0.22f);
  const Footprint fp;
  const Pose2 here{0.0, 0.0, 0.0};
  const auto path = SamplePath(here, 0.0, 0.6, 0.0);  // its right front corner meets the rock
  ASSERT_EQ(SweepFootprint(g, fp, path, here, 0.0).unsafe, 0);

  const int marked = MarkTopsOverGround(&g, kRadius, kRise);
  EXPECT_GE(marked, 1);
  EXPECT_LE(marked, 9);
  EXPECT_EQ(At(g, 1.3, 0.7), CellClass::kUnsafe);
  EXPECT_FLOAT_EQ(g.goodness[g.IndexAt(1.3, 0.7)], 0.0f);
  EXPECT_NEAR(g.step_m[g.IndexAt(1.3, 0.7)], 0.27, 0.03);  // the rise, over the 0.22 read
  EXPECT_NEAR(TopOverGround(g, g.IndexAt(1.3, 0.7), kRadius, kTopGroundBandFraction * kRise), 0.27, 0.03);
  EXPECT_EQ(At(g, 1.3 + 0.2, 0.7), CellClass::kCaution);  // its flank, 0.23 m up
  EXPECT_EQ(At(g, 0.5, -1.0), CellClass::kSafe);
  EXPECT_GT(SweepFootprint(g, fp, path, here, 0.0).unsafe, 0);
  EXPECT_EQ(MarkTopsOverGround(&g, kRadius, kRise), 0);  // nothing left to mark
}

// A cobble 0.20 m tall (under the limit) stays as the map rated it; a rock 0.40 m tall and
// 1.2 m across, filling much of its cells' ground discs, is found all the same.
TEST(TopsOverGround, ACobbleUnderTheLimitStaysAndABigRockIsFound) {
  Grid g = Ground();
  Rock(&g, -2.0, -2.0, 0.3, 0.20, 0.18f);
  Rock(&g, 2.0, 2.0, 0.6, 0.40, 0.24f);
  MarkTopsOverGround(&g, kRadius, kRise);
  EXPECT_EQ(At(g, -2.0, -2.0), CellClass::kCaution);
  EXPECT_EQ(At(g, 2.0, 2.0), CellClass::kUnsafe);
  EXPECT_EQ(At(g, 2.0 + 0.2, 2.0 - 0.2), CellClass::kUnsafe);
  EXPECT_EQ(At(g, 0.0, 0.0), CellClass::kSafe);
}

// A uniform 25 deg slope rises nothing, and a 0.20 m cobble on it stays under the limit;
// a 0.30 m rock on it does not.
TEST(TopsOverGround, ASlopeRisesNothing) {
  Grid g = Ground(std::tan(25.0 * M_PI / 180.0));
  Rock(&g, -1.0, 1.0, 0.3, 0.20, 0.18f);
  Rock(&g, 1.5, -1.5, 0.35, 0.30, 0.22f);
  MarkTopsOverGround(&g, kRadius, kRise);
  EXPECT_EQ(At(g, -1.0, 1.0), CellClass::kCaution);
  EXPECT_EQ(At(g, 1.5, -1.5), CellClass::kUnsafe);
  int unsafe = 0;
  for (CellClass s : g.state) unsafe += s == CellClass::kUnsafe;
  EXPECT_LE(unsafe, 9);  // the rock's top only
}

// Too little known ground round a cell, or no heights at all, or the rule off: the map's
// rating stands.
TEST(TopsOverGround, WithoutGroundToFitTheRatingStands) {
  Grid g = Ground();
  Rock(&g, 0.1, 0.1, 0.1, 0.40, 0.22f);  // one cell, 0.40 m up, and two of ground beside it
  for (int k = 0; k < g.rows * g.cols; ++k)
    if (k != g.IndexAt(0.1, 0.1) && k != g.IndexAt(0.3, 0.1) && k != g.IndexAt(0.1, 0.3)) g.sigma_m[k] = -1.0f;
  EXPECT_LT(TopOverGround(g, g.IndexAt(0.1, 0.1), kRadius, kTopGroundBandFraction * kRise), 0.0);
  EXPECT_EQ(MarkTopsOverGround(&g, kRadius, kRise), 0);
  EXPECT_EQ(At(g, 0.1, 0.1), CellClass::kCaution);

  Grid h = Ground();
  Rock(&h, 0.0, 0.0, 0.35, 0.30, 0.22f);
  EXPECT_EQ(MarkTopsOverGround(&h, kRadius, 0.0), 0);  // off
  EXPECT_EQ(MarkTopsOverGround(&h, 0.0, kRise), 0);    // off
  h.elevation_m.clear();
  h.sigma_m.clear();
  EXPECT_EQ(MarkTopsOverGround(&h, kRadius, kRise), 0);  // no heights
  EXPECT_EQ(At(h, 0.0, 0.0), CellClass::kCaution);
}

}  // namespace
}  // namespace rover::avoidance
