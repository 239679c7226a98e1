#include "geometry/pinhole_camera.hpp"

#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace rover::geometry {

namespace {

// Smallest s = r^2 > 0 where d/dr [r (1 + k1 r^2 + k2 r^4 + k3 r^6)] = 1 + 3 k1 s + 5 k2 s^2 +
// 7 k3 s^3 reaches zero; infinity if it stays positive up to r = 20 (87 deg off axis).
double MonotonicRadiusSquared(double k1, double k2, double k3) {
  auto slope = [&](double s) { return 1.0 + s * (3 * k1 + s * (5 * k2 + s * 7 * k3)); };
  const double s_max = 400.0;
  const int steps = 40000;
  double prev = 0.0;
  for (int i = 1; i <= steps; ++i) {
    const double s = s_max * i / steps;
    if (slope(s) <= 0.0) {
      double lo = prev, hi = s;
      for (int it = 0; it < 100; ++it) {
        const double mid = 0.5 * (lo + hi);
        (slope(mid) > 0.0 ? lo : hi) = mid;
      }
      return lo;
    }
    prev = s;
  }
  return std::numeric_limits<double>::infinity();
}

}  // namespace

PinholeCamera::PinholeCamera(int width, int height, double fx, double fy, double cx, double cy,
                             std::vector<double> distortion, Eigen::Isometry3d T_ref_cam)
    : width_(width),
      height_(height),
      fx_(fx),
      fy_(fy),
      cx_(cx),
      cy_(cy),
      distortion_(std::move(distortion)),
      T_ref_cam_(T_ref_cam) {
  std::ostringstream err;
  if (width <= 0 || height <= 0) {
    err << "PinholeCamera: image size " << width << "x" << height << " (expected both > 0)";
  } else if (!(fx > 0) || !(fy > 0) || !std::isfinite(fx) || !std::isfinite(fy)) {
    err << "PinholeCamera: focal lengths fx=" << fx << " fy=" << fy << " (expected > 0)";
  } else if (!std::isfinite(cx) || !std::isfinite(cy)) {
    err << "PinholeCamera: principal point (" << cx << ", " << cy << ") (expected finite)";
  } else if (!distortion_.empty() && distortion_.size() != 4 && distortion_.size() != 5) {
    err << "PinholeCamera: " << distortion_.size()
        << " distortion coefficients (expected 0, 4 (k1 k2 p1 p2) or 5 (k1 k2 p1 p2 k3))";
  } else {
    const Eigen::Matrix3d R = T_ref_cam.linear();
    const double ortho_err = (R.transpose() * R - Eigen::Matrix3d::Identity()).norm();
    if (!(ortho_err < 1e-6) || R.determinant() < 0) {
      err << "PinholeCamera: T_ref_cam rotation is not a rotation (|R^T R - I| = " << ortho_err
          << ", det = " << R.determinant() << ")";
    }
  }
  if (!err.str().empty()) throw std::invalid_argument(err.str());
  for (double d : distortion_) {
    if (!std::isfinite(d)) throw std::invalid_argument("PinholeCamera: non-finite distortion");
  }
  if (distortion_.size() >= 4) {
    k1_ = distortion_[0];
    k2_ = distortion_[1];
    p1_ = distortion_[2];
    p2_ = distortion_[3];
  }
  if (distortion_.size() == 5) k3_ = distortion_[4];
  T_cam_ref_ = T_ref_cam_.inverse();
  max_r2_ = MonotonicRadiusSquared(k1_, k2_, k3_);
}

bool PinholeCamera::HasDistortion() const {
  return k1_ != 0 || k2_ != 0 || p1_ != 0 || p2_ != 0 || k3_ != 0;
}

Eigen::Vector2d PinholeCamera::Distort(const Eigen::Vector2d& xn, Eigen::Matrix2d* J) const {
  const double x = xn.x(), y = xn.y();
  const double r2 = x * x + y * y;
  const double radial = 1.0 + r2 * (k1_ + r2 * (k2_ + r2 * k3_));
  const Eigen::Vector2d xd(x * radial + 2 * p1_ * x * y + p2_ * (r2 + 2 * x * x),
                           y * radial + p1_ * (r2 + 2 * y * y) + 2 * p2_ * x * y);
  if (J) {
    const double dradial = k1_ + r2 * (2 * k2_ + r2 * 3 * k3_);  // d(radial)/d(r2)
    const double cross = 2 * x * y * dradial + 2 * p1_ * x + 2 * p2_ * y;
    (*J) << radial + 2 * x * x * dradial + 2 * p1_ * y + 6 * p2_ * x, cross,  //
        cross, radial + 2 * y * y * dradial + 6 * p1_ * y + 2 * p2_ * x;
  }
  return xd;
}

bool PinholeCamera::Undistort(const Eigen::Vector2d& xd, Eigen::Vector2d* xn) const {
  Eigen::Vector2d x = xd;
  if (!HasDistortion()) {
    *xn = x;
    return true;
  }
  Eigen::Matrix2d J;
  Eigen::Vector2d f = Distort(x, &J) - xd;
  for (int it = 0; it < 100 && f.norm() > 1e-15; ++it) {
    const Eigen::Vector2d step = J.partialPivLu().solve(f);
    // Damped when a full step would not reduce the residual (strong distortion, far corners).
    double scale = 1.0;
    Eigen::Vector2d x_new;
    Eigen::Vector2d f_new;
    for (int halving = 0; halving < 30; ++halving) {
      x_new = x - scale * step;
      f_new = Distort(x_new, nullptr) - xd;
      if (f_new.norm() < f.norm()) break;
      scale *= 0.5;
    }
    if (!(f_new.norm() < f.norm())) break;
    x = x_new;
    f = Distort(x, &J) - xd;
  }
  *xn = x;
  return f.norm() < 1e-12;
}

bool PinholeCamera::Project(const Eigen::Vector3d& p_ref, Eigen::Vector2d* pixel,
                            Eigen::Matrix<double, 2, 3>* J) const {
  const Eigen::Vector3d p = T_cam_ref_ * p_ref;
  if (!(p.z() > 0.0)) return false;
  const double inv_z = 1.0 / p.z();
  const Eigen::Vector2d xn(p.x() * inv_z, p.y() * inv_z);
  if (xn.squaredNorm() > max_r2_) return false;
  Eigen::Matrix2d Jd;
  const Eigen::Vector2d xd = Distort(xn, J ? &Jd : nullptr);
  *pixel = Eigen::Vector2d(fx_ * xd.x() + cx_, fy_ * xd.y() + cy_);
  if (J) {
    Eigen::Matrix<double, 2, 3> dxn_dp;
    dxn_dp << inv_z, 0, -xn.x() * inv_z,  //
        0, inv_z, -xn.y() * inv_z;
    const Eigen::Matrix2d F = Eigen::Vector2d(fx_, fy_).asDiagonal();
    *J = F * Jd * dxn_dp * T_cam_ref_.linear();
  }
  return true;
}

void PinholeCamera::BackProject(const Eigen::Vector2d& pixel, Eigen::Vector3d* origin,
                                Eigen::Vector3d* direction,
                                Eigen::Matrix<double, 3, 2>* J_dir) const {
  const Eigen::Vector2d xd((pixel.x() - cx_) / fx_, (pixel.y() - cy_) / fy_);
  Eigen::Vector2d xn;
  Undistort(xd, &xn);
  const Eigen::Vector3d n(xn.x(), xn.y(), 1.0);
  const double norm = n.norm();
  const Eigen::Vector3d d_cam = n / norm;
  const Eigen::Matrix3d& R = T_ref_cam_.linear();
  if (origin) *origin = T_ref_cam_.translation();
  if (direction) *direction = R * d_cam;
  if (J_dir) {
    Eigen::Matrix2d Jd;
    Distort(xn, &Jd);
    const Eigen::Matrix3d dunit_dn = (Eigen::Matrix3d::Identity() - d_cam * d_cam.transpose()) / norm;
    const Eigen::Matrix2d dxn_dpix =
        Jd.inverse() * Eigen::Vector2d(1.0 / fx_, 1.0 / fy_).asDiagonal();
    *J_dir = R * dunit_dn.leftCols<2>() * dxn_dpix;
  }
}

std::unique_ptr<CameraModel> PinholeCamera::Scaled(double factor) const {
  if (!(factor > 0) || !std::isfinite(factor)) {
    throw std::invalid_argument("PinholeCamera::Scaled: factor " + std::to_string(factor) +
                                " (expected > 0)");
  }
  const int w = std::max(1, static_cast<int>(std::lround(width_ * factor)));
  const int h = std::max(1, static_cast<int>(std::lround(height_ * factor)));
  return std::make_unique<PinholeCamera>(w, h, factor * fx_, factor * fy_,
                                         factor * (cx_ + 0.5) - 0.5, factor * (cy_ + 0.5) - 0.5,
                                         distortion_, T_ref_cam_);
}

std::vector<double> PinholeCamera::Params() const {
  const Eigen::Quaterniond q(T_ref_cam_.linear());
  const Eigen::Vector3d& t = T_ref_cam_.translation();
  std::vector<double> params = {fx_, fy_, cx_, cy_, t.x(), t.y(), t.z(),
                                q.w(), q.x(), q.y(), q.z()};
  params.insert(params.end(), distortion_.begin(), distortion_.end());
  return params;
}

std::unique_ptr<CameraModel> PinholeCamera::Clone() const {
  return std::make_unique<PinholeCamera>(*this);
}

std::unique_ptr<CameraModel> PinholeCamera::Moved(const Eigen::Isometry3d& T) const {
  // Through the constructor, so that T_cam_ref follows.
  return std::make_unique<PinholeCamera>(width_, height_, fx_, fy_, cx_, cy_, distortion_, T * T_ref_cam_);
}

}  // namespace rover::geometry
