// The hardware sources' options: defaults, every key, and one-line errors naming the key.
#include "camera_hw/camera_options.hpp"

#include <gtest/gtest.h>

#include <functional>

using namespace rover::camera_hw;
using rover::config::ConfigError;
using rover::config::ConfigNode;

namespace {

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

GenicamOptions Genicam(const std::string& yaml) {
  return GenicamOptions::Load(ConfigNode::FromString(yaml, "cams.yaml")["genicam"]);
}

GstreamerOptions Gst(const std::string& yaml) {
  return GstreamerOptions::Load(ConfigNode::FromString(yaml, "cams.yaml")["gstreamer"]);
}

}  // namespace

TEST(GenicamOptions, ReadsEveryKey) {
  const auto o = Genicam(
      "genicam:\n  left: {serial: GV01}\n  right: {device_id: Aravis-Fake-GV02}\n  pixel_format: Mono16\n"
      "  roi: {x: 8, y: 16, width: 640, height: 480}\n  binning: 2\n  exposure_us: auto\n  gain: 3.5\n"
      "  trigger: hardware\n  trigger_line: Line1\n  frame_rate_hz: 5\n  pairing_tolerance_ms: 0.5\n"
      "  timestamps: device\n  max_advances: 0\n  timeout_ms: 300\n  buffers: 8\n  fake_interface: true\n");
  EXPECT_EQ(o.left.serial, "GV01");
  EXPECT_EQ(o.right.device_id, "Aravis-Fake-GV02");
  EXPECT_EQ(o.left.Describe(), "serial GV01");
  EXPECT_EQ(o.right.Describe(), "device Aravis-Fake-GV02");
  EXPECT_EQ(o.pixel_format, "Mono16");
  EXPECT_EQ(o.roi_x, 8);
  EXPECT_EQ(o.roi_y, 16);
  EXPECT_EQ(o.roi_width, 640);
  EXPECT_EQ(o.roi_height, 480);
  EXPECT_EQ(o.binning, 2);
  EXPECT_TRUE(o.exposure_auto);
  EXPECT_FALSE(o.gain_auto);
  EXPECT_DOUBLE_EQ(o.gain, 3.5);
  EXPECT_EQ(o.trigger, "hardware");
  EXPECT_EQ(o.trigger_line, "Line1");
  EXPECT_DOUBLE_EQ(o.frame_rate_hz, 5.0);
  EXPECT_DOUBLE_EQ(o.pairing_tolerance_ms, 0.5);
  EXPECT_EQ(o.timestamps, "device");
  EXPECT_EQ(o.max_advances, 0);
  EXPECT_DOUBLE_EQ(o.timeout_ms, 300.0);
  EXPECT_EQ(o.buffers, 8);
  EXPECT_TRUE(o.fake_interface);
}

TEST(GenicamOptions, DefaultsAreFixedExposureSoftwareTriggerWholeSensor) {
  const auto o = Genicam("genicam:\n  left: {serial: A}\n  right: {serial: B}\n");
  EXPECT_EQ(o.pixel_format, "Mono8");
  EXPECT_EQ(o.roi_width, 0);
  EXPECT_EQ(o.binning, 1);
  EXPECT_FALSE(o.exposure_auto);
  EXPECT_DOUBLE_EQ(o.exposure_us, 10000.0);
  EXPECT_FALSE(o.gain_auto);
  EXPECT_EQ(o.trigger, "software");
  EXPECT_EQ(o.timestamps, "host");
  EXPECT_FALSE(o.fake_interface);
}

TEST(GenicamOptions, BadInputIsOneLineNamingFileAndKey) {
  EXPECT_EQ(ErrorOf([] { Genicam("genicam:\n  left: {serial: A}\n  right: {serial: B}\n  exposre_us: 5\n"); }),
            "cams.yaml: genicam.exposre_us: unknown key (expected one of: left, right, pixel_format, roi, binning, "
            "exposure_us, gain, trigger, trigger_line, frame_rate_hz, pairing_tolerance_ms, timestamps, max_advances, "
            "timeout_ms, buffers, fake_interface)");
  EXPECT_EQ(ErrorOf([] { Genicam("genicam:\n  left: {serial: A, device_id: B}\n  right: {serial: B}\n"); }),
            "cams.yaml: genicam.left: expected exactly one of serial: or device_id:");
  EXPECT_EQ(ErrorOf([] { Genicam("genicam:\n  left: {serial: A}\n"); }),
            "cams.yaml: genicam.right: missing (expected serial: or device_id: of the camera)");
  EXPECT_EQ(ErrorOf([] { Genicam("genicam:\n  left: {serial: A}\n  right: {serial: B}\n  roi: {x: 0, y: 0, width: 64}\n"); }),
            "cams.yaml: genicam.roi: missing height (expected x, y, width, height)");
  const std::string format = ErrorOf([] { Genicam("genicam:\n  left: {serial: A}\n  right: {serial: B}\n  pixel_format: RGB8\n"); });
  EXPECT_EQ(format.rfind("cams.yaml: genicam.pixel_format: ", 0), 0u) << format;
  const std::string gain = ErrorOf([] { Genicam("genicam:\n  left: {serial: A}\n  right: {serial: B}\n  gain: loud\n"); });
  EXPECT_EQ(gain.rfind("cams.yaml: genicam.gain: ", 0), 0u) << gain;
  EXPECT_EQ(ErrorOf([] { GenicamOptions::Load(ConfigNode::FromString("other: 1\n", "cams.yaml")["genicam"]); }),
            "cams.yaml: genicam: missing (expected the genicam cameras: left:, right: ...)");
  for (const auto& e : {format, gain}) EXPECT_EQ(e.find('\n'), std::string::npos);
}

TEST(GstreamerOptions, PipelinesMustEndInAnAppsink) {
  const auto o = Gst("gstreamer:\n  left: videotestsrc ! appsink\n  right: 'videotestsrc ! appsink name=s drop=true'\n"
                     "  pairing_tolerance_ms: 3\n");
  EXPECT_EQ(o.left_pipeline, "videotestsrc ! appsink");
  EXPECT_EQ(o.right_pipeline, "videotestsrc ! appsink name=s drop=true");
  EXPECT_DOUBLE_EQ(o.pairing_tolerance_ms, 3.0);
  EXPECT_EQ(ErrorOf([] { Gst("gstreamer:\n  left: videotestsrc ! appsink\n  right: videotestsrc ! fakesink\n"); }),
            "cams.yaml: gstreamer.right: expected a pipeline ending in appsink, got one ending in \"fakesink\"");
  EXPECT_EQ(ErrorOf([] { Gst("gstreamer:\n  left: videotestsrc ! appsinkx\n  right: videotestsrc ! appsink\n"); }),
            "cams.yaml: gstreamer.left: expected a pipeline ending in appsink, got one ending in \"appsinkx\"");
  EXPECT_EQ(ErrorOf([] { Gst("gstreamer:\n  left: videotestsrc ! appsink\n  rigth: x\n"); }).rfind(
                "cams.yaml: gstreamer.rigth: unknown key", 0),
            0u);
}

// The example configs in configs/cameras/ load (camera_capture reads the capture: section).
TEST(CameraHwOptions, ExampleConfigsLoad) {
  const std::string dir = std::string(ROVER_SOURCE_DIR) + "/configs/cameras/";
  const auto genicam = ConfigNode::LoadFile(dir + "capture_genicam.yaml")["capture"];
  EXPECT_EQ(genicam["source"].AsString(), "genicam");
  const auto g = GenicamOptions::Load(genicam["genicam"]);
  EXPECT_EQ(g.left.serial, "NAVL0001");
  EXPECT_EQ(g.roi_width, 1024);
  EXPECT_TRUE(g.exposure_auto);
  const auto gstreamer = ConfigNode::LoadFile(dir + "capture_gstreamer.yaml")["capture"];
  EXPECT_EQ(gstreamer["source"].AsString(), "gstreamer");
  const auto s = GstreamerOptions::Load(gstreamer["gstreamer"]);
  EXPECT_NE(s.left_pipeline.find("videotestsrc"), std::string::npos);
  EXPECT_DOUBLE_EQ(s.pairing_tolerance_ms, 34.0);
}
