// JPL's CAHVORE camera model (Gennery 2006, "Generalized camera calibration including
// fish-eye lenses"): CAHVOR plus a moving entrance pupil (E) and a linearity L that spans
// perspective (L = 1), fish-eye (L = 0) and general lenses. Perseverance's NAVCAMs and
// Curiosity's hazcams carry it.
//
// Forward, with O normalised to unit length (labels round it):
//   p = X - C;  zeta = p.O;  lambda = p - zeta O;  find theta, the angle of the incoming
//   ray from O through the entrance pupil C + s O, s = (theta/sin theta - 1)(E0 + E1 t^2 +
//   E2 t^4), by Newton on  zeta sin(theta) - lambda cos(theta) - (theta - sin theta) E(theta) = 0;
//   chi = tan(L theta)/L (L > 0), theta (L = 0), sin(L theta)/L (L < 0);
//   mu = R0 + R1 chi^2 + R2 chi^4;  p' = (|lambda|/chi) O + (1 + mu) lambda;  then CAHV on p'.
// A label's model type T and parameter P give L: T=1 -> 1, T=2 -> 0, T=3 -> P
// (LinearityFromCahvoreType).
//
// The ray through a pixel starts at the entrance pupil, which moves along O with the
// off-axis angle: BackProject's origin depends on the pixel (Center() is C).
//
// Serialised parameters (Params()): C A H V O R E L, 22 numbers (O as given).
#pragma once

#include "geometry/camera_model.hpp"

namespace rover::geometry {

class CahvoreCamera : public CameraModel {
 public:
  // Throws std::invalid_argument on a non-positive size, non-finite vectors, a zero A or
  // O, or coplanar A, H, V.
  CahvoreCamera(int width, int height, Eigen::Vector3d C, Eigen::Vector3d A, Eigen::Vector3d H,
                Eigen::Vector3d V, Eigen::Vector3d O, Eigen::Vector3d R, Eigen::Vector3d E,
                double linearity);

  const Eigen::Vector3d& C() const { return C_; }
  const Eigen::Vector3d& A() const { return A_; }
  const Eigen::Vector3d& H() const { return H_; }
  const Eigen::Vector3d& V() const { return V_; }
  const Eigen::Vector3d& O() const { return O_; }  // as given
  const Eigen::Vector3d& R() const { return R_; }
  const Eigen::Vector3d& E() const { return E_; }
  double linearity() const { return linearity_; }

  std::string type() const override { return "cahvore"; }
  int width() const override { return width_; }
  int height() const override { return height_; }
  // Returns false when the entrance-pupil angle cannot be solved, when L theta reaches
  // 90 deg (L > 0), or past the angle where the radial map stops increasing.
  bool Project(const Eigen::Vector3d& p_ref, Eigen::Vector2d* pixel,
               Eigen::Matrix<double, 2, 3>* J = nullptr) const override;
  // Closed form through the CAHV ray, then Newton on the radial polynomial (as JPL's
  // cmod): the origin is the entrance pupil for that pixel.
  void BackProject(const Eigen::Vector2d& pixel, Eigen::Vector3d* origin,
                   Eigen::Vector3d* direction,
                   Eigen::Matrix<double, 3, 2>* J_dir = nullptr) const override;
  // H and V as for CAHV (CahvCamera::Scaled); O, R, E, L do not change.
  std::unique_ptr<CameraModel> Scaled(double factor) const override;
  Eigen::Vector3d Center() const override { return C_; }
  std::vector<double> Params() const override;
  std::unique_ptr<CameraModel> Clone() const override;
  // As for CAHVOR: C -> T C, A, H, V, O rotated; R, E and L (functions of the angle off O)
  // unchanged.
  std::unique_ptr<CameraModel> Moved(const Eigen::Isometry3d& T) const override;

 private:
  double Chi(double theta, double* dchi_dtheta) const;
  double Theta(double chi) const;

  int width_, height_;
  Eigen::Vector3d C_, A_, H_, V_, O_, R_, E_;
  double linearity_;
  Eigen::Vector3d o_;    // unit O
  double max_chi_;       // chi beyond which chi (1 + mu(chi)) stops increasing
  double max_theta_;     // and the corresponding (or the L theta < 90 deg) angle limit
};

// T (1 perspective, 2 fish-eye, 3 general) and P from a label -> linearity.
double LinearityFromCahvoreType(int T, double P);

}  // namespace rover::geometry
