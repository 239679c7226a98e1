#include "calib/rectification_check.hpp"

#include "geometry/pinhole_camera.hpp"

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <stdexcept>

namespace rover::calib {

namespace {

const geometry::PinholeCamera& Pinhole(const geometry::CameraModel& m, const char* side) {
  const auto* p = dynamic_cast<const geometry::PinholeCamera*>(&m);
  if (p == nullptr) {
    throw std::invalid_argument(std::string(side) + " camera is a " + m.type() +
                                " model (expected pinhole, as calib_import writes)");
  }
  return *p;
}

cv::Mat K(const geometry::PinholeCamera& p) {
  return (cv::Mat_<double>(3, 3) << p.fx(), 0, p.cx(), 0, p.fy(), p.cy(), 0, 0, 1);
}

cv::Mat D(const geometry::PinholeCamera& p) {
  cv::Mat d = cv::Mat::zeros(1, 5, CV_64F);
  for (std::size_t i = 0; i < p.distortion().size() && i < 5; ++i) d.at<double>(0, static_cast<int>(i)) = p.distortion()[i];
  return d;
}

}  // namespace

RectificationError RowErrorAfterRectification(const geometry::StereoRig& rig, const std::vector<cv::Point2f>& left,
                                              const std::vector<cv::Point2f>& right) {
  const auto& l = Pinhole(*rig.left, "left");
  const auto& r = Pinhole(*rig.right, "right");
  if (left.size() != right.size() || left.empty()) {
    throw std::invalid_argument(std::to_string(left.size()) + " left and " + std::to_string(right.size()) +
                                " right corners (expected the same number, at least one)");
  }
  // OpenCV's stereo convention: X_right = R X_left + T in the optical frames.
  const Eigen::Isometry3d T_right_left = r.T_ref_cam().inverse() * l.T_ref_cam();
  cv::Mat R, T;
  cv::eigen2cv(Eigen::Matrix3d(T_right_left.linear()), R);
  cv::eigen2cv(Eigen::Vector3d(T_right_left.translation()), T);
  const cv::Size size(l.width(), l.height());
  cv::Mat R1, R2, P1, P2, Q;
  cv::stereoRectify(K(l), D(l), K(r), D(r), size, R, T, R1, R2, P1, P2, Q, cv::CALIB_ZERO_DISPARITY, 0);
  std::vector<cv::Point2f> left_rect, right_rect;
  cv::undistortPoints(left, left_rect, K(l), D(l), R1, P1);
  cv::undistortPoints(right, right_rect, K(r), D(r), R2, P2);
  RectificationError e;
  e.corners = static_cast<int>(left.size());
  double sum2 = 0, sum = 0;
  for (std::size_t i = 0; i < left.size(); ++i) {
    const double dy = right_rect[i].y - left_rect[i].y;
    sum += dy;
    sum2 += dy * dy;
    e.max_px = std::max(e.max_px, std::abs(dy));
  }
  e.rms_px = std::sqrt(sum2 / e.corners);
  e.mean_px = sum / e.corners;
  return e;
}

std::vector<cv::Point2f> FindChessboardCorners(const cv::Mat& image, cv::Size inner, const std::string& what) {
  cv::Mat gray = image;
  if (image.depth() == CV_16U) image.convertTo(gray, CV_8U, 1.0 / 256.0);
  std::vector<cv::Point2f> corners;
  if (!cv::findChessboardCorners(gray, inner, corners,
                                 cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE)) {
    throw std::runtime_error("no " + std::to_string(inner.width) + "x" + std::to_string(inner.height) +
                             " chessboard found in " + what + " (inner corners, columns x rows)");
  }
  cv::cornerSubPix(gray, corners, cv::Size(5, 5), cv::Size(-1, -1),
                   cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 100, 0.001));
  return corners;
}

}  // namespace rover::calib
