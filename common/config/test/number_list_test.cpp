#include "config/number_list.hpp"

#include <gtest/gtest.h>

namespace rover::config {
namespace {

TEST(NumberList, ReadsCommaSeparatedNumbers) {
  std::vector<double> v;
  ASSERT_TRUE(ParseNumberList("1.5,-2,3e2", &v));
  EXPECT_EQ(v, (std::vector<double>{1.5, -2, 300}));
}

TEST(NumberList, RefusesWhatIsNotAWholeFiniteNumber) {
  std::vector<double> v;
  for (const char* bad : {"", "abc", "1,,2", "1,2,", "1.5x", "nan", "inf", "1e999", " ,1"}) {
    EXPECT_FALSE(ParseNumberList(bad, &v)) << '"' << bad << '"';
  }
}

TEST(NumberList, OneNumberInRange) {
  double x = -1;
  EXPECT_TRUE(ParseNumberInRange("0.25", 0, 1, &x));
  EXPECT_EQ(x, 0.25);
  EXPECT_FALSE(ParseNumberInRange("1.5", 0, 1, &x));
  EXPECT_FALSE(ParseNumberInRange("0.1,0.2", 0, 1, &x));
  EXPECT_EQ(x, 0.25);  // untouched on failure
}

TEST(NumberList, IntegersInRange) {
  std::vector<int> v;
  ASSERT_TRUE(ParseIntList("512,1024", 64, 4096, &v));
  EXPECT_EQ(v, (std::vector<int>{512, 1024}));
  EXPECT_FALSE(ParseIntList("512.5", 64, 4096, &v));
  EXPECT_FALSE(ParseIntList("32", 64, 4096, &v));
}

}  // namespace
}  // namespace rover::config
