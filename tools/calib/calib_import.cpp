#include "calib/calib_import.hpp"

#include "config/file_read.hpp"
#include "config/yaml_config.hpp"
#include "geometry/camera_io.hpp"
#include "geometry/pose.hpp"

#include <opencv2/core.hpp>

#include <cmath>
#include <cstdio>
#include <sstream>

namespace rover::calib {

namespace {

using config::ConfigError;

// 15 significant digits: far below any calibration's uncertainty, and 0.2 stays "0.2".
std::string Num(double v) {
  char text[40];
  std::snprintf(text, sizeof(text), "%.15g", v);
  return text;
}

// For messages: short, and still exact for the numbers people type.
std::string Short(double v) {
  char text[40];
  std::snprintf(text, sizeof(text), "%.10g", v);
  return text;
}

void CheckIntrinsics(const Intrinsics& in, const std::string& where) {
  if (!(in.fx > 0) || !(in.fy > 0) || !std::isfinite(in.cx) || !std::isfinite(in.cy)) {
    throw ConfigError(where + ": expected positive focal lengths and a finite principal point");
  }
  for (double d : in.distortion) {
    if (!std::isfinite(d)) throw ConfigError(where + ": distortion: expected finite numbers");
  }
}

// ---- OpenCV FileStorage ----

// A matrix stored under `key` (or `alternative`), of rows x cols; throws naming the key.
cv::Mat ReadMat(const cv::FileStorage& fs, const std::string& path, const std::string& key,
                const std::string& alternative, int rows, int cols, const std::string& what) {
  cv::FileNode node = fs[key];
  std::string name = key;
  if (node.empty() && !alternative.empty()) {
    node = fs[alternative];
    name = alternative;
  }
  const std::string expected = what + " as " + key + (alternative.empty() ? "" : " or " + alternative) + ", a " +
                               std::to_string(rows) + "x" + std::to_string(cols) + " opencv-matrix";
  if (node.empty()) throw ConfigError(path + ": " + key + ": missing (expected " + expected + ")");
  cv::Mat m;
  try {
    node >> m;
  } catch (const cv::Exception&) {
    m.release();
  }
  if (m.empty() || m.channels() != 1) throw ConfigError(path + ": " + name + ": expected " + expected);
  m.convertTo(m, CV_64F);
  if (rows > 0 && m.total() == static_cast<std::size_t>(rows * cols)) m = m.reshape(1, rows);
  if (m.rows != rows || m.cols != cols) {
    throw ConfigError(path + ": " + name + ": expected " + expected + ", got " + std::to_string(m.rows) + "x" +
                      std::to_string(m.cols));
  }
  for (int r = 0; r < m.rows; ++r) {
    for (int c = 0; c < m.cols; ++c) {
      if (!std::isfinite(m.at<double>(r, c))) throw ConfigError(path + ": " + name + ": expected finite numbers");
    }
  }
  return m;
}

std::vector<double> ReadDistortion(const cv::FileStorage& fs, const std::string& path, const std::string& key) {
  cv::FileNode node = fs[key];
  if (node.empty()) return {};  // no distortion recorded: an ideal pinhole
  cv::Mat m;
  try {
    node >> m;
  } catch (const cv::Exception&) {
    m.release();
  }
  m.convertTo(m, CV_64F);
  const std::size_t n = m.total();
  if (m.empty() || m.channels() != 1 || (n != 4 && n != 5 && n != 8 && n != 12 && n != 14)) {
    throw ConfigError(path + ": " + key + ": expected an opencv-matrix of 4 or 5 distortion coefficients (k1 k2 p1 p2 [k3])");
  }
  std::vector<double> d(m.begin<double>(), m.end<double>());
  // OpenCV's rational and thin-prism models add terms the project's pinhole model does not
  // have: accepted only when those terms are zero.
  for (std::size_t i = 5; i < d.size(); ++i) {
    if (d[i] != 0.0) {
      throw ConfigError(path + ": " + key + ": coefficient " + std::to_string(i + 1) + " of " + std::to_string(n) +
                        " is " + Short(d[i]) + " (expected k1 k2 p1 p2 [k3] only: the rational and thin-prism "
                        "terms are not in the project's pinhole model)");
    }
  }
  if (d.size() > 5) d.resize(5);
  return d;
}

Intrinsics FromK(const cv::Mat& K, const std::string& path, const std::string& key) {
  if (std::abs(K.at<double>(0, 1)) > 1e-9 * std::abs(K.at<double>(0, 0)) || K.at<double>(1, 0) != 0.0 ||
      K.at<double>(2, 0) != 0.0 || K.at<double>(2, 1) != 0.0 || K.at<double>(2, 2) != 1.0) {
    throw ConfigError(path + ": " + key + ": expected [fx 0 cx; 0 fy cy; 0 0 1] (no skew)");
  }
  Intrinsics in;
  in.fx = K.at<double>(0, 0);
  in.fy = K.at<double>(1, 1);
  in.cx = K.at<double>(0, 2);
  in.cy = K.at<double>(1, 2);
  return in;
}

// ---- ROS camera_info ----

std::vector<double> RosMatrix(const config::ConfigNode& root, const std::string& key, int rows, int cols) {
  const auto node = root[key];
  if (node.IsNull()) root.Fail("missing " + key);
  node.CheckKeys({"rows", "cols", "data"});
  int r = 0, c = 0;
  node.Get("rows", r, 0, 100);
  node.Get("cols", c, 0, 100);
  std::vector<double> data = node.RequireVector("data");
  if (rows > 0 && (r != rows || c != cols || static_cast<int>(data.size()) != rows * cols)) {
    node.Fail("expected a " + std::to_string(rows) + "x" + std::to_string(cols) + " matrix (rows: " +
              std::to_string(rows) + ", cols: " + std::to_string(cols) + ", " + std::to_string(rows * cols) +
              " numbers in data), got rows " + std::to_string(r) + ", cols " + std::to_string(c) + " and " +
              std::to_string(data.size()) + " numbers");
  }
  if (rows == 0 && static_cast<int>(data.size()) != r * c) {
    node.Fail("rows x cols is " + std::to_string(r * c) + " but data has " + std::to_string(data.size()) + " numbers");
  }
  return data;
}

struct RosCamera {
  Intrinsics intrinsics;
  Eigen::Matrix3d rectification;
  Eigen::Matrix<double, 3, 4> projection;
};

RosCamera LoadRosCamera(const std::string& path) {
  const auto root = config::ConfigNode::LoadFile(path);
  root.CheckKeys({"image_width", "image_height", "camera_name", "camera_matrix", "distortion_model",
                  "distortion_coefficients", "rectification_matrix", "projection_matrix", "binning_x", "binning_y",
                  "roi"});
  RosCamera cam;
  if (!root.Has("image_width") || !root.Has("image_height")) root.Fail("missing image_width or image_height");
  root.Get("image_width", cam.intrinsics.width, 1, 100000);
  root.Get("image_height", cam.intrinsics.height, 1, 100000);
  // Binned or cropped calibrations describe other images than the full frame.
  int binning = 0;
  for (const char* key : {"binning_x", "binning_y"}) {
    binning = 0;
    root.Get(key, binning, 0, 64);
    if (binning > 1) root[key].Fail("expected 0 or 1 (calibrate the images the cameras deliver, unbinned here)");
  }
  const std::vector<double> K = RosMatrix(root, "camera_matrix", 3, 3);
  cv::Mat k(3, 3, CV_64F, const_cast<double*>(K.data()));
  const std::string where = path + ": camera_matrix";
  Intrinsics in = FromK(k, path, "camera_matrix");
  in.width = cam.intrinsics.width;
  in.height = cam.intrinsics.height;
  std::string model = "plumb_bob";
  root.Get("distortion_model", model);
  const std::vector<double> D = RosMatrix(root, "distortion_coefficients", 0, 0);
  if (model != "plumb_bob" && !(D.empty() || model.empty())) {
    root["distortion_model"].Fail("expected plumb_bob (k1 k2 p1 p2 k3), got \"" + model +
                                  "\" (not in the project's pinhole model)");
  }
  if (!D.empty() && D.size() != 4 && D.size() != 5) {
    root["distortion_coefficients"].Fail("expected 4 or 5 numbers (k1 k2 p1 p2 [k3]), got " + std::to_string(D.size()));
  }
  in.distortion = D;
  CheckIntrinsics(in, where);
  cam.intrinsics = in;
  const std::vector<double> R = RosMatrix(root, "rectification_matrix", 3, 3);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) cam.rectification(r, c) = R[3 * r + c];
  }
  if ((cam.rectification * cam.rectification.transpose() - Eigen::Matrix3d::Identity()).norm() > 1e-6 ||
      cam.rectification.determinant() < 0) {
    root["rectification_matrix"].Fail("expected a rotation");
  }
  const std::vector<double> P = RosMatrix(root, "projection_matrix", 3, 4);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) cam.projection(r, c) = P[4 * r + c];
  }
  if (!(cam.projection(0, 0) > 0)) root["projection_matrix"].Fail("expected a positive focal length P[0][0]");
  return cam;
}

void CameraYaml(std::ostringstream& out, const char* name, const Intrinsics& in, const Eigen::Vector3d& position,
                const Eigen::Matrix3d& R_rover_optical) {
  const Eigen::Quaterniond q(R_rover_optical);
  out << name << ":\n"
      << "  type: pinhole\n"
      << "  width: " << in.width << "\n"
      << "  height: " << in.height << "\n"
      << "  fx: " << Num(in.fx) << "\n"
      << "  fy: " << Num(in.fy) << "\n"
      << "  cx: " << Num(in.cx) << "\n"
      << "  cy: " << Num(in.cy) << "\n";
  if (!in.distortion.empty()) {
    out << "  distortion: [";
    for (std::size_t i = 0; i < in.distortion.size(); ++i) out << (i ? ", " : "") << Num(in.distortion[i]);
    out << "]\n";
  }
  out << "  position: [" << Num(position.x()) << ", " << Num(position.y()) << ", " << Num(position.z()) << "]\n"
      << "  quaternion_wxyz: [" << Num(q.w()) << ", " << Num(q.x()) << ", " << Num(q.y()) << ", " << Num(q.z())
      << "]\n";
}

}  // namespace

StereoCalibration LoadOpenCvStereo(const std::string& path, double translation_scale, int width, int height) {
  config::CheckRegularFile(path, config::kMaxConfigFileBytes, "OpenCV calibration");
  cv::FileStorage fs;
  try {
    if (!fs.open(path, cv::FileStorage::READ | cv::FileStorage::FORMAT_YAML)) {
      throw ConfigError(path + ": cannot read as an OpenCV FileStorage YAML file");
    }
  } catch (const cv::Exception& e) {
    std::string why = e.err;
    for (char& c : why) {
      if (c == '\n') c = ' ';
    }
    throw ConfigError(path + ": not an OpenCV FileStorage YAML file (" + why + ")");
  }
  StereoCalibration cal;
  cal.source = path + " (OpenCV stereoCalibrate)";
  const cv::Mat K1 = ReadMat(fs, path, "K1", "M1", 3, 3, "the left camera matrix");
  const cv::Mat K2 = ReadMat(fs, path, "K2", "M2", 3, 3, "the right camera matrix");
  cal.left = FromK(K1, path, fs["K1"].empty() ? "M1" : "K1");
  cal.right = FromK(K2, path, fs["K2"].empty() ? "M2" : "K2");
  cal.left.distortion = ReadDistortion(fs, path, "D1");
  cal.right.distortion = ReadDistortion(fs, path, "D2");
  const cv::Mat R = ReadMat(fs, path, "R", "", 3, 3, "the rotation from the left camera to the right one");
  const cv::Mat T = ReadMat(fs, path, "T", "", 3, 1, "the translation from the left camera to the right one");
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) cal.R(r, c) = R.at<double>(r, c);
    cal.T(r) = T.at<double>(r, 0) * translation_scale;
  }
  if ((cal.R * cal.R.transpose() - Eigen::Matrix3d::Identity()).norm() > 1e-6 || cal.R.determinant() < 0) {
    throw ConfigError(path + ": R: expected a rotation matrix");
  }
  // The image size: in the file (as calibration tools write it) or from the caller.
  int w = 0, h = 0;
  if (!fs["image_width"].empty() && !fs["image_height"].empty()) {
    w = static_cast<int>(fs["image_width"]);
    h = static_cast<int>(fs["image_height"]);
  } else {
    for (const char* key : {"imageSize", "image_size"}) {
      const cv::FileNode n = fs[key];
      if (!n.empty() && n.isSeq() && n.size() == 2) {
        w = static_cast<int>(n[0]);
        h = static_cast<int>(n[1]);
      }
    }
  }
  if (w == 0 && h == 0) {
    w = width;
    h = height;
  }
  if (w <= 0 || h <= 0) {
    throw ConfigError(path + ": image_width: missing (expected image_width and image_height, or imageSize: [w, h], "
                             "in the file, or --size WxH)");
  }
  cal.left.width = cal.right.width = w;
  cal.left.height = cal.right.height = h;
  CheckIntrinsics(cal.left, path + ": K1");
  CheckIntrinsics(cal.right, path + ": K2");
  return cal;
}

StereoCalibration LoadRosCameraInfoPair(const std::string& left_path, const std::string& right_path) {
  const RosCamera left = LoadRosCamera(left_path);
  const RosCamera right = LoadRosCamera(right_path);
  if (std::abs(left.projection(0, 3)) > 1e-9 || std::abs(left.projection(1, 3)) > 1e-9) {
    throw ConfigError(left_path + ": projection_matrix: expected Tx = Ty = 0 for the left camera (is it the right one?)");
  }
  if (right.projection(0, 3) >= 0) {
    throw ConfigError(right_path + ": projection_matrix: expected Tx = -fx * baseline < 0 for the right camera, got " +
                      Short(right.projection(0, 3)) + " (is it the left one?)");
  }
  StereoCalibration cal;
  cal.source = left_path + ", " + right_path + " (ROS camera_info)";
  cal.left = left.intrinsics;
  cal.right = right.intrinsics;
  // In the rectified frame the right camera's centre is c = (-Tx/fx', -Ty/fy', 0). With
  // X_rect_left = R1 X_left and X_rect_right = R2 X_right = X_rect_left - c:
  // X_right = R2^T R1 X_left - R2^T c.
  const Eigen::Vector3d c(-right.projection(0, 3) / right.projection(0, 0),
                          -right.projection(1, 3) / right.projection(1, 1), 0.0);
  cal.R = right.rectification.transpose() * left.rectification;
  cal.T = -right.rectification.transpose() * c;
  return cal;
}

namespace {

double UnitScale(const std::string& unit) { return unit == "mm" ? 1e-3 : unit == "cm" ? 1e-2 : 1.0; }

// The --t-unit that puts a baseline read in `unit` inside the plausible range, or "";
// of two that do, the one nearer a typical 0.2 m rover baseline (in ratio).
std::string FittingUnit(double baseline_m, const std::string& unit) {
  const double raw = baseline_m / UnitScale(unit);
  std::string best;
  double best_off = 0;
  for (const char* u : {"mm", "cm", "m"}) {
    const double b = raw * UnitScale(u);
    const double off = std::abs(std::log(b / 0.2));
    if (u != unit && b >= kMinBaselineM && b <= kMaxBaselineM && (best.empty() || off < best_off)) {
      best = u;
      best_off = off;
    }
  }
  return best;
}

std::string FocalProblem(const Intrinsics& in, const char* camera) {
  for (const auto& [name, f] : {std::pair<const char*, double>{"fx", in.fx}, {"fy", in.fy}}) {
    if (f < kMinFocalPx || f > kMaxFocalPx) {
      return std::string(camera) + " camera's " + name + " " + Short(f) + " px is outside " + Short(kMinFocalPx) +
             " to " + Short(kMaxFocalPx) + " px: is its camera matrix in pixels, for images of " +
             std::to_string(in.width) + "x" + std::to_string(in.height) + "?";
    }
  }
  return "";
}

}  // namespace

std::string PlausibilityProblem(const StereoCalibration& cal, const std::string& t_unit) {
  const double b = cal.T.norm();
  if (!(b >= kMinBaselineM && b <= kMaxBaselineM)) {
    std::string why = "baseline " + Short(b) + " m is outside " + Short(kMinBaselineM) + " to " +
                      Short(kMaxBaselineM) + " m";
    if (t_unit.empty()) return why + ": is the right camera's projection_matrix Tx = -fx * baseline in metres?";
    const std::string fit = FittingUnit(b, t_unit);
    why += ": T was read in " + t_unit + (t_unit == "m" ? " (the default)" : "");
    return why + (fit.empty() ? "; is T the translation between the two cameras?"
                              : "; if the calibration target was measured in " + fit + ", pass --t-unit " + fit);
  }
  if (std::string p = FocalProblem(cal.left, "the left"); !p.empty()) return p;
  return FocalProblem(cal.right, "the right");
}

std::string RigYaml(const StereoCalibration& cal, const Mount& mount) {
  const double k = M_PI / 180.0;
  const Eigen::Matrix3d R_rover_left =
      geometry::RotationFromRpy(mount.rpy_deg.x() * k, mount.rpy_deg.y() * k, mount.rpy_deg.z() * k) *
      geometry::BodyFromOptical();
  // A vector v_right in the right camera's optical frame is R^T v_right in the left's; the
  // right centre is -R^T T there.
  const Eigen::Matrix3d R_rover_right = R_rover_left * cal.R.transpose();
  const Eigen::Vector3d right_position = mount.position + R_rover_left * (-cal.R.transpose() * cal.T);
  std::ostringstream out;
  out << "# Stereo rig imported by calib_import from " << cal.source << ".\n"
      << "# Rover frame (X forward, Y right, Z down); left camera mounted at position ["
      << Num(mount.position.x()) << ", " << Num(mount.position.y()) << ", " << Num(mount.position.z())
      << "], rpy_deg [" << Num(mount.rpy_deg.x()) << ", " << Num(mount.rpy_deg.y()) << ", " << Num(mount.rpy_deg.z())
      << "];\n# quaternion_wxyz: each camera's optical frame (x right, y down, z forward) in the rover frame.\n"
      << "# Baseline " << Num(cal.T.norm()) << " m.\n";
  CameraYaml(out, "left", cal.left, mount.position, R_rover_left);
  CameraYaml(out, "right", cal.right, right_position, R_rover_right);
  return out.str();
}

}  // namespace rover::calib
