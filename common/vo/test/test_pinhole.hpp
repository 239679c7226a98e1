// A minimal undistorted pinhole for the VO tests only (camera frame x right, y down,
// z forward; the camera sits at `center` in the reference frame with the reference
// frame's axes). The project's full model is geometry/pinhole_camera.hpp.
#pragma once

#include "geometry/camera_model.hpp"

#include <cmath>
#include <memory>

namespace rover::vo::test {

class TestPinhole : public geometry::CameraModel {
 public:
  TestPinhole(int w, int h, double f, double cx, double cy, Eigen::Vector3d center)
      : w_(w), h_(h), f_(f), cx_(cx), cy_(cy), c_(center) {}
  std::string type() const override { return "pinhole"; }
  int width() const override { return w_; }
  int height() const override { return h_; }
  bool Project(const Eigen::Vector3d& p_ref, Eigen::Vector2d* px,
               Eigen::Matrix<double, 2, 3>* J) const override {
    const Eigen::Vector3d p = p_ref - c_;
    if (p.z() <= 1e-9) return false;
    *px = Eigen::Vector2d(f_ * p.x() / p.z() + cx_, f_ * p.y() / p.z() + cy_);
    if (J) {
      *J << f_ / p.z(), 0, -f_ * p.x() / (p.z() * p.z()), 0, f_ / p.z(),
          -f_ * p.y() / (p.z() * p.z());
    }
    return true;
  }
  void BackProject(const Eigen::Vector2d& px, Eigen::Vector3d* origin, Eigen::Vector3d* dir,
                   Eigen::Matrix<double, 3, 2>* J) const override {
    const Eigen::Vector3d v((px.x() - cx_) / f_, (px.y() - cy_) / f_, 1.0);
    const double n = v.norm();
    *origin = c_;
    *dir = v / n;
    if (J) {
      Eigen::Matrix<double, 3, 2> dv;
      dv << 1 / f_, 0, 0, 1 / f_, 0, 0;
      *J = (Eigen::Matrix3d::Identity() - (*dir) * dir->transpose()) / n * dv;
    }
  }
  std::unique_ptr<geometry::CameraModel> Scaled(double s) const override {
    return std::make_unique<TestPinhole>(static_cast<int>(std::lround(w_ * s)),
                                         static_cast<int>(std::lround(h_ * s)), f_ * s,
                                         s * (cx_ + 0.5) - 0.5, s * (cy_ + 0.5) - 0.5, c_);
  }
  Eigen::Vector3d Center() const override { return c_; }
  std::vector<double> Params() const override { return {f_, cx_, cy_, c_.x(), c_.y(), c_.z()}; }
  std::unique_ptr<geometry::CameraModel> Clone() const override {
    return std::make_unique<TestPinhole>(*this);
  }

 private:
  int w_, h_;
  double f_, cx_, cy_;
  Eigen::Vector3d c_;
};

inline geometry::StereoRig MakeRig(int w, int h, double f, double cx, double cy, double baseline) {
  geometry::StereoRig rig;
  rig.left = std::make_shared<TestPinhole>(w, h, f, cx, cy, Eigen::Vector3d::Zero());
  rig.right = std::make_shared<TestPinhole>(w, h, f, cx, cy, Eigen::Vector3d(baseline, 0, 0));
  return rig;
}

}  // namespace rover::vo::test
