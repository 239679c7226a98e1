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

}  // namespace
}  // namespace rover::avoidance
