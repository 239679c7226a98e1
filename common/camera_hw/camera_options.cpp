#include "camera_hw/camera_options.hpp"

#include <cctype>

namespace rover::camera_hw {

namespace {

CameraId LoadCameraId(const config::ConfigNode& node) {
  if (node.IsNull()) node.Fail("missing (expected serial: or device_id: of the camera)");
  node.CheckKeys({"serial", "device_id"});
  CameraId id;
  node.Get("serial", id.serial);
  node.Get("device_id", id.device_id);
  if (id.serial.empty() == id.device_id.empty()) {
    node.Fail("expected exactly one of serial: or device_id:");
  }
  return id;
}

// `key: auto` or a number in [lo, hi].
void GetAutoOrNumber(const config::ConfigNode& node, const std::string& key, bool& is_auto,
                     double& value, double lo, double hi) {
  if (!node.Has(key)) return;
  const auto child = node[key];
  if (child.yaml().IsScalar() && child.yaml().Scalar() == "auto") {
    is_auto = true;
    return;
  }
  is_auto = false;
  value = child.AsDouble(lo, hi);
}

std::string Trim(const std::string& s) {
  std::size_t a = 0, b = s.size();
  while (a < b && std::isspace(static_cast<unsigned char>(s[a]))) ++a;
  while (b > a && std::isspace(static_cast<unsigned char>(s[b - 1]))) --b;
  return s.substr(a, b - a);
}

std::string LoadPipeline(const config::ConfigNode& node, const std::string& key) {
  std::string pipeline = Trim(node.RequireString(key));
  // The frames are pulled from the pipeline's last element; anything after the appsink
  // would never be read.
  const std::size_t bang = pipeline.rfind('!');
  const std::string last = Trim(bang == std::string::npos ? pipeline : pipeline.substr(bang + 1));
  if (last.rfind("appsink", 0) != 0 || (last.size() > 7 && !std::isspace(static_cast<unsigned char>(last[7])))) {
    node[key].Fail("expected a pipeline ending in appsink, got one ending in \"" + last + "\"");
  }
  return pipeline;
}

}  // namespace

std::string CameraId::Describe() const {
  return serial.empty() ? "device " + device_id : "serial " + serial;
}

GenicamOptions GenicamOptions::Load(const config::ConfigNode& node) {
  if (node.IsNull()) node.Fail("missing (expected the genicam cameras: left:, right: ...)");
  node.CheckKeys({"left", "right", "pixel_format", "roi", "binning", "exposure_us", "gain", "trigger",
                  "trigger_line", "frame_rate_hz", "pairing_tolerance_ms", "timestamps", "max_advances",
                  "timeout_ms", "buffers", "fake_interface"});
  GenicamOptions o;
  o.left = LoadCameraId(node["left"]);
  o.right = LoadCameraId(node["right"]);
  node.GetEnum("pixel_format", o.pixel_format, {"Mono8", "Mono16"});
  if (node.Has("roi")) {
    const auto roi = node["roi"];
    roi.CheckKeys({"x", "y", "width", "height"});
    roi.Get("x", o.roi_x, 0, 65535);
    roi.Get("y", o.roi_y, 0, 65535);
    for (const char* key : {"width", "height"}) {
      if (!roi.Has(key)) roi.Fail(std::string("missing ") + key + " (expected x, y, width, height)");
    }
    roi.Get("width", o.roi_width, 1, 65535);
    roi.Get("height", o.roi_height, 1, 65535);
  }
  node.Get("binning", o.binning, 1, 16);
  GetAutoOrNumber(node, "exposure_us", o.exposure_auto, o.exposure_us, 1.0, 10e6);
  GetAutoOrNumber(node, "gain", o.gain_auto, o.gain, 0.0, 1000.0);
  node.GetEnum("trigger", o.trigger, {"software", "hardware", "free"});
  node.Get("trigger_line", o.trigger_line);
  node.Get("frame_rate_hz", o.frame_rate_hz, 0.01, 1000.0);
  node.Get("pairing_tolerance_ms", o.pairing_tolerance_ms, 0.0, 10000.0);
  node.GetEnum("timestamps", o.timestamps, {"device", "host"});
  node.Get("max_advances", o.max_advances, 0, 100);
  node.Get("timeout_ms", o.timeout_ms, 1.0, 600000.0);
  node.Get("buffers", o.buffers, 2, 64);
  node.Get("fake_interface", o.fake_interface);
  return o;
}

GstreamerOptions GstreamerOptions::Load(const config::ConfigNode& node) {
  if (node.IsNull()) node.Fail("missing (expected left: and right: pipelines)");
  node.CheckKeys({"left", "right", "pairing_tolerance_ms", "max_advances", "timeout_ms"});
  GstreamerOptions o;
  o.left_pipeline = LoadPipeline(node, "left");
  o.right_pipeline = LoadPipeline(node, "right");
  node.Get("pairing_tolerance_ms", o.pairing_tolerance_ms, 0.0, 10000.0);
  node.Get("max_advances", o.max_advances, 0, 1000);
  node.Get("timeout_ms", o.timeout_ms, 1.0, 600000.0);
  return o;
}

}  // namespace rover::camera_hw
