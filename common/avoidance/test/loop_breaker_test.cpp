// The tabu rule that breaks a loop of votes (loop_breaker.hpp), with known answers.
#include "avoidance/loop_breaker.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace rover::avoidance {
namespace {

Candidate Arc(double distance_m, double k, double vote, bool vetoed = false) {
  Candidate c;
  c.kind = distance_m < 0 ? Candidate::Kind::kBackup : Candidate::Kind::kArc;
  c.distance_m = distance_m;
  c.curvature_per_m = k;
  c.vote = vote;
  c.vetoed = vetoed;
  c.clear_m = 3.0;
  return c;
}

Candidate Turn(double rad, double vote, double clear_m) {
  Candidate c;
  c.kind = Candidate::Kind::kTurn;
  c.turn_rad = c.planned_turn_rad = rad;
  c.vote = vote;
  c.clear_m = clear_m;
  return c;
}

TEST(LoopBreaker, TheSamePoseIsWithinTheRadiusAndHeading) {
  const std::vector<Visit> history = {{{0.0, 0.0, 0.0}, Arc(0.6, 0.0, 0.5)},
                                      {{0.6, 0.0, 0.0}, Arc(-0.3, 0.0, 0.5)},
                                      {{0.05, 0.05, 0.5}, Arc(0.6, 0.2, 0.5)}};  // turned 29 deg
  const auto here = ChosenHereBefore(history, {0.1, 0.0, 0.1});
  ASSERT_EQ(here.size(), 1u);
  EXPECT_DOUBLE_EQ(here[0].distance_m, 0.6);
  EXPECT_DOUBLE_EQ(here[0].curvature_per_m, 0.0);
  EXPECT_TRUE(ChosenHereBefore(history, {0.3, 0.0, 0.0}).empty());  // 0.3 m from both
}

TEST(LoopBreaker, SameMoveComparesKindCurvatureDirectionAndTurn) {
  EXPECT_TRUE(SameMove(Arc(0.6, 0.1, 0), Arc(0.45, 0.1, 1)));  // a shorter step of the same arc
  EXPECT_FALSE(SameMove(Arc(0.6, 0.1, 0), Arc(0.6, 0.2, 0)));
  EXPECT_FALSE(SameMove(Arc(0.6, 0.0, 0), Arc(-0.3, 0.0, 0)));
  EXPECT_TRUE(SameMove(Turn(0.3, 0, 3), Turn(0.3, 1, 3)));
  EXPECT_FALSE(SameMove(Turn(0.3, 0, 3), Turn(-0.3, 0, 3)));
}

// Forward, back, back, forward...: on the second visit the forward arc gives way to the
// next best allowed candidate; vetoed ones and turns that lead nowhere come after.
TEST(LoopBreaker, TheNextBestAllowedMoveReplacesARepeatedOne) {
  Choice choice;
  choice.candidates = {Arc(0.6, 0.0, 0.9), Arc(0.6, 0.3, 0.95, /*vetoed=*/true), Turn(0.3, 0.8, 0.2),
                       Arc(0.6, -0.2, 0.7), Turn(-0.3, 0.6, 3.0)};
  const std::vector<Candidate> before = {Arc(0.6, 0.0, 0.9)};
  const Candidate* next = BestNotRepeating(choice, before, 0.6);
  ASSERT_NE(next, nullptr);
  EXPECT_EQ(next->kind, Candidate::Kind::kArc);
  EXPECT_DOUBLE_EQ(next->curvature_per_m, -0.2);
  // Each visit after that takes the next one.
  const Candidate* third = BestNotRepeating(choice, {Arc(0.6, 0.0, 0), Arc(0.6, -0.2, 0)}, 0.6);
  ASSERT_NE(third, nullptr);
  EXPECT_EQ(third->kind, Candidate::Kind::kTurn);
  EXPECT_DOUBLE_EQ(third->turn_rad, -0.3);
  // The turn that leads nowhere is the last resort; then nothing is left.
  const Candidate* last =
      BestNotRepeating(choice, {Arc(0.6, 0.0, 0), Arc(0.6, -0.2, 0), Turn(-0.3, 0, 3)}, 0.6);
  ASSERT_NE(last, nullptr);
  EXPECT_DOUBLE_EQ(last->turn_rad, 0.3);
  EXPECT_EQ(BestNotRepeating(choice, {Arc(0.6, 0.0, 0), Arc(0.6, -0.2, 0), Turn(-0.3, 0, 3), Turn(0.3, 0, 3)}, 0.6),
            nullptr);
}

// The dither of navbench k = 0.20: at A the rover backs up 0.3 m to B, again to C, turns a
// few degrees and drives 0.6 m forward to A. Back at A it has closed a cycle of positions,
// though no move and no heading repeats; standing at A turning in place, or driving on,
// closes none.
TEST(LoopBreaker, APositionCycleIsFoundWhateverTheMovesAndHeadings) {
  const double yaw = -123.0 * M_PI / 180.0;
  const double cx = std::cos(yaw), cy = std::sin(yaw);
  const Pose2 a{-9.8, -7.9, yaw};
  const Pose2 b{a.x - 0.3 * cx, a.y - 0.3 * cy, yaw};
  const Pose2 c{a.x - 0.6 * cx, a.y - 0.6 * cy, yaw + 0.05};
  std::vector<Visit> history = {{a, Turn(0.05, 0.5, 0.2)}, {a, Arc(-0.3, 0.0, 0.5)}};
  // Turning at A, then backing up: nothing closed yet.
  EXPECT_FALSE(BackWhereItWas({history[0]}, a));
  EXPECT_FALSE(BackWhereItWas(history, b));
  history.push_back({b, Arc(-0.3, 0.0, 0.5)});
  EXPECT_FALSE(BackWhereItWas(history, c));
  history.push_back({c, Arc(0.6, -0.1, 0.5)});
  // Forward to A (2 cm off, 6 deg round): a cycle.
  const Pose2 a_again{a.x + 0.02, a.y, yaw - 0.1};
  EXPECT_TRUE(BackWhereItWas(history, a_again));
  // Backing from C to B, where it stood before: retreating along its tracks is no cycle.
  std::vector<Visit> retreat = history;
  retreat.back().chosen = Arc(-0.3, 0.0, 0.5);
  EXPECT_FALSE(BackWhereItWas(retreat, b));
  // Turning in place at A once back: the cycle was closed by the step that arrived.
  std::vector<Visit> turned = history;
  turned.push_back({a_again, Turn(0.3, 0.5, 3.0)});
  EXPECT_FALSE(BackWhereItWas(turned, {a_again.x, a_again.y, a_again.yaw + 0.3}));
  // Forward past A instead: no cycle.
  EXPECT_FALSE(BackWhereItWas(history, {a.x + 0.6 * cx, a.y + 0.6 * cy, yaw}));
  // A cycle older than the window is no longer one.
  CycleOptions narrow;
  narrow.window_steps = 1;
  EXPECT_FALSE(BackWhereItWas(history, a_again, narrow));
  narrow.window_steps = 4;
  EXPECT_TRUE(BackWhereItWas(history, a_again, narrow));
}

// navbench seed 11 k0.20_r01: at A the rover backs up five times, 1.5 m along its tracks
// (B1 .. B5), then drives forward over them again. Passing B3 and B1 closes no cycle (it
// only ever passed them, backing); arriving at A, where the backing began, closes one. Each
// cycle is a refused way for the planner: before, this retreat counted three.
TEST(LoopBreaker, DrivingBackOverItsRetreatClosesOneCycleWhereTheRetreatBegan) {
  const double yaw = 2.1;
  const double cx = std::cos(yaw), cy = std::sin(yaw);
  auto along = [&](double s) { return Pose2{3.0 + s * cx, -1.0 + s * cy, yaw}; };
  std::vector<Visit> history = {{along(-1.2), Arc(0.6, 0.0, 0.5)}, {along(-0.6), Arc(0.6, 0.0, 0.5)}};
  for (int k = 0; k < 5; ++k) history.push_back({along(-0.3 * k), Arc(-0.3, 0.0, 0.5)});  // A, B1 .. B4
  // At B5 (1.5 m back): forward 0.6 m to B3, 0.6 m to B1, 0.3 m to A.
  int cycles = 0;
  history.push_back({along(-1.5), Arc(0.6, 0.1, 0.5)});
  const Pose2 b3{along(-0.9).x + 0.03, along(-0.9).y, yaw + 0.05};
  EXPECT_FALSE(BackWhereItWas(history, b3));
  cycles += BackWhereItWas(history, b3);
  history.push_back({b3, Arc(0.6, -0.1, 0.5)});
  const Pose2 b1{along(-0.3).x, along(-0.3).y + 0.04, yaw};
  EXPECT_FALSE(BackWhereItWas(history, b1));
  cycles += BackWhereItWas(history, b1);
  history.push_back({b1, Arc(0.3, 0.0, 0.5)});
  const Pose2 a{along(0.0).x + 0.02, along(0.0).y, yaw};
  EXPECT_TRUE(BackWhereItWas(history, a));
  cycles += BackWhereItWas(history, a);
  EXPECT_EQ(cycles, 1);
  // A pose reached backing where the rover then turned is one it stood at: the visit after
  // the turn was reached by the turn. At B3 (reached backing) it turns, drives 0.6 m off
  // and comes back to B3: a cycle.
  std::vector<Visit> turned(history.begin(), history.begin() + 5);  // .. A, B1, B2, each then backing
  const Pose2 b3_turned{along(-0.9).x, along(-0.9).y, yaw + 0.3};
  turned.push_back({along(-0.9), Turn(0.3, 0.5, 3.0)});
  turned.push_back({b3_turned, Arc(0.6, 0.0, 0.5)});
  turned.push_back({{b3_turned.x + 0.6 * std::cos(yaw + 0.3), b3_turned.y + 0.6 * std::sin(yaw + 0.3), yaw + 0.3},
                    Arc(0.6, 1.0, 0.5)});
  EXPECT_TRUE(BackWhereItWas(turned, {along(-0.9).x + 0.05, along(-0.9).y, yaw + 3.0}));
}

// A rover turning round in place in a pocket (many steps at one position) has left nowhere.
TEST(LoopBreaker, TurningInPlaceIsNoPositionCycle) {
  std::vector<Visit> history;
  for (int k = 0; k < 8; ++k) history.push_back({{1.0, 2.0, 0.3 * k}, Turn(0.3, 0.5, 3.0)});
  EXPECT_FALSE(BackWhereItWas(history, {1.01, 2.0, 2.4}));
  EXPECT_FALSE(BackWhereItWas({}, {1.0, 2.0, 0.0}));
}

}  // namespace
}  // namespace rover::avoidance
