// Stereo calibrations made by other tools, turned into the project's rig files
// (configs/cameras/*.yaml, geometry/camera_io.hpp): pinhole models with OpenCV distortion,
// placed in the rover frame. Two inputs:
//   - an OpenCV stereoCalibrate result written with cv::FileStorage (YAML): the camera
//     matrices K1/K2 (or M1/M2), distortions D1/D2, and R, T with X_right = R X_left + T
//     in the cameras' optical frames (x right, y down, z forward);
//   - a pair of ROS camera_info YAML files (camera_calibration's stereo output): each
//     camera's K, plumb_bob distortion, rectification R and projection P; the baseline is
//     -P_right[0][3] / P_right[0][0].
// A calibration says where the right camera is relative to the left one; where the left
// one is on the rover (its mount) comes from the caller. Bad input is a ConfigError whose
// one line names the file and the key.
#pragma once

#include <Eigen/Dense>

#include <string>
#include <vector>

namespace rover::calib {

struct Intrinsics {
  int width = 0, height = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;
  std::vector<double> distortion;  // OpenCV order k1 k2 p1 p2 [k3]; empty when none
};

struct StereoCalibration {
  Intrinsics left, right;
  // X_right = R * X_left + T, optical frames, metres.
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d T = Eigen::Vector3d::Zero();
  std::string source;  // for the rig file's header comment
};

// `translation_scale` turns T into metres (0.001 when the calibration target was measured
// in millimetres). `width`, `height`: the image size when the file does not hold it
// (image_width/image_height or imageSize); 0 when it must.
StereoCalibration LoadOpenCvStereo(const std::string& path, double translation_scale = 1.0, int width = 0,
                                   int height = 0);
StereoCalibration LoadRosCameraInfoPair(const std::string& left_path, const std::string& right_path);

// What makes a calibration implausible for a rover's stereo camera, in one line, or "" when
// nothing does: a baseline outside kMinBaselineM..kMaxBaselineM (naming the --t-unit that
// would bring it inside: a file in millimetres read as metres gives 1000 times the
// baseline), or a focal length outside kMinFocalPx..kMaxFocalPx. `t_unit` is the unit T
// was read in (m, cm or mm; "" for a ROS pair, whose baseline is in metres by definition).
inline constexpr double kMinBaselineM = 0.01, kMaxBaselineM = 2.0;
inline constexpr double kMinFocalPx = 50.0, kMaxFocalPx = 50000.0;
std::string PlausibilityProblem(const StereoCalibration& calibration, const std::string& t_unit);

// The left camera's mount in the rover frame: centre, and body roll/pitch/yaw (x along
// the optical axis, y right, z down; as rpy_deg in a rig file).
struct Mount {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Vector3d rpy_deg = Eigen::Vector3d::Zero();
};

// The rig file's text: left and right pinhole models, orientations as optical-frame
// quaternions in the rover frame.
std::string RigYaml(const StereoCalibration& calibration, const Mount& left_mount);

}  // namespace rover::calib
