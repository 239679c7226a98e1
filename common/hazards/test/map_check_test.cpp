// The predictive check of a step against a traversability grid, on synthetic grids.
#include "hazards/map_check.hpp"

#include <gtest/gtest.h>

namespace rover::hazards {
namespace {

using avoidance::CellClass;
using avoidance::Grid;

std::vector<Pose2> Straight(double d) { return SampleStepPath({0, 0, 0}, d, 0.0, 0.0, 0.05, 0.035); }

TEST(MapCheck, SafeGroundIsSafe) {
  const Grid g = Grid::Filled(-5, -5, 0.2, 50, 50, CellClass::kSafe, 0.8f);
  const auto c = CheckPathOnMap(g, avoidance::Footprint{}, Straight(0.6), MapCheckOptions{});
  EXPECT_EQ(c.verdict, Verdict::kSafe) << c.detail;
}

TEST(MapCheck, RockAheadIsUnsafeAndNamed) {
  Grid g = Grid::Filled(-5, -5, 0.2, 50, 50, CellClass::kSafe, 0.8f);
  g.Paint(1.3, 0.3, 0.15, CellClass::kUnsafe, 0.0f, 0.35f);
  const auto c = CheckPathOnMap(g, avoidance::Footprint{}, Straight(0.6), MapCheckOptions{});
  EXPECT_EQ(c.verdict, Verdict::kUnsafe);
  EXPECT_EQ(c.zone_name, "hazard_map");
  EXPECT_EQ(c.detail.rfind("hazard_map: step 0.35 m at 1.", 0), 0u) << c.detail;
  // Beyond the step, the same rock does not stop a shorter step.
  const auto short_step = CheckPathOnMap(g, avoidance::Footprint{}, Straight(0.2), MapCheckOptions{});
  EXPECT_EQ(short_step.verdict, Verdict::kSafe) << short_step.detail;
}

TEST(MapCheck, ASlopeTooSteepIsNamedByItsTilt) {
  // A cell refused for its slope, not its step: with the cells' tilts known (the monitor's
  // own map) the refusal gives both, so an operator does not read "step 0.05 m" alone.
  Grid g = Grid::Filled(-5, -5, 0.2, 50, 50, CellClass::kSafe, 0.8f);
  g.tilt_deg.assign(g.state.size(), 12.0f);
  g.Paint(1.3, 0.0, 0.15, CellClass::kUnsafe, 0.0f, 0.05f);
  g.tilt_deg[static_cast<std::size_t>(g.IndexAt(1.3, 0.0))] = 33.5f;
  const auto c = CheckPathOnMap(g, avoidance::Footprint{}, Straight(0.6), MapCheckOptions{});
  EXPECT_EQ(c.verdict, Verdict::kUnsafe);
  EXPECT_NE(c.detail.find("hazard_map: step 0.05 m, tilt "), std::string::npos) << c.detail;
  EXPECT_NE(c.detail.find(" deg at 1."), std::string::npos) << c.detail;
  // A tilt array of the wrong size is a bad map: the check cannot decide.
  g.tilt_deg.pop_back();
  const auto bad = CheckPathOnMap(g, avoidance::Footprint{}, Straight(0.6), MapCheckOptions{});
  EXPECT_EQ(bad.verdict, Verdict::kUnknown);
  EXPECT_NE(bad.detail.find("tilt array holds"), std::string::npos) << bad.detail;
}

TEST(MapCheck, UnknownAheadCannotDecide) {
  const Grid u = Grid::Filled(-5, -5, 0.2, 50, 50, CellClass::kUnknown, 0.0f);
  const auto c = CheckPathOnMap(u, avoidance::Footprint{}, Straight(0.6), MapCheckOptions{});
  EXPECT_EQ(c.verdict, Verdict::kUnknown);
  EXPECT_NE(c.detail.find("hazard_map: unknown:"), std::string::npos) << c.detail;
  // A turn in place sweeps only the blind ring: decidable.
  const auto turn = CheckPathOnMap(u, avoidance::Footprint{}, SampleStepPath({0, 0, 0}, 0, 0, 0.3, 0.05, 0.035),
                                   MapCheckOptions{});
  EXPECT_EQ(turn.verdict, Verdict::kSafe) << turn.detail;
  // With every unknown cell accepted, the step goes.
  MapCheckOptions go;
  go.max_unknown_fraction = 1.0;
  EXPECT_EQ(CheckPathOnMap(u, avoidance::Footprint{}, Straight(0.6), go).verdict, Verdict::kSafe);
}

// Marks the cells whose centre lies in [x0, x1) x [y0, y1) unknown.
void MarkUnknown(Grid* g, double x0, double x1, double y0, double y1) {
  for (int i = 0; i < g->rows; ++i)
    for (int j = 0; j < g->cols; ++j) {
      const double x = g->CellCentreX(i), y = g->CellCentreY(j);
      if (x >= x0 && x < x1 && y >= y0 && y < y1) g->state[static_cast<std::size_t>(i) * g->cols + j] = CellClass::kUnknown;
    }
}

TEST(MapCheck, UnknownGroundWideEnoughToHideARockCannotDecide) {
  MapCheckOptions o;
  o.max_unknown_fraction = 0.1;
  o.hidden_patch_m = 0.6;
  o.max_scattered_unknown_fraction = 0.5;
  // A 0.8 m square of unknown ground in the path, about a fifth of the cells the 1.2 m
  // step crosses: a rock over the step limit fits in it.
  Grid block = Grid::Filled(-5, -5, 0.2, 50, 50, CellClass::kSafe, 0.8f);
  MarkUnknown(&block, 1.6, 2.4, -0.4, 0.4);
  const auto c = CheckPathOnMap(block, avoidance::Footprint{}, Straight(1.2), o);
  EXPECT_EQ(c.verdict, Verdict::kUnknown) << c.detail;
  EXPECT_NE(c.detail.find("hazard_map: unknown ground 0.60 m across at "), std::string::npos) << c.detail;
  EXPECT_NE(c.detail.find("could hide a rock"), std::string::npos) << c.detail;
  // Under max_unknown_fraction, the same patch is tolerated, as by the fraction alone.
  MapCheckOptions loose = o;
  loose.max_unknown_fraction = 0.3;
  EXPECT_EQ(CheckPathOnMap(block, avoidance::Footprint{}, Straight(1.2), loose).verdict, Verdict::kSafe);

  // Two bands, each two cells deep, across the whole path: twice the block's unknown
  // cells, but neither wide enough to hold a rock the map would not see a flank of.
  Grid bands = Grid::Filled(-5, -5, 0.2, 50, 50, CellClass::kSafe, 0.8f);
  for (double x0 : {1.4, 2.0}) MarkUnknown(&bands, x0, x0 + 0.4, -1.0, 1.0);
  const auto b = CheckPathOnMap(bands, avoidance::Footprint{}, Straight(1.2), o);
  EXPECT_EQ(b.verdict, Verdict::kSafe) << b.detail;
  // The fraction alone refuses them; and more than max_scattered_unknown_fraction of
  // scattered unknown cells is a map that knows too little.
  MapCheckOptions fraction_only = o;
  fraction_only.hidden_patch_m = 0.0;
  const auto f = CheckPathOnMap(bands, avoidance::Footprint{}, Straight(1.2), fraction_only);
  EXPECT_EQ(f.verdict, Verdict::kUnknown);
  EXPECT_NE(f.detail.find("(limit 10 %)"), std::string::npos) << f.detail;
  MapCheckOptions strict = o;
  strict.max_scattered_unknown_fraction = 0.2;
  const auto t = CheckPathOnMap(bands, avoidance::Footprint{}, Straight(1.2), strict);
  EXPECT_EQ(t.verdict, Verdict::kUnknown);
  EXPECT_NE(t.detail.find("(limit 20 %)"), std::string::npos) << t.detail;

  // Unknown ground that joins the blind ring is not made wide by it: the ring (0.5 m
  // beyond the standing body) was in view from earlier stops.
  Grid ring = Grid::Filled(-5, -5, 0.2, 50, 50, CellClass::kSafe, 0.8f);
  MarkUnknown(&ring, -1.3, 1.6, -1.2, 1.2);  // the body, its ring, and a 0.3 m band beyond
  const auto r = CheckPathOnMap(ring, avoidance::Footprint{}, Straight(0.6), o);
  EXPECT_EQ(r.verdict, Verdict::kSafe) << r.detail;
  // A wider patch beyond the ring is not.
  MarkUnknown(&ring, 1.2, 2.0, -1.2, 1.2);
  EXPECT_EQ(CheckPathOnMap(ring, avoidance::Footprint{}, Straight(0.6), o).verdict, Verdict::kUnknown);
}

// A small rock read at 85 % of a 0.25 m step limit (0.2125 m: caution, goodness 0.15) beside
// the path, under the body's left half along a 0.6 m step: with driven_step_refused and the
// 0.8 fraction (0.20 m) refused, with the fraction at 1 or the refusal off (the default: the
// arc vote only avoids such steps) allowed. A rock read at 50 % (0.125 m), and the 85 % rock
// beyond the step, are driven over / past.
TEST(MapCheck, ACellNearTheStepLimitIsNotDrivenOverWhenRefused) {
  MapCheckOptions o;
  ASSERT_DOUBLE_EQ(o.driven_step_fraction, 1.0);  // off by default (README)
  ASSERT_EQ(o.DrivenStepLimit(0.25), 0.0);
  // A map that marks unseen crests at its step limit: that limit, off at a fraction of 1.
  ASSERT_EQ(o.DrivenStepLimit(0.25, true), 0.25);
  ASSERT_EQ(o.DrivenStepLimit(0.25, false), 0.0);
  ASSERT_FALSE(o.driven_step_refused);
  o.driven_step_fraction = 0.8;
  o.driven_step_refused = true;
  o.max_driven_step_m = o.DrivenStepLimit(0.25);
  ASSERT_NEAR(o.max_driven_step_m, 0.20, 1e-12);
  auto rock = [](double x, double y, float step) {
    Grid g = Grid::Filled(-5, -5, 0.2, 50, 50, CellClass::kSafe, 0.9f);
    g.Paint(x, y, 0.15, CellClass::kCaution, 1.0f - step / 0.25f, step);
    return g;
  };
  const Grid near_limit = rock(1.1, -0.5, 0.2125f);
  const auto c = CheckPathOnMap(near_limit, avoidance::Footprint{}, Straight(0.6), o);
  EXPECT_EQ(c.verdict, Verdict::kUnsafe) << c.detail;
  EXPECT_EQ(c.detail.rfind("hazard_map: step 0.21 m at 1.", 0), 0u) << c.detail;
  EXPECT_NE(c.detail.find("is over the 0.20 m a step drives over"), std::string::npos) << c.detail;
  MapCheckOptions off = o;
  off.driven_step_fraction = 1.0;
  off.max_driven_step_m = off.DrivenStepLimit(0.25);
  EXPECT_EQ(off.max_driven_step_m, 0.0);
  EXPECT_EQ(CheckPathOnMap(near_limit, avoidance::Footprint{}, Straight(0.6), off).verdict, Verdict::kSafe);
  MapCheckOptions not_refused = o;
  not_refused.driven_step_refused = false;
  EXPECT_EQ(CheckPathOnMap(near_limit, avoidance::Footprint{}, Straight(0.6), not_refused).verdict, Verdict::kSafe);
  const auto half = CheckPathOnMap(rock(1.1, -0.5, 0.125f), avoidance::Footprint{}, Straight(0.6), o);
  EXPECT_EQ(half.verdict, Verdict::kSafe) << half.detail;
  // Beyond the step (the look-ahead): planned past, not refused.
  const auto beyond = CheckPathOnMap(rock(2.4, -0.5, 0.2125f), avoidance::Footprint{}, Straight(0.6), o);
  EXPECT_EQ(beyond.verdict, Verdict::kSafe) << beyond.detail;
}

TEST(MapCheck, DrivenStepFractionIsReadAndChecked) {
  const auto load = [](const std::string& text) {
    return LoadMapCheckOptions(config::ConfigNode(YAML::Load(text), "test", "hazards.map"));
  };
  EXPECT_DOUBLE_EQ(load("{driven_step_fraction: 0.7}").driven_step_fraction, 0.7);
  EXPECT_DOUBLE_EQ(load("{enabled: true}").driven_step_fraction, 1.0);
  EXPECT_TRUE(load("{driven_step_refused: true}").driven_step_refused);
  EXPECT_THROW(load("{driven_step_refused: 3}"), config::ConfigError);
  EXPECT_THROW(load("{driven_step_fraction: 0}"), config::ConfigError);
  EXPECT_THROW(load("{driven_step_fraction: 1.2}"), config::ConfigError);
  MapCheckOptions bad;
  bad.driven_step_fraction = 0.0;
  EXPECT_THROW(bad.Validate(), std::invalid_argument);
  MapCheckOptions negative;
  negative.max_driven_step_m = -0.1;
  EXPECT_THROW(negative.Validate(), std::invalid_argument);
}

TEST(MapCheck, BadInputIsUnknown) {
  Grid g = Grid::Filled(-5, -5, 0.2, 50, 50, CellClass::kSafe, 0.8f);
  EXPECT_EQ(CheckPathOnMap(g, avoidance::Footprint{}, {}, MapCheckOptions{}).verdict, Verdict::kUnknown);
  g.step_m.resize(3);
  EXPECT_EQ(CheckPathOnMap(g, avoidance::Footprint{}, Straight(0.6), MapCheckOptions{}).verdict, Verdict::kUnknown);
  MapCheckOptions bad;
  bad.max_unknown_fraction = 2;
  EXPECT_THROW(bad.Validate(), std::invalid_argument);
  MapCheckOptions negative;
  negative.hidden_patch_m = -0.1;
  EXPECT_THROW(negative.Validate(), std::invalid_argument);
  MapCheckOptions scattered;
  scattered.max_scattered_unknown_fraction = 1.5;
  EXPECT_THROW(scattered.Validate(), std::invalid_argument);
}

TEST(MapCheck, TiltLimitTighterThanTheRoversIsNamed) {
  TiltLimits rover;  // 30 deg roll and pitch
  EXPECT_EQ(MapTiltLimitProblem(30.0, rover), "");
  EXPECT_EQ(MapTiltLimitProblem(35.0, rover), "");
  const std::string note = MapTiltLimitProblem(25.0, rover);
  EXPECT_NE(note.find("max_tilt_deg 25.0 is tighter than the rover's own tilt limit 30.0"), std::string::npos) << note;
  // The smaller of the two limits is the rover's, whatever the heading.
  rover.pitch_limit_rad = 20.0 * M_PI / 180.0;
  EXPECT_EQ(MapTiltLimitProblem(20.0, rover), "");
  EXPECT_NE(MapTiltLimitProblem(19.0, rover), "");
}

}  // namespace
}  // namespace rover::hazards

namespace rover::hazards {
namespace {

TEST(DrivenTrail, GroundTheRoverCoveredIsKnownAndUnsafeCellsStayUnsafe) {
  // A 6 x 6 m map, all unknown, with one unsafe cell the rover's path crossed (a map
  // error or a rock it drove beside: the map's verdict stands).
  avoidance::Grid grid = avoidance::Grid::Filled(-3.0, -3.0, 0.2, 30, 30, avoidance::CellClass::kUnknown, 0.0f);
  const int rock = grid.IndexAt(0.5, 0.1);
  grid.state[static_cast<std::size_t>(rock)] = avoidance::CellClass::kUnsafe;
  Footprint body;
  body.length_m = 1.5;  // edges between cell centres: x in [-0.75, 1.75], y in [-0.65, 0.65]
  body.width_m = 1.3;
  body.margin_m = 0.3;  // not part of the driven ground
  DrivenTrail trail(0.2);
  for (double x = 0.0; x <= 1.0 + 1e-9; x += 0.1) trail.Add({x, 0.0, 0.0}, body);  // drove 1 m north
  // Cell centres -0.7 .. 1.7 along (13), -0.5 .. 0.5 across (6).
  EXPECT_EQ(trail.size(), 13u * 6u);
  EXPECT_EQ(trail.MarkDriven(&grid), 13 * 6 - 1);
  const auto at = [&grid](double x, double y) { return grid.state[static_cast<std::size_t>(grid.IndexAt(x, y))]; };
  EXPECT_EQ(at(-0.7, 0.0), avoidance::CellClass::kSafe);
  EXPECT_EQ(at(1.7, 0.5), avoidance::CellClass::kSafe);
  EXPECT_EQ(at(0.5, 0.1), avoidance::CellClass::kUnsafe);
  EXPECT_EQ(at(-0.9, 0.0), avoidance::CellClass::kUnknown);
  EXPECT_EQ(at(0.5, 0.7), avoidance::CellClass::kUnknown);
  EXPECT_EQ(trail.MarkDriven(&grid), 0);  // nothing left to mark

  // Backing down its own tracks is judged on known ground; a step off them is not.
  grid.state[static_cast<std::size_t>(rock)] = avoidance::CellClass::kSafe;  // judge unknowns only
  MapCheckOptions o;
  o.blind_margin_m = 0.0;
  Footprint narrower = body;
  narrower.margin_m = 0.0;
  narrower.length_m = 1.3;
  narrower.width_m = 1.1;
  const avoidance::Footprint fp = GridFootprint(narrower);
  std::vector<Pose2> back, aside;
  for (double x = 1.0; x >= -1e-9; x -= 0.1) back.push_back({x, 0.0, 0.0});
  for (double y = 0.0; y >= -1.0 - 1e-9; y -= 0.1) aside.push_back({0.5, y, 0.0});
  EXPECT_EQ(CheckPathOnMap(grid, fp, back, o).verdict, Verdict::kSafe) << CheckPathOnMap(grid, fp, back, o).detail;
  EXPECT_EQ(CheckPathOnMap(grid, fp, aside, o).verdict, Verdict::kUnknown);
}

TEST(DrivenTrail, NonFinitePoseIsIgnoredAndBadCellSizeThrows) {
  DrivenTrail trail(0.2);
  Footprint body;
  trail.Add({std::nan(""), 0.0, 0.0}, body);
  EXPECT_EQ(trail.size(), 0u);
  EXPECT_THROW(DrivenTrail(0.0), std::invalid_argument);
}

}  // namespace
}  // namespace rover::hazards
