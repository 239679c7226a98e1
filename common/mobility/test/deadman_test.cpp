#include "mobility/deadman.hpp"
#include "mobility/rover_simulator.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace rover::mobility {
namespace {

TEST(Deadman, NeverTripsWhileNothingMoves) {
  const Deadman d;
  EXPECT_FALSE(d.Check(false, 1000.0));
  EXPECT_TRUE(std::isinf(d.SilenceS(1000.0)));
}

TEST(Deadman, TripsOnlyAfterTheTimeoutOfSilenceDuringAMotion) {
  Deadman d(DeadmanOptions{1.5, "sequence_executor"});
  d.OnCommanderMessage(10.0);  // the command that started the motion
  EXPECT_FALSE(d.Check(true, 11.0));
  EXPECT_FALSE(d.Check(true, 11.5));  // exactly the limit: still alive
  const auto detail = d.Check(true, 11.6);
  ASSERT_TRUE(detail);
  EXPECT_EQ(*detail, "dead-man: nothing from sequence_executor for 1.6 s of wall time (limit 1.5 s); stopped");
  EXPECT_FALSE(d.Check(false, 11.6));  // stopped: nothing more to do
}

TEST(Deadman, TheCommandersHeartbeatsAndCommandsKeepTheMotionGoing) {
  Deadman d;
  d.OnCommanderMessage(0.0);
  for (double t = 1.0; t <= 30.0; t += 1.0) {
    d.OnHeartbeat("sequence_executor", t);
    EXPECT_FALSE(d.Check(true, t + 0.99)) << t;
  }
  // A new command half a period later counts as well.
  d.OnCommanderMessage(30.5);
  EXPECT_FALSE(d.Check(true, 31.9));
  EXPECT_TRUE(d.Check(true, 32.1));
}

TEST(Deadman, OtherProcessesHeartbeatsDoNotCount) {
  Deadman d;
  d.OnCommanderMessage(0.0);
  d.OnHeartbeat("state_estimator", 1.0);
  d.OnHeartbeat("rover_sim", 1.4);
  EXPECT_TRUE(d.Check(true, 1.6));
}

TEST(Deadman, LateMessagesNeverMoveTheLastHeardTimeBack) {
  Deadman d;
  d.OnCommanderMessage(5.0);
  d.OnCommanderMessage(2.0);
  EXPECT_DOUBLE_EQ(d.SilenceS(6.0), 1.0);
}

TEST(Deadman, NeverHeardCommanderStopsAMotion) {
  const Deadman d(DeadmanOptions{0.5, "teleop"});
  const auto detail = d.Check(true, 0.0);
  ASSERT_TRUE(detail);
  EXPECT_EQ(*detail, "dead-man: nothing from teleop within 0.5 s of wall time; stopped");
}

TEST(Deadman, TimeoutOutOfRangeIsRefused) {
  EXPECT_THROW(Deadman(DeadmanOptions{0.0, "x"}), std::invalid_argument);
  EXPECT_THROW(Deadman(DeadmanOptions{NAN, "x"}), std::invalid_argument);
  EXPECT_THROW(Deadman(DeadmanOptions{61.0, "x"}), std::invalid_argument);
}

TEST(Deadman, ConfigKeyWithRangeCheck) {
  using config::ConfigNode;
  EXPECT_DOUBLE_EQ(LoadDeadmanOptions(ConfigNode::FromString("{}", "r.yaml")).timeout_s, 1.5);
  EXPECT_DOUBLE_EQ(
      LoadDeadmanOptions(ConfigNode::FromString("mobility:\n  deadman_s: 0.8\n", "r.yaml")).timeout_s, 0.8);
  try {
    LoadDeadmanOptions(ConfigNode::FromString("mobility:\n  deadman_s: 1e9\n", "r.yaml"));
    FAIL() << "accepted 1e9";
  } catch (const config::ConfigError& e) {
    EXPECT_EQ(std::string(e.what()),
              "r.yaml: mobility.deadman_s: expected a number in [0.2, 60], got \"1e9\"");
  }
  // MobilityOptions accepts the key it does not read itself.
  EXPECT_NO_THROW(MobilityOptions::Load(ConfigNode::FromString("mobility:\n  deadman_s: 2\n", "r.yaml")));
}

TEST(RoverSimulatorHalt, StopsTheMotionKeepingItsIdAndTheRoverStaysPut) {
  terrain::WorldOptions wo;
  wo.map_size_m = {30.0, 30.0};
  wo.resolution_m = 0.05;
  const terrain::World world(wo);
  RoverSimulator sim(world, MobilityOptions(), 0.0, 0.0, 0.0);
  sim.Command(MotionCommand::Arc(42, 5.0));
  for (int i = 0; i < 500; ++i) sim.Step(0.01);  // 5 s: 20 cm at 4 cm/s
  ASSERT_TRUE(sim.moving());
  sim.Halt("dead-man: test");
  const StepOutput& out = sim.Step(0.01);
  ASSERT_FALSE(out.status.empty());
  EXPECT_EQ(out.status.back().state, MobilityState::kStopped);
  EXPECT_EQ(out.status.back().command_id, 42);
  EXPECT_EQ(out.status.back().detail, "dead-man: test");
  EXPECT_NEAR(out.status.back().wheel_distance_m, 0.2, 0.002);
  const double x = sim.Truth().position.x();
  for (int i = 0; i < 1000; ++i) sim.Step(0.01);
  EXPECT_NEAR(sim.Truth().position.x(), x, 1e-9);
  sim.Halt("again");  // nothing moves: no new status
  EXPECT_TRUE(sim.Step(0.01).status.empty());
}

// The process loop in miniature: rover time runs 50x the wall clock; the commander
// sends a heartbeat once a wall second and dies at wall 3.2 s. The rover must stop no
// later than its last heartbeat + the timeout + one loop, and not move afterwards.
TEST(RoverSimulatorHalt, ADeadCommanderStopsTheRoverWithinTheTimeout) {
  terrain::WorldOptions wo;
  wo.map_size_m = {60.0, 60.0};
  wo.resolution_m = 0.1;
  const terrain::World world(wo);
  RoverSimulator sim(world, MobilityOptions(), 0.0, 0.0, 0.0);
  Deadman deadman;
  const double rate = 50.0, loop_wall_s = 0.002, death_s = 3.2;
  double stopped_at = -1.0, last_heartbeat = 0.0;
  deadman.OnCommanderMessage(0.0);
  sim.Command(MotionCommand::Arc(1, 20.0));  // 500 s of rover time: 10 s of wall
  for (double wall = 0.0; wall < 8.0; wall += loop_wall_s) {
    if (wall < death_s && wall - last_heartbeat >= 1.0) {
      last_heartbeat = wall;
      deadman.OnHeartbeat("sequence_executor", wall);
    }
    if (const auto why = deadman.Check(sim.moving(), wall)) {
      sim.Halt(*why);
      stopped_at = wall;
    }
    sim.Step(loop_wall_s * rate);
  }
  EXPECT_EQ(sim.status().state, MobilityState::kStopped);
  EXPECT_NE(sim.status().detail.find("dead-man"), std::string::npos);
  EXPECT_GT(stopped_at, last_heartbeat + 1.5);
  EXPECT_LE(stopped_at, last_heartbeat + 1.5 + 2 * loop_wall_s);
  EXPECT_LT(stopped_at, death_s + 2.0);
  // Travelled only while the commander lived (plus the timeout): 4.5 s wall x 50 x 4 cm/s.
  EXPECT_NEAR(sim.status().wheel_distance_m, stopped_at * rate * 0.04, 0.05);
}

}  // namespace
}  // namespace rover::mobility
