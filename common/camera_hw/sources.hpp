// The hardware sources. Each is built only when its library was found at configure time
// (Aravis: libaravis-dev; GStreamer: libgstreamer1.0-dev, libgstreamer-plugins-base1.0-dev);
// otherwise its Make* throws CaptureError saying which package is missing.
#pragma once

#include "camera_hw/camera_options.hpp"
#include "camera_hw/stereo_source.hpp"

#include <memory>

namespace rover::camera_hw {

bool GenicamAvailable();
bool GstreamerAvailable();

// Opens nothing yet: the cameras are opened by the first Capture(), and again after one
// vanished, so a process may start before its cameras are powered.
std::unique_ptr<StereoSource> MakeGenicamSource(const GenicamOptions& options);
// Builds and starts both pipelines; a pipeline that does not parse is a CaptureError. One
// that parses but cannot start (its camera absent) is started again at each Capture().
std::unique_ptr<StereoSource> MakeGstreamerSource(const GstreamerOptions& options);

}  // namespace rover::camera_hw
