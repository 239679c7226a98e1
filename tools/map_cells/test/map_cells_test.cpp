// map_cells on a log written here: known maps in, their cells' history out.
#include "map_cells/map_cells.hpp"

#include "bus/channels.hpp"
#include "bus/traversability_convert.hpp"

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <cstdio>
#include <filesystem>
#include <sstream>
#include <string>
#include <unistd.h>

namespace rover::map_cells {
namespace {

namespace fs = std::filesystem;

// Level ground (heights 0) with one rock cell at (1.3, 0.7) whose top stands `top` m up,
// rated `state` with a step read of 0.22 m.
avoidance::Grid Map(avoidance::CellClass state, float top) {
  avoidance::Grid g = avoidance::Grid::Filled(-3.0, -3.0, 0.2, 30, 30, avoidance::CellClass::kSafe, 0.9f);
  g.SetHeights(0.0f, 0.01f);
  const int k = g.IndexAt(1.3, 0.7);
  g.state[k] = state;
  g.step_m[k] = 0.22f;
  g.goodness[k] = 0.12f;
  g.elevation_m[k] = top;
  return g;
}

class Log {
 public:
  Log() : path_((fs::temp_directory_path() / ("map_cells_test_" + std::to_string(getpid()) + ".lcm")).string()) {
    file_ = std::make_unique<lcm::LogFile>(path_, "w");
  }
  ~Log() { fs::remove(path_); }
  void Add(const std::string& channel, const std::vector<std::uint8_t>& bytes) {
    lcm::LogEvent ev{};
    ev.timestamp = ++t_;
    ev.channel = channel;
    ev.datalen = static_cast<std::int32_t>(bytes.size());
    ev.data = const_cast<std::uint8_t*>(bytes.data());
    ASSERT_EQ(file_->writeEvent(&ev), 0);
  }
  void AddMap(const avoidance::Grid& g, std::int64_t utime, std::int64_t frame) {
    const auto m = bus::MapToMsg(g, bus::MapRules{}, utime, frame);
    std::vector<std::uint8_t> buf(static_cast<std::size_t>(m.getEncodedSize()));
    ASSERT_GT(m.encode(buf.data(), 0, static_cast<int>(buf.size())), 0);
    Add(channels::kTraversabilityMap, buf);
  }
  const std::string& Close() {
    file_.reset();
    return path_;
  }

 private:
  std::string path_;
  std::unique_ptr<lcm::LogFile> file_;
  std::int64_t t_ = 0;
};

TEST(MapCells, ReadsEachMapsCellsRoundThePointWithTheirTopsOverTheGround) {
  Log log;
  log.AddMap(Map(avoidance::CellClass::kUnsafe, 0.29f), 1'000'000, 4);
  log.Add("POSE", {1, 2, 3});                         // another channel: not read
  log.Add(channels::kTraversabilityMap, {0xde, 0xad});     // a corrupt map: counted, left out
  log.AddMap(Map(avoidance::CellClass::kCaution, 0.27f), 2'000'000, 5);
  Query q;
  q.x = 1.3;
  q.y = 0.7;
  q.radius_m = 0.15;  // the rock's cell alone
  const History h = ReadHistory(log.Close(), q);
  ASSERT_EQ(h.maps.size(), 2u);
  EXPECT_EQ(h.undecodable, 1);
  ASSERT_EQ(h.maps[1].cells.size(), 1u);
  const CellReading& c = h.maps[1].cells[0];
  EXPECT_EQ(h.maps[1].last_frame_id, 5);
  EXPECT_NEAR(c.x, 1.3, 1e-9);
  EXPECT_EQ(c.state, 2);  // caution
  EXPECT_NEAR(c.step_m, 0.22, 1e-6);
  EXPECT_NEAR(c.elevation_m, 0.27, 1e-6);
  EXPECT_NEAR(c.top_over_ground_m, 0.27, 0.01);
  EXPECT_EQ(h.maps[0].cells[0].state, 3);

  std::ostringstream out;
  Print(h, q, out);
  const std::string s = out.str();
  EXPECT_NE(s.find("2 maps, 1 undecodable"), std::string::npos) << s;
  EXPECT_NE(s.find("1.3,0.7 caution 0.22 0.27 (0.01) +0.27"), std::string::npos) << s;
  EXPECT_NE(s.find("maps with a cell unsafe: 1"), std::string::npos) << s;
  EXPECT_NE(s.find("maps with a cell caution: 1"), std::string::npos) << s;

  q.x = 40.0;  // outside every map
  std::ostringstream far;
  Print(ReadHistory(log.Close(), q), q, far);
  EXPECT_NE(far.str().find("(outside the map)"), std::string::npos) << far.str();
}

std::string RunTool(const std::string& args, int* rc) {
  const std::string cmd = std::string(ROVER_BINARY_DIR) + "/bin/map_cells " + args + " 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  std::string out;
  char buf[512];
  while (p && fgets(buf, sizeof buf, p)) out += buf;
  *rc = p ? WEXITSTATUS(pclose(p)) : -1;
  return out;
}

TEST(MapCells, BadArgumentsAndAMissingLogGiveOneLineErrors) {
  int rc = 0;
  std::string out = RunTool("/nonexistent.lcm --at 1,x", &rc);
  EXPECT_EQ(rc, 2);
  EXPECT_EQ(out, "map_cells: --at: 'x' is not a number in [-1000000.000000, 1000000.000000]\n");
  out = RunTool("/nonexistent.lcm", &rc);
  EXPECT_EQ(rc, 2);
  EXPECT_NE(out.find("missing --at X,Y"), std::string::npos) << out;
  out = RunTool("/nonexistent.lcm --at 1,2", &rc);
  EXPECT_EQ(rc, 1);
  EXPECT_EQ(out, "map_cells: /nonexistent.lcm: cannot open the log (expected an LCM log file)\n");
}

}  // namespace
}  // namespace rover::map_cells
