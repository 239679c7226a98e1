// Options of the hardware sources, each one plain struct loaded from a YAML section
// (capture.genicam, capture.gstreamer). Unknown keys and bad values are one ConfigError
// line naming the file and the key (config/yaml_config.hpp). docs/HARDWARE.md explains
// every key; configs/cameras/genicam_pair.yaml is an example.
#pragma once

#include "config/yaml_config.hpp"

#include <string>

namespace rover::camera_hw {

// Which physical camera: by serial number (printed on the camera, stable), or by Aravis
// device id ("Vendor-Model-Serial", or a GigE camera's IP address). Exactly one is set.
struct CameraId {
  std::string serial;
  std::string device_id;
  std::string Describe() const;  // "serial GV01" or "device Fake_1", for messages
};

struct GenicamOptions {
  CameraId left, right;
  std::string pixel_format = "Mono8";  // Mono8 | Mono16
  // Region of interest on the sensor, in binned pixels; width 0 takes the whole sensor.
  int roi_x = 0, roi_y = 0, roi_width = 0, roi_height = 0;
  int binning = 1;  // the same horizontally and vertically
  // Exposure and gain, fixed or auto. Auto runs on the left camera only and its value is
  // copied to the right before each pair, so the pair always shares one exposure and one
  // gain (VO matches the two images' brightness).
  bool exposure_auto = false;
  double exposure_us = 10000.0;
  bool gain_auto = false;
  double gain = 0.0;
  // software: both cameras are triggered back to back for each pair; hardware: both wait
  // for one pulse on trigger_line (wired to both: the pair is exposed at the same instant);
  // free: free-running at frame_rate_hz, the newest agreeing pair is taken.
  std::string trigger = "software";
  std::string trigger_line = "Line0";
  double frame_rate_hz = 10.0;
  // A pair is accepted only when the two buffer timestamps agree within this.
  double pairing_tolerance_ms = 2.0;
  // device: the cameras' own timestamps (comparable only when their clocks are
  // synchronised, PTP/IEEE 1588, or for cameras sharing one clock); host: when each buffer
  // arrived on this computer (always comparable, but includes transfer jitter).
  std::string timestamps = "host";
  int max_advances = 2;     // free-running: older frames skipped before a pair is rejected
  double timeout_ms = 2000; // one capture's whole budget, triggers and transfers included
  int buffers = 4;          // stream buffers per camera
  bool fake_interface = false;  // also search Aravis's in-process Fake interface (tests)

  static GenicamOptions Load(const config::ConfigNode& node);
};

struct GstreamerOptions {
  // One gst-launch pipeline per camera, each ending in an appsink that delivers GRAY8 or
  // GRAY16_LE, e.g. "v4l2src device=/dev/video0 ! videoconvert ! video/x-raw,format=GRAY8
  // ! appsink max-buffers=1 drop=true".
  std::string left_pipeline, right_pipeline;
  double pairing_tolerance_ms = 5.0;
  int max_advances = 5;
  double timeout_ms = 2000;

  static GstreamerOptions Load(const config::ConfigNode& node);
};

}  // namespace rover::camera_hw
