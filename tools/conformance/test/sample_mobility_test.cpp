// The sample driver's logic, known answers: an arc rolls its distance in distance / speed,
// each side scaled by its distance from the centre of the turn; a turn rolls the left wheels
// forward; a STOP, a newer command, the dead-man and a refusal report what the contract says.
#include "sample_driver/sample_mobility.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace rover::sample_driver {
namespace {

Command Arc(std::int64_t id, double d, double k, double speed) {
  Command c;
  c.id = id;
  c.type = 0;
  c.distance_m = d;
  c.curvature_per_m = k;
  c.speed_mps = speed;
  return c;
}

TEST(SampleMobility, ArcRollsItsDistanceAtItsSpeed) {
  SampleMobility drive;
  const auto started = drive.Execute(Arc(1, 0.10, 1.0, 0.05));
  ASSERT_EQ(started.size(), 1u);
  EXPECT_EQ(started[0].state, State::kMoving);
  double t = 0;
  std::optional<Status> end;
  while (!end && t < 10) {
    end = drive.Advance(0.01);
    t += 0.01;
  }
  ASSERT_TRUE(end);
  EXPECT_EQ(end->state, State::kDone);
  EXPECT_NEAR(t, 2.0, 0.011);
  EXPECT_NEAR(end->wheel_distance_m, 0.10, 1e-12);
  // Curvature 1/m to the right, track 1 m: the left wheels 0.5 m out roll 1.5x, the right 0.5x.
  EXPECT_NEAR(drive.wheel_distance_m()[0], 0.15, 1e-9);
  EXPECT_NEAR(drive.wheel_distance_m()[5], 0.05, 1e-9);
  EXPECT_NEAR(drive.yaw_rad(), 0.10, 1e-9);
}

TEST(SampleMobility, TurnRollsTheLeftWheelsForward) {
  SampleMobility drive;
  Command c;
  c.id = 2;
  c.type = 1;
  c.turn_rad = 0.2;
  c.turn_rate_rps = 0.1;
  drive.Execute(c);
  for (int i = 0; i < 300 && drive.moving(); ++i) drive.Advance(0.01);
  EXPECT_EQ(drive.status().state, State::kDone);
  EXPECT_NEAR(drive.status().wheel_turn_rad, 0.2, 1e-12);
  EXPECT_NEAR(drive.wheel_distance_m()[0], 0.1, 1e-9);   // 0.2 rad x 0.5 m
  EXPECT_NEAR(drive.wheel_distance_m()[3], -0.1, 1e-9);
}

TEST(SampleMobility, StopPreemptDeadmanAndRefusals) {
  SampleMobility drive;
  drive.Execute(Arc(3, 1.0, 0, 0.05));
  drive.Advance(1.0);
  Command stop;
  stop.id = 4;
  stop.type = 2;
  const auto stopped = drive.Execute(stop);
  ASSERT_EQ(stopped.size(), 2u);
  EXPECT_EQ(stopped[0].command_id, 3);
  EXPECT_EQ(stopped[0].state, State::kStopped);
  EXPECT_EQ(stopped[0].detail, "stopped by command 4");
  EXPECT_EQ(stopped[1].command_id, 4);
  EXPECT_EQ(stopped[1].state, State::kStopped);
  EXPECT_FALSE(drive.Advance(1.0));

  drive.Execute(Arc(5, 1.0, 0, 0.05));
  const auto halted = drive.Halt("dead-man: nothing from sequence_executor for 1.6 s");
  ASSERT_TRUE(halted);
  EXPECT_EQ(halted->command_id, 5);
  EXPECT_EQ(halted->state, State::kStopped);
  EXPECT_FALSE(drive.Halt("again"));

  const auto curved = drive.Execute(Arc(6, 0.1, 1000, 0.05));
  ASSERT_EQ(curved.size(), 1u);
  EXPECT_EQ(curved[0].state, State::kFault);
  EXPECT_EQ(curved[0].detail, "command 6 refused: curvature_per_m 1000 is beyond the limit 4");
  EXPECT_EQ(drive.Execute(Arc(7, 0.1, 0, -0.05))[0].detail,
            "command 7 refused: speed_mps -0.05 is outside [0, 0.2]");
  EXPECT_EQ(drive.Execute(Arc(8, std::nan(""), 0, 0.05))[0].detail, "command 8 refused: distance_m is not finite");
  Command unknown = Arc(9, 0.1, 0, 0.05);
  unknown.type = 7;
  EXPECT_EQ(drive.Execute(unknown)[0].detail, "command 9 refused: unknown type 7 (expected 0 arc, 1 turn, 2 stop)");
  EXPECT_FALSE(drive.moving());
  EXPECT_EQ(drive.status().command_id, 5);  // refusals leave the state alone
}

}  // namespace
}  // namespace rover::sample_driver
