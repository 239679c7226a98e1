#include "vo/motion_prior.hpp"

#include <algorithm>
#include <cmath>

namespace rover::vo {

MotionPriorOptions LoadMotionPriorOptions(const config::ConfigNode& section) {
  MotionPriorOptions o;
  section.Get("translation_sigma_fraction", o.translation_sigma_fraction, 0.0, 10.0);
  section.Get("min_translation_sigma_m", o.min_translation_sigma_m, 0.0, 10.0);
  section.Get("rotation_sigma_fraction", o.rotation_sigma_fraction, 0.0, 10.0);
  section.Get("min_rotation_sigma_deg", o.min_rotation_sigma_deg, 0.0, 90.0);
  return o;
}

Eigen::Matrix<double, 6, 6> MotionPriorCovariance(const Eigen::Isometry3d& T_prev_curr,
                                                  const MotionPriorOptions& o) {
  const double t_sigma =
      std::max(o.min_translation_sigma_m, o.translation_sigma_fraction * T_prev_curr.translation().norm());
  const double r_sigma = std::max(o.min_rotation_sigma_deg * M_PI / 180.0,
                                  o.rotation_sigma_fraction * Eigen::AngleAxisd(T_prev_curr.linear()).angle());
  Eigen::Matrix<double, 6, 6> cov = Eigen::Matrix<double, 6, 6>::Zero();
  cov.diagonal() << t_sigma * t_sigma, t_sigma * t_sigma, t_sigma * t_sigma, r_sigma * r_sigma,
      r_sigma * r_sigma, r_sigma * r_sigma;
  return cov;
}

}  // namespace rover::vo
