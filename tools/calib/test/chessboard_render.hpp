// Chessboard views rendered through a known camera model, for the calibration tools'
// known-answer tests. The board is a plane placed anywhere in the model's reference frame;
// each pixel is the mean of the board over the pixel's whole footprint (area sampling, as a
// sensor with a 100 % fill factor integrates light), then the optics' blur is a Gaussian.
#pragma once

#include "geometry/camera_model.hpp"

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include <vector>

namespace rover::calib::test {

struct Chessboard {
  int cols = 9, rows = 6;  // inner corners
  double square = 0.04;    // m
  // Board frame: inner corner (i, j) at (i * square, j * square, 0); the plane is z = 0.
  // Squares one beyond the inner corners on every side ((cols + 1) x (rows + 1) squares),
  // then a light margin one square wide (the detector needs it), then a grey background.
  double ValueAt(double u, double v) const;
  // The board point of inner corner (i, j), in the board frame.
  Eigen::Vector3d Corner(int i, int j) const { return {i * square, j * square, 0}; }
};

struct RenderOptions {
  int supersampling = 16;   // samples per pixel side where a pixel straddles an edge
  double blur_sigma = 0.8;  // px, the optics' point spread (0: none)
};

// The view of `board` placed at `T_ref_board` through `camera`, 8-bit gray.
cv::Mat RenderChessboard(const geometry::CameraModel& camera, const Chessboard& board,
                         const Eigen::Isometry3d& T_ref_board, const RenderOptions& options = {});

// The inner corners' exact pixels through `camera`, in OpenCV's order (rows of columns).
// Returns false when one of them, or the board's outer edge plus `margin_px`, is not in
// the image.
bool ExactCorners(const geometry::CameraModel& camera, const Chessboard& board, const Eigen::Isometry3d& T_ref_board,
                  std::vector<cv::Point2f>* corners, double margin_px = 8.0);

}  // namespace rover::calib::test
