// A stereo sequence in KITTI odometry layout:
//   DIR/image_0/NNNNNN.png  left, 8-bit gray      DIR/calib.txt  P0: and P1: rows
//   DIR/image_1/NNNNNN.png  right, same names      DIR/times.txt  one time (s) per frame
//   DIR/poses.txt (optional) row-major 3x4 [R|t] of the left camera in the world frame
// Everything is checked when the sequence is opened, so a bad dataset fails before any
// VO runs, with one line naming the path and what was expected.
#pragma once

#include "geometry/camera_model.hpp"
#include "vo_eval/trajectory_metrics.hpp"

#include <opencv2/core.hpp>

#include <stdexcept>
#include <string>
#include <vector>

namespace rover::vo_eval {

// A malformed or missing dataset. what() is one line naming the path.
class DatasetError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct KittiSequence {
  std::string dir;
  std::vector<std::string> left_paths;
  std::vector<std::string> right_paths;
  std::vector<double> times_s;
  PoseList truth;  // empty when poses.txt is absent
  // calib.txt's rectified pair as two pinhole models in the left camera frame, read once
  // (geometry::LoadKittiCalib) at the first image's size.
  geometry::StereoRig rig;
  std::string calib_path;
  int width = 0;   // of the first left image; every image must match
  int height = 0;
  int size() const { return static_cast<int>(left_paths.size()); }
  bool has_truth() const { return !truth.empty(); }
};

// Reads a KITTI poses file (12 numbers a line).
PoseList ReadKittiPoses(const std::string& path);
// Writes poses in the same format (%e, like the KITTI files).
void WriteKittiPoses(const std::string& path, const PoseList& poses);

// Opens and checks the whole layout (counts, names, calib, times, poses, and the first
// image's size). Throws DatasetError.
KittiSequence OpenKittiSequence(const std::string& dir);

// The left and right images of frame `index`, 8-bit gray. Throws DatasetError when a file
// cannot be decoded or its size differs from the sequence's.
struct StereoFrameImages {
  cv::Mat left;
  cv::Mat right;
};
StereoFrameImages LoadStereoFrame(const KittiSequence& sequence, int index);

}  // namespace rover::vo_eval
