#include "sequence/parser.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <numbers>
#include <random>

using namespace rover::sequence;

namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

SequenceError FirstError(const std::string& text) {
  ParseResult r = ParseSequence(text, "t.seq");
  EXPECT_FALSE(r.ok()) << "expected an error for: " << text;
  return r.ok() ? SequenceError{} : r.errors.front();
}

void ExpectError(const std::string& text, int line, int col, const std::string& fragment) {
  const SequenceError e = FirstError(text);
  EXPECT_EQ(e.line, line) << e.ToString();
  EXPECT_EQ(e.column, col) << e.ToString();
  EXPECT_NE(e.message.find(fragment), std::string::npos) << e.ToString();
  EXPECT_FALSE(e.expected.empty()) << e.ToString();
}

const char* kExample = R"(# approach the outcrop
vo on step 60 cm maxturn 18 deg failures 3 then abort
slip limit 40 % noprogress 10 % over 2 steps
tilt roll 20 deg pitch 25 deg
limit time 1800 s distance 20 m
keepout rock1 circle 4.2 m 1.0 m radius 0.6 m
keepout ridge polygon 1 m 2 m, 3 m 2 m, 3 m 5 m
drive 2.34 m
turn -20.4 deg
turnto 90 deg
arc radius 3 m distance 1.5 m   # curves right
goto 6 m 1.5 m within 0.3 m time 600 s distance 10 m
images
site
)";

}  // namespace

TEST(SequenceParser, ParsesTheReferenceExampleWithSiValues) {
  ParseResult r = ParseSequence(kExample, "example.seq");
  ASSERT_TRUE(r.ok()) << r.errors.front().ToString();
  const auto& c = r.sequence.commands;
  ASSERT_EQ(c.size(), 13u);
  const auto& vo = std::get<VoSetting>(c[0].action);
  EXPECT_TRUE(vo.enabled);
  EXPECT_DOUBLE_EQ(*vo.step_m, 0.60);
  EXPECT_NEAR(*vo.max_turn_rad, 18 * kDeg, 1e-12);
  EXPECT_EQ(*vo.max_failures, 3);
  EXPECT_EQ(*vo.past_max, VoFailureAction::kAbort);
  const auto& slip = std::get<SlipSetting>(c[1].action);
  EXPECT_DOUBLE_EQ(slip.limit_pct, 40.0);
  EXPECT_DOUBLE_EQ(slip.no_progress_fraction, 0.10);
  EXPECT_EQ(slip.over_steps, 2);
  EXPECT_NEAR(*std::get<TiltSetting>(c[2].action).pitch_rad, 25 * kDeg, 1e-12);
  EXPECT_DOUBLE_EQ(*std::get<LimitSetting>(c[3].action).time_s, 1800.0);
  const auto& rock = std::get<KeepOutAdd>(c[4].action).zone;
  EXPECT_EQ(rock.name, "rock1");
  EXPECT_DOUBLE_EQ(rock.center.x(), 4.2);
  EXPECT_DOUBLE_EQ(rock.radius_m, 0.6);
  EXPECT_EQ(std::get<KeepOutAdd>(c[5].action).zone.vertices.size(), 3u);
  EXPECT_DOUBLE_EQ(std::get<Drive>(c[6].action).distance_m, 2.34);
  EXPECT_EQ(c[6].line, 8);
  EXPECT_EQ(c[6].text, "drive 2.34 m");
  EXPECT_NEAR(std::get<Turn>(c[7].action).angle_rad, -20.4 * kDeg, 1e-12);
  EXPECT_NEAR(std::get<TurnTo>(c[8].action).heading_rad, 90 * kDeg, 1e-12);
  EXPECT_DOUBLE_EQ(std::get<Arc>(c[9].action).radius_m, 3.0);
  EXPECT_EQ(c[9].text, "arc radius 3 m distance 1.5 m");
  const auto& g = std::get<Goto>(c[10].action);
  EXPECT_DOUBLE_EQ(g.target.y(), 1.5);
  EXPECT_DOUBLE_EQ(g.tolerance_m, 0.3);
  EXPECT_DOUBLE_EQ(*g.time_limit_s, 600.0);
  EXPECT_DOUBLE_EQ(*g.distance_limit_m, 10.0);
  EXPECT_EQ(std::get<Images>(c[11].action).purpose, ImagePurpose::kScience);
  EXPECT_TRUE(std::holds_alternative<NewSite>(c[12].action));
}

TEST(SequenceParser, AcceptsUnitVariants) {
  ParseResult r = ParseSequence("drive 60cm\ndrive -0.5 m\nturn 0.3567 rad\nslip limit 70%\r\n"
                                "drive +1e-1 m\nvo off step 35 cm\nimages baseline\n",
                                "t.seq");
  ASSERT_TRUE(r.ok()) << r.errors.front().ToString();
  EXPECT_DOUBLE_EQ(std::get<Drive>(r.sequence.commands[0].action).distance_m, 0.60);
  EXPECT_DOUBLE_EQ(std::get<Drive>(r.sequence.commands[1].action).distance_m, -0.5);
  EXPECT_DOUBLE_EQ(std::get<Turn>(r.sequence.commands[2].action).angle_rad, 0.3567);
  EXPECT_DOUBLE_EQ(std::get<SlipSetting>(r.sequence.commands[3].action).limit_pct, 70.0);
  EXPECT_DOUBLE_EQ(std::get<Drive>(r.sequence.commands[4].action).distance_m, 0.1);
  EXPECT_EQ(std::get<Images>(r.sequence.commands[6].action).purpose, ImagePurpose::kVoBaseline);
}

TEST(SequenceParser, ErrorLineFormat) {
  const SequenceError e = FirstError("drive 1 m\n  jump 3 m\n");
  EXPECT_EQ(e.ToString(),
            "t.seq:2:3: unknown command 'jump' (expected drive, arc, turn, turnto, goto, vo, slip, "
            "tilt, limit, keepout, site or images)");
}

TEST(SequenceParser, UnknownCommands) {
  ExpectError("drive 1 m\nfly 2 m\n", 2, 1, "unknown command 'fly'");
  ExpectError("Drive 1 m\n", 1, 1, "unknown command 'Drive'");  // keywords are case-sensitive
  ExpectError("vo maybe\n", 1, 4, "unknown VO mode");
}

TEST(SequenceParser, MissingUnits) {
  ExpectError("drive 3\n", 1, 7, "missing unit after 3");
  ExpectError("goto 6 1.5 m within 0.3 m\n", 1, 6, "missing unit after 6");
  ExpectError("arc radius 3 distance 1 m\n", 1, 12, "missing unit");
  ExpectError("slip limit 40\n", 1, 12, "missing unit");
}

TEST(SequenceParser, WrongAndUnknownUnits) {
  ExpectError("drive 3 deg\n", 1, 9, "wrong unit 'deg'");
  ExpectError("turn 20 m\n", 1, 9, "wrong unit 'm'");
  ExpectError("limit time 30 m\n", 1, 15, "wrong unit 'm'");
  ExpectError("drive 3ft\n", 1, 8, "unknown unit 'ft'");
  ExpectError("drive 3 meters\n", 1, 9, "unknown unit 'meters'");
}

TEST(SequenceParser, NanAndInfinity) {
  ExpectError("drive nan m\n", 1, 7, "not a finite number");
  ExpectError("drive -inf m\n", 1, 7, "not a finite number");
  ExpectError("turn Infinity deg\n", 1, 6, "not a finite number");
  ExpectError("drive 1e999 m\n", 1, 7, "not a finite number");
  ExpectError("vo on failures nan then abort\n", 1, 16, "not a finite number");
}

TEST(SequenceParser, OutOfRangeValues) {
  ExpectError("vo on step 5 m\n", 1, 12, "step length 5 m is out of range");
  ExpectError("slip limit 150 %\n", 1, 12, "slip limit 150 % is out of range");
  ExpectError("keepout r circle 1 m 1 m radius -0.5 m\n", 1, 33, "circle radius");
  ExpectError("goto 1 m 1 m within 0 m\n", 1, 21, "goto tolerance");
  ExpectError("goto 1 m 1 m within -1 m\n", 1, 21, "goto tolerance");
  ExpectError("drive 0 m\n", 1, 7, "drive distance");
  ExpectError("drive 500 m\n", 1, 7, "drive distance");
  ExpectError("arc radius 0 m distance 1 m\n", 1, 12, "arc radius");
  ExpectError("tilt roll 60 deg\n", 1, 11, "roll limit");
  ExpectError("vo on maxturn 120 deg\n", 1, 15, "max turn per step");
  ExpectError("slip limit 40 % noprogress 100 % over 2 steps\n", 1, 28, "no-progress");
  ExpectError("slip limit 40 % noprogress 10 % over 0 steps\n", 1, 38, "out of range");
  ExpectError("limit time -5 s\n", 1, 12, "time limit");
  // The boundaries are inside.
  EXPECT_TRUE(ParseSequence("vo on step 75 cm\nslip limit 100 %\ndrive 1 m\n", "t").ok());
}

TEST(SequenceParser, DuplicateZoneNames) {
  const std::string text = "keepout rock1 circle 1 m 1 m radius 0.5 m\n"
                           "keepout rock1 circle 2 m 2 m radius 0.5 m\n";
  ExpectError(text, 2, 9, "duplicate zone name 'rock1' (first declared at line 1)");
  // A removed or cleared name may be used again; so may any name after `site`.
  EXPECT_TRUE(ParseSequence("keepout a circle 1 m 1 m radius 1 m\nkeepout remove a\n"
                            "keepout a circle 2 m 1 m radius 1 m\nkeepout clear\n"
                            "keepout a circle 1 m 1 m radius 1 m\nsite\n"
                            "keepout a circle 1 m 1 m radius 1 m\n",
                            "t")
                  .ok());
  ExpectError("keepout remove b\n", 1, 16, "no zone named 'b'");
  // A rejected line does not declare its zone.
  ExpectError("keepout a circle 1 m 1 m radius 1 m junk\nkeepout a circle 1 m 1 m radius 1 m\n"
              "keepout a circle 1 m 1 m radius 1 m\n",
              1, 37, "unexpected 'junk'");
  ParseResult r = ParseSequence("keepout a circle 1 m 1 m radius 1 m junk\nkeepout a circle 1 m 1 m radius 1 m\n"
                                "keepout a circle 1 m 1 m radius 1 m\n", "t");
  ASSERT_EQ(r.errors.size(), 2u);
  EXPECT_EQ(r.errors[1].line, 3);
}

TEST(SequenceParser, EmptyFiles) {
  ExpectError("", 1, 1, "empty");
  ExpectError("# only a comment\n\n   \n# another\n", 1, 1, "no commands");
}

TEST(SequenceParser, BinaryJunkReportsTheFirstBadByte) {
  ExpectError(std::string("drive 1 m\nturn 2\0 deg\n", 22), 2, 7, "invalid byte 0x00");
  ExpectError("drive 1 m # caf\xC3(\n", 1, 16, "invalid byte 0xC3");
  ExpectError("\x7f" "ELF\x02\x01\x01\n", 1, 1, "invalid byte 0x7F");
  ExpectError("drive 1 m\n\xff\xfe" "d\n", 2, 1, "invalid byte 0xFF");
  ExpectError("drive 1 m # \xC0\xAF overlong\n", 1, 13, "invalid byte 0xC0");
  // Valid UTF-8 in a comment is fine.
  EXPECT_TRUE(ParseSequence("drive 1 m # café, 10 °\n", "t").ok());
  // ...but not in a command.
  ExpectError("drive 1 m°\n", 1, 9, "unknown unit 'm°'");
}

TEST(SequenceParser, TrailingTokensAndMissingArguments) {
  ExpectError("drive 1 m 2 m\n", 1, 11, "unexpected '2' after the command");
  ExpectError("site now\n", 1, 6, "unexpected 'now'");
  ExpectError("drive\n", 1, 7, "missing drive distance");
  ExpectError("arc radius 3 m\n", 1, 16, "missing 'distance'");
  ExpectError("goto 1 m 2 m\n", 1, 14, "missing 'within'");
  ExpectError("keepout\n", 1, 9, "missing zone name");
  ExpectError("keepout r circle 1 m 1 m\n", 1, 26, "missing 'radius'");
  ExpectError("vo on failures 3\n", 1, 18, "missing 'then'");
  ExpectError("vo on failures 3 then maybe\n", 1, 23, "unknown VO failure action");
  ExpectError("limit\n", 1, 7, "missing limit");
  ExpectError("goto 1 m 2 m within 1 m time 5 s time 6 s\n", 1, 34, "'time' given twice");
}

TEST(SequenceParser, MalformedPolygons) {
  ExpectError("keepout p polygon 1 m 1 m, 2 m 2 m\n", 1, 11, "polygon has 2 vertices");
  ExpectError("keepout p polygon 0 m 0 m, 2 m 2 m, 2 m 0 m, 0 m 2 m\n", 1, 37, "edges 1 and 3 cross");
  ExpectError("keepout p polygon 0 m 0 m 2 m 2 m, 2 m 0 m\n", 1, 27, "unexpected '2' in polygon");
  ExpectError("keepout p polygon 0 m 0 m, 2 m 0 m, 0 m 0 m\n", 1, 37, "repeats vertex 1");
  ExpectError("keepout p polygon 0 m 0 m, 1 m 1 m, 2 m 2 m\n", 1, 11, "no area");
  ExpectError("keepout p polygon 0 m 0 m, 1 m 1 m,\n", 1, 37, "missing polygon vertex x");
  ExpectError("keepout p polygon 0 m 0 m, 1 m\n", 1, 32, "missing polygon vertex y");
  EXPECT_TRUE(ParseSequence("keepout p polygon 0 m 0 m, 2 m 0 m, 2 m 2 m, 0 m 2 m\n", "t").ok());
}

TEST(SequenceParser, ReturnsAllErrorsInFileOrder) {
  ParseResult r = ParseSequence("drive 1 m\nfly\ndrive 3\n# ok\nturn 5 m\ndrive 2 m\n", "t.seq");
  ASSERT_EQ(r.errors.size(), 3u);
  EXPECT_EQ(r.errors[0].line, 2);
  EXPECT_EQ(r.errors[1].line, 3);
  EXPECT_EQ(r.errors[2].line, 5);
  EXPECT_THROW(ParseSequenceOrThrow("fly\n", "t.seq"), SequenceCheckError);
  try {
    ParseSequenceOrThrow("drive 1 m\nfly\n", "t.seq");
  } catch (const SequenceCheckError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("t.seq:2:1: unknown command 'fly'", 0), 0u) << e.what();
  }
}

// The samples this module ships (others in the folder may be deliberately malformed).
TEST(SequenceParser, SampleSequencesInConfigsPass) {
  const std::filesystem::path dir = std::filesystem::path(ROVER_SOURCE_DIR) / "configs" / "sequences";
  for (const char* name : {"approach_outcrop.seq", "demo_drive.seq", "keepout_rock.seq",
                           "rock_course_vo.seq", "slope_climb.seq"}) {
    ParseResult r = ParseSequenceFile((dir / name).string());
    EXPECT_TRUE(r.ok()) << (r.ok() ? "" : r.errors.front().ToString());
  }
}

// Parsing must never crash or throw, whatever the bytes: seeded random and mutated inputs.
TEST(SequenceParserFuzz, ThousandsOfMutatedInputsReturnCleanly) {
  std::mt19937 rng(20260422);
  const std::string base = kExample;
  const std::vector<std::string> fragments = {"drive", "arc", "radius", "distance", "m", "cm", "deg",
                                              "rad", "%", "s", "nan", "inf", "1e999", "-", ",",
                                              "keepout", "polygon", "circle", "remove", "clear",
                                              "#", "\n", "\r", std::string(1, '\0'), "\xff", "\xC3",
                                              "0", "-0", "1e-400", "9999999999999999999", "then",
                                              "abort", "vo", "on", "failures", "  ", "\t", "goto"};
  int ok = 0, failed = 0;
  for (int iter = 0; iter < 6000; ++iter) {
    std::string text;
    if (iter % 10 == 0) {
      // Pure random bytes.
      const int n = std::uniform_int_distribution<int>(0, 400)(rng);
      for (int i = 0; i < n; ++i) text.push_back(static_cast<char>(rng() & 0xff));
    } else if (iter % 10 == 1) {
      // Random token soup.
      const int n = std::uniform_int_distribution<int>(0, 60)(rng);
      for (int i = 0; i < n; ++i) {
        text += fragments[rng() % fragments.size()];
        text += (rng() % 4 == 0) ? "\n" : " ";
      }
    } else {
      // Mutations of a valid sequence.
      text = base;
      const int edits = std::uniform_int_distribution<int>(1, 8)(rng);
      for (int e = 0; e < edits && !text.empty(); ++e) {
        const std::size_t pos = rng() % text.size();
        switch (rng() % 5) {
          case 0: text[pos] = static_cast<char>(rng() & 0xff); break;
          case 1: text.erase(pos, rng() % 12); break;
          case 2: text.insert(pos, fragments[rng() % fragments.size()]); break;
          case 3: text.insert(pos, text.substr(rng() % text.size(), rng() % 40)); break;
          default: text[pos] ^= static_cast<char>(1u << (rng() % 8)); break;
        }
      }
    }
    ParseResult r;
    ASSERT_NO_THROW(r = ParseSequence(text, "fuzz.seq")) << "iteration " << iter;
    const int lines = static_cast<int>(std::count(text.begin(), text.end(), '\n')) + 1;
    if (r.ok()) {
      ++ok;
      ASSERT_FALSE(r.sequence.commands.empty());
    } else {
      ++failed;
      for (const auto& e : r.errors) {
        ASSERT_GE(e.line, 1);
        ASSERT_LE(e.line, lines);
        ASSERT_GE(e.column, 1);
        ASSERT_FALSE(e.message.empty());
        ASSERT_EQ(e.ToString().find('\n'), std::string::npos);  // one line each
      }
    }
  }
  // Both outcomes occur, so the mutations exercise the accepting and the rejecting paths.
  EXPECT_GT(ok, 50);
  EXPECT_GT(failed, 3000);
}

TEST(SequenceParser, VoLostPolicies) {
  ParseResult r = ParseSequence("vo lost abort\nvo lost shorten slope 12 deg\n"
                                "vo lost retry 2 slip 25 % slope 0.3 rad\n", "t.seq");
  ASSERT_TRUE(r.ok()) << r.errors.front().ToString();
  const auto& a = std::get<VoLostSetting>(r.sequence.commands[0].action);
  EXPECT_EQ(a.action, VoLostAction::kAbort);
  EXPECT_FALSE(a.slope_rad);
  EXPECT_FALSE(a.slip_pct);
  const auto& s = std::get<VoLostSetting>(r.sequence.commands[1].action);
  EXPECT_EQ(s.action, VoLostAction::kShorten);
  EXPECT_NEAR(*s.slope_rad, 12 * kDeg, 1e-12);
  const auto& t = std::get<VoLostSetting>(r.sequence.commands[2].action);
  EXPECT_EQ(t.action, VoLostAction::kRetry);
  EXPECT_EQ(t.retries, 2);
  EXPECT_DOUBLE_EQ(*t.slip_pct, 25.0);
  EXPECT_DOUBLE_EQ(*t.slope_rad, 0.3);
  EXPECT_FALSE(IsMotion(r.sequence.commands[0]));

  ExpectError("vo lost\n", 1, 9, "missing VO lost action");
  ExpectError("vo lost sometimes\n", 1, 9, "unknown VO lost action 'sometimes'");
  ExpectError("vo lost retry\n", 1, 15, "missing number of retries");
  ExpectError("vo lost retry 0\n", 1, 15, "number of retries 0 is out of range");
  ExpectError("vo lost retry 11\n", 1, 15, "out of range");
  ExpectError("vo lost abort slope 50 deg\n", 1, 21, "slip-prone slope 50 deg is out of range");
  ExpectError("vo lost abort slope 10 m\n", 1, 24, "wrong unit 'm'");
  ExpectError("vo lost abort slip 0 %\n", 1, 20, "out of range");
  ExpectError("vo lost abort slope 10 deg slope 12 deg\n", 1, 28, "'slope' given twice");
  ExpectError("vo lost shorten 3\n", 1, 17, "unknown vo lost option '3'");
  ExpectError("vo maybe\n", 1, 4, "unknown VO mode 'maybe'");
}

TEST(SequenceParser, GotoAvoid) {
  ParseResult r = ParseSequence("goto 6 m 1 m within 0.3 m avoid on\n"
                                "goto 6 m 1 m within 0.3 m time 60 s avoid off distance 9 m\n"
                                "goto 6 m 1 m within 0.3 m\n",
                                "t.seq");
  ASSERT_TRUE(r.ok()) << r.errors.front().ToString();
  EXPECT_TRUE(std::get<Goto>(r.sequence.commands[0].action).avoid);
  const Goto& off = std::get<Goto>(r.sequence.commands[1].action);
  EXPECT_FALSE(off.avoid);
  EXPECT_DOUBLE_EQ(*off.distance_limit_m, 9.0);
  EXPECT_FALSE(std::get<Goto>(r.sequence.commands[2].action).avoid);
  ExpectError("goto 1 m 2 m within 1 m avoid\n", 1, 31, "missing goto avoid mode");
  ExpectError("goto 1 m 2 m within 1 m avoid maybe\n", 1, 31, "unknown goto avoid mode");
  ExpectError("goto 1 m 2 m within 1 m avoid on avoid off\n", 1, 34, "'avoid' given twice");
}

// The operator's slips get a hint that names the fix, not a generic complaint.
TEST(SequenceParser, HintsForCommonSlips) {
  // "turn to" is turnto's absolute heading written as two words.
  ExpectError("turn to -10 deg\n", 1, 6, "unexpected 'to' after 'turn'");
  EXPECT_NE(FirstError("turn to -10 deg\n").expected.find("turnto -10 deg"), std::string::npos);
  // A decimal comma: the error is at the comma and shows the number with a point.
  ExpectError("drive 1,5 m\n", 1, 8, "decimal comma in '1,5' for drive distance");
  EXPECT_EQ(FirstError("drive 1,5 m\n").expected, "a decimal point: 1.5");
  ExpectError("goto 2 m 0,25m within 0.3 m\n", 1, 11, "decimal comma in '0,25'");
  // Spaced commas are still polygon separators; a missing unit before one is still that.
  ExpectError("keepout p polygon 1 m 2, 3 m 2 m, 3 m 5 m\n", 1, 23, "missing unit after 2");
  EXPECT_TRUE(ParseSequence("keepout p polygon 1 m 2 m,3 m 2 m, 3 m 5 m\n", "t").ok());
}

// Zone names are case-sensitive everywhere (the executor and the hazard monitor match them
// exactly), so two names that differ only in case are refused as a clash.
TEST(SequenceParser, ZoneNamesDifferingOnlyInCaseClash) {
  ExpectError("keepout mazatzal circle 1 m 1 m radius 1 m\nkeepout Mazatzal circle 5 m 1 m radius 1 m\n", 2, 9,
              "zone name 'Mazatzal' differs only in case from zone 'mazatzal' (declared at line 1)");
  ExpectError("keepout Mazatzal circle 1 m 1 m radius 1 m\nkeepout remove mazatzal\n", 2, 16,
              "no zone named 'mazatzal' is in force (names are case-sensitive)");
  EXPECT_EQ(FirstError("keepout Mazatzal circle 1 m 1 m radius 1 m\nkeepout remove mazatzal\n").expected,
            "'keepout remove Mazatzal' (declared at line 1)");
  // Once one is removed (or after a new site), the other spelling is a new zone.
  EXPECT_TRUE(ParseSequence("keepout mazatzal circle 1 m 1 m radius 1 m\nkeepout remove mazatzal\n"
                            "keepout Mazatzal circle 5 m 1 m radius 1 m\n", "t").ok());
  // A zone of an earlier sequence is not in force: the message says why.
  const SequenceError e = FirstError("keepout remove mazatzal\n");
  EXPECT_NE(e.expected.find("cleared when this one starts"), std::string::npos) << e.ToString();
}
