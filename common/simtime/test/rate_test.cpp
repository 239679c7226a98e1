// A run's pace: max, or a number in rover_sim's range; nothing else.
#include "simtime/rate.hpp"

#include <gtest/gtest.h>

using rover::simtime::ParseRate;

TEST(Rate, MaxIsZeroAndANumberInRangeIsItself) {
  double r = -1;
  EXPECT_TRUE(ParseRate("max", &r));
  EXPECT_EQ(r, 0.0);
  EXPECT_TRUE(ParseRate("50", &r));
  EXPECT_EQ(r, 50.0);
  EXPECT_TRUE(ParseRate("0.1", &r));
  EXPECT_TRUE(ParseRate("10000", &r));
}

TEST(Rate, AnythingElseIsRefused) {
  double r = 7;
  for (const char* bad : {"", "fast", "MAX", "50x", "0.05", "1e12", "-1", "nan", "inf", "50 "}) {
    EXPECT_FALSE(ParseRate(bad, &r)) << bad;
  }
  EXPECT_EQ(r, 7.0);  // untouched
}
