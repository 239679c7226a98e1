// camera_capture with a hardware source (README "Camera hardware"): the gstreamer source
// on GStreamer's test pattern publishes STEREO_FRAMEs on request, and a bad hardware
// config is one line and exit 2. (The genicam source's own tests, on Aravis's fake
// cameras, are in common/camera_hw/test/.)
#include "bus/bus.hpp"
#include "bus/channels.hpp"
#include "camera_hw/sources.hpp"
#include "integration/run_support.hpp"
#include "launch/process_set.hpp"

#include <rover_msgs/capture_request_t.hpp>
#include <rover_msgs/stereo_frame_t.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <iterator>
#include <optional>

namespace rover::test {
namespace {

TEST(CameraCaptureHardware, GstreamerSourcePublishesRequestedPairs) {
  if (!camera_hw::GstreamerAvailable()) GTEST_SKIP() << "built without GStreamer (libgstreamer1.0-dev)";
  const std::string dir = OutDir("camera_hw_gstreamer");
  const std::string url = PrivateUrl(11);
  bus::Bus bus(url);
  std::optional<rover_msgs::stereo_frame_t> frame;
  bus.Subscribe<rover_msgs::stereo_frame_t>(channels::kStereoFrame,
                                            [&](const rover_msgs::stereo_frame_t& f) { frame = f; });
  launch::ProcessSet set(std::string(ROVER_BINARY_DIR) + "/bin", dir, false);
  // The example config: two live 1024x1024 test-pattern pipelines and the NAVCAM rig.
  set.Start({"camera_capture", "camera_capture", {"--config", SourceDir() + "/configs/cameras/capture_gstreamer.yaml"}},
            {"ROVER_LCM_URL=" + url});
  rover_msgs::capture_request_t request{};
  request.frame_id = 7;
  request.purpose = "vo";
  const auto start = std::chrono::steady_clock::now();
  // Asked again every second until camera_capture has subscribed and answered.
  auto next_request = start;
  while (!frame && std::chrono::steady_clock::now() - start < std::chrono::seconds(30)) {
    if (std::chrono::steady_clock::now() >= next_request) {
      bus.Publish(channels::kCaptureRequest, request);
      next_request += std::chrono::seconds(1);
    }
    bus.Handle(100);
  }
  ASSERT_TRUE(frame.has_value()) << "no STEREO_FRAME within 30 s";
  EXPECT_EQ(frame->frame_id, 7);
  EXPECT_EQ(frame->purpose, "vo");
  for (const auto* image : {&frame->left, &frame->right}) {
    EXPECT_EQ(image->width, 1024);
    EXPECT_EQ(image->height, 1024);
    EXPECT_EQ(image->encoding, +rover_msgs::image_t::ENCODING_PNG);  // (+: a value, not the header's static member)
    EXPECT_GT(image->size, 0);
  }
  EXPECT_EQ(frame->left_model.width, 1024);  // the rig file's models travel with the pair
  EXPECT_TRUE(set.Running("camera_capture"));
  set.StopAll();
}

TEST(CameraCaptureHardware, ImagesOfAnotherSizeThanTheRigAreRefusedInOneLine) {
  if (!camera_hw::GstreamerAvailable()) GTEST_SKIP() << "built without GStreamer (libgstreamer1.0-dev)";
  const std::string dir = OutDir("camera_hw_rig_size");
  const std::string config = dir + "/small.yaml";
  // 64x48 images against the 1024x1024 NAVCAM models.
  const std::string pipeline = "videotestsrc ! video/x-raw,format=GRAY8,width=64,height=48,framerate=10/1 ! appsink";
  std::ofstream(config) << "capture:\n  source: gstreamer\n  rig: " << SourceDir()
                        << "/configs/cameras/navcam_pinhole.yaml\n  gstreamer:\n    left: \"" << pipeline
                        << "\"\n    right: \"" << pipeline << "\"\n";
  const std::string url = PrivateUrl(12);
  bus::Bus bus(url);
  int frames = 0;
  bus.Subscribe<rover_msgs::stereo_frame_t>(channels::kStereoFrame, [&](const rover_msgs::stereo_frame_t&) { ++frames; });
  {
    launch::ProcessSet set(std::string(ROVER_BINARY_DIR) + "/bin", dir, false);
    set.Start({"camera_capture", "camera_capture", {"--config", config}}, {"ROVER_LCM_URL=" + url});
    rover_msgs::capture_request_t request{};
    request.frame_id = 1;
    request.purpose = "vo";
    for (int i = 0; i < 5; ++i) {
      bus.Publish(channels::kCaptureRequest, request);
      bus.Handle(1000);
    }
    EXPECT_TRUE(set.Running("camera_capture"));  // a refused pair is not a crash
    set.StopAll();
  }
  EXPECT_EQ(frames, 0);
  std::ifstream log(dir + "/camera_capture.log");
  const std::string text((std::istreambuf_iterator<char>(log)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("camera_capture: capture failed, no frame sent: left image is 64x48 but its camera model is "
                      "1024x1024 (capture.rig against the region and binning)"),
            std::string::npos)
      << text;
}

TEST(CameraCaptureHardware, BadHardwareConfigIsOneLineAndExitTwo) {
  const std::string dir = OutDir("camera_hw_bad_config");
  const std::string bad = dir + "/bad.yaml";
  std::ofstream(bad) << "capture:\n  source: genicam\n  rig: " << SourceDir()
                     << "/configs/cameras/navcam_pinhole.yaml\n  genicam:\n    left: {serial: A}\n"
                        "    right: {serial: B}\n    exposre_us: 100\n";
  auto r = RunCommand(Bin("camera_capture") + " --config " + bad);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.output.rfind(bad + ": capture.genicam.exposre_us: unknown key (expected one of: left, right, ", 0), 0u)
      << r.output;
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;

  std::ofstream(bad) << "capture:\n  source: gstreamer\n  gstreamer:\n    left: videotestsrc ! fakesink\n"
                        "    right: videotestsrc ! appsink\n";
  r = RunCommand(Bin("camera_capture") + " --config " + bad);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.output, bad + ": capture.gstreamer.left: expected a pipeline ending in appsink, got one ending in "
                            "\"fakesink\"\n");
}

TEST(CameraTools, CameraCheckTakesPairsWithNoBus) {
  if (!camera_hw::GstreamerAvailable()) GTEST_SKIP() << "built without GStreamer (libgstreamer1.0-dev)";
  const std::string dir = OutDir("camera_check");
  auto r = RunCommand(Bin("camera_check") + " --config configs/cameras/capture_gstreamer.yaml --pairs 3 --out " + dir);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("pair 0: 1024x1024 8-bit, frames 0/0, left-right "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("3 pairs: 3 taken, 0 failed; left-right at most "), std::string::npos) << r.output;
  for (const char* name : {"/left_000.png", "/right_002.png"}) {
    EXPECT_TRUE(std::ifstream(dir + name).good()) << name;
  }
  r = RunCommand(Bin("camera_check") + " --config configs/rover.yaml");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.output, "configs/rover.yaml: capture.source: expected genicam or gstreamer (camera_check takes pictures "
                      "from real cameras), got \"sim\"\n");
  r = RunCommand(Bin("camera_check") + " --config configs/cameras/capture_gstreamer.yaml --pairs 0");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.output, "camera_check: argument --pairs: \"0\": expected an integer in [1, 100000]\n");
}

TEST(CameraTools, CalibImportArgumentsAreOneLine) {
  auto r = RunCommand(Bin("calib_import") + " --opencv x.yaml --left-rpy 0,0,0 --out /dev/null");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.output, "calib_import: missing argument --left-position X,Y,Z (the left camera's centre, rover frame, m)\n");
  r = RunCommand(Bin("calib_import") + " --opencv /nonexistent.yaml --left-position 0,0,0 --left-rpy 0,0 --out /dev/null");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.output, "calib_import: argument --left-rpy: \"0,0\": expected 3 finite numbers separated by commas\n");
  r = RunCommand(Bin("calib_import") + " --opencv /nonexistent.yaml --left-position 0,0,0 --left-rpy 0,0,0 --out /dev/null");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
  EXPECT_EQ(r.output.rfind("/nonexistent.yaml: ", 0), 0u) << r.output;
}

}  // namespace
}  // namespace rover::test
