// The console's frame from messages fed directly: every section shows what its message
// said, stale heartbeats read SILENT, and a finished sequence shows no current step.
#include "console/console_view.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace rover::console {
namespace {

std::string Join(const std::vector<std::string>& lines) {
  std::string s;
  for (const auto& l : lines) s += l + "\n";
  return s;
}

rover_msgs::sequence_status_t Running() {
  rover_msgs::sequence_status_t st{};
  st.utime = 310'100'000;
  st.submission_id = 1;
  st.sequence_name = "configs/sequences/demo.seq";
  st.state = rover_msgs::sequence_status_t::STATE_RUNNING;
  st.num_commands = 11;
  st.command_index = 9;
  st.command_line = 13;
  st.command_text = "goto 5 m 3 m within 0.3 m";
  st.step_index = 3;
  st.detail = "step 4: 2.41 m to go";
  st.distance_m = 3.21;
  st.elapsed_s = 310.1;
  st.vo_failures = 1;
  return st;
}

ConsoleState FullState() {
  ConsoleState s;
  s.On(Running(), 100.0);
  rover_msgs::step_report_t r{};
  r.submission_id = 1;
  r.command_index = 9;
  r.step_index = 2;
  r.commanded_distance_m = 0.5;
  r.estimated_distance_m = 0.482;
  r.slip_pct = 3.6;
  r.vo_status = 0;
  s.On(r, 99.0);
  r.step_index = 3;
  r.vo_status = 2;  // too few features: blind
  r.estimated_distance_m = 0.5;
  r.slip_pct = 0.0;
  s.On(r, 99.5);
  rover_msgs::vo_update_t u{};
  u.status = 0;
  u.from_frame_id = 320;
  u.to_frame_id = 323;
  u.num_detected = 300;
  u.num_matched = 251;
  u.num_tracked = 116;
  u.num_inliers = 72;
  u.ms_total = 113;
  s.On(u, 99.0);
  rover_msgs::hazard_status_t h{};
  h.state = rover_msgs::hazard_status_t::STATE_SAFE;
  h.zone_name = "humphrey";
  h.min_clearance_m = 1.46;
  h.roll_limit_rad = h.pitch_limit_rad = 25 * M_PI / 180;
  h.pitch_rad = 1.2 * M_PI / 180;
  s.On(h, 99.9);
  rover_msgs::pose_t p{};
  p.position[0] = 4.922;
  p.position[1] = 2.923;
  p.position[2] = -0.367;
  // Yaw 90 deg (east): q = (cos 45, 0, 0, sin 45).
  p.orientation[0] = std::cos(M_PI / 4);
  p.orientation[3] = std::sin(M_PI / 4);
  p.covariance[0][0] = 0.03 * 0.03;
  p.covariance[1][1] = 0.04 * 0.04;
  p.covariance[2][2] = 0.01 * 0.01;
  p.covariance[5][5] = std::pow(0.5 * M_PI / 180, 2);
  p.source = rover_msgs::pose_t::SOURCE_VO;
  p.odometer_m = 6.28;
  s.On(p, 99.95);
  rover_msgs::heartbeat_t hb{};
  hb.process = "state_estimator";
  hb.dropped = 7;
  s.On(hb, 99.6);
  hb.process = "visual_odometry";
  hb.dropped = 0;
  s.On(hb, 90.0);  // ten seconds before "now": silent
  return s;
}

TEST(ConsoleFrame, ShowsEverySectionOfARunningDrive) {
  FrameOptions o;
  o.bus_url = "udpm://239.255.76.67:7667";
  const std::string f = Join(RenderFrame(FullState(), 100.0, o));
  // Sequence, command and step.
  EXPECT_NE(f.find("configs/sequences/demo.seq (#1)  RUNNING  t=310.1 s  driven 3.21 m  VO failures 1"), std::string::npos) << f;
  EXPECT_NE(f.find("10/11, line 13: goto 5 m 3 m within 0.3 m   step 4"), std::string::npos) << f;
  EXPECT_NE(f.find("step 4: 2.41 m to go"), std::string::npos) << f;
  // A command that does not drive has no step; a detail that only repeats it is not shown.
  ConsoleState images = FullState();
  auto st = Running();
  st.command_index = 10;
  st.command_line = 14;
  st.command_text = "images science";
  st.detail = "line 14: images science";
  images.On(st, 100.0);
  const std::string g = Join(RenderFrame(images, 100.0, o));
  EXPECT_NE(g.find("11/11, line 14: images science\n"), std::string::npos) << g;
  EXPECT_EQ(g.find("          line 14: images science"), std::string::npos) << g;
  // Steps: commanded against measured, slip, how measured.
  EXPECT_NE(f.find("10.3      0.500 m 0.0 deg    0.482 m 0.0 deg    3.6 %    VO"), std::string::npos) << f;
  EXPECT_NE(f.find("10.4      0.500 m 0.0 deg    0.500 m 0.0 deg    0.0 %    wheel odometry (VO too_few_features)"),
            std::string::npos) << f;
  // VO, hazard, pose and sigma.
  EXPECT_NE(f.find("ok  frames 320 -> 323  detected 300  matched 251  tracked 116  inliers 72  113 ms"), std::string::npos) << f;
  EXPECT_NE(f.find("SAFE  nearest zone humphrey 1.46 m  roll 0.0/25 deg  pitch 1.2/25 deg"), std::string::npos) << f;
  EXPECT_NE(f.find("x 4.922  y 2.923  z -0.367 m   roll 0.0  pitch 0.0  yaw 90.0 deg"), std::string::npos) << f;
  EXPECT_NE(f.find("1-sigma: position 0.040 m, height 0.010 m, heading 0.50 deg   source VO"), std::string::npos) << f;
  // Processes: liveness and dropped counts.
  EXPECT_NE(f.find("state_estimator     ok        0.4 s ago    7"), std::string::npos) << f;
  EXPECT_NE(f.find("visual_odometry     SILENT    10.0 s ago   0"), std::string::npos) << f;
}

TEST(ConsoleFrame, AFinishedSequenceShowsNoCurrentStepAndTheRecentStepsAreBounded) {
  ConsoleState s = FullState();
  auto st = Running();
  st.state = rover_msgs::sequence_status_t::STATE_COMPLETED;
  st.detail = "all 11 commands done";
  s.On(st, 100.0);
  for (int i = 0; i < 12; ++i) {
    rover_msgs::step_report_t r{};
    r.submission_id = 1;
    r.command_index = 10;
    r.step_index = i;
    s.On(r, 100.0);
  }
  FrameOptions o;
  o.recent_steps = 3;
  const auto lines = RenderFrame(s, 100.0, o);
  const std::string f = Join(lines);
  EXPECT_NE(f.find("COMPLETED"), std::string::npos) << f;
  EXPECT_EQ(f.find("COMMAND"), std::string::npos) << f;
  EXPECT_NE(f.find("all 11 commands done"), std::string::npos) << f;
  EXPECT_NE(f.find("11.12"), std::string::npos) << f;
  EXPECT_NE(f.find("11.10"), std::string::npos) << f;
  EXPECT_EQ(f.find("11.9 "), std::string::npos) << f;  // only the last three
}

// The zones in force: the set the executor sent, and, for a console started after it was
// sent, what the hazard monitor's status says.
TEST(ConsoleFrame, ZonesInForceFromTheExecutorOrTheMonitor) {
  FrameOptions o;
  ConsoleState s = FullState();  // the monitor's status names humphrey as nearest
  std::string f = Join(RenderFrame(s, 100.0, o));
  EXPECT_NE(f.find("ZONES     the hazard monitor holds zones, nearest humphrey (the whole set shows when the "
                   "executor next sends it)"), std::string::npos) << f;
  rover_msgs::keepout_zones_t set{};
  set.num_zones = 2;
  set.zones.resize(2);
  set.zones[0].name = "humphrey";
  set.zones[0].shape = rover_msgs::keepout_zone_t::SHAPE_CIRCLE;
  set.zones[0].center[0] = 3.0;
  set.zones[0].center[1] = -2.8;
  set.zones[0].radius_m = 0.7;
  set.zones[1].name = "ridge";
  set.zones[1].shape = rover_msgs::keepout_zone_t::SHAPE_POLYGON;
  set.zones[1].num_vertices = 3;
  s.On(set, 99.0);
  f = Join(RenderFrame(s, 100.0, o));
  EXPECT_NE(f.find("ZONES     2 in force: humphrey (circle 3.00 -2.80 m r 0.70 m) ridge (polygon, 3 vertices)"),
            std::string::npos) << f;
  // The next sequence starts: the executor sends an empty set.
  s.On(rover_msgs::keepout_zones_t{}, 99.5);
  auto h = s.hazard->msg;
  h.zone_name.clear();
  s.On(h, 99.6);
  f = Join(RenderFrame(s, 100.0, o));
  EXPECT_NE(f.find("ZONES     none in force (a sequence's zones are cleared when the next one starts)\n"),
            std::string::npos) << f;
  ConsoleState nothing;
  EXPECT_NE(Join(RenderFrame(nothing, 100.0, o)).find("ZONES     no KEEPOUT_ZONES or HAZARD_STATUS heard yet"),
            std::string::npos);
}

TEST(ConsoleFrame, NothingHeardSaysSoInEverySection) {
  FrameOptions o;
  o.listened_s = 2.5;
  const std::string f = Join(RenderFrame(ConsoleState{}, 100.0, o));
  EXPECT_NE(f.find("no SEQUENCE_STATUS heard in 2.5 s"), std::string::npos) << f;
  EXPECT_NE(f.find("no POSE heard yet"), std::string::npos) << f;
  EXPECT_NE(f.find("no HEARTBEAT heard in 2.5 s"), std::string::npos) << f;
  EXPECT_NE(f.find("rover time unknown"), std::string::npos) << f;
}

}  // namespace
}  // namespace rover::console
