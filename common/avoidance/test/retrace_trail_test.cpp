#include "avoidance/retrace_trail.hpp"

#include <gtest/gtest.h>

namespace rover::avoidance {
namespace {

TEST(RetraceTrail, BackupsAlongTheLastArcShortenItThenReachTheOneBefore) {
  RetraceTrail t;
  EXPECT_EQ(t.Last().length_m, 0.0);
  t.Driven(true, 0.5, 0.2);
  t.Driven(true, 0.6, -0.4);
  EXPECT_DOUBLE_EQ(t.Last().length_m, 0.6);
  EXPECT_DOUBLE_EQ(t.Last().curvature_per_m, -0.4);
  t.Driven(true, -0.3, -0.4);  // back along the last arc, half of it
  EXPECT_NEAR(t.Last().length_m, 0.3, 1e-12);
  t.Driven(true, -0.3, -0.4);  // the rest of it: the arc before is next
  EXPECT_EQ(t.size(), 1u);
  EXPECT_DOUBLE_EQ(t.Last().length_m, 0.5);
  EXPECT_DOUBLE_EQ(t.Last().curvature_per_m, 0.2);
  t.Driven(true, -0.3, 0.2);
  t.Driven(true, -0.2, 0.2);
  EXPECT_TRUE(t.empty());
}

TEST(RetraceTrail, ATurnOrABackupOffTheArcEndsIt) {
  RetraceTrail t;
  t.Driven(true, 0.5, 0.2);
  t.Driven(false, 0.0, 0.0);  // a turn in place
  EXPECT_TRUE(t.empty());
  t.Driven(true, 0.5, 0.2);
  t.Driven(true, -0.3, 0.0);  // straight back after a curved arc: off its ground
  EXPECT_TRUE(t.empty());
  t.Driven(true, 0.2, 0.2);
  t.Driven(true, -0.3, 0.2);  // further back than the arc ran
  EXPECT_TRUE(t.empty());
  t.Driven(true, 0.4, 0.0);  // a straight arc is retraced straight back
  t.Driven(true, -0.3, 0.0);
  EXPECT_NEAR(t.Last().length_m, 0.1, 1e-12);
}

TEST(RetraceTrail, KeepsOnlyTheNewestArcs) {
  RetraceTrail t;
  for (std::size_t k = 0; k < RetraceTrail::kMaxArcs + 5; ++k) t.Driven(true, 0.1 * static_cast<double>(k + 1), 0.0);
  EXPECT_EQ(t.size(), RetraceTrail::kMaxArcs);
  EXPECT_NEAR(t.Last().length_m, 0.1 * (RetraceTrail::kMaxArcs + 5), 1e-12);
}

}  // namespace
}  // namespace rover::avoidance
