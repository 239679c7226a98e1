// The checks that refuse an estimate (VO-10: the prior stays in force): VO-11 the rover's
// shadow, VO-10 a motion too large for the overlap, VO-9 the sanity limits, VO-12
// degenerate geometry.
#include "geometry/pose.hpp"
#include "vo/vo_state.hpp"

#include <Eigen/Eigenvalues>

namespace rover::vo {

// VO-11: features fixed in the image (the rover's own shadow) carrying RANSAC's winner.
bool VisualOdometry::State::CheckShadow(Step* st) {
  const std::vector<int>& inliers = st->rs.inliers;
  int fixed_inliers = 0;
  for (int k : inliers) fixed_inliers += st->fixed[k];
  if (2 * fixed_inliers <= static_cast<int>(inliers.size())) return true;
  // The winning motion rests on image-fixed features. If the other features agree on
  // a different motion, the two explanations compete: refuse rather than guess.
  const int n = static_cast<int>(st->corr.size());
  std::vector<char> in(n, 0);
  for (int k : inliers) in[k] = 1;
  std::vector<int> rest;
  for (int k = 0; k < n; ++k) {
    if (!in[k] && !st->fixed[k]) rest.push_back(k);
  }
  if (static_cast<int>(rest.size()) < o.min_inliers) return true;
  const RansacOutcome alt = RansacMotion(st->corr, st->c->rig, st->ransac, rest);
  if (static_cast<int>(alt.inliers.size()) < o.min_inliers) return true;
  st->res.times.ransac_ms = Ms(st->t, Clock::now());
  return st->Stop(VoStatus::kShadowAmbiguous,
                  Format("%.0f inliers fixed in the image against %.0f features moving otherwise",
                         fixed_inliers, alt.inliers.size()));
}

// VO-10 on the estimate (re-initialises like the check on the prior), then VO-9.
bool VisualOdometry::State::CheckSanity(Step* st) {
  const Eigen::Isometry3d& T = st->ml.T_prev_curr;
  const Eigen::Vector3d dt = T.translation();
  const Eigen::Vector3d drpy = geometry::RpyFromRotation(T.linear());
  const double angle = Eigen::AngleAxisd(T.linear()).angle();
  if (o.motion_max_translation_m > 0 && dt.norm() > o.motion_max_translation_m) {
    return st->Refuse(VoStatus::kMotionTooLarge, Format("step %.3f m exceeds %.3f m; re-initialised",
                                                        dt.norm(), o.motion_max_translation_m));
  }
  if (o.motion_max_rotation_deg > 0 && angle > o.motion_max_rotation_deg * kDeg) {
    return st->Refuse(VoStatus::kMotionTooLarge, Format("turn %.1f deg exceeds %.1f deg; re-initialised",
                                                        angle / kDeg, o.motion_max_rotation_deg));
  }
  if (o.sanity_max_translation_m > 0 && dt.norm() > o.sanity_max_translation_m) {
    return st->Refuse(VoStatus::kSanityFailed,
                      Format("update %.3f m exceeds %.3f m", dt.norm(), o.sanity_max_translation_m));
  }
  const char* axis[3] = {"roll", "pitch", "yaw"};
  const double limit_deg[3] = {o.sanity_max_roll_deg, o.sanity_max_pitch_deg, o.sanity_max_yaw_deg};
  for (int i = 0; i < 3; ++i) {
    if (limit_deg[i] > 0 && std::abs(drpy[i]) > limit_deg[i] * kDeg) {
      return st->Refuse(VoStatus::kSanityFailed,
                        std::string(axis[i]) + Format(" update %.2f deg exceeds %.2f deg",
                                                      std::abs(drpy[i]) / kDeg, limit_deg[i]));
    }
  }
  return !st->images.R_site_ref || CheckSiteFrame(st);
}

// VO-9's limits in the site frame (they need the rig's attitude at capture).
bool VisualOdometry::State::CheckSiteFrame(Step* st) {
  const Eigen::Matrix3d& R_site_ref = *st->images.R_site_ref;
  const Eigen::Vector3d dt = st->ml.T_prev_curr.translation();
  const Eigen::Vector3d site = R_site_ref * dt;
  if (o.sanity_max_site_dx_m > 0 && std::abs(site.x()) > o.sanity_max_site_dx_m) {
    return st->Refuse(VoStatus::kSanityFailed,
                      Format("site X update %.3f m exceeds %.3f m", site.x(), o.sanity_max_site_dx_m));
  }
  if (o.sanity_max_site_dy_m > 0 && std::abs(site.y()) > o.sanity_max_site_dy_m) {
    return st->Refuse(VoStatus::kSanityFailed,
                      Format("site Y update %.3f m exceeds %.3f m", site.y(), o.sanity_max_site_dy_m));
  }
  if (o.sanity_max_downslope_angle_deg > 0 && site.norm() > 0.01) {
    // Downslope: gravity (site +Z) projected on the ground plane, whose normal is the
    // reference frame's z axis (rover frame, Z down).
    const Eigen::Vector3d normal = R_site_ref.col(2);
    const Eigen::Vector3d g(0, 0, 1);
    const Eigen::Vector3d down = g - g.dot(normal) * normal;
    if (down.norm() > std::sin(2.0 * kDeg)) {
      const double a = std::acos(std::clamp(site.normalized().dot(down.normalized()), -1.0, 1.0));
      if (a > o.sanity_max_downslope_angle_deg * kDeg) {
        return st->Refuse(VoStatus::kSanityFailed,
                          Format("update is %.1f deg from downslope (limit %.1f deg)", a / kDeg,
                                 o.sanity_max_downslope_angle_deg));
      }
    }
  }
  return true;
}

// VO-12: inliers clustered in the image, or a motion the covariance leaves poorly determined.
bool VisualOdometry::State::CheckGeometry(Step* st) {
  const Pair& c = *st->c;
  const std::vector<int>& inliers = st->inliers;
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (int k : inliers) mean += st->corr[k].left;
  mean /= double(inliers.size());
  Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
  for (int k : inliers) scatter += (st->corr[k].left - mean) * (st->corr[k].left - mean).transpose();
  scatter /= double(inliers.size());
  const Eigen::Vector2d ev = scatter.selfadjointView<Eigen::Upper>().eigenvalues().cwiseMax(0.0);
  const double side = std::min(c.width, c.height);
  const double spread = std::sqrt(ev.minCoeff()) / side;  // across the inliers' narrowest direction
  const double patch = std::sqrt(std::sqrt(ev(0) * ev(1))) / side;  // the geometric mean of both
  if (spread < o.degenerate_min_spread) {
    return st->Refuse(VoStatus::kDegenerate, Format("inliers clustered: spread %.3f of the image (need %.3f)",
                                                    spread, o.degenerate_min_spread));
  }
  if (patch < o.degenerate_min_patch_spread) {
    return st->Refuse(VoStatus::kDegenerate,
                      Format("inliers clustered in one patch: spread %.3f by %.3f of the image", spread,
                             std::sqrt(ev.maxCoeff()) / side) +
                          Format(" (geometric mean %.3f, need %.3f)", patch, o.degenerate_min_patch_spread));
  }
  const Matrix6d& cov = st->res.covariance;
  const double sigma_t = std::sqrt(cov.topLeftCorner<3, 3>().trace());
  const double sigma_r = std::sqrt(cov.bottomRightCorner<3, 3>().trace());
  if (o.degenerate_max_translation_sigma_m > 0 && sigma_t > o.degenerate_max_translation_sigma_m) {
    return st->Refuse(VoStatus::kDegenerate, Format("translation poorly determined: sigma %.3f m (limit %.3f m)",
                                                    sigma_t, o.degenerate_max_translation_sigma_m));
  }
  if (o.degenerate_max_rotation_sigma_deg > 0 && sigma_r > o.degenerate_max_rotation_sigma_deg * kDeg) {
    return st->Refuse(VoStatus::kDegenerate, Format("rotation poorly determined: sigma %.2f deg (limit %.2f deg)",
                                                    sigma_r / kDeg, o.degenerate_max_rotation_sigma_deg));
  }
  return true;
}

}  // namespace rover::vo
