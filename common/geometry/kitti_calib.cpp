#include "geometry/kitti_calib.hpp"

#include "config/file_read.hpp"
#include "geometry/pinhole_camera.hpp"

#include <array>
#include <cmath>
#include <fstream>
#include <optional>
#include <sstream>
#include <stdexcept>

namespace rover::geometry {

namespace {

using Row = std::array<double, 12>;

[[noreturn]] void Fail(const std::string& path, int line, const std::string& message) {
  throw std::runtime_error(path + ":" + std::to_string(line) + ": " + message);
}

bool ParseNumber(const std::string& token, double& value) {
  try {
    std::size_t used = 0;
    value = std::stod(token, &used);
    return used == token.size() && std::isfinite(value);
  } catch (const std::exception&) {
    return false;
  }
}

}  // namespace

StereoRig LoadKittiCalib(const std::string& path, int image_width, int image_height) {
  if (image_width <= 0 || image_height <= 0) {
    throw std::invalid_argument("LoadKittiCalib: image size " + std::to_string(image_width) +
                                "x" + std::to_string(image_height) + " (expected both > 0)");
  }
  std::string content;
  try {  // a regular file of bounded size: a FIFO or a device is refused, not read
    content = config::ReadBoundedRegularFile(path, config::kMaxDatasetTextBytes, "KITTI calib.txt");
  } catch (const config::FileReadError& e) {
    throw std::runtime_error(path + ":0: " + e.problem() + " (expected " + e.expected() + ")");
  }
  std::istringstream in(content);
  std::optional<Row> P[2];
  int line_of[2] = {0, 0};
  std::string text;
  int line_no = 0;
  while (std::getline(in, text)) {
    ++line_no;
    if (!text.empty() && text.back() == '\r') text.pop_back();
    std::istringstream ls(text);
    std::string label;
    if (!(ls >> label)) continue;  // blank line
    if (label.back() != ':') {
      Fail(path, line_no, "\"" + label + "\" is not a label (expected \"P0:\", \"P1:\", ...)");
    }
    const int which = label == "P0:" ? 0 : label == "P1:" ? 1 : -1;
    if (which < 0) continue;
    if (P[which]) Fail(path, line_no, label + " given twice (expected it once)");
    Row row;
    std::string token;
    int count = 0;
    while (ls >> token) {
      double value = 0;
      if (!ParseNumber(token, value)) {
        std::ostringstream msg;
        msg << label << " entry " << count + 1 << " is \"" << token << "\" (expected a number)";
        Fail(path, line_no, msg.str());
      }
      if (count < 12) row[count] = value;
      ++count;
    }
    if (count != 12) {
      std::ostringstream msg;
      msg << label << " has " << count << " numbers (expected 12, a row-major 3x4 projection matrix)";
      Fail(path, line_no, msg.str());
    }
    P[which] = row;
    line_of[which] = line_no;
  }
  for (int i = 0; i < 2; ++i) {
    if (!P[i]) {
      std::ostringstream msg;
      msg << "no P" << i << ": line (expected \"P" << i << ": \" and 12 numbers)";
      Fail(path, line_no, msg.str());
    }
  }
  for (int i = 0; i < 2; ++i) {
    const Row& p = *P[i];
    // Rectified: [fx 0 cx tx; 0 fy cy 0; 0 0 1 0].
    const bool rectified = p[0] > 0 && p[5] > 0 && p[1] == 0 && p[4] == 0 && p[7] == 0 &&
                           p[8] == 0 && p[9] == 0 && p[10] == 1 && p[11] == 0 &&
                           (i == 1 || p[3] == 0);
    if (!rectified) {
      std::ostringstream msg;
      msg << "P" << i << " is not a rectified projection (expected [fx 0 cx "
          << (i == 0 ? "0" : "-fx*b") << "; 0 fy cy 0; 0 0 1 0] with fx, fy > 0)";
      Fail(path, line_of[i], msg.str());
    }
  }
  const Row& p0 = *P[0];
  const Row& p1 = *P[1];
  const double baseline = -p1[3] / p1[0];
  if (!(baseline > 0)) {
    Fail(path, line_of[1], "baseline -P1[3]/P1[0] = " + std::to_string(baseline) +
                               " m (expected > 0: the right camera at +x)");
  }
  Eigen::Isometry3d T_left_right = Eigen::Isometry3d::Identity();
  T_left_right.translation() = Eigen::Vector3d(baseline, 0, 0);
  StereoRig rig;
  rig.left = std::make_shared<PinholeCamera>(image_width, image_height, p0[0], p0[5], p0[2],
                                             p0[6]);
  rig.right = std::make_shared<PinholeCamera>(image_width, image_height, p1[0], p1[5], p1[2],
                                              p1[6], std::vector<double>{}, T_left_right);
  return rig;
}

}  // namespace rover::geometry
