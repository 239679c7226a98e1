#include "geometry/cahvore_camera.hpp"

#include "geometry/cahv_camera.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace rover::geometry {

namespace {

constexpr double kLinearityEps = 1e-15;

// d(direction)/d(pixel) of the plain CAHV ray (see cahv_camera.cpp): [J; d^T] J_dir = [I; 0].
Eigen::Matrix<double, 3, 2> CahvRayJacobian(const Eigen::Vector3d& d, const Eigen::Vector3d& A,
                                            const Eigen::Vector3d& H, const Eigen::Vector3d& V) {
  const double a = d.dot(A);
  const double x = d.dot(H) / a, y = d.dot(V) / a;
  Eigen::Matrix3d M;
  M.row(0) = (H - x * A).transpose() / a;
  M.row(1) = (V - y * A).transpose() / a;
  M.row(2) = d.transpose();
  Eigen::Matrix<double, 3, 2> rhs = Eigen::Matrix<double, 3, 2>::Zero();
  rhs(0, 0) = 1.0;
  rhs(1, 1) = 1.0;
  return M.partialPivLu().solve(rhs);
}

}  // namespace

double LinearityFromCahvoreType(int T, double P) {
  switch (T) {
    case 1:
      return 1.0;
    case 2:
      return 0.0;
    case 3:
      return P;
    default:
      throw std::invalid_argument("LinearityFromCahvoreType: T = " + std::to_string(T) +
                                  " (expected 1 perspective, 2 fish-eye or 3 general)");
  }
}

CahvoreCamera::CahvoreCamera(int width, int height, Eigen::Vector3d C, Eigen::Vector3d A,
                             Eigen::Vector3d H, Eigen::Vector3d V, Eigen::Vector3d O,
                             Eigen::Vector3d R, Eigen::Vector3d E, double linearity)
    : width_(width),
      height_(height),
      C_(C),
      A_(A),
      H_(H),
      V_(V),
      O_(O),
      R_(R),
      E_(E),
      linearity_(linearity) {
  std::ostringstream err;
  if (width <= 0 || height <= 0) {
    err << "CahvoreCamera: image size " << width << "x" << height << " (expected both > 0)";
  } else if (!(C_.allFinite() && A_.allFinite() && H_.allFinite() && V_.allFinite() &&
               O_.allFinite() && R_.allFinite() && E_.allFinite() && std::isfinite(linearity))) {
    err << "CahvoreCamera: non-finite vector or linearity (expected finite numbers)";
  } else if (!(A_.norm() > 1e-12) || !(O_.norm() > 1e-12)) {
    err << "CahvoreCamera: vector " << (A_.norm() > 1e-12 ? "O" : "A")
        << " is zero (expected a direction)";
  } else if (!(A_.dot(H_.cross(V_)) != 0.0)) {
    err << "CahvoreCamera: A, H, V are coplanar (expected independent axes)";
  } else if (!(1.0 + R_[0] > 0.0)) {
    err << "CahvoreCamera: R0 = " << R_[0] << " (expected > -1)";
  }
  if (!err.str().empty()) throw std::invalid_argument(err.str());
  o_ = O_.normalized();

  // chi (1 + R0 + R1 chi^2 + R2 chi^4) must increase: slope 1 + R0 + 3 R1 chi^2 + 5 R2 chi^4.
  auto slope = [&](double c2) { return 1.0 + R_[0] + c2 * (3 * R_[1] + c2 * 5 * R_[2]); };
  max_chi_ = std::numeric_limits<double>::infinity();
  const double c2_max = 400.0;
  const int steps = 40000;
  double prev = 0.0;
  for (int i = 1; i <= steps; ++i) {
    const double c2 = c2_max * i / steps;
    if (slope(c2) <= 0.0) {
      double lo = prev, hi = c2;
      for (int it = 0; it < 100; ++it) {
        const double mid = 0.5 * (lo + hi);
        (slope(mid) > 0.0 ? lo : hi) = mid;
      }
      max_chi_ = std::sqrt(lo);
      break;
    }
    prev = c2;
  }
  // The incoming ray is at most 180 deg off O; L theta must stay below 90 deg for tan/sin.
  max_theta_ = M_PI;
  if (std::abs(linearity_) > kLinearityEps) {
    max_theta_ = std::min(max_theta_, 0.5 * M_PI / std::abs(linearity_));
  }
  if (std::isfinite(max_chi_)) {
    // Theta is increasing in chi; asin needs |L chi| <= 1.
    if (linearity_ < -kLinearityEps && std::abs(linearity_ * max_chi_) >= 1.0) {
      // sin(L theta)/L saturates first: keep the L theta limit.
    } else {
      max_theta_ = std::min(max_theta_, Theta(max_chi_));
    }
  }
}

double CahvoreCamera::Chi(double theta, double* dchi_dtheta) const {
  const double L = linearity_;
  if (L > kLinearityEps) {
    const double chi = std::tan(L * theta) / L;
    *dchi_dtheta = 1.0 + (L * chi) * (L * chi);
    return chi;
  }
  if (L < -kLinearityEps) {
    *dchi_dtheta = std::cos(L * theta);
    return std::sin(L * theta) / L;
  }
  *dchi_dtheta = 1.0;
  return theta;
}

double CahvoreCamera::Theta(double chi) const {
  const double L = linearity_;
  if (L > kLinearityEps) return std::atan(L * chi) / L;
  if (L < -kLinearityEps) return std::asin(std::clamp(L * chi, -1.0, 1.0)) / L;
  return chi;
}

bool CahvoreCamera::Project(const Eigen::Vector3d& p_ref, Eigen::Vector2d* pixel,
                            Eigen::Matrix<double, 2, 3>* J) const {
  const Eigen::Vector3d p = p_ref - C_;
  const double zeta = p.dot(o_);
  const Eigen::Vector3d lvec = p - zeta * o_;
  const double lambda = lvec.norm();
  const Eigen::Matrix3d P = Eigen::Matrix3d::Identity() - o_ * o_.transpose();

  // Newton for theta: f = zeta sin - lambda cos - (theta - sin) E(theta).
  double theta = std::atan2(lambda, zeta);
  double upsilon = 1.0;
  bool converged = false;
  for (int it = 0; it < 100; ++it) {
    const double c = std::cos(theta), s = std::sin(theta), t2 = theta * theta;
    const double e = E_[0] + t2 * (E_[1] + t2 * E_[2]);
    const double de = theta * (2 * E_[1] + t2 * 4 * E_[2]);
    upsilon = zeta * c + lambda * s - (1 - c) * e - (theta - s) * de;
    if (!(upsilon > 0.0)) return false;
    const double step = (zeta * s - lambda * c - (theta - s) * e) / upsilon;
    theta -= step;
    if (std::abs(step) < 1e-15) {
      converged = true;
      break;
    }
  }
  if (!converged || !(theta >= 0.0) || !(theta < max_theta_)) return false;

  Eigen::Vector3d pp;
  Eigen::Matrix3d dpp_dp;
  if (theta < 1e-8) {
    // On the axis: chi -> theta, |lambda|/chi -> zeta.
    pp = zeta * o_ + (1.0 + R_[0]) * lvec;
    dpp_dp = o_ * o_.transpose() + (1.0 + R_[0]) * P;
  } else {
    double dchi_dtheta = 0;
    const double chi = Chi(theta, &dchi_dtheta);
    if (!(chi > 0.0) || chi > max_chi_) return false;
    const double chi2 = chi * chi;
    const double mu = R_[0] + chi2 * (R_[1] + chi2 * R_[2]);
    const double zetap = lambda / chi;
    pp = zetap * o_ + (1.0 + mu) * lvec;
    if (J) {
      // dtheta/dp from the implicit function f(theta, zeta, lambda) = 0.
      const Eigen::RowVector3d dlambda_dp = (lvec / lambda).transpose();
      const Eigen::RowVector3d dzeta_dp = o_.transpose();
      const Eigen::RowVector3d dtheta_dp =
          (-std::sin(theta) * dzeta_dp + std::cos(theta) * dlambda_dp) / upsilon;
      const Eigen::RowVector3d dchi_dp = dchi_dtheta * dtheta_dp;
      const Eigen::RowVector3d dzetap_dp = dlambda_dp / chi - lambda / chi2 * dchi_dp;
      const Eigen::RowVector3d dmu_dp = (2 * R_[1] * chi + 4 * R_[2] * chi2 * chi) * dchi_dp;
      dpp_dp = o_ * dzetap_dp + lvec * dmu_dp + (1.0 + mu) * P;
    }
  }
  const double a = pp.dot(A_);
  if (!(a > 0.0)) return false;
  const double x = pp.dot(H_) / a, y = pp.dot(V_) / a;
  *pixel = Eigen::Vector2d(x, y);
  if (J) {
    Eigen::Matrix<double, 2, 3> J_cahv;
    J_cahv.row(0) = (H_ - x * A_).transpose() / a;
    J_cahv.row(1) = (V_ - y * A_).transpose() / a;
    *J = J_cahv * dpp_dp;
  }
  return true;
}

void CahvoreCamera::BackProject(const Eigen::Vector2d& pixel, Eigen::Vector3d* origin,
                                Eigen::Vector3d* direction,
                                Eigen::Matrix<double, 3, 2>* J_dir) const {
  // The CAHV ray gives p' up to scale: p' = zeta' O + (1 + mu) lambda.
  Eigen::Vector3d rr = (V_ - pixel.y() * A_).cross(H_ - pixel.x() * A_);
  if (rr.dot(A_) < 0.0) rr = -rr;
  rr.normalize();
  const double omega = rr.dot(o_);
  const Eigen::Vector3d lp = rr - omega * o_;
  const double lpm = lp.norm();
  const double chip = lpm / omega;  // = chi (1 + mu(chi))

  // Newton for chi on chi (1 + R0 + R1 chi^2 + R2 chi^4) = chip.
  double chi = chip / (1.0 + R_[0]);
  double gprime = 1.0 + R_[0];
  for (int it = 0; it < 100; ++it) {
    const double c2 = chi * chi;
    gprime = 1.0 + R_[0] + c2 * (3 * R_[1] + c2 * 5 * R_[2]);
    const double step = (chi * (1.0 + R_[0] + c2 * (R_[1] + c2 * R_[2])) - chip) / gprime;
    chi -= step;
    if (std::abs(step) < 1e-16 * std::max(1.0, chi)) break;
  }
  const double c2 = chi * chi;
  gprime = 1.0 + R_[0] + c2 * (3 * R_[1] + c2 * 5 * R_[2]);
  const double theta = Theta(chi);
  const double st = std::sin(theta), ct = std::cos(theta), t2 = theta * theta;
  const double e = E_[0] + t2 * (E_[1] + t2 * E_[2]);
  const double shift = theta < 1e-8 ? 0.0 : (theta / st - 1.0) * e;
  if (origin) *origin = C_ + shift * o_;

  const bool on_axis = lpm < 1e-15;
  const Eigen::Vector3d w = on_axis ? Eigen::Vector3d::Zero() : Eigen::Vector3d(lp / lpm);
  const Eigen::Vector3d d = on_axis ? o_ : Eigen::Vector3d(ct * o_ + st * w);
  if (direction) *direction = d;
  if (J_dir) {
    const Eigen::Matrix<double, 3, 2> J_rr = CahvRayJacobian(rr, A_, H_, V_);
    const Eigen::Matrix3d P = Eigen::Matrix3d::Identity() - o_ * o_.transpose();
    const Eigen::Matrix<double, 3, 2> dlp = P * J_rr;
    if (on_axis) {
      // d ~ O + lp / (omega (1 + R0)) to first order.
      *J_dir = dlp / (omega * (1.0 + R_[0]));
      return;
    }
    const Eigen::RowVector2d domega = o_.transpose() * J_rr;
    const Eigen::RowVector2d dlpm = w.transpose() * dlp;
    const Eigen::RowVector2d dchip = dlpm / omega - lpm / (omega * omega) * domega;
    double dchi_dtheta = 0;
    Chi(theta, &dchi_dtheta);
    const Eigen::RowVector2d dtheta = dchip / gprime / dchi_dtheta;
    const Eigen::Matrix<double, 3, 2> dw = (Eigen::Matrix3d::Identity() - w * w.transpose()) * dlp / lpm;
    *J_dir = (ct * w - st * o_) * dtheta + st * dw;
  }
}

std::unique_ptr<CameraModel> CahvoreCamera::Scaled(double factor) const {
  const auto size = [factor](int s) { return std::max(1, static_cast<int>(std::lround(s * factor))); };
  return std::make_unique<CahvoreCamera>(size(width_), size(height_), C_, A_,
                                         ScaledCahvAxis(H_, A_, factor),
                                         ScaledCahvAxis(V_, A_, factor), O_, R_, E_, linearity_);
}

std::vector<double> CahvoreCamera::Params() const {
  std::vector<double> out;
  for (const Eigen::Vector3d* v : {&C_, &A_, &H_, &V_, &O_, &R_, &E_}) {
    out.insert(out.end(), v->data(), v->data() + 3);
  }
  out.push_back(linearity_);
  return out;
}

std::unique_ptr<CameraModel> CahvoreCamera::Clone() const {
  return std::make_unique<CahvoreCamera>(*this);
}

std::unique_ptr<CameraModel> CahvoreCamera::Moved(const Eigen::Isometry3d& T) const {
  // Through the constructor, so that the unit O and the angle limits follow (the limits
  // depend on R, E and L only, and come out the same).
  const Eigen::Matrix3d R = T.linear();
  return std::make_unique<CahvoreCamera>(width_, height_, T * C_, R * A_, R * H_, R * V_, R * O_, R_, E_,
                                         linearity_);
}

}  // namespace rover::geometry
