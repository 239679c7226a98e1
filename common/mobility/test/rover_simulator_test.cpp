#include "mobility/rover_simulator.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>

namespace rover::mobility {
namespace {

using terrain::Soil;
using terrain::World;
using terrain::WorldOptions;
constexpr double kDeg = M_PI / 180.0;

WorldOptions Plane(Soil soil, double slope_deg, double uphill_azimuth_deg) {
  WorldOptions o;
  o.map_size_m = {30.0, 30.0};
  o.resolution_m = 0.05;
  o.default_soil = soil;
  if (slope_deg > 0.0) {
    terrain::SlopeOptions s;
    s.angle_deg = slope_deg;
    s.uphill_azimuth_deg = uphill_azimuth_deg;
    o.slopes.push_back(s);
  }
  return o;
}

MobilityOptions Quiet() {
  MobilityOptions o;
  for (auto& s : o.slip.soils) s.noise_std = 0.0;
  return o;
}

// Slip measured from truth: 1 - (true 3-D displacement along the heading) / (wheel distance).
double MeasuredSlip(const RoverTruth& a, const RoverTruth& b, double wheel_distance) {
  const Eigen::Vector3d fwd = a.q_site_rover * Eigen::Vector3d::UnitX();
  return 1.0 - (b.position - a.position).dot(fwd) / wheel_distance;
}

TEST(RoverSimulator, StraightDriveOnFlatBedrockEndsAtCommandedDistance) {
  const World world(Plane(Soil::kBedrock, 0.0, 0.0));
  RoverSimulator sim(world, MobilityOptions(), 0.0, 0.0, 0.0);
  sim.Command(MotionCommand::Arc(7, 2.0));
  const MobilityStatus st = sim.RunUntilIdle();
  EXPECT_EQ(st.state, MobilityState::kDone);
  EXPECT_EQ(st.command_id, 7);
  EXPECT_NEAR(st.wheel_distance_m, 2.0, 1e-9);
  const RoverTruth t = sim.Truth();
  EXPECT_NEAR(t.position.x(), 2.0, 0.03);  // bedrock: slip noise 0.5 %
  EXPECT_NEAR(t.position.y(), 0.0, 0.01);
  EXPECT_NEAR(t.rpy.x(), 0.0, 1e-6);
  EXPECT_NEAR(t.rpy.y(), 0.0, 1e-6);
  EXPECT_NEAR(sim.Odometry().distance_m, 2.0, 1e-9);
  for (double d : sim.Odometry().wheel_distance_m) EXPECT_NEAR(d, 2.0, 1e-9);
  // 2 m at 4 cm/s: 50 s of rover time.
  EXPECT_NEAR(static_cast<double>(sim.utime()) * 1e-6, 50.0, 0.2);

  RoverSimulator quiet(world, Quiet(), 0.0, 0.0, 0.0);
  quiet.Command(MotionCommand::Arc(1, -1.5));
  quiet.RunUntilIdle();
  EXPECT_NEAR(quiet.Truth().position.x(), -1.5, 1e-6);
}

TEST(RoverSimulator, TurnInPlaceNinetyDegrees) {
  const World world(Plane(Soil::kBedrock, 0.0, 0.0));
  RoverSimulator sim(world, MobilityOptions(), 1.0, 2.0, 0.0);
  sim.Command(MotionCommand::Turn(3, 90.0 * kDeg));
  const MobilityStatus st = sim.RunUntilIdle();
  EXPECT_EQ(st.state, MobilityState::kDone);
  EXPECT_NEAR(st.wheel_turn_rad, 90.0 * kDeg, 1e-9);
  const RoverTruth t = sim.Truth();
  // Bedrock turn slip is 2 %: 88.2 deg, +- noise.
  EXPECT_NEAR(t.rpy.z() / kDeg, 90.0 * (1 - 0.02), 1.0);
  EXPECT_NEAR((t.position.head<2>() - Eigen::Vector2d(1.0, 2.0)).norm(), 0.0, 1e-6);
  // Clockwise: the left wheels rolled forward, the right ones backward, arc = angle * arm.
  const WheelOdometrySample odo = sim.Odometry();
  const double arm = sim.options().geometry.WheelPosition(kLeftFront).norm();
  EXPECT_NEAR(odo.wheel_distance_m[kLeftFront], 90.0 * kDeg * arm, 1e-9);
  EXPECT_NEAR(odo.wheel_distance_m[kRightFront], -90.0 * kDeg * arm, 1e-9);
  EXPECT_GT(odo.wheel_distance_m[kLeftMiddle], 0.0);
  EXPECT_NEAR(odo.distance_m, 0.0, 1e-12);

  // Turning on loose sand loses more of the turn.
  const World sand(Plane(Soil::kSand, 0.0, 0.0));
  RoverSimulator on_sand(sand, Quiet(), 0.0, 0.0, 0.0);
  on_sand.Command(MotionCommand::Turn(4, -90.0 * kDeg));
  on_sand.RunUntilIdle();
  EXPECT_NEAR(on_sand.Truth().rpy.z() / kDeg, -90.0 * (1 - 0.1), 1e-6);
}

TEST(RoverSimulator, ArcEndsWhereGeometrySays) {
  const World world(Plane(Soil::kBedrock, 0.0, 0.0));
  const double R = 2.5, L = 3.0;
  RoverSimulator sim(world, Quiet(), 0.0, 0.0, 0.0);
  sim.Command(MotionCommand::Arc(1, L, 1.0 / R));  // + curvature: toward the right (east)
  sim.RunUntilIdle();
  const RoverTruth t = sim.Truth();
  EXPECT_NEAR(t.position.x(), R * std::sin(L / R), 1e-3);
  EXPECT_NEAR(t.position.y(), R * (1.0 - std::cos(L / R)), 1e-3);
  EXPECT_NEAR(t.rpy.z(), L / R, 1e-6);
  // The outer (left) wheels roll farther than the inner ones; the body estimate is exact.
  const WheelOdometrySample odo = sim.Odometry();
  EXPECT_GT(odo.wheel_distance_m[kLeftMiddle], L);
  EXPECT_LT(odo.wheel_distance_m[kRightMiddle], L);
  EXPECT_NEAR(odo.wheel_distance_m[kLeftMiddle], L * (1.0 + 0.5 / R), 1e-9);
  EXPECT_NEAR(odo.distance_m, L, 1e-9);
}

TEST(RoverSimulator, SandAtTenDegreesUphillSlipsModerately) {
  const World world(Plane(Soil::kSand, 10.0, 0.0));
  RoverSimulator sim(world, MobilityOptions(), 0.0, 0.0, 0.0);
  const RoverTruth start = sim.Truth();
  sim.Command(MotionCommand::Arc(1, 3.0));
  sim.RunUntilIdle();
  const double slip = MeasuredSlip(start, sim.Truth(), 3.0);
  std::printf("sand 10 deg uphill: slip %.1f %%\n", 100 * slip);
  EXPECT_GT(slip, 0.10);
  EXPECT_LT(slip, 0.20);
  EXPECT_GT(sim.Truth().position.x(), 2.0);
}

TEST(RoverSimulator, LooseSandAt28DegreesUphillSlidesBack) {
  const World world(Plane(Soil::kSand, 28.0, 0.0));
  RoverSimulator sim(world, MobilityOptions(), 0.0, 0.0, 0.0);
  const RoverTruth start = sim.Truth();
  sim.Command(MotionCommand::Arc(1, 2.0));
  const MobilityStatus st = sim.RunUntilIdle();
  EXPECT_EQ(st.state, MobilityState::kDone);  // the rover believes it drove 2 m
  const RoverTruth end = sim.Truth();
  const double slip = MeasuredSlip(start, end, 2.0);
  std::printf("sand 28 deg uphill: slip %.1f %%, moved %.3f m north, elevation %+.3f m\n",
              100 * slip, end.position.x() - start.position.x(),
              -(end.position.z() - start.position.z()));
  EXPECT_GT(slip, 1.0);
  EXPECT_LT(end.position.x(), start.position.x());
  EXPECT_GT(end.position.z(), start.position.z());  // Z down: it ends below its start
}

TEST(RoverSimulator, CrossSlopeDriveDriftsDownslope) {
  // Uphill toward the east; the rover drives north, across the slope.
  const World world(Plane(Soil::kSand, 15.0, 90.0));
  RoverSimulator sim(world, MobilityOptions(), 0.0, 0.0, 0.0);
  const RoverTruth start = sim.Truth();
  EXPECT_NEAR(start.rpy.x() / kDeg, -15.0, 0.05);  // right (east) side high: negative roll
  sim.Command(MotionCommand::Arc(1, 3.0));
  sim.RunUntilIdle();
  const RoverTruth end = sim.Truth();
  std::printf("sand 15 deg cross slope: drift %.3f m west over 3 m\n", -end.position.y());
  EXPECT_LT(end.position.y(), -0.2);
  EXPECT_GT(end.position.z(), start.position.z() + 0.05);  // lower
}

// Sideways slip follows the soil's table: on packed soil across a 20 deg slope the rover
// crabs 0.45 m downslope per metre rolled, and travels further than its wheels roll.
TEST(RoverSimulator, CrossSlopeCrabFollowsTheSoilTable) {
  const World world(Plane(Soil::kPackedSoil, 20.0, 90.0));
  MobilityOptions o = Quiet();
  const double table = o.slip.For(Soil::kPackedSoil).DriftAt(20.0);
  EXPECT_DOUBLE_EQ(table, 0.45);
  EXPECT_DOUBLE_EQ(o.slip.For(Soil::kPackedSoil).DriftAt(-20.0), table);  // either side
  EXPECT_NEAR(o.slip.For(Soil::kPackedSoil).DriftAt(17.5), 0.15 + 0.5 * 0.3, 1e-12);
  RoverSimulator sim(world, o, 0.0, 0.0, 0.0);
  const RoverTruth start = sim.Truth();
  sim.Command(MotionCommand::Arc(1, 2.0));
  sim.RunUntilIdle();
  const RoverTruth end = sim.Truth();
  // Downslope is west (-y); the drift is horizontal motion along the rover's Y axis.
  EXPECT_NEAR(-(end.position.y() - start.position.y()) / std::cos(20.0 * kDeg), 2.0 * table, 0.02);
  EXPECT_NEAR(end.position.x() - start.position.x(), 2.0 * (1.0 - 0.02), 0.01);  // flat-ground slip
  EXPECT_GT(end.odometer_m, 2.0 * 1.05);  // true path longer than the wheels' 2 m
  // drift_per_deg is the linear form of the same thing.
  SoilSlip linear;
  linear.drift_per_deg = 0.01;
  EXPECT_DOUBLE_EQ(linear.DriftAt(-15.0), 0.15);
}

// A rock under a wheel: the climbing wheel's share of the weight makes the rover drive up
// a steeper grade. On loose sand that can stall it, never push it back; on bedrock the
// same rock costs little.
TEST(RoverSimulator, RocksStallTheRoverOnSandButNotOnBedrock) {
  auto slip_over_rocks = [](Soil soil, double incline_deg) {
    WorldOptions w = Plane(soil, incline_deg, 0.0);
    // Cobbles 18 cm tall in both wheel tracks, one under each wheel pair's path.
    for (int k = 0; k < 3; ++k) {
      for (double y : {-0.5, 0.5}) {
        terrain::Rock r;
        r.name = "cobble_" + std::to_string(k) + (y < 0 ? "l" : "r");
        r.position = {0.9 + 0.35 * k + (y < 0 ? 0.0 : 0.17), y};
        r.diameter_m = 0.36;
        r.height_m = 0.18;
        r.placed = true;
        w.placed_rocks.push_back(r);
      }
    }
    const World world(w);
    RoverSimulator sim(world, Quiet(), 0.0, 0.0, 0.0);
    double max_slip = 0.0;
    for (int step = 0; step < 6; ++step) {
      const RoverTruth a = sim.Truth();
      sim.Command(MotionCommand::Arc(step, 0.35));
      sim.RunUntilIdle();
      max_slip = std::max(max_slip, MeasuredSlip(a, sim.Truth(), 0.35));
    }
    return max_slip;
  };
  const double sand = slip_over_rocks(Soil::kSand, 0.0), bedrock = slip_over_rocks(Soil::kBedrock, 0.0);
  const double sand_up = slip_over_rocks(Soil::kSand, 10.0);
  std::printf("cobbles in both tracks, 35 cm steps: max step slip %.0f %% on flat sand, %.0f %% on "
              "flat bedrock, %.0f %% up 10 deg of sand\n", 100 * sand, 100 * bedrock, 100 * sand_up);
  EXPECT_GT(sand, 0.3);
  EXPECT_LT(bedrock, 0.1);
  EXPECT_GT(sand_up, 0.75);  // sand alone slips 15 % there
  EXPECT_LE(sand_up, MobilityOptions().slip.rock_stall_slip + 0.03);  // stalled, not pushed back
}

TEST(RoverSimulator, PitchEqualsSlopeDrivingStraightUp) {
  const World world(Plane(Soil::kBedrock, 20.0, 0.0));
  RoverSimulator sim(world, MobilityOptions(), 0.0, 0.0, 0.0);
  sim.Command(MotionCommand::Arc(1, 1.0));
  sim.RunUntilIdle();
  const RoverTruth t = sim.Truth();
  EXPECT_NEAR(t.rpy.y() / kDeg, 20.0, 0.05);
  EXPECT_NEAR(t.rpy.x() / kDeg, 0.0, 0.05);
  // Wheel distance is along the surface: 1 m rolled at ~0 slip climbs sin(20 deg).
  EXPECT_NEAR(-t.position.z(), std::sin(20.0 * kDeg) * (1.0 - t.slip), 0.02);
  // The IMU sees the same pitch, and gravity along -X of the nose-up rover... frame.
  const ImuSample imu = sim.Imu();
  const Eigen::Vector3d rpy = geometry::RpyFromRotation(imu.q_site_rover.toRotationMatrix());
  EXPECT_NEAR(rpy.y() / kDeg, 20.0, 0.2);
  EXPECT_NEAR(imu.accel_mps2.x(), 3.711 * std::sin(20.0 * kDeg), 0.03);
}

TEST(RoverSimulator, CraterBowlPitchesDownOnTheWayIn) {
  WorldOptions o = Plane(Soil::kPackedSoil, 0.0, 0.0);
  terrain::CraterOptions c;
  c.center = {6.0, 0.0};
  c.radius_m = 5.0;
  c.depth_m = 1.0;
  c.rim_height_m = 0.0;
  o.craters.push_back(c);
  const World world(o);
  RoverSimulator sim(world, Quiet(), 0.0, 0.0, 0.0);
  sim.Command(MotionCommand::Arc(1, 3.0));
  sim.RunUntilIdle();
  // At x ~ 3 (r ~ 3), the bowl wall slopes down at 2 * depth * r / R^2.
  const RoverTruth t = sim.Truth();
  const double r = 6.0 - t.position.x();
  EXPECT_NEAR(std::tan(-t.rpy.y()), 2.0 * 1.0 * r / 25.0, 0.01);
  // The rover sits on its wheels: a plane fitted to a bowl of curvature 2 * depth / R^2
  // lies above the floor by half the curvature times the mean squared wheel offset.
  const auto& g = sim.options().geometry;
  const double mean_sq = (2.0 / 3.0) * std::pow(0.5 * g.wheelbase_m, 2) + std::pow(0.5 * g.track_m, 2);
  EXPECT_NEAR(-t.position.z(), -1.0 * (1.0 - r * r / 25.0) + 0.5 * (2.0 / 25.0) * mean_sq, 0.002);
}

TEST(RoverSimulator, ImuYawDriftsAboutThreeDegreesPerHour) {
  const World world(Plane(Soil::kBedrock, 5.0, 30.0));
  RoverSimulator sim(world, MobilityOptions(), 0.0, 0.0, 0.3);
  double max_tilt_err = 0.0;
  for (int k = 0; k < 60; ++k) {
    const StepOutput& out = sim.Step(60.0);
    ASSERT_EQ(out.imu.size(), 1200u);  // 20 Hz
    for (const auto& s : out.imu) {
      const Eigen::Vector3d rpy = geometry::RpyFromRotation(s.q_site_rover.toRotationMatrix());
      const Eigen::Vector3d truth = sim.Truth().rpy;
      max_tilt_err = std::max({max_tilt_err, std::abs(rpy.x() - truth.x()), std::abs(rpy.y() - truth.y())});
    }
  }
  const Eigen::Vector3d rpy = geometry::RpyFromRotation(sim.Imu().q_site_rover.toRotationMatrix());
  const double drift_deg = geometry::WrapAngle(rpy.z() - sim.Truth().rpy.z()) / kDeg;
  std::printf("IMU yaw drift after 1 h: %.3f deg; max roll/pitch error %.3f deg\n", drift_deg,
              max_tilt_err / kDeg);
  EXPECT_NEAR(drift_deg, 3.0, 0.6);
  EXPECT_LT(max_tilt_err / kDeg, 0.2);
  EXPECT_NEAR(sim.Imu().angular_rate_rps.z(), 3.0 * kDeg / 3600.0, 0.002);
}

TEST(RoverSimulator, ImuRatesFollowTheTurnAndOdometryFlagsIt) {
  const World world(Plane(Soil::kBedrock, 0.0, 0.0));
  MobilityOptions o = Quiet();
  o.imu.rate_noise_deg_s = 0.0;
  RoverSimulator sim(world, o, 0.0, 0.0, 0.0);
  MotionCommand turn = MotionCommand::Turn(1, -30.0 * kDeg);
  turn.turn_rate_rps = 2.0 * kDeg;
  sim.Command(turn);
  const StepOutput& out = sim.Step(3.0);
  ASSERT_FALSE(out.imu.empty());
  // Counter-clockwise at 2 deg/s through the wheels, 2 % lost to turn slip.
  EXPECT_NEAR(out.imu.back().angular_rate_rps.z() / kDeg, -2.0 * 0.98, 0.01);
  ASSERT_FALSE(out.odometry.empty());
  EXPECT_TRUE(out.odometry.back().turning_in_place);
  sim.RunUntilIdle();
  EXPECT_FALSE(sim.Odometry().turning_in_place);
  sim.Command(MotionCommand::Arc(2, 0.5, -0.5));
  EXPECT_DOUBLE_EQ(sim.Step(1.0).odometry.back().curvature_per_m, -0.5);
  const RoverTruth t = sim.Truth();
  EXPECT_TRUE(t.T_site_rover().translation().isApprox(t.position));
  EXPECT_NEAR(geometry::RpyFromRotation(t.T_site_rover().linear()).z(), t.rpy.z(), 1e-9);
  EXPECT_EQ(t.command_id, 2);
}

TEST(RoverSimulator, EncodersReportAtEightHertzOrMore) {
  const World world(Plane(Soil::kPackedSoil, 0.0, 0.0));
  RoverSimulator sim(world, MobilityOptions(), 0.0, 0.0, 0.0, 1'000'000);
  sim.Command(MotionCommand::Arc(1, 1.0));
  std::int64_t last = 1'000'000;
  int count = 0;
  double last_distance = 0.0;
  for (int k = 0; k < 100; ++k) {
    const StepOutput& out = sim.Step(0.1 + 0.03 * (k % 3));  // uneven caller steps
    for (const auto& s : out.odometry) {
      EXPECT_LE(s.utime - last, 125'000);
      EXPECT_GT(s.utime, last);
      EXPECT_GE(s.distance_m, last_distance);
      last = s.utime;
      last_distance = s.distance_m;
      ++count;
    }
  }
  const double seconds = (sim.utime() - 1'000'000) * 1e-6;
  EXPECT_GE(count / seconds, 8.0);
}

TEST(RoverSimulator, DraggedWheelMakesWheelOdometryUnderestimate) {
  const World world(Plane(Soil::kPackedSoil, 0.0, 0.0));
  MobilityOptions o;
  o.slip.dragged.wheel = kRightFront;
  o.slip.dragged.encoder = DraggedWheel::Encoder::kZero;
  RoverSimulator sim(world, o, 0.0, 0.0, 0.0);
  sim.Command(MotionCommand::Arc(1, 5.0));
  sim.RunUntilIdle();
  const WheelOdometrySample odo = sim.Odometry();
  const RoverTruth t = sim.Truth();
  std::printf("dragged wheel: wheel odometry %.3f m, truth %.3f m, heading change %.2f deg\n",
              odo.distance_m, t.odometer_m, t.rpy.z() / kDeg);
  EXPECT_EQ(odo.wheel_distance_m[kRightFront], 0.0);
  EXPECT_NEAR(odo.wheel_distance_m[kLeftFront], 5.0, 1e-9);
  EXPECT_LT(odo.distance_m, t.odometer_m - 0.2);
  EXPECT_GT(t.rpy.z(), 0.02);  // it pulls toward the dragged (right) side
}

std::vector<double> Trace(std::uint64_t seed) {
  const World world(Plane(Soil::kSand, 12.0, 60.0));
  MobilityOptions o;
  o.seed = seed;
  RoverSimulator sim(world, o, 0.0, 0.0, 0.0);
  std::vector<double> trace;
  sim.Command(MotionCommand::Arc(1, 1.0, 0.2));
  for (int k = 0; k < 300; ++k) {
    const StepOutput& out = sim.Step(0.1);
    for (const auto& s : out.imu) trace.push_back(s.q_site_rover.z());
    for (const auto& s : out.odometry) trace.push_back(s.distance_m);
    trace.push_back(sim.Truth().position.x());
    trace.push_back(sim.Truth().position.y());
  }
  return trace;
}

TEST(RoverSimulator, SameSeedSameOutputs) {
  const auto a = Trace(5), b = Trace(5), c = Trace(6);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
}

// Substeps end on multiples of max_substep_s and on sample times, whatever the caller's
// dt, so a process stepping at 100 Hz and a test stepping at 2 Hz see the same rover.
TEST(RoverSimulator, CallerStepSizeDoesNotChangeTheOutcome) {
  const World world(Plane(Soil::kSand, 14.0, 100.0));
  auto run = [&](double dt) {
    RoverSimulator sim(world, MobilityOptions(), 0.0, 0.0, 0.0);
    sim.Command(MotionCommand::Arc(1, 1.2, 0.3));
    std::vector<double> imu_z;
    while (sim.utime() < 40'000'000) {
      for (const auto& s : sim.Step(dt).imu) imu_z.push_back(s.q_site_rover.z());
    }
    const RoverTruth t = sim.Truth();
    imu_z.push_back(t.position.x());
    imu_z.push_back(t.position.y());
    imu_z.push_back(t.rpy.z());
    return imu_z;
  };
  const auto fine = run(0.01);
  EXPECT_EQ(fine, run(0.5));
  EXPECT_EQ(fine, run(2.0));
}

TEST(RoverSimulator, StatusStopPreemptAndFaults) {
  WorldOptions wo = Plane(Soil::kBedrock, 0.0, 0.0);
  wo.map_size_m = {8.0, 8.0};
  terrain::Rock boulder;
  boulder.name = "Boulder";
  boulder.position = {-2.5, 0.0};
  boulder.diameter_m = 0.8;
  boulder.height_m = 0.5;
  wo.placed_rocks.push_back(boulder);
  const World world(wo);
  RoverSimulator sim(world, Quiet(), 0.0, 0.0, 0.0);
  sim.Command(MotionCommand::Arc(1, 1.0));
  const StepOutput& out1 = sim.Step(5.0);
  ASSERT_EQ(out1.status.size(), 1u);
  EXPECT_EQ(out1.status[0].state, MobilityState::kMoving);
  EXPECT_EQ(out1.status[0].command_id, 1);
  sim.Command(MotionCommand::Arc(2, 0.5));  // preempts 1
  sim.Command(MotionCommand::Stop(3));      // stops 2
  const StepOutput& out2 = sim.Step(1.0);
  ASSERT_EQ(out2.status.size(), 4u);
  EXPECT_EQ(out2.status[0].command_id, 1);
  EXPECT_EQ(out2.status[0].state, MobilityState::kStopped);
  EXPECT_EQ(out2.status[1].command_id, 2);
  EXPECT_EQ(out2.status[1].state, MobilityState::kMoving);
  EXPECT_EQ(out2.status[2].state, MobilityState::kStopped);
  EXPECT_EQ(out2.status[3].command_id, 3);
  const double x_stopped = sim.Truth().position.x();
  sim.Step(10.0);
  EXPECT_DOUBLE_EQ(sim.Truth().position.x(), x_stopped);
  EXPECT_NEAR(x_stopped, 0.2, 1e-6);  // 5 s at 4 cm/s

  // Backing into the 0.5 m boulder: a fault, the rover stops where the boulder's surface
  // under the rear edge rises over the 0.3 m clearance, 0.32 m from its centre
  // (0.5 sqrt(1 - (0.32 / 0.4)^2) = 0.3), with the origin 0.8 m ahead of that edge.
  sim.Command(MotionCommand::Arc(4, -3.0));
  EXPECT_EQ(sim.RunUntilIdle().state, MobilityState::kFault);
  EXPECT_NE(sim.status().detail.find("Boulder"), std::string::npos) << sim.status().detail;
  EXPECT_NEAR(sim.Truth().position.x(), -2.5 + 0.32 + 0.8, 0.005);

  // Driving off the map: a fault.
  sim.Command(MotionCommand::Arc(5, 6.0));
  EXPECT_EQ(sim.RunUntilIdle().state, MobilityState::kFault);
  EXPECT_NE(sim.status().detail.find("left the map"), std::string::npos);

  EXPECT_THROW(sim.Command(MotionCommand::Arc(6, std::nan(""))), std::invalid_argument);
  EXPECT_THROW(sim.Command(MotionCommand::Arc(6, 1.0, 50.0)), std::invalid_argument);
  EXPECT_THROW(sim.Step(0.0), std::invalid_argument);
  EXPECT_THROW(RoverSimulator(world, Quiet(), 20.0, 0.0, 0.0), std::invalid_argument);
}

// A rock over the clearance whose low rim a footprint's side passes over is no collision; the
// same rock 0.3 m nearer the line, its surface under the side 0.307 m high, is. Both 0.31 m
// tall and 0.78 m across (navbench's rock_1877), beside a 6 m drive north along y = 0.
TEST(RoverSimulator, ARockCollidesWhereItRisesOverTheBellyNotWhereItsRimIsGrazed) {
  auto drive_past = [](double rock_y) {
    WorldOptions wo = Plane(Soil::kBedrock, 0.0, 0.0);
    wo.map_size_m = {16.0, 16.0};
    terrain::Rock rock;
    rock.name = "Rim";
    rock.position = {3.0, rock_y};
    rock.diameter_m = 0.78;
    rock.height_m = 0.31;
    wo.placed_rocks.push_back(rock);
    const World world(wo);
    RoverSimulator sim(world, Quiet(), 0.0, 0.0, 0.0);
    sim.Command(MotionCommand::Arc(1, 6.0));
    const MobilityStatus st = sim.RunUntilIdle();
    return std::make_pair(st, sim.Truth());
  };
  // Centre 1.05 m off the line: 0.35 m beyond the footprint's side (half width 0.7), 0.04 m
  // inside the rock's 0.39 m radius, where it stands 0.31 sqrt(1 - (0.35 / 0.39)^2) = 0.14 m.
  const auto [grazed, grazed_truth] = drive_past(1.05);
  EXPECT_EQ(grazed.state, MobilityState::kDone) << grazed.detail;
  EXPECT_NEAR(grazed_truth.position.x(), 6.0, 0.05);
  // Centre 0.75 m off: 0.05 m beyond the side, 0.31 sqrt(1 - (0.05 / 0.39)^2) = 0.307 m.
  const auto [hit, hit_truth] = drive_past(-0.75);
  EXPECT_EQ(hit.state, MobilityState::kFault);
  EXPECT_NE(hit.detail.find("rock Rim (0.31 m tall, centred at (3.00, -0.75)) 0.30 m high under the footprint"),
            std::string::npos) << hit.detail;
  // Where the rover stood is named apart from where the rock stands.
  EXPECT_NE(hit.detail.find("the rover at (2.1"), std::string::npos) << hit.detail;
  // Stopped as the front edge (0.8 m ahead) came within 0.085 m of the centre's x, where
  // the surface under the corner first rose over 0.3 m: 0.098 m from the centre
  // (0.39 sqrt(1 - (0.3 / 0.31)^2)), hypot(0.085, 0.05).
  EXPECT_NEAR(hit_truth.position.x(), 3.0 - 0.8 - 0.085, 0.01);
}

// 20 m at 4 cm/s is 500 s of rover time; at 100 Hz it must take well under a second.
TEST(RoverSimulator, TwentyMetreDriveStepsInWellUnderASecond) {
  const World world(WorldOptions::LoadFile(std::string(ROVER_SOURCE_DIR) +
                                           "/configs/worlds/columbia_hills_traverse.yaml"));
  RoverSimulator sim(world, MobilityOptions(), 0.0, 0.0, 45.0 * kDeg);
  sim.Command(MotionCommand::Arc(1, 20.0, 0.01));
  const std::clock_t t0 = std::clock();
  std::size_t samples = 0;
  while (sim.moving() || sim.utime() == 0) {
    const StepOutput& out = sim.Step(0.01);
    samples += out.imu.size() + out.odometry.size();
  }
  const double cpu = static_cast<double>(std::clock() - t0) / CLOCKS_PER_SEC;
  std::printf("20 m drive: %.1f s rover time in %.3f s CPU (%zu samples), truth odometer %.2f m\n",
              sim.utime() * 1e-6, cpu, samples, sim.Truth().odometer_m);
  EXPECT_NEAR(sim.utime() * 1e-6, 500.0, 1.0);
  EXPECT_LT(cpu, 0.5);
}

TEST(MobilityOptions, LoadsRoverYamlAndNamesBadKeys) {
  const MobilityOptions o =
      MobilityOptions::LoadFile(std::string(ROVER_SOURCE_DIR) + "/configs/rover.yaml");
  EXPECT_NEAR(o.geometry.speed_mps, 0.04, 0.02);
  EXPECT_GE(o.encoders.rate_hz, 8.0);
  using config::ConfigError;
  using config::ConfigNode;
  auto load = [](const std::string& text) {
    return MobilityOptions::Load(ConfigNode::FromString(text, "rover.yaml"));
  };
  try {
    load("mobility:\n  slip:\n    soils:\n      sand: {drift_per_deg: 0.01, turnslip: 1}\n");
    FAIL() << "expected ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("rover.yaml: mobility.slip.soils.sand.turnslip: unknown key"),
              std::string::npos) << e.what();
  }
  EXPECT_THROW(load("sensors: {wheel_encoders: {rate_hz: 4}}\n"), ConfigError);
  EXPECT_THROW(load("mobility: {slip: {dragged_wheel: {wheel: left_back}}}\n"), ConfigError);
  EXPECT_THROW(load("mobility: {slip: {soils: {sand: {slip_vs_pitch: [[10, 0.1], [5, 0.2]]}}}}\n"),
               ConfigError);
  EXPECT_THROW(load("mobility: {slip: {soils: {sand: {drift_vs_cross_slope: [[0, 0], [10, -0.1]]}}}}\n"),
               ConfigError);
  EXPECT_THROW(load("mobility: {slip: {soils: {sand: {drift_per_deg: 0.01, drift_vs_cross_slope: [[0, 0]]}}}}\n"),
               ConfigError);
  EXPECT_THROW(load("mobility: {slip: {rock_climb_slip: 0.4}}\n"), ConfigError);  // renamed
  const MobilityOptions crab = load(
      "mobility: {slip: {rock_climb_grade: 2, rock_stall_slip: 0.8, soils: {sand: {drift_vs_cross_slope: "
      "[[0, 0], [10, 0.2]]}, bedrock: {drift_per_deg: 0.004}}}}\n");
  EXPECT_DOUBLE_EQ(crab.slip.rock_climb_grade, 2.0);
  EXPECT_DOUBLE_EQ(crab.slip.rock_stall_slip, 0.8);
  EXPECT_DOUBLE_EQ(crab.slip.For(Soil::kSand).DriftAt(5.0), 0.1);
  EXPECT_DOUBLE_EQ(crab.slip.For(Soil::kSand).DriftAt(20.0), 0.2);
  EXPECT_DOUBLE_EQ(crab.slip.For(Soil::kBedrock).DriftAt(10.0), 0.04);  // replaces the table
  const MobilityOptions d = load(
      "mobility:\n  seed: 9\n  speed_mps: 0.05\n  slip:\n    dragged_wheel: {wheel: right_front,"
      " encoder: commanded}\nsensors: {imu: {rate_hz: 50}, navcam: {anything: 1}}\nother: 1\n");
  EXPECT_EQ(d.seed, 9u);
  EXPECT_DOUBLE_EQ(d.geometry.speed_mps, 0.05);
  EXPECT_EQ(d.slip.dragged.wheel, kRightFront);
  EXPECT_EQ(d.slip.dragged.encoder, DraggedWheel::Encoder::kCommanded);
  EXPECT_DOUBLE_EQ(d.imu.rate_hz, 50.0);
}

}  // namespace
}  // namespace rover::mobility
