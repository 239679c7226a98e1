// MapOptions::framed_height, with known answers on synthetic points: a rock's cell seen
// whole by one view (its top framed) and from beside by another (its foot in view, its top
// not) reads the mean of every point without the option, and at least what the framing
// view read with it.
#include "traversability/traversability_map.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace rover::traversability {
namespace {

using Mode = MapOptions::FramedHeight;

MapOptions Options(Mode framed_height) {
  MapOptions o;
  o.extent_m = 8.0;
  o.cell_size_m = 0.2;
  o.footprint_radius_m = 0.6;
  o.max_step_m = 0.25;
  o.crest_view_range_m = 6.0;
  o.framed_height = framed_height;
  return o;
}

// The rock's cell: x in [1.0, 1.2), y in [0.0, 0.2) (the grid is centred on the origin in
// whole cells of 0.2 m).
constexpr double kRockX = 1.1, kRockY = 0.1;
bool InRockCell(double x, double y) { return x >= 1.0 && x < 1.2 && y >= 0.0 && y < 0.2; }

struct Points {
  std::vector<Eigen::Vector3d> p;
  std::vector<double> sigma;
  void Add(double x, double y, double h) {
    p.emplace_back(x, y, -h);  // site frame: z down
    sigma.push_back(0.01);
  }
};

// Level ground at 0 round the rock's cell, every 0.05 m over 3 x 3 m, and `top_points`
// points in the rock's cell at `top_m`: a view that framed every cell it saw.
Points FramingView(double top_m, int top_points) {
  Points v;
  for (double x = -0.475; x < 2.5; x += 0.05)
    for (double y = -1.475; y < 1.5; y += 0.05)
      if (!InRockCell(x, y)) v.Add(x, y, 0.0);
  for (int k = 0; k < top_points; ++k) v.Add(1.12 + 0.01 * (k % 4), 0.05 + 0.02 * (k / 4), top_m);
  return v;
}

// A view from beside: `n` points in the rock's cell at `flank_m` (its foot, its top cut off).
Points CuttingView(double flank_m, int n) {
  Points v;
  for (int k = 0; k < n; ++k) v.Add(1.02 + 0.01 * (k % 6), 0.03 + 0.02 * (k / 6), flank_m);
  return v;
}

Cell RockCell(Mode framed_height, double top_m, double flank_m) {
  TraversabilityMap map(Options(framed_height));
  const Points framing = FramingView(top_m, 4), cutting = CuttingView(flank_m, 12);
  map.AddViewedPoints(framing.p, framing.sigma, true);
  map.AddViewedPoints(cutting.p, cutting.sigma, false);
  return map.At(kRockX, kRockY);
}

// A 0.31 m rock's top framed by one view (4 points), its flank at 0.15 m seen by another
// (12 points): the mean of every point is (4 x 0.31 + 12 x 0.15) / 16 = 0.19 m, caution
// under the 0.25 m limit. With `mean` the cell reads the framed 0.31 m, with `max` the one
// framing pair's 0.31 m less its points' 0.01 m sigma: unsafe either way.
TEST(FramedHeight, ARockCutFromBesideReadsWhatItsFramingViewRead) {
  const Cell off = RockCell(Mode::kOff, 0.31, 0.15);
  EXPECT_NEAR(off.step_m, 0.19, 1e-3);
  EXPECT_EQ(off.state, CellState::kCaution);
  const Cell mean = RockCell(Mode::kMean, 0.31, 0.15);
  EXPECT_NEAR(mean.step_m, 0.31, 1e-3);
  EXPECT_EQ(mean.state, CellState::kUnsafe);
  const Cell max = RockCell(Mode::kMax, 0.31, 0.15);
  EXPECT_NEAR(max.step_m, 0.30, 1e-3);
  EXPECT_EQ(max.state, CellState::kUnsafe);
}

// Never lower: a framing view that read the cell lower than the cut one (0.10 against
// 0.30 m) leaves the mean of every point, (4 x 0.10 + 12 x 0.30) / 16 = 0.25 m.
TEST(FramedHeight, NeverLowerThanTheMeanOfEveryPoint) {
  const Cell off = RockCell(Mode::kOff, 0.10, 0.30);
  EXPECT_NEAR(off.step_m, 0.25, 1e-3);
  for (const Mode mode : {Mode::kMean, Mode::kMax}) {
    const Cell on = RockCell(mode, 0.10, 0.30);
    EXPECT_FLOAT_EQ(on.step_m, off.step_m);
    EXPECT_EQ(on.state, off.state);
  }
}

// Two framing pairs: a near one reads the rock's cell at 0.30 m (4 points), a far one at
// 0.14 m (12 points, a rock read low by its resolution). `mean`: (4 x 0.30 + 12 x 0.14) /
// 16 = 0.18 m, caution; `max`: the near pair's 0.30 m less 0.01 m, unsafe.
TEST(FramedHeight, MaxKeepsTheHighestPairsReading) {
  auto cell = [](Mode mode) {
    TraversabilityMap map(Options(mode));
    const Points near = FramingView(0.30, 4), far = CuttingView(0.14, 12);
    map.AddViewedPoints(near.p, near.sigma, true);
    map.AddViewedPoints(far.p, far.sigma, true);
    return map.At(kRockX, kRockY);
  };
  EXPECT_NEAR(cell(Mode::kOff).step_m, 0.18, 1e-3);
  EXPECT_NEAR(cell(Mode::kMean).step_m, 0.18, 1e-3);
  const Cell max = cell(Mode::kMax);
  EXPECT_NEAR(max.step_m, 0.29, 1e-3);
  EXPECT_EQ(max.state, CellState::kUnsafe);
}

// Under min_points framed points (3) in the framing pair: not credible, and the cell reads
// the mean of every point. Level ground reads the same in every mode.
TEST(FramedHeight, TooFewFramedPointsAndLevelGroundReadAsBefore) {
  for (const Mode mode : {Mode::kOff, Mode::kMean, Mode::kMax}) {
    TraversabilityMap map(Options(mode));
    const Points framing = FramingView(0.31, 2), cutting = CuttingView(0.15, 12);
    map.AddViewedPoints(framing.p, framing.sigma, true);
    map.AddViewedPoints(cutting.p, cutting.sigma, false);
    // (2 x 0.31 + 12 x 0.15) / 14 = 0.173 m
    const int m = static_cast<int>(mode);
    EXPECT_NEAR(map.At(kRockX, kRockY).step_m, (2 * 0.31 + 12 * 0.15) / 14, 1e-3) << m;
    const Cell ground = map.At(-0.2, -0.9);
    EXPECT_EQ(ground.state, CellState::kSafe) << m;
    EXPECT_NEAR(ground.step_m, 0.0, 1e-4) << m;
  }
}

// The option needs the crest rule's views (crest_view_range_m): without them it is inert.
TEST(FramedHeight, WithoutTheCrestRuleItIsInert) {
  MapOptions o = Options(Mode::kMax);
  o.crest_view_range_m = 0;
  TraversabilityMap map(o);
  const Points framing = FramingView(0.31, 4), cutting = CuttingView(0.15, 12);
  map.AddViewedPoints(framing.p, framing.sigma, true);
  map.AddViewedPoints(cutting.p, cutting.sigma, false);
  EXPECT_NEAR(map.At(kRockX, kRockY).step_m, 0.19, 1e-3);
}

TEST(FramedHeight, ReadFromYaml) {
  EXPECT_EQ(LoadMapOptions(YAML::Load("{}"), "t").framed_height, Mode::kOff);
  EXPECT_EQ(LoadMapOptions(YAML::Load("{framed_height: mean}"), "t").framed_height, Mode::kMean);
  EXPECT_EQ(LoadMapOptions(YAML::Load("{framed_height: max}"), "t").framed_height, Mode::kMax);
  try {
    LoadMapOptions(YAML::Load("{framed_height: true}"), "t");
    FAIL() << "a word outside off, mean, max was taken";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("framed_height"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace rover::traversability
