// Pinhole camera with OpenCV-style lens distortion (Brown-Conrady: k1 k2 p1 p2 [k3]).
//
// Camera frame: x right, y down, z forward (optical axis). T_ref_cam is the camera's pose
// in the model's reference frame (p_ref = T_ref_cam * p_cam), so that both cameras of a
// stereo rig, and CAHV models, share one reference frame (the rover frame on a rover, the
// left camera frame for KITTI).
//
// Pixel convention (camera_model.hpp): (0,0) is the centre of the top-left pixel, the same
// as OpenCV's, so (cx, cy) carry over from an OpenCV calibration unchanged.
//
// Serialised parameters (Params()):
//   fx fy cx cy  tx ty tz  qw qx qy qz  [k1 k2 p1 p2 [k3]]
// i.e. 11, 15 or 16 numbers; (t, q) is T_ref_cam.
#pragma once

#include "geometry/camera_model.hpp"

#include <vector>

namespace rover::geometry {

class PinholeCamera : public CameraModel {
 public:
  // distortion: OpenCV order k1 k2 p1 p2 [k3]; empty, 4 or 5 numbers. Throws
  // std::invalid_argument on a non-positive size or focal length, or another count.
  PinholeCamera(int width, int height, double fx, double fy, double cx, double cy,
                std::vector<double> distortion = {},
                Eigen::Isometry3d T_ref_cam = Eigen::Isometry3d::Identity());

  double fx() const { return fx_; }
  double fy() const { return fy_; }
  double cx() const { return cx_; }
  double cy() const { return cy_; }
  const std::vector<double>& distortion() const { return distortion_; }
  const Eigen::Isometry3d& T_ref_cam() const { return T_ref_cam_; }
  bool HasDistortion() const;

  std::string type() const override { return "pinhole"; }
  int width() const override { return width_; }
  int height() const override { return height_; }

  // Returns false behind the camera (z <= 0) and beyond the radius where the radial
  // polynomial stops increasing: past it a distorted model folds far-off points back into
  // the image, and VO would match them.
  bool Project(const Eigen::Vector3d& p_ref, Eigen::Vector2d* pixel,
               Eigen::Matrix<double, 2, 3>* J = nullptr) const override;
  // Undistorts by Newton's method on the distortion polynomial (converged to 1e-12 in
  // normalised coordinates, i.e. far below 1e-9 px).
  void BackProject(const Eigen::Vector2d& pixel, Eigen::Vector3d* origin,
                   Eigen::Vector3d* direction,
                   Eigen::Matrix<double, 3, 2>* J_dir = nullptr) const override;
  // fx' = s fx, cx' = s (cx + 0.5) - 0.5 (pixel centres stay centres); distortion is in
  // normalised coordinates and does not change. Size becomes round(s * size).
  std::unique_ptr<CameraModel> Scaled(double factor) const override;
  Eigen::Vector3d Center() const override { return T_ref_cam_.translation(); }
  std::vector<double> Params() const override;
  std::unique_ptr<CameraModel> Clone() const override;
  // T_ref_cam -> T * T_ref_cam.
  std::unique_ptr<CameraModel> Moved(const Eigen::Isometry3d& T) const override;

  // Normalised image coordinates (x/z, y/z) -> distorted normalised coordinates, with the
  // 2x2 Jacobian.
  Eigen::Vector2d Distort(const Eigen::Vector2d& xn, Eigen::Matrix2d* J = nullptr) const;
  // Inverse of Distort (Newton); returns false if it did not converge.
  bool Undistort(const Eigen::Vector2d& xd, Eigen::Vector2d* xn) const;

  static constexpr int kBaseParamCount = 11;

 private:
  int width_, height_;
  double fx_, fy_, cx_, cy_;
  std::vector<double> distortion_;
  double k1_ = 0, k2_ = 0, p1_ = 0, p2_ = 0, k3_ = 0;
  Eigen::Isometry3d T_ref_cam_;
  Eigen::Isometry3d T_cam_ref_;
  // Largest r^2 = (x/z)^2 + (y/z)^2 where the radial map r * (1 + k1 r^2 + ...) still
  // increases; infinite without radial distortion.
  double max_r2_;
};

}  // namespace rover::geometry
