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

TEST(MapCheck, BadInputIsUnknown) {
  Grid g = Grid::Filled(-5, -5, 0.2, 50, 50, CellClass::kSafe, 0.8f);
  EXPECT_EQ(CheckPathOnMap(g, avoidance::Footprint{}, {}, MapCheckOptions{}).verdict, Verdict::kUnknown);
  g.step_m.resize(3);
  EXPECT_EQ(CheckPathOnMap(g, avoidance::Footprint{}, Straight(0.6), MapCheckOptions{}).verdict, Verdict::kUnknown);
  MapCheckOptions bad;
  bad.max_unknown_fraction = 2;
  EXPECT_THROW(bad.Validate(), std::invalid_argument);
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
