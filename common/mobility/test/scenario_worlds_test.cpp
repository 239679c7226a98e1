// The shipped worlds keep the promises their scenarios rely on (OPERATIONS.md catalogue),
// driven open loop from each world's start pose.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "mobility/rover_simulator.hpp"

namespace rover::mobility {
namespace {

constexpr double kDeg = M_PI / 180.0;

terrain::World LoadWorld(const std::string& name) {
  return terrain::World(terrain::WorldOptions::LoadFile(std::string(ROVER_SOURCE_DIR) +
                                                        "/configs/worlds/" + name + ".yaml"));
}

MobilityOptions RoverOptions() {
  return MobilityOptions::LoadFile(std::string(ROVER_SOURCE_DIR) + "/configs/rover.yaml");
}

// Runs a command to its end, tracking the largest |pitch| and |roll| seen.
struct DriveResult {
  MobilityStatus status;
  double max_pitch_deg = 0.0, max_roll_deg = 0.0;
};
DriveResult Drive(RoverSimulator& sim, const MotionCommand& c) {
  DriveResult r;
  sim.Command(c);
  sim.Step(0.1);
  while (sim.moving()) {
    sim.Step(0.5);
    r.max_pitch_deg = std::max(r.max_pitch_deg, std::abs(sim.Truth().rpy.y()) / kDeg);
    r.max_roll_deg = std::max(r.max_roll_deg, std::abs(sim.Truth().rpy.x()) / kDeg);
  }
  r.status = sim.status();
  return r;
}

TEST(ScenarioWorlds, SteepSandSlopeSlidesBack) {
  const auto world = LoadWorld("steep_sand_slope");
  RoverSimulator sim(world, RoverOptions());
  const RoverTruth start = sim.Truth();
  EXPECT_GT(start.rpy.y() / kDeg, 25.0);
  const DriveResult r = Drive(sim, MotionCommand::Arc(1, 1.5));
  EXPECT_EQ(r.status.state, MobilityState::kDone);
  EXPECT_LT(sim.Truth().position.x(), start.position.x());
}

TEST(ScenarioWorlds, TiltSlopeIsClimbableBeyondTwentyDegrees) {
  const auto world = LoadWorld("tilt_slope");
  RoverSimulator sim(world, RoverOptions());
  EXPECT_LT(std::abs(sim.Truth().rpy.y()) / kDeg, 3.0);  // flat start
  const DriveResult r = Drive(sim, MotionCommand::Arc(1, 7.0));
  std::printf("tilt_slope: max pitch %.1f deg, reached x = %.2f m\n", r.max_pitch_deg,
              sim.Truth().position.x());
  EXPECT_EQ(r.status.state, MobilityState::kDone);
  EXPECT_GT(r.max_pitch_deg, 22.0);
  EXPECT_GT(sim.Truth().position.x(), 6.0);  // bedrock: low slip, it climbs
}

TEST(ScenarioWorlds, OutcropSlopeAcrossThenUp) {
  const auto world = LoadWorld("outcrop_slope");
  RoverSimulator sim(world, RoverOptions());
  const DriveResult across = Drive(sim, MotionCommand::Arc(1, 3.0));
  EXPECT_EQ(across.status.state, MobilityState::kDone);
  EXPECT_GT(across.max_roll_deg, 18.0);
  Drive(sim, MotionCommand::Turn(2, 90.0 * kDeg));
  const DriveResult up = Drive(sim, MotionCommand::Arc(3, 5.0));
  std::printf("outcrop_slope: roll across %.1f deg, pitch up %.1f deg, end (%.2f, %.2f)\n",
              across.max_roll_deg, up.max_pitch_deg, sim.Truth().position.x(),
              sim.Truth().position.y());
  EXPECT_EQ(up.status.state, MobilityState::kDone);
  EXPECT_GT(up.max_pitch_deg, 20.0);
  EXPECT_LT(up.max_pitch_deg, 27.0);
  EXPECT_GT(sim.Truth().position.y(), 4.0);
}

TEST(ScenarioWorlds, WopmayLiesBelowTheStartOnLooseSand) {
  const auto world = LoadWorld("wopmay_sand_slope");
  const terrain::Rock* wopmay = world.FindRock("Wopmay");
  ASSERT_NE(wopmay, nullptr);
  EXPECT_TRUE(wopmay->keepout);
  const auto& start = world.options().start;
  // Below the start: lower ground, and the slope falls toward it at 17 to 20 deg.
  EXPECT_LT(world.GroundElevation(wopmay->position.x(), wopmay->position.y()),
            world.GroundElevation(start.x, start.y) - 1.0);
  for (double x = start.x; x < wopmay->position.x() - 1.0; x += 0.5) {
    // Over a rover-length baseline, so ripples do not count.
    const double slope =
        std::atan(world.Elevation(x - 0.5, start.y - 1.5) - world.Elevation(x + 0.5, start.y - 1.5)) /
        kDeg;
    EXPECT_GT(slope, 16.0) << x;
    EXPECT_LT(slope, 21.5) << x;
    EXPECT_EQ(world.SoilAt(x, start.y), terrain::Soil::kSand);
  }
  // Driving straight at it without a keep-out check ends on the rock.
  RoverSimulator sim(world, RoverOptions());
  const DriveResult r = Drive(sim, MotionCommand::Arc(1, 6.0));
  EXPECT_EQ(r.status.state, MobilityState::kFault);
  EXPECT_NE(r.status.detail.find("Wopmay"), std::string::npos) << r.status.detail;
}

TEST(ScenarioWorlds, RockCourseRocksAreUnderTwentyCentimetresExceptKeepOutOnes) {
  const auto world = LoadWorld("flat_rock_course");
  int keepout = 0;
  for (const auto& r : world.rocks()) {
    if (r.keepout) {
      ++keepout;
      EXPECT_GT(r.height_m, 0.3) << r.name;  // a real obstacle
    } else {
      EXPECT_LT(r.height_m, 0.2) << r.name;
    }
  }
  EXPECT_GE(keepout, 3);
  EXPECT_GT(world.rocks().size(), 500u);
}

// MER testbed rock course: driving north over the cobbles in 35 cm steps, wheel odometry
// passes 10 % error within 1.4 m.
TEST(ScenarioWorlds, RockCourseSlipDefeatsWheelOdometry) {
  const auto world = LoadWorld("flat_rock_course");
  RoverSimulator sim(world, RoverOptions());
  double max_step_slip = 0.0;
  for (int step = 0; step < 4; ++step) {
    const RoverTruth a = sim.Truth();
    const DriveResult r = Drive(sim, MotionCommand::Arc(step, 0.35));
    ASSERT_EQ(r.status.state, MobilityState::kDone) << r.status.detail;
    const Eigen::Vector3d fwd = a.q_site_rover * Eigen::Vector3d::UnitX();
    max_step_slip = std::max(max_step_slip, 1.0 - (sim.Truth().position - a.position).dot(fwd) / 0.35);
  }
  const double true_progress = sim.Truth().position.x();
  const double odo_error = (sim.Odometry().distance_m - true_progress) / sim.Odometry().distance_m;
  std::printf("rock course: after 1.4 m, wheel odometry error %.1f %%, max step slip %.0f %%\n",
              100 * odo_error, 100 * max_step_slip);
  EXPECT_GT(odo_error, 0.10);
}

TEST(ScenarioWorlds, LowSunAndFeaturelessSandHaveTheirSettings) {
  const auto shadow = LoadWorld("sand_two_rocks_low_sun");
  EXPECT_LT(shadow.sun().elevation_deg, 20.0);
  EXPECT_EQ(shadow.rocks().size(), 2u);
  EXPECT_EQ(shadow.SoilAt(2.0, 0.0), terrain::Soil::kSand);
  const auto bland = LoadWorld("featureless_sand");
  EXPECT_TRUE(bland.rocks().empty());
  EXPECT_LT(bland.options().albedo.sand.contrast, 0.02);
}

}  // namespace
}  // namespace rover::mobility
