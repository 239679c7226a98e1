// The shipped worlds keep the promises their scenarios rely on (the catalogue in
// configs/scenarios/README.md), driven open loop from each world's start pose.
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

// Slip of one step: 1 - true progress along the start heading / wheel distance.
double StepSlip(RoverSimulator& sim, int id, double distance_m) {
  const RoverTruth a = sim.Truth();
  const DriveResult r = Drive(sim, MotionCommand::Arc(id, distance_m));
  EXPECT_EQ(r.status.state, MobilityState::kDone) << r.status.detail;
  const Eigen::Vector3d fwd = a.q_site_rover * Eigen::Vector3d::UnitX();
  return 1.0 - (sim.Truth().position - a.position).dot(fwd) / distance_m;
}

// MER testbed rock course: driving north over the cobbles in 35 cm steps, wheel odometry
// passes 10 % error within 1.4 m, and over the 2.45 m slip reaches the paper's 85 %.
TEST(ScenarioWorlds, RockCourseSlipDefeatsWheelOdometry) {
  const auto world = LoadWorld("rock_course_testbed");
  for (const auto& r : world.rocks()) EXPECT_LT(r.height_m, 0.2) << r.name;
  RoverSimulator sim(world, RoverOptions());
  double max_step_slip = 0.0, odo_error_at_1_4 = 0.0;
  for (int step = 0; step < 7; ++step) {
    max_step_slip = std::max(max_step_slip, StepSlip(sim, step, 0.35));
    if (step == 3) {
      odo_error_at_1_4 = (sim.Odometry().distance_m - sim.Truth().position.x()) / sim.Odometry().distance_m;
    }
  }
  std::printf("rock course: after 1.4 m, wheel odometry error %.1f %%, max step slip %.0f %%\n",
              100 * odo_error_at_1_4, 100 * max_step_slip);
  EXPECT_GT(odo_error_at_1_4, 0.10);
  EXPECT_GT(max_step_slip, 0.75);
  EXPECT_LT(max_step_slip, 1.0);  // rocks stall the rover; on a 10 deg incline it does not slide back
}

// The demo drives 2 m north over flat_rock_course's cobbles and drift sand in 50 cm steps
// under a 40 % slip limit: the cobbles cost slip there, but far from the limit.
TEST(ScenarioWorlds, DemoGroundSlipsWellUnderTheDemoSlipLimit) {
  const auto world = LoadWorld("flat_rock_course");
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    MobilityOptions options = RoverOptions();
    options.seed = seed;
    RoverSimulator sim(world, options);
    double max_step_slip = 0.0;
    for (int step = 0; step < 4; ++step) max_step_slip = std::max(max_step_slip, StepSlip(sim, step, 0.5));
    EXPECT_GT(max_step_slip, 0.08) << seed;
    EXPECT_LT(max_step_slip, 0.30) << seed;
  }
}

// Sols 188 to 191: 19 m up and across a 20 deg hillside of Gusev soil. The rover slides
// down and across the slope: it travels further than its wheels say, ends lower than
// wheel odometry (integrated along its attitude) puts it, and metres away.
TEST(ScenarioWorlds, ColumbiaHillsCrossSlopeOutrunsWheelOdometry) {
  const auto world = LoadWorld("columbia_hills_traverse");
  RoverSimulator sim(world, RoverOptions());
  const RoverTruth start = sim.Truth();
  Eigen::Vector3d odometry = start.position;  // wheel distance along the true attitude
  for (int step = 0; step < 32; ++step) {
    const RoverTruth a = sim.Truth();
    const double before = sim.Odometry().distance_m;
    const DriveResult r = Drive(sim, MotionCommand::Arc(step, 0.6));
    ASSERT_EQ(r.status.state, MobilityState::kDone) << r.status.detail;
    const Eigen::Vector3d fwd = a.q_site_rover * Eigen::Vector3d::UnitX();
    odometry += (sim.Odometry().distance_m - before) * fwd;
  }
  const RoverTruth end = sim.Truth();
  const double wheels = sim.Odometry().distance_m;
  std::printf("columbia hills: truth %.2f m, wheels %.2f m; end %.2f m from odometry's, %.2f m lower\n",
              end.odometer_m, wheels, (end.position - odometry).head<2>().norm(),
              end.position.z() - odometry.z());
  EXPECT_NEAR(wheels, 19.2, 1e-6);
  EXPECT_GT(end.odometer_m - wheels, 0.8);                      // Mars: 1.6 m over 19 m
  EXPECT_GT((end.position - odometry).head<2>().norm(), 3.0);  // Mars: nearly 5 m
  EXPECT_GT(end.position.z() - odometry.z(), 1.0);              // Z down: truth lower
  EXPECT_LT(odometry.z(), start.position.z());                  // the wheels say it climbed
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
