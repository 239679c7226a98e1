// The calib tools' shared command line: options and values in order, and one-line errors
// naming the option.
#include "calib/arguments.hpp"

#include <gtest/gtest.h>

#include <vector>

using rover::calib::Arguments;
using rover::calib::BadArgument;

namespace {

std::string ErrorOf(std::vector<const char*> words, void (*use)(Arguments&)) {
  words.insert(words.begin(), "tool");
  Arguments args(static_cast<int>(words.size()), const_cast<char**>(words.data()));
  try {
    use(args);
  } catch (const BadArgument& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(CalibArguments, OptionsValuesAndSizesInOrder) {
  std::vector<const char*> words{"tool", "--board", "9x6", "--rig", "r.yaml", "-h"};
  Arguments args(static_cast<int>(words.size()), const_cast<char**>(words.data()));
  ASSERT_TRUE(args.Next());
  EXPECT_EQ(args.option(), "--board");
  int w = 0, h = 0;
  args.Size(2, "COLSxROWS", &w, &h);
  EXPECT_EQ(w, 9);
  EXPECT_EQ(h, 6);
  ASSERT_TRUE(args.Next());
  EXPECT_FALSE(args.IsHelp());
  EXPECT_EQ(args.Value(), "r.yaml");
  ASSERT_TRUE(args.Next());
  EXPECT_TRUE(args.IsHelp());
  EXPECT_FALSE(args.Next());
}

TEST(CalibArguments, BadArgumentsAreOneLineNamingTheOption) {
  auto size = [](Arguments& a) {
    int w = 0, h = 0;
    a.Next();
    a.Size(2, "COLSxROWS inner corners", &w, &h);
  };
  EXPECT_EQ(ErrorOf({"--board", "9x1"}, size), "argument --board: \"9x1\": expected COLSxROWS inner corners");
  EXPECT_EQ(ErrorOf({"--board", "9x6x"}, size), "argument --board: \"9x6x\": expected COLSxROWS inner corners");
  EXPECT_EQ(ErrorOf({"--board"}, size), "argument --board: missing value");
  EXPECT_EQ(ErrorOf({"--bored", "9x6"}, [](Arguments& a) {
              a.Next();
              throw a.Unknown();
            }),
            "argument --bored: unknown option (expected one of the options in --help)");
}
