// Stand-ins for the sources whose library was not found at configure time (see
// CMakeLists.txt): asking for one says which Debian package to install.
#include "camera_hw/sources.hpp"

namespace rover::camera_hw {

#ifndef ROVER_HAVE_ARAVIS
bool GenicamAvailable() { return false; }
std::unique_ptr<StereoSource> MakeGenicamSource(const GenicamOptions&) {
  throw CaptureError("genicam: this build has no Aravis (install libaravis-dev and rebuild)");
}
#endif

#ifndef ROVER_HAVE_GSTREAMER
bool GstreamerAvailable() { return false; }
std::unique_ptr<StereoSource> MakeGstreamerSource(const GstreamerOptions&) {
  throw CaptureError("gstreamer: this build has no GStreamer (install libgstreamer1.0-dev "
                     "libgstreamer-plugins-base1.0-dev and rebuild)");
}
#endif

}  // namespace rover::camera_hw
