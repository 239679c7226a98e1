// Known answers for the calibration import: rigs whose right camera's place and
// projection were worked out by hand, read back through the project's own rig loader.
#include "calib/calib_import.hpp"
#include "config/yaml_config.hpp"
#include "geometry/camera_io.hpp"

#include <opencv2/core.hpp>

#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>

using namespace rover;
namespace fs = std::filesystem;

namespace {

std::string Dir() {
  const std::string dir = std::string(ROVER_BINARY_DIR) + "/test-out/calib_import";
  fs::create_directories(dir);
  return dir;
}

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const config::ConfigError& e) {
    return e.what();
  }
  return "";
}

// An OpenCV stereoCalibrate result as cv::FileStorage writes it.
std::string WriteOpenCv(const std::string& name, const cv::Matx33d& R, const cv::Vec3d& T,
                        const std::vector<double>& d1 = {0, 0, 0, 0, 0}, bool with_size = true) {
  const std::string path = Dir() + "/" + name;
  cv::FileStorage fs(path, cv::FileStorage::WRITE | cv::FileStorage::FORMAT_YAML);
  if (with_size) {
    fs << "image_width" << 640 << "image_height" << 480;
  }
  fs << "K1" << cv::Mat(cv::Matx33d(500, 0, 320, 0, 510, 240, 0, 0, 1));
  fs << "D1" << cv::Mat(d1).t();
  fs << "K2" << cv::Mat(cv::Matx33d(505, 0, 318, 0, 512, 244, 0, 0, 1));
  fs << "D2" << cv::Mat(cv::Matx<double, 1, 5>(0, 0, 0, 0, 0));
  fs << "R" << cv::Mat(R) << "T" << cv::Mat(T);
  return path;
}

geometry::StereoRig Rig(const calib::StereoCalibration& cal, const calib::Mount& mount, const std::string& name) {
  const std::string path = Dir() + "/" + name;
  std::ofstream(path) << calib::RigYaml(cal, mount);
  return geometry::LoadStereoRigFile(path);
}

cv::Matx33d RotY(double deg) {
  const double a = deg * M_PI / 180.0;
  return {std::cos(a), 0, std::sin(a), 0, 1, 0, -std::sin(a), 0, std::cos(a)};
}

}  // namespace

TEST(CalibImport, OpenCvBaselineLandsOnTheRoverYAxis) {
  // X_right = X_left + T, T = (-0.2, 0, 0): the right camera is 0.2 m along the left one's
  // optical x (image right). Mounted level looking forward, that is +Y in the rover frame;
  // pitched 31 deg down about Y, still +Y.
  const auto cal = calib::LoadOpenCvStereo(WriteOpenCv("level.yaml", cv::Matx33d::eye(), {-0.2, 0, 0}));
  EXPECT_EQ(cal.left.width, 640);
  EXPECT_EQ(cal.left.height, 480);
  EXPECT_DOUBLE_EQ(cal.right.fx, 505.0);
  calib::Mount mount;
  auto rig = Rig(cal, mount, "level_rig.yaml");
  EXPECT_LT((rig.left->Center() - Eigen::Vector3d(0, 0, 0)).norm(), 1e-12);
  EXPECT_LT((rig.right->Center() - Eigen::Vector3d(0, 0.2, 0)).norm(), 1e-12);
  mount.position = {0.2, -0.1, -1.5};
  mount.rpy_deg = {0, -31, 0};
  rig = Rig(cal, mount, "navcam_rig.yaml");
  EXPECT_LT((rig.left->Center() - Eigen::Vector3d(0.2, -0.1, -1.5)).norm(), 1e-12);
  EXPECT_LT((rig.right->Center() - Eigen::Vector3d(0.2, 0.1, -1.5)).norm(), 1e-12);
  EXPECT_NEAR(rig.Baseline(), 0.2, 1e-12);
  // A point straight ahead of the level left camera, 10 m out, at the left principal point.
  mount = calib::Mount{};
  rig = Rig(cal, mount, "level_rig.yaml");
  Eigen::Vector2d px;
  ASSERT_TRUE(rig.left->Project({10, 0, 0}, &px));
  EXPECT_NEAR(px.x(), 320.0, 1e-9);
  EXPECT_NEAR(px.y(), 240.0, 1e-9);
  // In the right camera it is 0.2 m to the left: x = 318 - 505 * 0.2 / 10 = 307.9.
  ASSERT_TRUE(rig.right->Project({10, 0, 0}, &px));
  EXPECT_NEAR(px.x(), 307.9, 1e-9);
  EXPECT_NEAR(px.y(), 244.0, 1e-9);
}

TEST(CalibImport, OpenCvRotationAndTranslationReproduceItsProjection) {
  // The right camera turned 3 deg about the vertical and offset in all three axes, with T
  // in millimetres: its pixel of a point must be K2 (R X + T) as OpenCV defines it.
  const cv::Matx33d R = RotY(3.0);
  const cv::Vec3d T_mm(-198.0, 4.0, -7.0);
  const auto cal = calib::LoadOpenCvStereo(WriteOpenCv("turned.yaml", R, T_mm), 1e-3);
  calib::Mount mount;
  mount.position = {0.5, 0.0, -1.2};
  mount.rpy_deg = {2.0, -20.0, 10.0};
  const auto rig = Rig(cal, mount, "turned_rig.yaml");
  const cv::Vec3d X_left(0.7, -0.3, 6.0);  // left optical frame, m
  const cv::Vec3d X_right = R * X_left + T_mm * 1e-3;
  const double u = 505 * X_right[0] / X_right[2] + 318, v = 512 * X_right[1] / X_right[2] + 244;
  // The same point in the rover frame, through the left camera's mount.
  Eigen::Vector2d left_px;
  Eigen::Vector3d origin, direction;
  rig.left->BackProject({500 * 0.7 / 6.0 + 320, 510 * -0.3 / 6.0 + 240}, &origin, &direction);
  const Eigen::Vector3d p_rover = origin + direction.normalized() * std::sqrt(0.7 * 0.7 + 0.3 * 0.3 + 36.0);
  Eigen::Vector2d px;
  ASSERT_TRUE(rig.right->Project(p_rover, &px));
  EXPECT_NEAR(px.x(), u, 1e-6);
  EXPECT_NEAR(px.y(), v, 1e-6);
  EXPECT_NEAR(rig.Baseline(), cv::norm(T_mm) * 1e-3, 1e-12);
}

TEST(CalibImport, RosCameraInfoPair) {
  // camera_calibration's stereo output: both rectified with R1 = R2 = I, the right
  // projection's Tx = -fx' * baseline = -500 * 0.12.
  const std::string left = Dir() + "/left.yaml", right = Dir() + "/right.yaml";
  const std::string common =
      "image_width: 640\nimage_height: 480\ndistortion_model: plumb_bob\n"
      "rectification_matrix: {rows: 3, cols: 3, data: [1, 0, 0, 0, 1, 0, 0, 0, 1]}\n";
  std::ofstream(left) << "camera_name: narrow_stereo/left\n" << common
                      << "camera_matrix: {rows: 3, cols: 3, data: [498, 0, 321, 0, 499, 239, 0, 0, 1]}\n"
                         "distortion_coefficients: {rows: 1, cols: 5, data: [-0.1, 0.02, 0.001, -0.002, 0.0]}\n"
                         "projection_matrix: {rows: 3, cols: 4, data: [500, 0, 320, 0, 0, 500, 240, 0, 0, 0, 1, 0]}\n";
  std::ofstream(right) << "camera_name: narrow_stereo/right\n" << common
                       << "camera_matrix: {rows: 3, cols: 3, data: [502, 0, 319, 0, 503, 241, 0, 0, 1]}\n"
                          "distortion_coefficients: {rows: 1, cols: 5, data: [-0.09, 0.01, 0.0, 0.0, 0.0]}\n"
                          "projection_matrix: {rows: 3, cols: 4, data: [500, 0, 320, -60, 0, 500, 240, 0, 0, 0, 1, 0]}\n";
  const auto cal = calib::LoadRosCameraInfoPair(left, right);
  EXPECT_LT((cal.T - Eigen::Vector3d(-0.12, 0, 0)).norm(), 1e-12);
  EXPECT_LT((cal.R - Eigen::Matrix3d::Identity()).norm(), 1e-12);
  ASSERT_EQ(cal.left.distortion.size(), 5u);
  EXPECT_DOUBLE_EQ(cal.left.distortion[0], -0.1);
  EXPECT_DOUBLE_EQ(cal.left.distortion[3], -0.002);
  const auto rig = Rig(cal, calib::Mount{}, "ros_rig.yaml");
  EXPECT_LT((rig.right->Center() - Eigen::Vector3d(0, 0.12, 0)).norm(), 1e-12);
  EXPECT_EQ(rig.left->width(), 640);
  // The distortion travels: the model's parameters end with k1 k2 p1 p2 k3.
  const auto params = rig.left->Params();
  ASSERT_GE(params.size(), 5u);
  EXPECT_DOUBLE_EQ(params[params.size() - 5], -0.1);

  // Rectified cameras turned by R1, R2: the relative rotation is R2^T R1.
  std::string turned = common;
  const double a = 2.0 * M_PI / 180.0;
  char r2[200];
  std::snprintf(r2, sizeof(r2), "rectification_matrix: {rows: 3, cols: 3, data: [%.17g, 0, %.17g, 0, 1, 0, %.17g, 0, %.17g]}\n",
                std::cos(a), std::sin(a), -std::sin(a), std::cos(a));
  std::ofstream(right) << "image_width: 640\nimage_height: 480\ndistortion_model: plumb_bob\n" << r2
                       << "camera_matrix: {rows: 3, cols: 3, data: [502, 0, 319, 0, 503, 241, 0, 0, 1]}\n"
                          "distortion_coefficients: {rows: 1, cols: 5, data: [0, 0, 0, 0, 0]}\n"
                          "projection_matrix: {rows: 3, cols: 4, data: [500, 0, 320, -60, 0, 500, 240, 0, 0, 0, 1, 0]}\n";
  const auto cal2 = calib::LoadRosCameraInfoPair(left, right);
  Eigen::Matrix3d R2;
  R2 << std::cos(a), 0, std::sin(a), 0, 1, 0, -std::sin(a), 0, std::cos(a);
  EXPECT_LT((cal2.R - R2.transpose()).norm(), 1e-12);
  EXPECT_LT((cal2.T - R2.transpose() * Eigen::Vector3d(-0.12, 0, 0)).norm(), 1e-12);
}

TEST(CalibImport, BadInputIsOneLineNamingTheKey) {
  // OpenCV: a missing matrix, a rational distortion model, no image size.
  const std::string path = Dir() + "/bad.yaml";
  {
    cv::FileStorage fs(path, cv::FileStorage::WRITE | cv::FileStorage::FORMAT_YAML);
    fs << "image_width" << 640 << "image_height" << 480 << "K1" << cv::Mat(cv::Matx33d::eye());
  }
  EXPECT_EQ(ErrorOf([&] { calib::LoadOpenCvStereo(path); }),
            path + ": K2: missing (expected the right camera matrix as K2 or M2, a 3x3 opencv-matrix)");
  const std::string rational =
      WriteOpenCv("rational.yaml", cv::Matx33d::eye(), {-0.2, 0, 0}, {0.1, 0.01, 0, 0, 0, 0.3, 0, 0});
  EXPECT_EQ(ErrorOf([&] { calib::LoadOpenCvStereo(rational); }),
            rational + ": D1: coefficient 6 of 8 is 0.3 (expected k1 k2 p1 p2 [k3] only: the rational "
                       "and thin-prism terms are not in the project's pinhole model)");
  const std::string no_size = WriteOpenCv("nosize.yaml", cv::Matx33d::eye(), {-0.2, 0, 0}, {0, 0, 0, 0, 0}, false);
  EXPECT_EQ(ErrorOf([&] { calib::LoadOpenCvStereo(no_size); }),
            no_size + ": image_width: missing (expected image_width and image_height, or imageSize: [w, h], in the "
                      "file, or --size WxH)");
  EXPECT_EQ(calib::LoadOpenCvStereo(no_size, 1.0, 1024, 768).left.width, 1024);
  std::ofstream(path) << "%YAML:1.0\n---\nK1: [1, 2\n";
  const std::string parse = ErrorOf([&] { calib::LoadOpenCvStereo(path); });
  EXPECT_EQ(parse.rfind(path + ": ", 0), 0u) << parse;
  EXPECT_EQ(parse.find('\n'), std::string::npos) << parse;

  // ROS: a model the pinhole cannot hold, a short matrix, an unknown key.
  const std::string ros = Dir() + "/ros_bad.yaml";
  const std::string good =
      "image_width: 640\nimage_height: 480\n"
      "rectification_matrix: {rows: 3, cols: 3, data: [1, 0, 0, 0, 1, 0, 0, 0, 1]}\n"
      "projection_matrix: {rows: 3, cols: 4, data: [500, 0, 320, 0, 0, 500, 240, 0, 0, 0, 1, 0]}\n";
  std::ofstream(ros) << good << "distortion_model: equidistant\n"
                     << "distortion_coefficients: {rows: 1, cols: 4, data: [0.1, 0, 0, 0]}\n"
                     << "camera_matrix: {rows: 3, cols: 3, data: [500, 0, 320, 0, 500, 240, 0, 0, 1]}\n";
  EXPECT_EQ(ErrorOf([&] { calib::LoadRosCameraInfoPair(ros, ros); }),
            ros + ": distortion_model: expected plumb_bob (k1 k2 p1 p2 k3), got \"equidistant\" (not in the project's "
                  "pinhole model)");
  std::ofstream(ros) << good << "distortion_model: plumb_bob\n"
                     << "distortion_coefficients: {rows: 1, cols: 5, data: [0, 0, 0, 0, 0]}\n"
                     << "camera_matrix: {rows: 3, cols: 3, data: [500, 0, 320, 0, 500, 240, 0, 0]}\n";
  EXPECT_EQ(ErrorOf([&] { calib::LoadRosCameraInfoPair(ros, ros); }),
            ros + ": camera_matrix: expected a 3x3 matrix (rows: 3, cols: 3, 9 numbers in data), got rows 3, cols 3 "
                  "and 8 numbers");
  std::ofstream(ros) << good << "camera_matrx: {rows: 3, cols: 3, data: [500, 0, 320, 0, 500, 240, 0, 0, 1]}\n";
  const std::string unknown = ErrorOf([&] { calib::LoadRosCameraInfoPair(ros, ros); });
  EXPECT_EQ(unknown.rfind(ros + ": camera_matrx: unknown key (expected one of: ", 0), 0u) << unknown;
}

// ---- plausibility (issue 44): a unit mismatch or a focal length not in pixels ----

TEST(CalibImportPlausibility, AMillimetreFileReadAsMetresNamesTheUnit) {
  // T = (-200, 0, 0) written in millimetres: read as metres it is a 200 m baseline.
  const std::string mm = WriteOpenCv("mm.yaml", cv::Matx33d::eye(), {-200.0, 0, 0});
  const auto as_m = calib::LoadOpenCvStereo(mm);
  EXPECT_DOUBLE_EQ(as_m.T.norm(), 200.0);
  EXPECT_EQ(calib::PlausibilityProblem(as_m, "m"),
            "baseline 200 m is outside 0.01 to 2 m: T was read in m (the default); if the calibration target "
            "was measured in mm, pass --t-unit mm");
  // Read in millimetres it is 0.2 m, and nothing is wrong.
  const auto as_mm = calib::LoadOpenCvStereo(mm, 1e-3);
  EXPECT_NEAR(as_mm.T.norm(), 0.2, 1e-15);
  EXPECT_EQ(calib::PlausibilityProblem(as_mm, "mm"), "");
  // 20 read as metres fits both cm (0.2 m) and mm (0.02 m): cm, nearer a rover's baseline.
  const auto cm = calib::LoadOpenCvStereo(WriteOpenCv("cm.yaml", cv::Matx33d::eye(), {-20.0, 0, 0}));
  EXPECT_NE(calib::PlausibilityProblem(cm, "m").find("pass --t-unit cm"), std::string::npos);
  // A metre file read with --t-unit mm: 0.2 mm, and the fix is metres.
  const auto tiny = calib::LoadOpenCvStereo(WriteOpenCv("m.yaml", cv::Matx33d::eye(), {-0.2, 0, 0}), 1e-3);
  EXPECT_EQ(calib::PlausibilityProblem(tiny, "mm"),
            "baseline 0.0002 m is outside 0.01 to 2 m: T was read in mm; if the calibration target was "
            "measured in m, pass --t-unit m");
}

TEST(CalibImportPlausibility, TheBoundsAreInclusiveAndFocalLengthsInPixels) {
  calib::StereoCalibration cal;
  cal.left.fx = cal.left.fy = cal.right.fx = cal.right.fy = 500;
  cal.left.width = cal.right.width = 640;
  cal.left.height = cal.right.height = 480;
  for (double b : {0.01, 0.2, 2.0}) {
    cal.T = {-b, 0, 0};
    EXPECT_EQ(calib::PlausibilityProblem(cal, "m"), "") << b;
  }
  cal.T = {-2.001, 0, 0};
  EXPECT_NE(calib::PlausibilityProblem(cal, "m"), "");
  cal.T = {0, 0, 0};  // both cameras at one place
  EXPECT_EQ(calib::PlausibilityProblem(cal, "m").rfind("baseline 0 m is outside", 0), 0u);
  cal.T = {-0.2, 0, 0};
  // A ROS pair's baseline is in metres by definition: the cause named is its Tx.
  cal.T = {-300, 0, 0};
  EXPECT_EQ(calib::PlausibilityProblem(cal, ""),
            "baseline 300 m is outside 0.01 to 2 m: is the right camera's projection_matrix Tx = -fx * baseline "
            "in metres?");
  cal.T = {-0.2, 0, 0};
  cal.right.fy = 4.8;  // a normalised or millimetre focal length
  EXPECT_EQ(calib::PlausibilityProblem(cal, "m"),
            "the right camera's fy 4.8 px is outside 50 to 50000 px: is its camera matrix in pixels, for images "
            "of 640x480?");
  cal.right.fy = 50;
  cal.left.fx = 50000;
  EXPECT_EQ(calib::PlausibilityProblem(cal, "m"), "");
  cal.left.fx = 50001;
  EXPECT_EQ(calib::PlausibilityProblem(cal, "m").rfind("the left camera's fx 50001 px", 0), 0u);
}

namespace {
// calib_import as a user runs it: exit status, and what it printed (both streams).
int RunImport(const std::string& args, std::string* output) {
  const std::string command = std::string(ROVER_BINARY_DIR) + "/bin/calib_import " + args + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return -1;
  output->clear();
  char buffer[512];
  while (fgets(buffer, sizeof buffer, pipe) != nullptr) *output += buffer;
  const int status = pclose(pipe);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}
std::string FileText(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}
}  // namespace

TEST(CalibImportPlausibility, TheToolRefusesWithOneLineUnlessForcedAndKeepsAnExistingOut) {
  const std::string mm = WriteOpenCv("tool_mm.yaml", cv::Matx33d::eye(), {-200.0, 0, 0});
  const std::string out = Dir() + "/tool_rig.yaml";
  fs::remove(out);
  const std::string mount = " --left-position 0,0,-1 --left-rpy 0,-20,0 --out " + out;
  std::string text;
  EXPECT_EQ(RunImport("--opencv " + mm + mount, &text), 2);
  EXPECT_EQ(text, "calib_import: " + mm + ": baseline 200 m is outside 0.01 to 2 m: T was read in m (the default); "
                  "if the calibration target was measured in mm, pass --t-unit mm (nothing written; --force writes "
                  "it anyway)\n");
  EXPECT_FALSE(fs::exists(out));
  // The suggested unit: written, a 0.2 m baseline.
  ASSERT_EQ(RunImport("--opencv " + mm + " --t-unit mm" + mount, &text), 0) << text;
  EXPECT_NEAR(geometry::LoadStereoRigFile(out).Baseline(), 0.2, 1e-12);
  const std::string first = FileText(out);
  // Again: the rig written is kept, one line, exit 2.
  EXPECT_EQ(RunImport("--opencv " + mm + " --t-unit mm" + mount, &text), 2);
  EXPECT_EQ(text, "calib_import: --out " + out + ": exists; kept (pass --force to replace it)\n");
  EXPECT_EQ(FileText(out), first);
  // --force replaces it, and writes the implausible one with a warning.
  EXPECT_EQ(RunImport("--opencv " + mm + mount + " --force", &text), 0) << text;
  EXPECT_NE(text.find("calib_import: warning: baseline 200 m"), std::string::npos) << text;
  EXPECT_NEAR(geometry::LoadStereoRigFile(out).Baseline(), 200.0, 1e-9);
}
