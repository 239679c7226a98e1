// Known answers for the rectification check: a chessboard rendered through two known
// pinhole models (the left one with barrel distortion) by the calibration tests' renderer
// (chessboard_render.hpp). With the true rig the corners'
// rows agree after rectification within a tenth of a pixel; with a rig whose right camera
// is pitched 0.3 deg the check reports the row error that the exact corner projections
// predict (worked out with no image at all), and a blank image is one line.
#include "calib/rectification_check.hpp"
#include "chessboard_render.hpp"
#include "config/yaml_config.hpp"

#include <opencv2/imgcodecs.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sys/wait.h>
#include <iostream>

using namespace rover;

namespace {

constexpr int kCols = 9, kRows = 6;            // inner corners
constexpr double kSquare = 0.06;               // m
constexpr double kBoardX = 1.5;                // the board's plane, rover frame (X forward)
constexpr double kBoardY0 = -0.3, kBoardZ0 = -1.21;  // its top-left outer corner (Y right, Z down)

std::string RigText(double right_pitch_deg) {
  char text[1024];
  std::snprintf(text, sizeof(text),
                "left: {type: pinhole, width: 640, height: 480, fx: 500, fy: 500, cx: 319.5, cy: 239.5, "
                "distortion: [-0.05, 0.01, 0, 0, 0], position: [0, -0.1, -1.0], rpy_deg: [0, 0, 0]}\n"
                "right: {type: pinhole, width: 640, height: 480, fx: 505, fy: 505, cx: 322.0, cy: 241.0, "
                "position: [0, 0.1, -1.0], rpy_deg: [0, %.6f, 0]}\n",
                right_pitch_deg);
  return text;
}

geometry::StereoRig Rig(double right_pitch_deg) {
  return geometry::LoadStereoRig(config::ConfigNode::FromString(RigText(right_pitch_deg), "rig"));
}

// The board (calib/test/chessboard_render.hpp: inner corner (i, j) at (i, j) squares in
// its own frame) standing in the plane X = kBoardX facing the rover: its x along the rover's
// Y (right), its y along Z (down), its normal along X; its first inner corner one square
// right of and below the top-left outer corner.
calib::test::Chessboard Board() {
  calib::test::Chessboard board;
  board.cols = kCols;
  board.rows = kRows;
  board.square = kSquare;
  return board;
}

Eigen::Isometry3d BoardPose() {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear().col(0) = Eigen::Vector3d::UnitY();
  T.linear().col(1) = Eigen::Vector3d::UnitZ();
  T.linear().col(2) = Eigen::Vector3d::UnitX();
  T.translation() = Eigen::Vector3d(kBoardX, kBoardY0 + kSquare, kBoardZ0 + kSquare);
  return T;
}

// Each pixel the mean of the board over its area, then the optics' blur (the renderer the
// calibration's known-answer test uses).
cv::Mat Render(const geometry::CameraModel& camera) {
  return calib::test::RenderChessboard(camera, Board(), BoardPose());
}

// The inner corners' exact pixels through a model, in OpenCV's order (rows of columns).
std::vector<cv::Point2f> Exact(const geometry::CameraModel& camera) {
  std::vector<cv::Point2f> out;
  EXPECT_TRUE(calib::test::ExactCorners(camera, Board(), BoardPose(), &out));
  return out;
}

}  // namespace

TEST(RectificationCheck, TrueRigPutsEveryCornerOnItsRow) {
  const auto truth = Rig(0.0);
  const cv::Mat left = Render(*truth.left), right = Render(*truth.right);
  const auto left_corners = calib::FindChessboardCorners(left, {kCols, kRows}, "left");
  const auto right_corners = calib::FindChessboardCorners(right, {kCols, kRows}, "right");
  // The detector finds the corners where they are (measured on the distorted left image:
  // 0.052 px RMS, 0.085 px at worst).
  const auto exact = Exact(*truth.left);
  ASSERT_EQ(left_corners.size(), exact.size());
  double worst = 0, sum2 = 0;
  for (std::size_t i = 0; i < exact.size(); ++i) {
    const double d = cv::norm(left_corners[i] - exact[i]);
    worst = std::max(worst, d);
    sum2 += d * d;
  }
  std::cout << "left corners found " << std::sqrt(sum2 / exact.size()) << " px rms, " << worst
            << " px at worst from the exact ones\n";
  EXPECT_LT(std::sqrt(sum2 / exact.size()), 0.2);
  EXPECT_LT(worst, 0.25);
  const auto e = calib::RowErrorAfterRectification(truth, left_corners, right_corners);
  EXPECT_EQ(e.corners, kCols * kRows);
  std::cout << "true rig: rms " << e.rms_px << " px, max " << e.max_px << " px\n";
  EXPECT_LT(e.rms_px, 0.1);
  EXPECT_LT(e.max_px, 0.25);
  // The command on the same pair: it passes, and says the same figures.
  const std::string dir = std::string(ROVER_BINARY_DIR) + "/test-out/rectification_check";
  std::filesystem::create_directories(dir);
  cv::imwrite(dir + "/left.png", left);
  cv::imwrite(dir + "/right.png", right);
  std::ofstream(dir + "/rig.yaml") << RigText(0.0);
  const std::string command = std::string(ROVER_BINARY_DIR) + "/bin/calib_check --rig " + dir + "/rig.yaml --left " +
                              dir + "/left.png --right " + dir + "/right.png --board 9x6";
  FILE* pipe = popen(command.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  char buf[512];
  std::string out;
  while (fgets(buf, sizeof(buf), pipe) != nullptr) out += buf;
  EXPECT_EQ(WEXITSTATUS(pclose(pipe)), 0) << out;
  char expected[128];
  std::snprintf(expected, sizeof(expected), "rectification error: rms %.3f px, max %.3f px", e.rms_px, e.max_px);
  EXPECT_NE(out.find(expected), std::string::npos) << out;
  EXPECT_NE(out.find("calib check: PASS (rms within 0.50 px)"), std::string::npos) << out;
  // And with the pitched rig it fails.
  std::ofstream(dir + "/rig.yaml") << RigText(0.3);
  EXPECT_EQ(WEXITSTATUS(std::system((command + " > /dev/null").c_str())), 1);

  // From the exact projections, the true rig's error is nil.
  EXPECT_LT(calib::RowErrorAfterRectification(truth, Exact(*truth.left), Exact(*truth.right)).max_px, 1e-3);
}

TEST(RectificationCheck, APitchedRightCameraShowsAsTheRowErrorItPredicts) {
  const auto truth = Rig(0.0);
  const auto wrong = Rig(0.3);  // the calibration says the right camera is pitched 0.3 deg
  const auto left_corners = calib::FindChessboardCorners(Render(*truth.left), {kCols, kRows}, "left");
  const auto right_corners = calib::FindChessboardCorners(Render(*truth.right), {kCols, kRows}, "right");
  const auto predicted = calib::RowErrorAfterRectification(wrong, Exact(*truth.left), Exact(*truth.right));
  // About f tan(0.3 deg) = 2.6 px.
  EXPECT_GT(predicted.rms_px, 2.0);
  EXPECT_LT(predicted.rms_px, 3.5);
  const auto measured = calib::RowErrorAfterRectification(wrong, left_corners, right_corners);
  std::cout << "pitched 0.3 deg: predicted rms " << predicted.rms_px << " px, measured " << measured.rms_px << " px\n";
  EXPECT_NEAR(measured.rms_px, predicted.rms_px, 0.1);
  EXPECT_NEAR(measured.mean_px, predicted.mean_px, 0.1);
}

TEST(RectificationCheck, NoBoardAndNotAPinholeAreOneLine) {
  const cv::Mat blank(480, 640, CV_8UC1, cv::Scalar(128));
  try {
    calib::FindChessboardCorners(blank, {kCols, kRows}, "left.png");
    FAIL() << "found a board in a blank image";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "no 9x6 chessboard found in left.png (inner corners, columns x rows)");
  }
  const auto cahv = geometry::LoadStereoRig(config::ConfigNode::FromString(
      "left: {type: cahv, width: 64, height: 48, C: [0, 0, 0], A: [1, 0, 0], H: [31.5, 50, 0], V: [23.5, 0, 50]}\n"
      "right: {type: cahv, width: 64, height: 48, C: [0, 0.2, 0], A: [1, 0, 0], H: [31.5, 50, 0], V: [23.5, 0, 50]}\n",
      "rig"));
  EXPECT_THROW(calib::RowErrorAfterRectification(cahv, {{1, 1}}, {{1, 1}}), std::invalid_argument);
}
