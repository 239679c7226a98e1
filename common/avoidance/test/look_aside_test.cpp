// CountUnknownBeside: the unknown ground a turn in place would sweep, by side.
#include "avoidance/look_aside.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace rover::avoidance {
namespace {

// A 10 m square of safe 0.1 m cells round the origin, with `state` painted where `where` holds.
template <typename Where>
Grid Painted(CellClass state, Where where) {
  Grid g = Grid::Filled(-5.0, -5.0, 0.1, 100, 100, CellClass::kSafe, 1.0f);
  for (int i = 0; i < g.rows; ++i)
    for (int j = 0; j < g.cols; ++j)
      if (where(g.CellCentreX(i), g.CellCentreY(j))) g.state[static_cast<std::size_t>(i) * g.cols + j] = state;
  return g;
}

Footprint Rover() {
  Footprint f;
  f.length_m = 1.6;
  f.width_m = 1.2;
  return f;
}

TEST(LookAside, AllKnownCountsNothing) {
  const Grid g = Grid::Filled(-5.0, -5.0, 0.1, 100, 100, CellClass::kSafe, 1.0f);
  const auto u = CountUnknownBeside(g, Rover(), {0.0, 0.0, 0.3});
  EXPECT_EQ(u.left, 0);
  EXPECT_EQ(u.right, 0);
}

TEST(LookAside, UnknownGroundEastIsRightOfARoverFacingNorthAndLeftOfOneFacingSouth) {
  // Site X north, Y east; yaw clockwise from north: facing north, east is to the right.
  const Grid g = Painted(CellClass::kUnknown, [](double x, double y) { return y > 0.5 && std::abs(x) < 0.3; });
  const auto north = CountUnknownBeside(g, Rover(), {0.0, 0.0, 0.0});
  EXPECT_GT(north.right, 0);
  EXPECT_EQ(north.left, 0);
  const auto south = CountUnknownBeside(g, Rover(), {0.0, 0.0, M_PI});
  EXPECT_EQ(south.right, 0);
  EXPECT_EQ(south.left, north.right);
}

TEST(LookAside, GroundAheadBehindAndBeyondTheTurnDiscIsNotCounted) {
  // Unknown ahead and behind (within 0.5 rad of the heading line) and a ring beyond the
  // disc the turn sweeps (1.0 m to the corner, plus half a cell).
  const double radius = std::hypot(0.8 + 0.05, 0.6 + 0.05);
  const Grid g = Painted(CellClass::kUnknown, [&](double x, double y) {
    const double r = std::hypot(x, y);
    return r > radius + 0.1 || std::abs(std::atan2(y, x)) < 0.4 || std::abs(std::atan2(y, x)) > M_PI - 0.4;
  });
  const auto u = CountUnknownBeside(g, Rover(), {0.0, 0.0, 0.0});
  EXPECT_EQ(u.left, 0);
  EXPECT_EQ(u.right, 0);
  EXPECT_GT(u.behind, 0);  // the sector behind, within the disc
}

TEST(LookAside, GroundBehindCountsOutToTheBackUpsReach) {
  // Unknown only in a band 1.2 to 1.4 m behind a rover facing north: beyond the turn disc
  // (about 1.06 m), within it plus a 0.5 m back-up.
  const Grid g = Painted(CellClass::kUnknown, [](double x, double y) { return x < -1.2 && x > -1.4 && std::abs(y) < 0.2; });
  EXPECT_EQ(CountUnknownBeside(g, Rover(), {0.0, 0.0, 0.0}).behind, 0);
  const auto u = CountUnknownBeside(g, Rover(), {0.0, 0.0, 0.0}, 0.5);
  EXPECT_GT(u.behind, 0);
  EXPECT_EQ(u.left + u.right, 0);
  // Facing south the same band is ahead: not behind, not beside.
  const auto ahead = CountUnknownBeside(g, Rover(), {0.0, 0.0, M_PI}, 0.5);
  EXPECT_EQ(ahead.behind + ahead.left + ahead.right, 0);
}

TEST(LookAside, UnsafeAndCautionCellsAreKnown) {
  const Grid g = Painted(CellClass::kUnsafe, [](double, double y) { return std::abs(y) > 0.4; });
  const auto u = CountUnknownBeside(g, Rover(), {0.0, 0.0, 0.0});
  EXPECT_EQ(u.left + u.right, 0);
}

}  // namespace
}  // namespace rover::avoidance
