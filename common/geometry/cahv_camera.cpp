#include "geometry/cahv_camera.hpp"

#include "geometry/pinhole_camera.hpp"

#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace rover::geometry {

namespace {

void CheckVectors(const char* who, int width, int height,
                  std::initializer_list<std::pair<const char*, const Eigen::Vector3d*>> vecs) {
  std::ostringstream err;
  if (width <= 0 || height <= 0) {
    err << who << ": image size " << width << "x" << height << " (expected both > 0)";
    throw std::invalid_argument(err.str());
  }
  for (const auto& [name, v] : vecs) {
    if (!v->allFinite()) {
      err << who << ": vector " << name << " = (" << v->transpose() << ") (expected finite)";
      throw std::invalid_argument(err.str());
    }
  }
}

void CheckNonZero(const char* who, const char* name, const Eigen::Vector3d& v) {
  if (!(v.norm() > 1e-12)) {
    throw std::invalid_argument(std::string(who) + ": vector " + name +
                                " is zero (expected a direction)");
  }
}

// CAHV on an already-distorted p' = X' - C. J (optional) is d(pixel)/d(p').
bool ProjectCahv(const Eigen::Vector3d& p, const Eigen::Vector3d& A, const Eigen::Vector3d& H,
                 const Eigen::Vector3d& V, Eigen::Vector2d* pixel,
                 Eigen::Matrix<double, 2, 3>* J) {
  const double a = p.dot(A);
  if (!(a > 0.0)) return false;
  const double x = p.dot(H) / a, y = p.dot(V) / a;
  *pixel = Eigen::Vector2d(x, y);
  if (J) {
    J->row(0) = (H - x * A).transpose() / a;
    J->row(1) = (V - y * A).transpose() / a;
  }
  return true;
}

// d(direction)/d(pixel) for a central model, from the projection Jacobian J at C + d
// (|d| = 1): J J_dir = I (moving the ray moves the pixel) and d^T J_dir = 0 (d stays unit).
Eigen::Matrix<double, 3, 2> RayJacobian(const Eigen::Matrix<double, 2, 3>& J,
                                        const Eigen::Vector3d& d) {
  Eigen::Matrix3d M;
  M.topRows<2>() = J;
  M.row(2) = d.transpose();
  Eigen::Matrix<double, 3, 2> rhs = Eigen::Matrix<double, 3, 2>::Zero();
  rhs(0, 0) = 1.0;
  rhs(1, 1) = 1.0;
  return M.partialPivLu().solve(rhs);
}

// The CAHV ray through a pixel (unit, oriented along A).
Eigen::Vector3d CahvRay(const Eigen::Vector2d& pixel, const Eigen::Vector3d& A,
                        const Eigen::Vector3d& H, const Eigen::Vector3d& V) {
  const Eigen::Vector3d f = V - pixel.y() * A;
  const Eigen::Vector3d g = H - pixel.x() * A;
  Eigen::Vector3d d = f.cross(g);
  if (d.dot(A) < 0.0) d = -d;
  return d.normalized();
}

}  // namespace

Eigen::Vector3d ScaledCahvAxis(const Eigen::Vector3d& H_or_V, const Eigen::Vector3d& A,
                               double factor) {
  if (!(factor > 0) || !std::isfinite(factor)) {
    throw std::invalid_argument("Scaled: factor " + std::to_string(factor) + " (expected > 0)");
  }
  // x' = s (x + 0.5) - 0.5 = (p.(s H + (s - 1)/2 A)) / (p.A).
  return factor * H_or_V + 0.5 * (factor - 1.0) * A;
}

static int ScaledSize(int size, double factor) {
  return std::max(1, static_cast<int>(std::lround(size * factor)));
}

// ---------------------------------------------------------------- CAHV

CahvCamera::CahvCamera(int width, int height, Eigen::Vector3d C, Eigen::Vector3d A,
                       Eigen::Vector3d H, Eigen::Vector3d V)
    : width_(width), height_(height), C_(C), A_(A), H_(H), V_(V) {
  CheckVectors("CahvCamera", width, height, {{"C", &C_}, {"A", &A_}, {"H", &H_}, {"V", &V_}});
  CheckNonZero("CahvCamera", "A", A_);
  if (!(A_.dot(H_.cross(V_)) != 0.0)) {
    throw std::invalid_argument("CahvCamera: A, H, V are coplanar (expected independent axes)");
  }
}

bool CahvCamera::Project(const Eigen::Vector3d& p_ref, Eigen::Vector2d* pixel,
                         Eigen::Matrix<double, 2, 3>* J) const {
  return ProjectCahv(p_ref - C_, A_, H_, V_, pixel, J);
}

void CahvCamera::BackProject(const Eigen::Vector2d& pixel, Eigen::Vector3d* origin,
                             Eigen::Vector3d* direction,
                             Eigen::Matrix<double, 3, 2>* J_dir) const {
  const Eigen::Vector3d d = CahvRay(pixel, A_, H_, V_);
  if (origin) *origin = C_;
  if (direction) *direction = d;
  if (J_dir) {
    Eigen::Vector2d unused;
    Eigen::Matrix<double, 2, 3> J;
    ProjectCahv(d, A_, H_, V_, &unused, &J);
    *J_dir = RayJacobian(J, d);
  }
}

std::unique_ptr<CameraModel> CahvCamera::Scaled(double factor) const {
  return std::make_unique<CahvCamera>(ScaledSize(width_, factor), ScaledSize(height_, factor),
                                      C_, A_, ScaledCahvAxis(H_, A_, factor),
                                      ScaledCahvAxis(V_, A_, factor));
}

std::vector<double> CahvCamera::Params() const {
  std::vector<double> out;
  for (const Eigen::Vector3d* v : {&C_, &A_, &H_, &V_}) out.insert(out.end(), v->data(), v->data() + 3);
  return out;
}

std::unique_ptr<CameraModel> CahvCamera::Clone() const {
  return std::make_unique<CahvCamera>(*this);
}

std::unique_ptr<CameraModel> CahvCamera::Moved(const Eigen::Isometry3d& T) const {
  const Eigen::Matrix3d R = T.linear();
  return std::make_unique<CahvCamera>(width_, height_, T * C_, R * A_, R * H_, R * V_);
}

// ---------------------------------------------------------------- CAHVOR

CahvorCamera::CahvorCamera(int width, int height, Eigen::Vector3d C, Eigen::Vector3d A,
                           Eigen::Vector3d H, Eigen::Vector3d V, Eigen::Vector3d O,
                           Eigen::Vector3d R)
    : width_(width), height_(height), C_(C), A_(A), H_(H), V_(V), O_(O), R_(R) {
  CheckVectors("CahvorCamera", width, height,
               {{"C", &C_}, {"A", &A_}, {"H", &H_}, {"V", &V_}, {"O", &O_}, {"R", &R_}});
  CheckNonZero("CahvorCamera", "A", A_);
  CheckNonZero("CahvorCamera", "O", O_);
  if (!(A_.dot(H_.cross(V_)) != 0.0)) {
    throw std::invalid_argument("CahvorCamera: A, H, V are coplanar (expected independent axes)");
  }
  // With w fixed, the lateral offset t = |l|/w maps to t (1 + mu(t^2)); its slope
  // 1 + R0 + 3 R1 tau + 5 R2 tau^2 must stay positive, or the model folds back.
  auto slope = [&](double tau) { return 1.0 + R_[0] + tau * (3 * R_[1] + tau * 5 * R_[2]); };
  max_tau_ = std::numeric_limits<double>::infinity();
  if (!(slope(0.0) > 0.0)) {
    throw std::invalid_argument("CahvorCamera: R0 = " + std::to_string(R_[0]) +
                                " (expected > -1)");
  }
  const double tau_max = 400.0;  // 87 deg off axis
  const int steps = 40000;
  double prev = 0.0;
  for (int i = 1; i <= steps; ++i) {
    const double tau = tau_max * i / steps;
    if (slope(tau) <= 0.0) {
      double lo = prev, hi = tau;
      for (int it = 0; it < 100; ++it) {
        const double mid = 0.5 * (lo + hi);
        (slope(mid) > 0.0 ? lo : hi) = mid;
      }
      max_tau_ = lo;
      break;
    }
    prev = tau;
  }
}

bool CahvorCamera::Project(const Eigen::Vector3d& p_ref, Eigen::Vector2d* pixel,
                           Eigen::Matrix<double, 2, 3>* J) const {
  const Eigen::Vector3d p = p_ref - C_;
  if (!(p.dot(A_) > 0.0)) return false;
  const double w = p.dot(O_);
  if (!(w > 0.0)) return false;
  const Eigen::Vector3d l = p - w * O_;
  const double ll = l.squaredNorm();
  const double tau = ll / (w * w);
  if (tau > max_tau_) return false;
  const double mu = R_[0] + tau * (R_[1] + tau * R_[2]);
  const Eigen::Vector3d pd = p + mu * l;
  if (!J) return ProjectCahv(pd, A_, H_, V_, pixel, nullptr);
  Eigen::Matrix<double, 2, 3> J_cahv;
  if (!ProjectCahv(pd, A_, H_, V_, pixel, &J_cahv)) return false;
  // dl/dp = I - O O^T; dtau/dp = 2 l^T (I - O O^T) / w^2 - 2 (l.l) O^T / w^3.
  const Eigen::Matrix3d dl_dp = Eigen::Matrix3d::Identity() - O_ * O_.transpose();
  const Eigen::RowVector3d dtau_dp =
      2.0 * l.transpose() * dl_dp / (w * w) - 2.0 * ll / (w * w * w) * O_.transpose();
  const Eigen::RowVector3d dmu_dp = (R_[1] + 2.0 * R_[2] * tau) * dtau_dp;
  const Eigen::Matrix3d dpd_dp = Eigen::Matrix3d::Identity() + mu * dl_dp + l * dmu_dp;
  *J = J_cahv * dpd_dp;
  return true;
}

void CahvorCamera::BackProject(const Eigen::Vector2d& pixel, Eigen::Vector3d* origin,
                               Eigen::Vector3d* direction,
                               Eigen::Matrix<double, 3, 2>* J_dir) const {
  // Newton on the unit direction d: solve [J; d^T] delta = [pixel - Project(C + d); 0].
  // The CAHV ray is within mu (a few per cent) of the answer, so this converges in 2-4
  // steps; the last step is taken after the residual is already at rounding level.
  Eigen::Vector3d d = CahvRay(pixel, A_, H_, V_);
  Eigen::Vector2d projected;
  Eigen::Matrix<double, 2, 3> J;
  for (int it = 0; it < 50; ++it) {
    if (!Project(C_ + d, &projected, &J)) break;
    const Eigen::Vector2d r = pixel - projected;
    const Eigen::Vector3d delta = RayJacobian(J, d) * r;
    d = (d + delta).normalized();
    if (delta.norm() < 1e-15) break;
  }
  if (origin) *origin = C_;
  if (direction) *direction = d;
  if (J_dir) {
    if (Project(C_ + d, &projected, &J)) {
      *J_dir = RayJacobian(J, d);
    } else {
      J_dir->setZero();
    }
  }
}

std::unique_ptr<CameraModel> CahvorCamera::Scaled(double factor) const {
  return std::make_unique<CahvorCamera>(ScaledSize(width_, factor),
                                        ScaledSize(height_, factor), C_, A_,
                                        ScaledCahvAxis(H_, A_, factor),
                                        ScaledCahvAxis(V_, A_, factor), O_, R_);
}

std::vector<double> CahvorCamera::Params() const {
  std::vector<double> out;
  for (const Eigen::Vector3d* v : {&C_, &A_, &H_, &V_, &O_, &R_}) {
    out.insert(out.end(), v->data(), v->data() + 3);
  }
  return out;
}

std::unique_ptr<CameraModel> CahvorCamera::Clone() const {
  return std::make_unique<CahvorCamera>(*this);
}

std::unique_ptr<CameraModel> CahvorCamera::Moved(const Eigen::Isometry3d& T) const {
  const Eigen::Matrix3d R = T.linear();
  return std::make_unique<CahvorCamera>(width_, height_, T * C_, R * A_, R * H_, R * V_, R * O_, R_);
}

// ---------------------------------------------------------------- conversions

CahvCamera CahvFromPinhole(const PinholeCamera& pinhole) {
  if (pinhole.HasDistortion()) {
    throw std::invalid_argument(
        "CahvFromPinhole: the pinhole has distortion (expected none: CAHV cannot carry it)");
  }
  const Eigen::Matrix3d& R = pinhole.T_ref_cam().linear();
  const Eigen::Vector3d A = R.col(2);
  const Eigen::Vector3d H = pinhole.fx() * R.col(0) + pinhole.cx() * A;
  const Eigen::Vector3d V = pinhole.fy() * R.col(1) + pinhole.cy() * A;
  return CahvCamera(pinhole.width(), pinhole.height(), pinhole.T_ref_cam().translation(), A, H,
                    V);
}

}  // namespace rover::geometry
