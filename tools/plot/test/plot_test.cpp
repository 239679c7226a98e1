// ./rover plot on a synthetic log written with lcm::LogFile: a 1 m drive north in two
// steps (blind, then VO-corrected) with known wheel odometry, estimate and truth, a
// keep-out zone, a slip limit and an abort. The series are checked against the values
// the log was built from; the pictures are checked to be PNG files (gnuplot needed).
#include "plot/drive_log.hpp"
#include "plot/gnuplot.hpp"
#include "plot/plot_series.hpp"
#include "plot/plots.hpp"
#include "plot/vo_steps.hpp"

#include "bus/channels.hpp"

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>
#include <rover_msgs/imu_t.hpp>
#include <rover_msgs/keepout_zones_t.hpp>
#include <rover_msgs/pose_t.hpp>
#include <rover_msgs/sequence_status_t.hpp>
#include <rover_msgs/sequence_submit_t.hpp>
#include <rover_msgs/sim_truth_t.hpp>
#include <rover_msgs/step_report_t.hpp>
#include <rover_msgs/wheel_odometry_t.hpp>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

namespace fs = std::filesystem;

namespace rover::plot {
namespace {

// The drive: wheels roll 0.1 m/s north for 10 s (1 m); the estimate says 90 % of that, the
// truth 80 % (20 % slip). Step 1 covers 0..5 s (blind), step 2 5..10 s (VO measured it).
constexpr std::int64_t kSecond = 1000000;
constexpr std::int64_t kT0 = 1000 * kSecond;

class SyntheticLog {
 public:
  explicit SyntheticLog(const std::string& path) : log_(path, "w") {}

  template <typename Msg>
  void Write(const char* channel, const Msg& msg, std::int64_t utime) {
    std::vector<std::uint8_t> buf(msg.getEncodedSize());
    msg.encode(buf.data(), 0, static_cast<int>(buf.size()));
    lcm::LogEvent ev;
    ev.eventnum = n_++;
    ev.timestamp = utime;
    ev.channel = channel;
    ev.datalen = static_cast<int32_t>(buf.size());
    ev.data = buf.data();
    ASSERT_EQ(log_.writeEvent(&ev), 0);
  }

 private:
  lcm::LogFile log_;
  std::int64_t n_ = 0;
};

rover_msgs::step_report_t Step(int index, std::int64_t before, std::int64_t after, int8_t vo_status) {
  rover_msgs::step_report_t r{};
  r.utime = after;
  r.command_index = 2;
  r.step_index = index;
  r.commanded_distance_m = 0.5;
  r.estimated_distance_m = 0.45;
  r.slip_pct = 10.0;
  r.vo_status = vo_status;
  r.utime_before = before;
  r.utime_after = after;
  r.pose_before[0] = 0.45 * index;
  r.pose_after[0] = 0.45 * (index + 1);
  return r;
}

std::string WriteDriveLog(const std::string& dir) {
  const std::string path = dir + "/log.lcm";
  SyntheticLog log(path);
  rover_msgs::sequence_submit_t submit{};
  submit.name = "synthetic.seq";
  submit.text = "slip limit 40 %\nkeepout rock circle 1 m 2 m radius 0.5 m\ndrive 1 m\n";
  log.Write(channels::kSequenceSubmit, submit, kT0);
  rover_msgs::keepout_zones_t zones{};
  zones.num_zones = 1;
  zones.zones.resize(1);
  zones.zones[0].name = "rock";
  zones.zones[0].shape = rover_msgs::keepout_zone_t::SHAPE_CIRCLE;
  zones.zones[0].center[0] = 1.0;
  zones.zones[0].center[1] = 2.0;
  zones.zones[0].radius_m = 0.5;
  log.Write(channels::kKeepOutZones, zones, kT0);
  for (int k = 0; k <= 200; ++k) {  // 20 Hz for 10 s
    const std::int64_t t = kT0 + k * kSecond / 20;
    const double rolled = 0.1 * k / 20.0;
    rover_msgs::imu_t imu{};
    imu.utime = t;
    imu.orientation[0] = 1.0;  // facing north, level
    log.Write(channels::kImu, imu, t);
    if (k % 2 != 0) continue;
    rover_msgs::wheel_odometry_t odo{};
    odo.utime = t;
    odo.distance_m = rolled;
    log.Write(channels::kWheelOdometry, odo, t);
    rover_msgs::pose_t pose{};
    pose.utime = t;
    pose.position[0] = 0.9 * rolled;
    pose.orientation[0] = 1.0;
    pose.covariance[0][0] = 0.01 * 0.01;
    pose.covariance[1][1] = 0.02 * 0.02;
    log.Write(channels::kPose, pose, t);
    rover_msgs::sim_truth_t truth{};
    truth.utime = t;
    truth.position[0] = 0.8 * rolled;
    truth.orientation[0] = 1.0;
    truth.odometer_m = 5.0 + 0.8 * rolled;  // the simulator's odometer need not start at 0
    log.Write(channels::kSimTruth, truth, t);
  }
  log.Write(channels::kStepReport, Step(0, kT0, kT0 + 5 * kSecond, -1), kT0 + 5 * kSecond);
  log.Write(channels::kStepReport, Step(1, kT0 + 5 * kSecond, kT0 + 10 * kSecond, 0), kT0 + 10 * kSecond);
  rover_msgs::sequence_status_t status{};
  status.utime = kT0 + 10 * kSecond;
  status.state = rover_msgs::sequence_status_t::STATE_ABORTED;
  status.abort_reason = "progress";
  status.pose[0] = 0.9;
  log.Write(channels::kSequenceStatus, status, status.utime);
  return path;
}

std::string FreshDir(const std::string& name) {
  const std::string dir = std::string(ROVER_BINARY_DIR) + "/test-out/plot_test/" + name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

bool IsPng(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  char sig[8] = {};
  in.read(sig, 8);
  return in && std::string(sig + 1, 3) == "PNG" && fs::file_size(path) > 1000;
}

TEST(DriveLog, ReadsEverySeriesOfTheSyntheticDrive) {
  const auto log = ReadDriveLog(WriteDriveLog(FreshDir("read")));
  EXPECT_EQ(log.estimate.size(), 101u);
  EXPECT_EQ(log.truth.size(), 101u);
  ASSERT_EQ(log.zones.size(), 1u);
  EXPECT_EQ(log.zones[0].zone.name, "rock");
  EXPECT_DOUBLE_EQ(log.zones[0].zone.radius_m, 0.5);
  ASSERT_EQ(log.steps.size(), 2u);
  ASSERT_TRUE(log.final_status.has_value());
  EXPECT_EQ(log.final_status->abort_reason, "progress");
  EXPECT_EQ(log.sequence_name, "synthetic.seq");
  // `slip limit 40 %` is line 1: in force for the drive (command 2).
  ASSERT_TRUE(log.slip_limit_pct.count(2));
  EXPECT_DOUBLE_EQ(log.slip_limit_pct.at(2), 40.0);
  EXPECT_NEAR(log.estimate.back().sigma_xy_m, 0.02, 1e-12);
  // Wheel odometry integrated along the IMU attitude (north, level): 1 m north.
  ASSERT_FALSE(log.wheel_only.empty());
  EXPECT_NEAR(log.wheel_only.back().p.x(), 1.0, 1e-9);
  EXPECT_NEAR(log.wheel_only.back().p.y(), 0.0, 1e-9);
}

TEST(DriveLog, AMissingLogIsOneClearError) {
  try {
    ReadDriveLog("/nonexistent/log.lcm");
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/log.lcm"), std::string::npos) << e.what();
  }
}

TEST(PlotSeries, SegmentsFollowTheStepsVoMeasured) {
  const auto log = ReadDriveLog(WriteDriveLog(FreshDir("segments")));
  const auto segments = EstimateSegments(log);
  ASSERT_EQ(segments.size(), 2u);
  EXPECT_EQ(segments[0].mode, Mode::kBlind);
  EXPECT_EQ(segments[1].mode, Mode::kVo);
  // The VO segment starts where the blind one ended, and ends at the last pose.
  EXPECT_TRUE(segments[1].points.front().isApprox(segments[0].points.back()));
  EXPECT_NEAR(segments[0].points.back().x(), 0.45, 1e-9);
  EXPECT_NEAR(segments[1].points.back().x(), 0.9, 1e-9);
}

TEST(PlotSeries, ErrorAgainstDistanceHasTheKnownSlopes) {
  const auto log = ReadDriveLog(WriteDriveLog(FreshDir("error")));
  const auto series = ErrorSeries(log);
  ASSERT_GT(series.size(), 10u);
  EXPECT_NEAR(series.front().distance_m, 0.0, 1e-12);
  // Truth travels 0.8 m; wheel odometry says 1.0 m (error 0.2 m), the estimate 0.9 m (0.1 m).
  EXPECT_NEAR(series.back().distance_m, 0.8, 1e-9);
  EXPECT_NEAR(series.back().wheel_only_error_m, 0.2, 1e-9);
  EXPECT_NEAR(series.back().estimate_error_m, 0.1, 1e-9);
  for (const auto& e : series) EXPECT_NEAR(e.wheel_only_error_m, 0.25 * e.distance_m, 1e-9);
}

TEST(PlotSeries, SlipRowsHoldCommandedMeasuredTrueAndTheLimit) {
  const auto log = ReadDriveLog(WriteDriveLog(FreshDir("slip")));
  const auto rows = SlipRows(log);
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_FALSE(rows[0].vo);
  EXPECT_TRUE(rows[1].vo);
  for (const auto& r : rows) {
    EXPECT_DOUBLE_EQ(r.commanded_m, 0.5);
    EXPECT_DOUBLE_EQ(r.measured_m, 0.45);
    ASSERT_TRUE(r.true_m && r.true_slip_pct && r.limit_pct && r.measured_slip_pct);
    EXPECT_NEAR(*r.true_m, 0.4, 1e-9);  // 80 % of 0.5 m
    EXPECT_NEAR(*r.true_slip_pct, 20.0, 1e-6);
    EXPECT_DOUBLE_EQ(*r.limit_pct, 40.0);
  }
}

TEST(PlotSeries, VoStepsAreEvenlySpacedOverTheMeasuredOnes) {
  DriveLog log;
  for (int i = 0; i < 11; ++i) {
    rover_msgs::step_report_t s{};
    s.utime_before = i * kSecond;
    s.utime_after = (i + 1) * kSecond;
    s.vo_status = i == 3 ? 2 : 0;  // step 4 failed: never chosen
    log.steps.push_back(s);
    rover_msgs::vo_update_t u{};
    u.status = s.vo_status;
    u.from_frame_id = i;
    u.to_frame_id = i + 1;
    u.to_utime = s.utime_after;
    log.vo_updates.push_back(u);
  }
  const auto chosen = ChooseVoSteps(log, 4);
  ASSERT_EQ(chosen.size(), 4u);
  // Measured: steps 1,2,3,5,...,11 (10 of them); picks 0, 3, 6, 9 of those.
  EXPECT_EQ(chosen[0].number, 1);
  EXPECT_EQ(chosen[1].number, 5);
  EXPECT_EQ(chosen[2].number, 8);
  EXPECT_EQ(chosen[3].number, 11);
  EXPECT_EQ(chosen[3].update.to_frame_id, 11);
  EXPECT_EQ(ChooseVoSteps(log, 20).size(), 10u);
  EXPECT_TRUE(ChooseVoSteps(log, 0).empty());
}

TEST(PlotSeries, TicsGiveAOneMetreGridAndAboutTenLabels) {
  EXPECT_DOUBLE_EQ(TicsFor(8).label_m, 1);
  EXPECT_EQ(TicsFor(8).minor_per_label, 1);
  EXPECT_DOUBLE_EQ(TicsFor(40).label_m, 5);
  EXPECT_EQ(TicsFor(40).minor_per_label, 5);  // grid every metre
  EXPECT_DOUBLE_EQ(TicsFor(1000).label_m, 100);
  EXPECT_EQ(TicsFor(1000).minor_per_label, 1);  // a 1 m grid would be a grey square
}

TEST(Gnuplot, QuotesAndNumbers) {
  EXPECT_EQ(Quoted("it's \"a\"\nb\\"), "\"it's \\\"a\\\"\\nb\\\\\"");
  EXPECT_EQ(Num(0.25), "0.25");
  EXPECT_EQ(Num(std::nan("")), "?");
}

// A title too long for its picture is broken into lines that fit, at "; " where it can,
// and loses nothing.
TEST(Gnuplot, LongTitlesWrapIntoLinesThatFit) {
  const std::string three =
      "day_one (first_drive.seq, second_leg.seq, third_goto.seq): traverse, first_drive.seq completed; "
      "second_leg.seq aborted (progress); third_goto.seq completed\nafter 12.345 m: on-board estimate off by "
      "0.012 m, wheel odometry alone by 0.345 m";
  const std::size_t width = TitleChars(900);
  EXPECT_GE(width, 100u);
  EXPECT_LE(width, 137u) << "137 characters filled 900 px";
  const std::string wrapped = WrapTitle(three, width);
  std::vector<std::string> lines;
  std::stringstream in(wrapped);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  ASSERT_GE(lines.size(), 3u) << wrapped;
  for (const auto& line : lines) EXPECT_LE(line.size(), width) << line;
  EXPECT_EQ(lines[0].back(), ';') << "broken after a sequence's outcome: " << lines[0];
  // Nothing lost: the same words in the same order.
  auto words = [](const std::string& text) {
    std::vector<std::string> w;
    std::stringstream ss(text);
    for (std::string word; ss >> word;) w.push_back(word);
    return w;
  };
  EXPECT_EQ(words(wrapped), words(three));
  // A title that fits is left alone; so is a word longer than a line.
  EXPECT_EQ(WrapTitle("demo (demo.seq): traverse, completed", width), "demo (demo.seq): traverse, completed");
  EXPECT_EQ(WrapTitle(std::string(50, 'x') + " y", 20), std::string(50, 'x') + "\ny");
}

TEST(Plots, WritesTheThreePicturesAndSaysWhyVoStepsAreEmpty) {
  const std::string terminal = PngTerminal();
  if (terminal.empty()) GTEST_SKIP() << "gnuplot is not installed (Debian gnuplot-nox; ./rover setup installs it)";
  const std::string dir = FreshDir("pictures");
  const auto log = ReadDriveLog(WriteDriveLog(dir));
  PlotPlace place{dir, dir + "/plot", terminal, "synthetic"};
  fs::create_directories(place.data_dir);
  for (const auto& o : {WriteTraversePlot(log, place), WriteErrorPlot(log, place), WriteSlipPlot(log, place)}) {
    EXPECT_TRUE(o.written) << o.note;
    EXPECT_TRUE(IsPng(o.file)) << o.file;
  }
  // The scripts stay beside the data, for anyone to re-run.
  EXPECT_TRUE(fs::exists(dir + "/plot/traverse.gp"));
  EXPECT_TRUE(fs::exists(dir + "/plot/traverse_estimate_vo.dat"));
  // The synthetic log has no stereo frames: VO update absent, so no step is chosen.
  const auto vo = WriteVoSteps(log, std::string(ROVER_SOURCE_DIR) + "/configs/vo.yaml", 6, place);
  EXPECT_EQ(vo.written, 0);
  EXPECT_FALSE(vo.failed);
  EXPECT_NE(vo.note.find("no step was measured by VO"), std::string::npos) << vo.note;
  EXPECT_TRUE(fs::exists(dir + "/vo_steps/README.txt"));
}

TEST(Plots, WithoutTruthErrorPngIsSkippedWithAReason) {
  const std::string terminal = PngTerminal();
  if (terminal.empty()) GTEST_SKIP() << "gnuplot is not installed (Debian gnuplot-nox; ./rover setup installs it)";
  const std::string dir = FreshDir("no_truth");
  auto log = ReadDriveLog(WriteDriveLog(dir));
  log.truth.clear();
  PlotPlace place{dir, dir + "/plot", terminal, "no truth"};
  fs::create_directories(place.data_dir);
  const auto error = WriteErrorPlot(log, place);
  EXPECT_FALSE(error.written);
  EXPECT_FALSE(error.failed);
  EXPECT_NE(error.note.find("no SIM_TRUTH"), std::string::npos) << error.note;
  EXPECT_TRUE(WriteTraversePlot(log, place).written);
  EXPECT_TRUE(WriteSlipPlot(log, place).written);
  // No step at all (a rejected sequence): slip.png is still written and says why.
  log.steps.clear();
  const auto slip = WriteSlipPlot(log, place);
  EXPECT_TRUE(slip.written) << slip.note;
  EXPECT_TRUE(IsPng(slip.file));
  std::ifstream script(dir + "/plot/slip.gp");
  const std::string text((std::istreambuf_iterator<char>(script)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("no step was driven"), std::string::npos) << text;
}

std::string ReadAll(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// A second sequence after the first, in the same log: a goto with avoidance whose first
// step steered straight at the goal and whose second was voted, aborted on the map.
std::string AppendSecondSequence(const std::string& dir) {
  const std::string path = dir + "/two.lcm";
  fs::copy_file(WriteDriveLog(dir), path, fs::copy_options::overwrite_existing);
  lcm::LogFile file(path, "a");
  auto write = [&](const char* channel, const auto& msg, std::int64_t utime) {
    std::vector<std::uint8_t> buf(msg.getEncodedSize());
    msg.encode(buf.data(), 0, static_cast<int>(buf.size()));
    lcm::LogEvent ev{};
    ev.timestamp = utime;
    ev.channel = channel;
    ev.datalen = static_cast<int32_t>(buf.size());
    ev.data = buf.data();
    ASSERT_EQ(file.writeEvent(&ev), 0);
  };
  const std::int64_t t = kT0 + 20 * kSecond;
  rover_msgs::sequence_submit_t submit{};
  submit.submission_id = 2;
  submit.name = "second.seq";
  submit.text = "goto 3 m 0 m within 0.5 m avoid on\n";
  write(channels::kSequenceSubmit, submit, t);
  rover_msgs::sequence_status_t st{};
  st.submission_id = 2;
  st.sequence_name = "second.seq";
  st.state = rover_msgs::sequence_status_t::STATE_RUNNING;
  st.command_index = 0;
  st.command_text = "goto 3 m 0 m within 0.5 m avoid on";
  st.detail = "avoid: step 0";  // the colours come from the step reports' choice, not this text
  write(channels::kSequenceStatus, st, t + kSecond);
  rover_msgs::step_report_t step = Step(0, t, t + 2 * kSecond, -1);
  step.submission_id = 2;
  step.command_index = 0;
  step.choice = rover_msgs::step_report_t::CHOICE_STEER_AT_GOAL;
  write(channels::kStepReport, step, t + 2 * kSecond);
  st.step_index = 1;
  st.detail = "avoid: step 1";
  write(channels::kSequenceStatus, st, t + 3 * kSecond);
  step = Step(1, t + 2 * kSecond, t + 4 * kSecond, -1);
  step.submission_id = 2;
  step.command_index = 0;
  step.choice = rover_msgs::step_report_t::CHOICE_ARC_VOTE;
  write(channels::kStepReport, step, t + 4 * kSecond);
  st.state = rover_msgs::sequence_status_t::STATE_ABORTED;
  st.abort_reason = "hazard_map";
  st.pose[0] = 1.4;
  st.pose[1] = 0.2;
  write(channels::kSequenceStatus, st, t + 5 * kSecond);
  return path;
}

TEST(DriveLog, TwoSequencesGoalDiscsAndStepsThatOnlySteered) {
  const auto log = ReadDriveLog(AppendSecondSequence(FreshDir("two_read")));
  ASSERT_EQ(log.runs.size(), 2u);
  EXPECT_EQ(log.runs[0].name, "synthetic.seq");
  ASSERT_TRUE(log.runs[0].final_status && log.runs[1].final_status);
  EXPECT_EQ(log.runs[0].final_status->abort_reason, "progress");
  EXPECT_EQ(log.runs[1].name, "second.seq");
  EXPECT_EQ(log.runs[1].final_status->abort_reason, "hazard_map");
  ASSERT_EQ(log.goals.size(), 1u);
  EXPECT_EQ(log.goals[0].submission_id, 2);
  EXPECT_DOUBLE_EQ(log.goals[0].target.x(), 3.0);
  EXPECT_DOUBLE_EQ(log.goals[0].radius_m, 0.5);
  // Each step's choice as the executor reported it: the first sequence's drive steps are
  // the command's own, the goto's first steered at the goal, its second was voted.
  std::map<std::pair<std::int64_t, int>, int> choices;
  for (const auto& s : log.steps) choices[{s.submission_id, s.step_index}] = s.choice;
  EXPECT_EQ(choices.at({0, 0}), int{rover_msgs::step_report_t::CHOICE_COMMAND});
  EXPECT_EQ(choices.at({2, 0}), int{rover_msgs::step_report_t::CHOICE_STEER_AT_GOAL});
  EXPECT_EQ(choices.at({2, 1}), int{rover_msgs::step_report_t::CHOICE_ARC_VOTE});
}

TEST(Plots, TraverseShowsBothSequencesTheirAbortsTheGoalRocksAndSteeringSteps) {
  const std::string terminal = PngTerminal();
  if (terminal.empty()) GTEST_SKIP() << "gnuplot is not installed (Debian gnuplot-nox; ./rover setup installs it)";
  const std::string dir = FreshDir("two_pictures");
  auto log = ReadDriveLog(AppendSecondSequence(dir));
  log.rocks = ReadWorldRocks(std::string(ROVER_SOURCE_DIR) + "/configs/worlds/flat_rock_course.yaml", 0.10);
  ASSERT_FALSE(log.rocks.empty());
  EXPECT_TRUE(std::any_of(log.rocks.begin(), log.rocks.end(), [](const RockMark& r) { return r.name == "Adirondack"; }));
  for (const auto& r : log.rocks) EXPECT_GE(r.height_m, 0.10);
  PlotPlace place{dir, dir + "/plot", terminal, "two"};
  fs::create_directories(place.data_dir);
  const auto out = WriteTraversePlot(log, place);
  ASSERT_TRUE(out.written) << out.note;
  EXPECT_TRUE(IsPng(out.file));
  std::ifstream script(dir + "/plot/traverse.gp");
  const std::string text((std::istreambuf_iterator<char>(script)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("synthetic.seq aborted (progress); second.seq aborted (hazard_map)"), std::string::npos) << text;
  EXPECT_NE(text.find("'traverse_abort.dat'"), std::string::npos) << text;
  EXPECT_NE(text.find("'traverse_abort2.dat'"), std::string::npos) << text;
  EXPECT_NE(text.find("abort: second.seq: hazard_map"), std::string::npos) << text;
  EXPECT_NE(text.find("abort: synthetic.seq: progress"), std::string::npos) << text;
  EXPECT_NE(text.find("'traverse_goals.dat' using 2:1:3 with circles"), std::string::npos) << text;
  EXPECT_NE(text.find("'traverse_rocks.dat' using 2:1:3 with circles"), std::string::npos) << text;
  EXPECT_NE(text.find("'traverse_steer.dat'"), std::string::npos) << text;
  EXPECT_NE(text.find("'traverse_avoid.dat'"), std::string::npos) << text;
  // One step each: the steered one and the voted one.
  auto lines = [&](const std::string& file) {
    std::ifstream in(dir + "/plot/" + file);
    int n = 0;
    for (std::string line; std::getline(in, line);) n += !line.empty();
    return n;
  };
  EXPECT_EQ(lines("traverse_steer.dat"), 2);
  EXPECT_EQ(lines("traverse_avoid.dat"), 2);
  // Which is which: step 0 (x 0 to 0.45) steered, step 1 (x 0.45 to 0.9) was voted.
  const std::string steer_rows = ReadAll(dir + "/plot/traverse_steer.dat");
  const std::string avoid_rows = ReadAll(dir + "/plot/traverse_avoid.dat");
  EXPECT_EQ(steer_rows.rfind("0 0\n0.45 0\n", 0), 0u) << steer_rows;
  EXPECT_EQ(avoid_rows.rfind("0.45 0\n0.9 0\n", 0), 0u) << avoid_rows;
  EXPECT_EQ(lines("traverse_goals.dat"), 1);
}

// A log with three sequences: the traverse title names each and fits its picture.
TEST(Plots, AThreeSequenceTitleFitsThePicture) {
  const std::string terminal = PngTerminal();
  if (terminal.empty()) GTEST_SKIP() << "gnuplot is not installed (Debian gnuplot-nox; ./rover setup installs it)";
  const std::string dir = FreshDir("three_title");
  const auto log = ReadDriveLog(AppendSecondSequence(dir));
  PlotPlace place{dir, dir + "/plot", terminal,
                  "a_long_day_of_operations (synthetic.seq, second.seq, a_third_sequence_with_a_long_name.seq)"};
  fs::create_directories(place.data_dir);
  ASSERT_TRUE(WriteTraversePlot(log, place).written);
  const std::string script = ReadAll(dir + "/plot/traverse.gp");
  const auto at = script.find("set title \"");
  ASSERT_NE(at, std::string::npos) << script;
  const std::string title = script.substr(at + 11, script.find('\n', at) - at - 12);  // between the quotes
  std::size_t lines = 0, start = 0;
  for (std::size_t end; start <= title.size(); start = end + 2) {
    end = std::min(title.find("\\n", start), title.size());
    EXPECT_LE(end - start, TitleChars(900)) << title.substr(start, end - start);
    ++lines;
    if (end == title.size()) break;
  }
  EXPECT_GE(lines, 3u) << title;
  for (const char* name : {"a_third_sequence_with_a_long_name.seq", "synthetic.seq aborted (progress);",
                           "second.seq aborted (hazard_map)"}) {
    EXPECT_NE(title.find(name), std::string::npos) << name << " is not in the title: " << title;
  }
}

}  // namespace
}  // namespace rover::plot

namespace rover::plot {

// rover_plot as a user runs it on a log recorded by hand: no run folder's commands.txt
// names the world, so one line says the rocks are not drawn and how to draw them; with
// --world that line is gone and the world's rocks are drawn.
TEST(PlotTool, AHandRecordedLogSaysTheRocksAreNotDrawnAndNamesWorld) {
  if (PngTerminal().empty()) GTEST_SKIP() << "gnuplot is not installed (Debian gnuplot-nox; ./rover setup installs it)";
  const std::string dir = FreshDir("hand_recorded");
  const std::string log = WriteDriveLog(dir);
  auto run = [&](const std::string& extra) {
    const std::string command = std::string(ROVER_BINARY_DIR) + "/bin/rover_plot " + log + " --vo-steps 0 " +
                                "--vo-config " + ROVER_SOURCE_DIR + "/configs/vo.yaml " + extra + " 2>&1";
    std::string out;
    FILE* pipe = popen(command.c_str(), "r");
    char buffer[512];
    while (pipe != nullptr && fgets(buffer, sizeof buffer, pipe) != nullptr) out += buffer;
    const int status = pipe != nullptr ? pclose(pipe) : -1;
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << command << "\n" << out;
    return out;
  };
  const std::string bare = run("");
  EXPECT_NE(bare.find("plot: no world: the log's folder has no commands.txt naming rover_sim's --world and no "
                      "--world was given, so traverse.png draws no rocks (pass --world FILE to draw them)\n"),
            std::string::npos)
      << bare;
  EXPECT_FALSE(fs::exists(dir + "/plot/traverse_rocks.dat"));
  const std::string with_world = run("--world " + std::string(ROVER_SOURCE_DIR) + "/configs/worlds/rock_field.yaml");
  EXPECT_EQ(with_world.find("no world"), std::string::npos) << with_world;
  // The picture's data holds the world's rocks now.
  EXPECT_TRUE(fs::exists(dir + "/plot/traverse_rocks.dat")) << with_world;
}

}  // namespace rover::plot
