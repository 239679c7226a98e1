// calib_check: the rectification error of a rig file on a stereo pair of a chessboard
// (tools/calib/rectification_check.hpp; ./rover calib check). Exit 0 when the RMS row error
// is within --max-rms, 1 when not, 2 on a bad argument or file.
#include "calib/arguments.hpp"
#include "calib/rectification_check.hpp"
#include "config/file_read.hpp"
#include "config/yaml_config.hpp"

#include <opencv2/imgcodecs.hpp>

#include <cstdio>
#include <iostream>

using namespace rover;

namespace {

const char* kUsage =
    "usage: calib_check --rig RIG.yaml --left LEFT.png --right RIGHT.png --board COLSxROWS [--max-rms PX]\n\n"
    "Finds the chessboard in both images (COLSxROWS inner corners, e.g. 9x6), rectifies the two\n"
    "sets of corners with the rig's pinhole models (OpenCV stereoRectify), and reports how many\n"
    "pixels apart in rows each corner's two images are: RMS, largest, and the signed mean (right\n"
    "minus left: a pitch between the cameras). Stereo matching needs rows within a fraction of\n"
    "a pixel. The images: the rig's cameras at the rig's size (region and binning), taken at once.\n"
    "  --max-rms PX   the RMS row error that passes (default 0.5)\n"
    "Exit code: 0 within --max-rms, 1 over it, 2 on a bad argument or file.\n";

using calib::BadArgument;

cv::Mat ReadGray(const std::string& path) {
  config::CheckRegularFile(path, config::kMaxImageFileBytes, "image");
  cv::Mat m = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (m.empty()) throw BadArgument(path + ": cannot read as an image (expected a gray PNG)");
  if (m.channels() != 1) throw BadArgument(path + ": " + std::to_string(m.channels()) + " channels (expected a gray image)");
  return m;
}

int Run(int argc, char** argv) {
  std::string rig_path, left_path, right_path;
  cv::Size board;
  double max_rms = 0.5;
  calib::Arguments args(argc, argv);
  while (args.Next()) {
    const std::string& arg = args.option();
    if (args.IsHelp()) {
      std::cout << kUsage;
      return 0;
    } else if (arg == "--rig") {
      rig_path = args.Value();
    } else if (arg == "--left") {
      left_path = args.Value();
    } else if (arg == "--right") {
      right_path = args.Value();
    } else if (arg == "--board") {
      args.Size(2, "COLSxROWS inner corners, e.g. 9x6", &board.width, &board.height);
    } else if (arg == "--max-rms") {
      const std::string v = args.Value();
      char* end = nullptr;
      max_rms = std::strtod(v.c_str(), &end);
      if (end == v.c_str() || *end != '\0' || !(max_rms > 0)) {
        throw BadArgument("argument --max-rms: \"" + v + "\": expected a number of pixels > 0");
      }
    } else {
      throw args.Unknown();
    }
  }
  if (rig_path.empty() || left_path.empty() || right_path.empty() || board.width == 0) {
    throw BadArgument("missing argument (expected --rig, --left, --right and --board; see --help)");
  }
  const auto rig = geometry::LoadStereoRigFile(rig_path);
  const cv::Mat left = ReadGray(left_path), right = ReadGray(right_path);
  for (const auto& [image, model, path] : {std::tuple{&left, rig.left.get(), left_path},
                                           std::tuple{&right, rig.right.get(), right_path}}) {
    if (image->cols != model->width() || image->rows != model->height()) {
      throw BadArgument(path + ": " + std::to_string(image->cols) + "x" + std::to_string(image->rows) +
                        " (expected " + std::to_string(model->width()) + "x" + std::to_string(model->height()) +
                        ", its camera model's size in " + rig_path + ")");
    }
  }
  const auto left_corners = calib::FindChessboardCorners(left, board, left_path);
  const auto right_corners = calib::FindChessboardCorners(right, board, right_path);
  const auto e = calib::RowErrorAfterRectification(rig, left_corners, right_corners);
  char line[256];
  std::snprintf(line, sizeof(line),
                "rectification error: rms %.3f px, max %.3f px, mean %+.3f px (right row - left row) over %d corners",
                e.rms_px, e.max_px, e.mean_px, e.corners);
  std::cout << line << "\n";
  const bool ok = e.rms_px <= max_rms;
  std::snprintf(line, sizeof(line), "calib check: %s (rms %s %.2f px)", ok ? "PASS" : "FAIL", ok ? "within" : "over",
                max_rms);
  std::cout << line << "\n";
  return ok ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return Run(argc, argv);
  } catch (const std::exception& e) {
    // Bad arguments, files (ConfigError names the file and key), a board not found.
    std::cerr << "calib_check: " << e.what() << "\n";
    return 2;
  }
}
