#include "vo_eval/kitti_sequence.hpp"

#include "config/file_read.hpp"
#include "geometry/kitti_calib.hpp"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>

namespace rover::vo_eval {
namespace fs = std::filesystem;

namespace {

[[noreturn]] void Fail(const std::string& path, const std::string& message) {
  throw DatasetError(path + ": " + message);
}

// A FIFO or a device named like an image would block or never end in cv::imread.
void CheckImageFile(const std::string& path) {
  try {
    config::CheckRegularFile(path, config::kMaxImageFileBytes, "PNG image");
  } catch (const config::FileReadError& e) {
    throw DatasetError(e.what());
  }
}

std::vector<std::string> PngNames(const std::string& dir) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) Fail(dir, "expected a directory of PNG images, not found");
  std::vector<std::string> names;
  for (const fs::directory_entry& e : fs::directory_iterator(dir, ec)) {
    if (e.path().extension() == ".png") names.push_back(e.path().filename().string());
  }
  if (ec) Fail(dir, "cannot list directory: " + ec.message());
  std::sort(names.begin(), names.end());
  return names;
}

// Numbers of one line; returns false when a token is not a number.
bool ParseNumbers(const std::string& text, std::vector<double>* out) {
  std::istringstream in(text);
  std::string token;
  out->clear();
  while (in >> token) {
    try {
      std::size_t used = 0;
      const double v = std::stod(token, &used);
      if (used != token.size()) return false;
      out->push_back(v);
    } catch (const std::exception&) {
      return false;
    }
  }
  return true;
}

std::string Trimmed(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t\r\n");
  return s.substr(b, e - b + 1);
}

// The non-blank lines of a text file of numbers, each exactly `count` of them; `what`
// says what a line holds, for the one-line error.
std::vector<std::vector<double>> ReadNumberLines(const std::string& path, std::size_t count,
                                                 const std::string& what) {
  std::string content;
  try {  // a regular file of bounded size: a FIFO or a device is refused, not read
    content = config::ReadBoundedRegularFile(path, config::kMaxDatasetTextBytes, "text file");
  } catch (const config::FileReadError& e) {
    Fail(path, "expected " + what + " a line, " + e.problem());
  }
  std::istringstream in(content);
  std::vector<std::vector<double>> rows;
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (Trimmed(line).empty()) continue;
    std::vector<double> v;
    if (!ParseNumbers(line, &v) || v.size() != count) {
      Fail(path, "line " + std::to_string(line_no) + ": expected " + what);
    }
    rows.push_back(std::move(v));
  }
  return rows;
}

}  // namespace

PoseList ReadKittiPoses(const std::string& path) {
  PoseList poses;
  for (const std::vector<double>& v : ReadNumberLines(path, 12, "12 numbers (row-major 3x4 [R|t])")) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) T.matrix()(r, c) = v[static_cast<std::size_t>(4 * r + c)];
    }
    poses.push_back(T);
  }
  return poses;
}

void WriteKittiPoses(const std::string& path, const PoseList& poses) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (!f) Fail(path, "cannot write");
  for (const Eigen::Isometry3d& T : poses) {
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) {
        std::fprintf(f, "%e%s", T.matrix()(r, c), (r == 2 && c == 3) ? "\n" : " ");
      }
    }
  }
  if (std::fclose(f) != 0) Fail(path, "write failed");
}

KittiSequence OpenKittiSequence(const std::string& dir) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) {
    Fail(dir, "expected a KITTI-layout dataset directory (image_0/, image_1/, calib.txt, "
              "times.txt), not found");
  }
  KittiSequence seq;
  seq.dir = dir;
  const std::string left_dir = (fs::path(dir) / "image_0").string();
  const std::string right_dir = (fs::path(dir) / "image_1").string();
  const std::vector<std::string> left = PngNames(left_dir);
  const std::vector<std::string> right = PngNames(right_dir);
  if (left.size() < 2) {
    Fail(left_dir, "expected at least 2 PNG images, found " + std::to_string(left.size()));
  }
  if (left.size() != right.size()) {
    Fail(right_dir, "expected " + std::to_string(left.size()) + " PNG images like image_0/, found " +
                        std::to_string(right.size()));
  }
  for (std::size_t i = 0; i < left.size(); ++i) {
    if (left[i] != right[i]) {
      Fail(right_dir, "expected " + left[i] + " to pair with image_0/" + left[i] + ", found " +
                          right[i]);
    }
    seq.left_paths.push_back((fs::path(left_dir) / left[i]).string());
    seq.right_paths.push_back((fs::path(right_dir) / right[i]).string());
  }

  const std::string times_path = (fs::path(dir) / "times.txt").string();
  for (const std::vector<double>& v : ReadNumberLines(times_path, 1, "one number (seconds)")) {
    seq.times_s.push_back(v[0]);
  }
  if (seq.times_s.size() != left.size()) {
    Fail(times_path, "expected " + std::to_string(left.size()) + " timestamps (one per image), found " +
                         std::to_string(seq.times_s.size()));
  }
  const std::string poses_path = (fs::path(dir) / "poses.txt").string();
  if (fs::exists(poses_path, ec)) {
    seq.truth = ReadKittiPoses(poses_path);
    if (seq.truth.size() != left.size()) {
      Fail(poses_path, "expected " + std::to_string(left.size()) + " poses (one per image), found " +
                           std::to_string(seq.truth.size()));
    }
  }
  CheckImageFile(seq.left_paths[0]);
  const cv::Mat first = cv::imread(seq.left_paths[0], cv::IMREAD_GRAYSCALE);
  if (first.empty()) Fail(seq.left_paths[0], "expected a readable PNG image, cannot decode");
  seq.width = first.cols;
  seq.height = first.rows;
  seq.calib_path = (fs::path(dir) / "calib.txt").string();
  try {
    seq.rig = geometry::LoadKittiCalib(seq.calib_path, seq.width, seq.height);
  } catch (const std::exception& e) {
    throw DatasetError(e.what());  // already one line naming the file and line
  }
  return seq;
}

namespace {

cv::Mat LoadGray(const std::string& path, int width, int height) {
  CheckImageFile(path);
  const cv::Mat raw = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (raw.empty()) Fail(path, "expected a readable PNG image, cannot decode");
  if (raw.cols != width || raw.rows != height) {
    Fail(path, "expected " + std::to_string(width) + "x" + std::to_string(height) +
                   " like the first image, found " + std::to_string(raw.cols) + "x" +
                   std::to_string(raw.rows));
  }
  if (raw.depth() != CV_8U) Fail(path, "expected an 8-bit image");
  if (raw.channels() == 1) return raw;
  cv::Mat gray;
  cv::cvtColor(raw, gray, raw.channels() == 4 ? cv::COLOR_BGRA2GRAY : cv::COLOR_BGR2GRAY);
  return gray;
}

}  // namespace

StereoFrameImages LoadStereoFrame(const KittiSequence& sequence, int index) {
  if (index < 0 || index >= sequence.size()) {
    throw std::out_of_range("LoadStereoFrame: frame " + std::to_string(index) + " outside [0, " +
                            std::to_string(sequence.size()) + ")");
  }
  const auto i = static_cast<std::size_t>(index);
  StereoFrameImages images;
  images.left = LoadGray(sequence.left_paths[i], sequence.width, sequence.height);
  images.right = LoadGray(sequence.right_paths[i], sequence.width, sequence.height);
  return images;
}

}  // namespace rover::vo_eval
