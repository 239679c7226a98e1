// JPL's CAHV and CAHVOR camera models (Yakimovsky & Cunningham 1978; Gennery 2001), as
// carried in MER and MSL image labels.
//
//   CAHV:   p = X - C;  x = (p.H)/(p.A);  y = (p.V)/(p.A)
//   CAHVOR: w = p.O;  l = p - w O;  tau = (l.l)/w^2;  mu = R0 + R1 tau + R2 tau^2;
//           p' = p + mu l;  then CAHV on p'.
//
// The vectors are used exactly as given (A, H, V, O are not normalised): label A vectors
// are off unit length by up to ~1e-6, and normalising A moves pixels by up to 8.6e-3 px on
// real Spirit models (their PDS label vectors). The reference frame is the frame of
// the vectors (the rover frame for a label's rover-frame model). Pixels follow
// camera_model.hpp: (0,0) is the centre of the top-left pixel.
//
// Serialised parameters (Params()): C A H V (12 numbers) and C A H V O R (18 numbers).
#pragma once

#include "geometry/camera_model.hpp"

namespace rover::geometry {

class PinholeCamera;

class CahvCamera : public CameraModel {
 public:
  // Throws std::invalid_argument on a non-positive size, non-finite vectors or a zero A.
  CahvCamera(int width, int height, Eigen::Vector3d C, Eigen::Vector3d A, Eigen::Vector3d H,
             Eigen::Vector3d V);

  const Eigen::Vector3d& C() const { return C_; }
  const Eigen::Vector3d& A() const { return A_; }
  const Eigen::Vector3d& H() const { return H_; }
  const Eigen::Vector3d& V() const { return V_; }

  std::string type() const override { return "cahv"; }
  int width() const override { return width_; }
  int height() const override { return height_; }
  // Returns false when (X - C).A <= 0.
  bool Project(const Eigen::Vector3d& p_ref, Eigen::Vector2d* pixel,
               Eigen::Matrix<double, 2, 3>* J = nullptr) const override;
  // Closed form: the ray is (V - yA) x (H - xA), oriented so that ray.A > 0.
  void BackProject(const Eigen::Vector2d& pixel, Eigen::Vector3d* origin,
                   Eigen::Vector3d* direction,
                   Eigen::Matrix<double, 3, 2>* J_dir = nullptr) const override;
  // H' = s H + (s - 1)/2 A, V' likewise: JPL's resampling H' = s H, V' = s V, shifted so
  // that x' = s (x + 0.5) - 0.5 keeps pixel centres on pixel centres.
  std::unique_ptr<CameraModel> Scaled(double factor) const override;
  Eigen::Vector3d Center() const override { return C_; }
  std::vector<double> Params() const override;
  std::unique_ptr<CameraModel> Clone() const override;
  // C -> T C; A, H, V rotated by T's rotation (p.A, p.H, p.V are unchanged for p = X - C).
  std::unique_ptr<CameraModel> Moved(const Eigen::Isometry3d& T) const override;

 private:
  int width_, height_;
  Eigen::Vector3d C_, A_, H_, V_;
};

class CahvorCamera : public CameraModel {
 public:
  // R = (R0, R1, R2). Throws std::invalid_argument on a non-positive size, non-finite
  // vectors, or a zero A or O.
  CahvorCamera(int width, int height, Eigen::Vector3d C, Eigen::Vector3d A, Eigen::Vector3d H,
               Eigen::Vector3d V, Eigen::Vector3d O, Eigen::Vector3d R);

  const Eigen::Vector3d& C() const { return C_; }
  const Eigen::Vector3d& A() const { return A_; }
  const Eigen::Vector3d& H() const { return H_; }
  const Eigen::Vector3d& V() const { return V_; }
  const Eigen::Vector3d& O() const { return O_; }
  const Eigen::Vector3d& R() const { return R_; }

  std::string type() const override { return "cahvor"; }
  int width() const override { return width_; }
  int height() const override { return height_; }
  // Returns false when (X - C).A <= 0 or (X - C).O <= 0, or beyond the off-axis angle
  // where the radial term stops increasing (there the model folds back on itself).
  bool Project(const Eigen::Vector3d& p_ref, Eigen::Vector2d* pixel,
               Eigen::Matrix<double, 2, 3>* J = nullptr) const override;
  // The exact inverse of Project: Newton on the ray direction from the CAHV ray, to
  // 1e-12 px. (JPL's cmod uses a radial Newton that assumes |O| = 1; label O vectors are
  // off unit length by up to 1e-5, which changes rays by ~1e-11 rad.)
  void BackProject(const Eigen::Vector2d& pixel, Eigen::Vector3d* origin,
                   Eigen::Vector3d* direction,
                   Eigen::Matrix<double, 3, 2>* J_dir = nullptr) const override;
  // H and V as for CAHV; O and R live in 3-D and do not change.
  std::unique_ptr<CameraModel> Scaled(double factor) const override;
  Eigen::Vector3d Center() const override { return C_; }
  std::vector<double> Params() const override;
  std::unique_ptr<CameraModel> Clone() const override;
  // As for CAHV, with O rotated too; R (radial, in the angle off O) does not change.
  std::unique_ptr<CameraModel> Moved(const Eigen::Isometry3d& T) const override;

 private:
  int width_, height_;
  Eigen::Vector3d C_, A_, H_, V_, O_, R_;
  double max_tau_;  // tau beyond which the radial map stops increasing
};

// The CAHV model that projects exactly as an undistorted pinhole:
//   C = t, A = R e_z, H = fx R e_x + cx A, V = fy R e_y + cy A, with (R, t) = T_ref_cam.
// Throws std::invalid_argument if the pinhole has distortion (CAHV cannot carry it).
CahvCamera CahvFromPinhole(const PinholeCamera& pinhole);

// Scaled H or V for a resampling by `factor` (see CahvCamera::Scaled).
Eigen::Vector3d ScaledCahvAxis(const Eigen::Vector3d& H_or_V, const Eigen::Vector3d& A,
                               double factor);

}  // namespace rover::geometry
