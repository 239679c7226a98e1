// The web console's state JSON from messages fed directly (no bus, no HTTP): every key the
// page draws from, read back with yaml-cpp (YAML 1.2 reads JSON).
#include "web_console/web_state.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <yaml-cpp/yaml.h>

#include <cmath>

namespace rover::web {
namespace {

TEST(WebState, ThreeSigmaEllipseAxesAndHeading) {
  // sigma 0.1 m north, 0.05 m east: 3-sigma 0.3 by 0.15, major axis north.
  Ellipse e = ThreeSigmaEllipse(0.01, 0.0, 0.0025);
  EXPECT_NEAR(e.major_m, 0.3, 1e-9);
  EXPECT_NEAR(e.minor_m, 0.15, 1e-9);
  EXPECT_NEAR(e.heading_deg, 0.0, 1e-9);
  // The same, turned 90 deg: major axis east.
  e = ThreeSigmaEllipse(0.0025, 0.0, 0.01);
  EXPECT_NEAR(e.major_m, 0.3, 1e-9);
  EXPECT_NEAR(std::abs(e.heading_deg), 90.0, 1e-9);
  // Correlated: the major axis lies north-east.
  e = ThreeSigmaEllipse(0.01, 0.008, 0.01);
  EXPECT_NEAR(e.heading_deg, 45.0, 1e-9);
  EXPECT_NEAR(e.major_m, 3 * std::sqrt(0.018), 1e-9);
  EXPECT_NEAR(e.minor_m, 3 * std::sqrt(0.002), 1e-9);
}

TEST(WebState, GoalDiscOnlyFromAGoto) {
  const auto g = GoalOf("goto 5 m 3 m within 0.3 m time 1800 s distance 8 m avoid on");
  ASSERT_TRUE(g.has_value());
  EXPECT_DOUBLE_EQ(g->x, 5.0);
  EXPECT_DOUBLE_EQ(g->y, 3.0);
  EXPECT_DOUBLE_EQ(g->radius, 0.3);
  EXPECT_FALSE(GoalOf("drive 2 m").has_value());
  EXPECT_FALSE(GoalOf("goto 5 m").has_value());  // malformed: no disc, no crash
  EXPECT_FALSE(GoalOf("").has_value());
}

TEST(WebState, JsonCarriesEveryPanel) {
  WebStateOptions opt;
  opt.bus_url = "udpm://239.255.76.67:7667?ttl=0";
  opt.commands_enabled = true;
  WebState state(opt);
  const double t = 100.0;
  EXPECT_EQ(YAML::Load(state.StateJson(t))["pose"].IsNull(), true);

  rover_msgs::pose_t pose{};
  pose.utime = 5000000;
  pose.position[0] = 1.25;
  pose.position[1] = -0.5;
  const double yaw = 30.0 * M_PI / 180;
  pose.orientation[0] = std::cos(yaw / 2);
  pose.orientation[3] = std::sin(yaw / 2);
  pose.covariance[0][0] = 0.01;
  pose.covariance[1][1] = 0.0025;
  pose.covariance[5][5] = 1e-4;
  pose.source = rover_msgs::pose_t::SOURCE_VO;
  state.On(pose, t);
  pose.position[0] = 1.5;  // a second point on the path
  pose.utime += 100000;
  state.On(pose, t);

  rover_msgs::sim_truth_t truth{};
  truth.utime = 5100000;
  truth.position[0] = 1.51;
  truth.position[1] = -0.49;
  truth.rpy[2] = yaw;
  truth.soil = "sand";
  state.On(truth, t);

  rover_msgs::traversability_map_t map{};
  map.origin_x = -1;
  map.origin_y = -2;
  map.cell_m = 0.2;
  map.rows = 2;
  map.cols = 3;
  map.num_cells = 6;
  map.state = {0, 1, 2, 3, 1, 1};
  map.goodness.assign(6, 0.5f);
  map.step_m.assign(6, 0.0f);
  map.elevation_m.assign(6, 0.0f);
  map.sigma_m = {-1, 0.02f, 0.02f, 0.02f, 0.02f, 0.02f};
  state.On(map, t);

  rover_msgs::keepout_zones_t zones{};
  zones.num_zones = 2;
  zones.zones.resize(2);
  zones.zones[0].name = "rock1";
  zones.zones[0].shape = rover_msgs::keepout_zone_t::SHAPE_CIRCLE;
  zones.zones[0].center[0] = 4.2;
  zones.zones[0].center[1] = 1.0;
  zones.zones[0].radius_m = 0.6;
  zones.zones[1].name = "ridge \"north\"";
  zones.zones[1].shape = rover_msgs::keepout_zone_t::SHAPE_POLYGON;
  zones.zones[1].num_vertices = 3;
  zones.zones[1].vertices_x = {1, 3, 3};
  zones.zones[1].vertices_y = {2, 2, 5};
  state.On(zones, t);

  rover_msgs::sequence_submit_t submit{};
  submit.submission_id = 42;
  submit.name = "web";
  submit.text = "drive 1 m\ngoto 5 m 3 m within 0.3 m\n";
  state.On(submit, t);
  rover_msgs::sequence_status_t st{};
  st.submission_id = 42;
  st.sequence_name = "web";
  st.state = rover_msgs::sequence_status_t::STATE_RUNNING;
  st.num_commands = 2;
  st.command_index = 1;
  st.command_line = 2;
  st.command_text = "goto 5 m 3 m within 0.3 m";
  st.detail = "a <b>detail</b>\nwith a newline";
  state.On(st, t);

  rover_msgs::step_report_t step{};
  step.submission_id = 41;  // an earlier sequence's step: not counted for this one
  state.On(step, t);
  step.submission_id = 42;
  step.command_index = 0;
  step.step_index = 1;
  step.commanded_distance_m = 0.5;
  step.estimated_distance_m = 0.45;
  step.slip_pct = 10;
  step.vo_status = rover_msgs::vo_update_t::STATUS_OK;
  state.On(step, t);
  step.vo_status = -1;
  step.choice = rover_msgs::step_report_t::CHOICE_STEER_AT_GOAL;
  state.On(step, t);

  rover_msgs::vo_update_t vo{};
  vo.status = rover_msgs::vo_update_t::STATUS_OK;
  vo.num_inliers = 107;
  vo.num_tracked = 109;
  state.On(vo, t);
  vo.status = rover_msgs::vo_update_t::STATUS_TOO_FEW_FEATURES;
  vo.reason = "too few";
  state.On(vo, t);

  rover_msgs::hazard_status_t hz{};
  hz.state = rover_msgs::hazard_status_t::STATE_SAFE;
  hz.zone_name = "rock1";
  hz.min_clearance_m = 2.08;
  state.On(hz, t);

  rover_msgs::heartbeat_t hb{};
  hb.process = "state_estimator";
  hb.dropped = 3;
  state.On(hb, t - 10);  // 10 s ago: silent
  hb.process = "visual_odometry";
  hb.dropped = 0;
  state.On(hb, t - 0.5);

  const YAML::Node j = YAML::Load(state.StateJson(t));
  EXPECT_TRUE(j["commands"]["enabled"].as<bool>());
  EXPECT_FALSE(j["commands"]["signed"].as<bool>());
  EXPECT_NEAR(j["pose"]["x"].as<double>(), 1.5, 1e-6);
  EXPECT_NEAR(j["pose"]["y"].as<double>(), -0.5, 1e-6);
  EXPECT_NEAR(j["pose"]["yaw_deg"].as<double>(), 30.0, 1e-3);
  EXPECT_NEAR(j["pose"]["ellipse_3sigma"]["major_m"].as<double>(), 0.3, 1e-6);
  EXPECT_NEAR(j["pose"]["ellipse_3sigma"]["minor_m"].as<double>(), 0.15, 1e-6);
  EXPECT_EQ(j["pose"]["source"].as<std::string>(), "vo");
  EXPECT_EQ(j["path"].size(), 4u);  // two points, x y each
  EXPECT_NEAR(j["truth"]["x"].as<double>(), 1.51, 1e-6);
  EXPECT_NEAR(j["truth"]["yaw_deg"].as<double>(), 30.0, 1e-3);
  EXPECT_EQ(j["map"]["cells"].as<std::string>(), "012311");
  EXPECT_EQ(j["map"]["rows"].as<int>(), 2);
  EXPECT_EQ(j["map"]["unsafe"].as<int>(), 1);
  EXPECT_EQ(j["map"]["safe"].as<int>(), 3);
  ASSERT_EQ(j["zones"].size(), 2u);
  EXPECT_EQ(j["zones"][0]["shape"].as<std::string>(), "circle");
  EXPECT_NEAR(j["zones"][0]["radius_m"].as<double>(), 0.6, 1e-9);
  EXPECT_EQ(j["zones"][1]["name"].as<std::string>(), "ridge \"north\"");
  EXPECT_EQ(j["zones"][1]["vertices"].size(), 6u);
  EXPECT_EQ(j["status"]["state"].as<std::string>(), "running");
  EXPECT_EQ(j["status"]["command_line"].as<int>(), 2);
  EXPECT_EQ(j["status"]["detail"].as<std::string>(), st.detail);  // escaped, read back whole
  EXPECT_EQ(j["sequence_text"].as<std::string>(), submit.text);
  EXPECT_NEAR(j["goal"]["x"].as<double>(), 5.0, 1e-9);
  EXPECT_NEAR(j["goal"]["y"].as<double>(), 3.0, 1e-9);
  EXPECT_NEAR(j["goal"]["radius_m"].as<double>(), 0.3, 1e-9);
  ASSERT_EQ(j["steps"].size(), 2u) << "the table: the sequence in the status, not the earlier one";
  EXPECT_EQ(j["step_count"].as<int>(), 2) << "the steps of the sequence in the status";
  EXPECT_EQ(j["steps"][0]["submission_id"].as<int>(), 42);
  EXPECT_NEAR(j["steps"][0]["measured_m"].as<double>(), 0.45, 1e-9);
  EXPECT_EQ(j["steps"][0]["vo"].as<std::string>(), "ok");
  EXPECT_EQ(j["steps"][1]["vo"].as<std::string>(), "blind");
  EXPECT_EQ(j["steps"][0]["choice"].as<std::string>(), "command");
  EXPECT_EQ(j["steps"][1]["choice"].as<std::string>(), "steer_at_goal");
  EXPECT_TRUE(j["playback"].IsNull()) << "live: no playback";
  EXPECT_EQ(j["vo"]["ok"].as<int>(), 1);
  EXPECT_EQ(j["vo"]["failed"].as<int>(), 1);
  EXPECT_EQ(j["vo"]["reason"].as<std::string>(), "too few");
  EXPECT_EQ(j["hazard"]["state"].as<std::string>(), "safe");
  ASSERT_EQ(j["processes"].size(), 2u);
  EXPECT_EQ(j["processes"][0]["name"].as<std::string>(), "state_estimator");
  EXPECT_EQ(j["processes"][0]["state"].as<std::string>(), "silent");
  EXPECT_EQ(j["processes"][0]["dropped"].as<int>(), 3);
  EXPECT_EQ(j["processes"][1]["state"].as<std::string>(), "ok");
  EXPECT_TRUE(j["image"].IsNull());

  // A new sequence without a heard text: the text is null, not the old one.
  st.submission_id = 43;
  st.command_text = "drive 1 m";
  state.On(st, t);
  const YAML::Node k = YAML::Load(state.StateJson(t));
  EXPECT_TRUE(k["sequence_text"].IsNull());
  EXPECT_TRUE(k["goal"].IsNull());
  EXPECT_EQ(k["step_count"].as<int>(), 0);
}

TEST(WebState, LeftImageIsAReducedPng) {
  WebState state(WebStateOptions{});
  std::string why;
  EXPECT_TRUE(state.LeftImagePng(64, &why).empty());
  EXPECT_NE(why.find("no STEREO_FRAME"), std::string::npos) << why;

  rover_msgs::stereo_frame_t f{};
  f.frame_id = 7;
  f.left_model.width = 128;
  f.left_model.height = 96;
  f.left.width = 128;
  f.left.height = 96;
  f.left.encoding = rover_msgs::image_t::ENCODING_GRAY8;
  f.left.size = 128 * 96;
  f.left.data.resize(128 * 96);
  for (int i = 0; i < 128 * 96; ++i) f.left.data[i] = static_cast<std::uint8_t>(i % 128 * 2);
  f.left_utime = 1'000'000;
  f.right_utime = 1'001'250;  // the right image exposed 1.25 ms after the left
  state.On(f, 0);
  EXPECT_EQ(YAML::Load(state.StateJson(0))["image"]["pair_skew_us"].as<int>(), 1250);
  const std::string png = state.LeftImagePng(64, &why);
  ASSERT_FALSE(png.empty()) << why;
  const cv::Mat img = cv::imdecode(std::vector<unsigned char>(png.begin(), png.end()), cv::IMREAD_UNCHANGED);
  EXPECT_EQ(img.cols, 64);
  EXPECT_EQ(img.rows, 48);
  // Left dark, right bright: the image is the frame's, not a blank.
  EXPECT_LT(img.at<std::uint8_t>(24, 2), 30);
  EXPECT_GT(img.at<std::uint8_t>(24, 61), 220);

  // A PNG-encoded frame (camera_capture's `png`), 16-bit: reduced and made 8-bit.
  cv::Mat wide(96, 128, CV_16UC1);
  for (int r = 0; r < 96; ++r)
    for (int c = 0; c < 128; ++c) wide.at<std::uint16_t>(r, c) = static_cast<std::uint16_t>(c < 64 ? 1000 : 60000);
  std::vector<unsigned char> encoded;
  ASSERT_TRUE(cv::imencode(".png", wide, encoded));
  f.frame_id = 9;
  f.left.encoding = rover_msgs::image_t::ENCODING_PNG;
  f.left.width = 128;
  f.left.height = 96;
  f.left.data.assign(encoded.begin(), encoded.end());
  f.left.size = static_cast<std::int32_t>(encoded.size());
  state.On(f, 0);
  const std::string png16 = state.LeftImagePng(64, &why);
  ASSERT_FALSE(png16.empty()) << why;
  const cv::Mat img16 = cv::imdecode(std::vector<unsigned char>(png16.begin(), png16.end()), cv::IMREAD_UNCHANGED);
  EXPECT_EQ(img16.type(), CV_8UC1);
  EXPECT_EQ(img16.cols, 64);
  EXPECT_LT(img16.at<std::uint8_t>(10, 5), 10);
  EXPECT_GT(img16.at<std::uint8_t>(10, 60), 220);

  // A frame whose bytes do not match its declared size: a reason, no image, no crash.
  f.left.encoding = rover_msgs::image_t::ENCODING_GRAY8;
  f.frame_id = 8;
  f.left.data.resize(100);
  f.left.size = 100;
  state.On(f, 0);
  EXPECT_TRUE(state.LeftImagePng(64, &why).empty());
  EXPECT_NE(why.find("frame 8"), std::string::npos) << why;
}

}  // namespace
}  // namespace rover::web
