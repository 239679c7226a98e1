// The check of a stereo calibration on a picture of a calibration target: how far apart,
// in rows, the two images of each target corner land once both images are rectified with
// the rig's models (OpenCV's stereoRectify and undistortPoints). A right calibration puts
// every corner on one row in both (a small fraction of a pixel); a wrong relative rotation
// or a wrong distortion shows as rows apart, which is what stereo matching (VO, the
// traversability map) cannot tolerate. `./rover calib check` (docs/HARDWARE.md, section 5).
#pragma once

#include "geometry/camera_io.hpp"

#include <opencv2/core.hpp>

#include <string>
#include <vector>

namespace rover::calib {

struct RectificationError {
  double rms_px = 0;   // root mean square of the row differences
  double max_px = 0;   // the largest one
  double mean_px = 0;  // signed mean: right row minus left row (a pitch between the cameras)
  int corners = 0;
};

// The row differences of matching corners (`left[i]` and `right[i]`, raw pixels of the
// rig's images) after rectification with the rig's pinhole models. Throws
// std::invalid_argument naming what is wrong (a model that is not a pinhole, counts that
// differ, no corners).
RectificationError RowErrorAfterRectification(const geometry::StereoRig& rig, const std::vector<cv::Point2f>& left,
                                              const std::vector<cv::Point2f>& right);

// The inner corners of a chessboard with `inner` corners (columns x rows) in an 8- or
// 16-bit gray image, refined to a tenth of a pixel, in OpenCV's order. Throws
// std::runtime_error "no WxH chessboard found in WHAT" when it is not there.
std::vector<cv::Point2f> FindChessboardCorners(const cv::Mat& image, cv::Size inner, const std::string& what);

}  // namespace rover::calib
