// camera_capture's front HAZCAM pair (capture.hazcam, README "HAZCAM"): with rover_sim on a
// private bus, one CAPTURE_REQUEST gives a HAZCAM_FRAME and then the STEREO_FRAME, both of
// the same exposure; without the section no HAZCAM_FRAME; with a source other than sim the
// section is refused at start in one line.
#include "bus/bus.hpp"
#include "bus/channels.hpp"
#include "integration/run_support.hpp"
#include "launch/process_set.hpp"

#include <rover_msgs/capture_request_t.hpp>
#include <rover_msgs/heartbeat_t.hpp>
#include <rover_msgs/sim_truth_t.hpp>
#include <rover_msgs/stereo_frame_t.hpp>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <gtest/gtest.h>

#include <chrono>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

namespace rover::test {
namespace {

using Clock = std::chrono::steady_clock;

struct Heard {
  std::string channel;
  rover_msgs::stereo_frame_t frame;
};

// rover_sim on a real clock and camera_capture with `config`; one CAPTURE_REQUEST (frame
// 5, "vo") once camera_capture heartbeats. Returns every STEREO_FRAME and HAZCAM_FRAME heard,
// in order, until 2 s after the first STEREO_FRAME (or 90 s).
std::vector<Heard> CaptureOnce(const std::string& name, int offset, const std::string& config) {
  const std::string url = PrivateUrl(offset);
  const std::string world = SourceDir() + "/configs/worlds/flat_rock_course.yaml";
  const std::vector<std::string> env = {"ROVER_LCM_URL=" + url, "ROVER_TIME=real"};
  bus::Bus bus(url);
  std::vector<Heard> heard;
  std::optional<std::int64_t> truth_utime;
  bool capture_up = false;
  for (const char* channel : {channels::kStereoFrame, channels::kHazcamFrame}) {
    bus.Subscribe<rover_msgs::stereo_frame_t>(
        channel, [&heard, channel](const rover_msgs::stereo_frame_t& f) { heard.push_back({channel, f}); }, 10);
  }
  bus.Subscribe<rover_msgs::sim_truth_t>(channels::kSimTruth,
                                         [&](const rover_msgs::sim_truth_t& t) { truth_utime = t.utime; });
  bus.Subscribe<rover_msgs::heartbeat_t>(channels::kHeartbeat, [&](const rover_msgs::heartbeat_t& h) {
    if (h.process == "camera_capture") capture_up = true;
  });
  launch::ProcessSet set(std::string(ROVER_BINARY_DIR) + "/bin", OutDir(name), false);
  set.Start({"rover_sim", "rover_sim",
             {"--config", SourceDir() + "/configs/rover.yaml", "--world", world, "--start", "0,0,0", "--rate", "1"}},
            env);
  set.Start({"camera_capture", "camera_capture", {"--config", config, "--world", world}}, env);
  const auto start = Clock::now();
  while (!(capture_up && truth_utime) && Clock::now() - start < std::chrono::seconds(30)) bus.Handle(100);
  EXPECT_TRUE(capture_up && truth_utime) << "camera_capture or rover_sim not up within 30 s";
  if (!(capture_up && truth_utime)) return heard;
  rover_msgs::capture_request_t request{};
  request.utime = *truth_utime;
  request.frame_id = 5;
  request.purpose = "vo";
  bus.Publish(channels::kCaptureRequest, request);
  std::optional<Clock::time_point> first_frame;
  while (Clock::now() - start < std::chrono::seconds(90) &&
         !(first_frame && Clock::now() - *first_frame > std::chrono::seconds(2))) {
    bus.Handle(100);
    if (!first_frame) {
      for (const auto& h : heard)
        if (h.channel == channels::kStereoFrame) first_frame = Clock::now();
    }
  }
  EXPECT_TRUE(set.Running("camera_capture"));
  set.StopAll();
  return heard;
}

cv::Mat Decode(const rover_msgs::image_t& image) {
  return cv::imdecode(cv::Mat(1, static_cast<int>(image.data.size()), CV_8UC1, const_cast<std::uint8_t*>(image.data.data())),
                      cv::IMREAD_UNCHANGED);
}

// The shipped capture section with the HAZCAM pair turned on, as README "HAZCAM" says
// (whether or not configs/rover.yaml ships it on): the two rigs and the NAVCAM's render options of
// configs/rover.yaml, the HAZCAM at 256x256.
std::string HazcamOnConfig(const std::string& name) {
  const std::string config = OutDir(name) + "/capture.yaml";
  std::ofstream(config) << "capture:\n  source: sim\n  rig: " << SourceDir()
                        << "/configs/cameras/navcam_pinhole.yaml\n  render: {image_scale: 0.5}\n"
                        << "  hazcam:\n    rig: " << SourceDir() << "/configs/cameras/hazcam_front.yaml\n"
                        << "    render: {image_scale: 0.25}\n";
  return config;
}

TEST(CameraCaptureHazcam, ARequestGivesAHazcamFrameThenTheStereoFrameOfTheSameExposure) {
  const auto heard = CaptureOnce("camera_hazcam", 81, HazcamOnConfig("camera_hazcam_config"));
  ASSERT_EQ(heard.size(), 2u) << "expected one HAZCAM_FRAME and one STEREO_FRAME";
  ASSERT_EQ(heard[0].channel, channels::kHazcamFrame) << "the HAZCAM_FRAME must come first";
  ASSERT_EQ(heard[1].channel, channels::kStereoFrame);
  const rover_msgs::stereo_frame_t& hazcam = heard[0].frame;
  const rover_msgs::stereo_frame_t& navcam = heard[1].frame;
  // One exposure: the same request, instant and pose.
  EXPECT_EQ(hazcam.frame_id, 5);
  EXPECT_EQ(navcam.frame_id, 5);
  EXPECT_EQ(hazcam.purpose, "vo");
  EXPECT_EQ(hazcam.utime, navcam.utime);
  EXPECT_GT(hazcam.utime, 0);
  EXPECT_EQ(hazcam.left_utime, navcam.left_utime);
  EXPECT_EQ(hazcam.right_utime, navcam.right_utime);
  EXPECT_EQ(hazcam.pose_at_capture.utime, navcam.pose_at_capture.utime);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(hazcam.pose_at_capture.position[k], navcam.pose_at_capture.position[k]);
  // The HAZCAM models: the fish-eye CAHVORE rig scaled to 256x256; the NAVCAM's 512x512 pinholes.
  for (const auto* model : {&hazcam.left_model, &hazcam.right_model}) {
    EXPECT_EQ(model->type, "cahvore");
    EXPECT_EQ(model->width, 256);
    EXPECT_EQ(model->height, 256);
  }
  EXPECT_EQ(navcam.left_model.type, "pinhole");
  EXPECT_EQ(navcam.left_model.width, 512);
  // PNG images as the STEREO_FRAME's, of the ground (not blank): the pair is a real render.
  for (const auto* image : {&hazcam.left, &hazcam.right}) {
    EXPECT_EQ(image->encoding, +rover_msgs::image_t::ENCODING_PNG);  // (+: a value, not the static member)
    const cv::Mat pixels = Decode(*image);
    ASSERT_FALSE(pixels.empty());
    EXPECT_EQ(pixels.cols, 256);
    EXPECT_EQ(pixels.rows, 256);
    cv::Scalar mean, stddev;
    cv::meanStdDev(pixels, mean, stddev);
    EXPECT_GT(stddev[0], 5.0) << "a blank HAZCAM image";
  }
  // Not the NAVCAM's images: another view of the world.
  EXPECT_NE(hazcam.left.data, navcam.left.data);
}

TEST(CameraCaptureHazcam, WithoutTheHazcamSectionNoHazcamFrame) {
  const std::string dir = OutDir("camera_hazcam_none_config");
  const std::string config = dir + "/capture.yaml";
  std::ofstream(config) << "capture:\n  source: sim\n  rig: " << SourceDir()
                        << "/configs/cameras/navcam_pinhole.yaml\n  render: {image_scale: 0.25}\n";
  const auto heard = CaptureOnce("camera_hazcam_none", 82, config);
  ASSERT_EQ(heard.size(), 1u);
  EXPECT_EQ(heard[0].channel, channels::kStereoFrame);
  EXPECT_EQ(heard[0].frame.frame_id, 5);
  EXPECT_EQ(heard[0].frame.left_model.width, 256);
}

TEST(CameraCaptureHazcam, AHazcamWithASourceOtherThanSimIsRefusedAtStartInOneLine) {
  const std::string env = "ROVER_LCM_URL='" + PrivateUrl(83) + "' ";
  // A sim config with the HAZCAM on, and --dataset: a dataset has no HAZCAM images, so the
  // pair is left out with one line, and the dataset source starts (and stops at the missing
  // folder).
  const std::string sim = HazcamOnConfig("camera_hazcam_dataset");
  const auto r = RunCommand(env + "timeout 10 " + Bin("camera_capture") + " --config " + sim + " --dataset /nonexistent");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("camera_capture: " + sim + ": capture.hazcam ignored: the dataset source has no HAZCAM images"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("/nonexistent/image_0: no images"), std::string::npos) << r.output;
  // A configured dataset source with a HAZCAM rig is a contradiction in the file: refused.
  const std::string bad = OutDir("camera_hazcam_contradiction");
  std::ofstream(bad + "/capture.yaml") << "capture:\n  source: dataset\n  hazcam: {rig: h.yaml}\n";
  const auto refused = RunCommand(env + "timeout 10 " + Bin("camera_capture") + " --config " + bad +
                                  "/capture.yaml --dataset /nonexistent");
  EXPECT_EQ(refused.exit_code, 2) << refused.output;
  EXPECT_EQ(refused.output, bad + "/capture.yaml: capture.hazcam: expected no HAZCAM rig with source dataset (only the "
                            "sim source takes a HAZCAM pair; remove capture.hazcam)\n");
  // An empty rig is no HAZCAM: the same source starts (and stops at the missing directory).
  const std::string dir = OutDir("camera_hazcam_refused");
  std::ofstream(dir + "/capture.yaml") << "capture:\n  source: dataset\n  hazcam: {rig: \"\"}\n";
  const auto empty = RunCommand(env + "timeout 10 " + Bin("camera_capture") + " --config " + dir +
                                "/capture.yaml --dataset /nonexistent");
  EXPECT_EQ(empty.exit_code, 2) << empty.output;
  EXPECT_EQ(empty.output.find("capture.hazcam"), std::string::npos) << empty.output;
  EXPECT_NE(empty.output.find("/nonexistent/image_0: no images"), std::string::npos) << empty.output;
}

}  // namespace
}  // namespace rover::test
