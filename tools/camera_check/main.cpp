// camera_check: takes pairs from the real cameras of a capture config (capture.source
// genicam or gstreamer), with no bus and no other process, and says what it got: each
// pair's size, frame ids, left-right timestamp difference and capture time, or the
// capture's one-line error; optionally writes the images. For bringing cameras up
// (docs/HARDWARE.md). Exit 0 when every pair was taken, 1 when one failed, 2 on a bad
// argument or config.
#include "camera_hw/sources.hpp"
#include "config/yaml_config.hpp"
#include "geometry/camera_io.hpp"

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

using namespace rover;
namespace fs = std::filesystem;

namespace {

const char* kUsage =
    "usage: camera_check --config FILE [--pairs N] [--out DIR]\n\n"
    "Takes N (default 10) stereo pairs from the cameras of FILE's capture: section\n"
    "(source genicam or gstreamer) with no bus, prints one line per pair (sizes, frame ids,\n"
    "left-right timestamp difference, capture time) or its error, and a summary; with --out\n"
    "writes DIR/left_000.png, right_000.png, ... Exit 0: every pair taken; 1: a capture\n"
    "failed; 2: bad argument or config.\n";

struct BadArgument : std::runtime_error {
  using std::runtime_error::runtime_error;
};

int Run(int argc, char** argv) {
  std::string config_path, out;
  int pairs = 10;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw BadArgument("argument " + arg + ": missing value");
      return argv[++i];
    };
    if (arg == "--help" || arg == "-h") {
      std::cout << kUsage;
      return 0;
    } else if (arg == "--config") {
      config_path = value();
    } else if (arg == "--out") {
      out = value();
    } else if (arg == "--pairs") {
      const std::string v = value();
      char* end = nullptr;
      const long n = std::strtol(v.c_str(), &end, 10);
      if (end == v.c_str() || *end != '\0' || n < 1 || n > 100000) {
        throw BadArgument("argument --pairs: \"" + v + "\": expected an integer in [1, 100000]");
      }
      pairs = static_cast<int>(n);
    } else {
      throw BadArgument("argument " + arg + ": unknown option (expected one of the options in --help)");
    }
  }
  if (config_path.empty()) throw BadArgument("missing argument --config FILE (expected a config with a capture: section)");

  const auto root = config::ConfigNode::LoadFile(config_path);
  const auto capture = root["capture"];
  if (capture.IsNull()) root.Fail("missing capture: section");
  std::string source = "sim";
  capture.Get("source", source);
  if (source != "genicam" && source != "gstreamer") {
    capture["source"].Fail("expected genicam or gstreamer (camera_check takes pictures from real cameras), got \"" +
                           source + "\"");
  }
  // The rig, when given, says what size the images must be (as camera_capture checks).
  int rig_width = 0, rig_height = 0;
  if (capture.Has("rig")) {
    std::string rig_path = capture["rig"].AsString();
    if (!rig_path.empty() && rig_path[0] != '/') rig_path = (fs::path(config_path).parent_path() / rig_path).string();
    const auto rig = geometry::LoadStereoRigFile(rig_path);
    rig_width = rig.left->width();
    rig_height = rig.left->height();
  }
  auto cameras = source == "genicam"
                     ? camera_hw::MakeGenicamSource(camera_hw::GenicamOptions::Load(capture["genicam"]))
                     : camera_hw::MakeGstreamerSource(camera_hw::GstreamerOptions::Load(capture["gstreamer"]));
  if (!out.empty()) fs::create_directories(out);

  int taken = 0, failed = 0;
  double worst_dt_ms = 0;
  std::vector<double> times_ms;
  for (int i = 0; i < pairs; ++i) {
    const auto start = std::chrono::steady_clock::now();
    try {
      const auto pair = cameras->Capture();
      const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
      const double dt_ms = std::abs(static_cast<double>(pair.right.timestamp_ns - pair.left.timestamp_ns)) / 1e6;
      ++taken;
      times_ms.push_back(ms);
      worst_dt_ms = std::max(worst_dt_ms, dt_ms);
      std::printf("pair %d: %dx%d %d-bit, frames %llu/%llu, left-right %.3f ms, %d advances, capture %.1f ms\n", i,
                  pair.left.image.cols, pair.left.image.rows, pair.left.image.depth() == CV_16U ? 16 : 8,
                  static_cast<unsigned long long>(pair.left.frame_id),
                  static_cast<unsigned long long>(pair.right.frame_id), dt_ms, pair.advances, ms);
      if (rig_width > 0 && (pair.left.image.cols != rig_width || pair.left.image.rows != rig_height)) {
        std::printf("pair %d: images are %dx%d but the rig's camera models are %dx%d (capture.rig against the "
                    "region and binning)\n", i, pair.left.image.cols, pair.left.image.rows, rig_width, rig_height);
      }
      if (!out.empty()) {
        char name[32];
        std::snprintf(name, sizeof(name), "_%03d.png", i);
        cv::imwrite(out + "/left" + name, pair.left.image);
        cv::imwrite(out + "/right" + name, pair.right.image);
      }
    } catch (const camera_hw::CaptureError& e) {
      ++failed;
      const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
      std::printf("pair %d: failed after %.1f ms: %s\n", i, ms, e.what());
    }
    std::fflush(stdout);
  }
  std::sort(times_ms.begin(), times_ms.end());
  std::printf("%d pairs: %d taken, %d failed", pairs, taken, failed);
  if (!times_ms.empty()) {
    std::printf("; left-right at most %.3f ms; capture median %.1f ms, max %.1f ms", worst_dt_ms,
                times_ms[times_ms.size() / 2], times_ms.back());
  }
  std::printf("\n");
  return failed == 0 ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return Run(argc, argv);
  } catch (const BadArgument& e) {
    std::cerr << "camera_check: " << e.what() << "\n";
  } catch (const config::ConfigError& e) {
    std::cerr << e.what() << "\n";
  } catch (const camera_hw::CaptureError& e) {  // a pipeline that does not start
    std::cerr << "camera_check: " << e.what() << "\n";
  } catch (const std::exception& e) {
    std::cerr << "camera_check: " << e.what() << "\n";
  }
  return 2;
}
