// VO-6 tracking: the reference pair's features are projected into the new left image
// through the motion prior, searched for by correlation in a window sized from the
// prior's uncertainty, matched in the new right image within the disparity their 3-D
// position allows, and dropped when their 3-D positions disagree with the prior. VO-10
// checks the prior and the tracking's outcome.
#include "geometry/pose.hpp"
#include "vo/vo_state.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

namespace rover::vo {

namespace {

// The prior as tracking uses it: a reference point P is R_cp (P - t) in the new frame;
// dR are the prior rotation's derivatives by roll, pitch and yaw.
struct PriorMap {
  PriorMap(const Eigen::Isometry3d& T_ref_cur, const Matrix6d& covariance_)
      : t(T_ref_cur.translation()), covariance(covariance_) {
    const Eigen::Matrix3d R_pc = T_ref_cur.linear();
    const Eigen::Vector3d rpy = geometry::RpyFromRotation(R_pc);
    geometry::RotationFromRpyDerivatives(rpy, nullptr, dR);
    R_cp = R_pc.transpose();
  }
  Eigen::Vector3d t;
  Eigen::Matrix3d R_cp;
  Eigen::Matrix3d dR[3];
  const Matrix6d& covariance;
};

// False when the feature falls outside the new image's usable part (or behind it).
bool Predict(const Feature& f, const PriorMap& prior, const Pair& c, const VoOptions& o, Prediction* p) {
  const Eigen::Vector3d d = f.P - prior.t;
  p->P = prior.R_cp * d;
  Eigen::Matrix<double, 3, 6> Jm;
  Jm.leftCols<3>() = -prior.R_cp;
  for (int i = 0; i < 3; ++i) Jm.col(3 + i) = prior.dR[i].transpose() * d;
  p->Sigma = prior.R_cp * f.Sigma * prior.R_cp.transpose() + Jm * prior.covariance * Jm.transpose();
  Eigen::Matrix<double, 2, 3> Jp;
  if (!c.rig.left->Project(p->P, &p->u, &Jp)) return false;
  const int border = o.feature_border_px;
  if (p->u.x() < border || p->u.y() < border || p->u.x() > c.width - 1 - border ||
      p->u.y() > c.height - 1 - border) {
    return false;
  }
  const Eigen::Matrix2d Sigma_u = Jp * p->Sigma * Jp.transpose();
  const double sigma_u = std::sqrt(std::max(0.0, Sigma_u.selfadjointView<Eigen::Upper>().eigenvalues().maxCoeff()));
  p->radius = std::clamp(static_cast<int>(std::ceil(o.track_window_sigmas * sigma_u)),
                         o.track_min_radius_px, o.track_max_radius_px);
  return true;
}

// The change of perspective the prior predicts round the feature, for the ground plane
// through it (the reference rover's x and y axes): d(new pixel) = A d(reference pixel),
// and p->warp = A^-1. Left unwarped when either view sees that plane edge-on or the
// change is implausible (a scale outside 1/2 to 2).
void PredictWarp(const Feature& f, const PriorMap& prior, const Pair& ref, const Pair& c, Prediction* p) {
  Eigen::Vector2d u;
  Eigen::Matrix<double, 2, 3> J_ref, J_cur;
  if (!ref.rig.left->Project(f.P, &u, &J_ref) || !c.rig.left->Project(p->P, &u, &J_cur)) return;
  Eigen::Matrix<double, 3, 2> ground = Eigen::Matrix<double, 3, 2>::Zero();
  ground(0, 0) = ground(1, 1) = 1.0;
  const Eigen::Matrix2d D_ref = J_ref * ground;
  const Eigen::Matrix2d D_cur = J_cur * prior.R_cp * ground;
  if (std::abs(D_ref.determinant()) < 1e-9 * D_ref.squaredNorm()) return;
  const Eigen::Matrix2d A = D_cur * D_ref.inverse();
  const double det = A.determinant();
  if (!std::isfinite(det) || det < 0.25 || det > 4.0) return;
  p->warp = A.inverse();
  p->warped = true;
}

}  // namespace

bool VisualOdometry::State::CheckPriorMotion(Step* st) {
  const Eigen::Vector3d prior_t = st->prior_ref.translation();
  const double prior_angle = Eigen::AngleAxisd(st->prior_ref.linear()).angle();
  if (o.motion_max_translation_m > 0 && prior_t.norm() > o.motion_max_translation_m) {
    return st->Stop(VoStatus::kMotionTooLarge,
                    Format("prior step %.3f m exceeds %.3f m; re-initialised", prior_t.norm(),
                           o.motion_max_translation_m));
  }
  if (o.motion_max_rotation_deg > 0 && prior_angle > o.motion_max_rotation_deg * kDeg) {
    return st->Stop(VoStatus::kMotionTooLarge,
                    Format("prior turn %.1f deg exceeds %.1f deg; re-initialised",
                           prior_angle / kDeg, o.motion_max_rotation_deg));
  }
  return true;
}

void VisualOdometry::State::TrackFeatures(Step* st) {
  const Pair& ref = *st->ref;
  const Pair& c = *st->c;
  const PriorMap prior(st->prior_ref, st->prior_covariance);
  const int levels = static_cast<int>(std::min(ref.left_band.size(), c.left_band.size()));
  const int n = static_cast<int>(ref.features.size());
  std::vector<Correspondence> tracked(n);
  std::vector<char> ok(n, 0), fixed(n, 0);
  if (Windowed()) st->carried.resize(n);
  double stereo_ms = 0;
  const auto at = [&](int i) { return ref.features[i].left; };
  for (const int fi : TopToBottom(n, at)) {
    Prediction p;
    if (!Predict(ref.features[fi], prior, c, o, &p)) continue;
    if (o.track_warp_template) PredictWarp(ref.features[fi], prior, ref, c, &p);
    ++st->predicted_inside;
    ok[fi] = TrackFeature(*st, fi, p, levels, &stereo_ms, &tracked[fi],
                          Windowed() ? &st->carried[fi] : nullptr, &fixed[fi]);
  }
  st->corr.reserve(n);
  st->fixed.reserve(n);
  for (int i = 0; i < n; ++i) {
    if (!ok[i]) continue;
    st->corr.push_back(tracked[i]);
    st->corr_source.push_back(i);
    TrackedFeature t;
    t.prev_left = ref.features[i].left;
    t.curr_left = tracked[i].left;
    t.prev_right = ref.features[i].right;
    t.curr_right = tracked[i].right;
    t.track_id = ref.features[i].track_id;
    st->res.tracks.push_back(t);
    st->fixed.push_back(fixed[i]);
  }
  st->res.num_tracked = static_cast<int>(st->corr.size());
  const auto now = Clock::now();
  st->res.times.track_ms = Ms(st->t, now) - stereo_ms;
  st->res.times.stereo_ms += stereo_ms;
  st->t = now;
}

// One feature of the reference pair found again: its correspondence, (windowed mode) the
// feature as seen now, and whether it stayed put in the image while predicted to move.
bool VisualOdometry::State::TrackFeature(const Step& st, int fi, const Prediction& p, int levels,
                                         double* stereo_ms, Correspondence* x, Feature* seen,
                                         char* fixed) {
  const Feature& f = st.ref->features[fi];
  const Pair& c = *st.c;
  MatchResult m;
  if (!SearchTracked(f, *st.ref, c, p, levels, &m)) return false;
  Eigen::Vector2d right;
  Eigen::Matrix2d Sigma_right;
  if (!MatchTrackedStereo(c, p, m.position, stereo_ms, &right, &Sigma_right)) return false;
  StereoPoint sp;
  Eigen::Matrix<double, 3, 4> J;
  if (!TriangulateStereo(c.rig, m.position, m.covariance, right, Sigma_right, Limits(c), &sp, &J,
                         StereoCarry())) {
    return false;
  }
  // Drop features whose 3-D positions disagree beyond their uncertainty (VO-6).
  const Eigen::Vector3d diff = sp.P - p.P;
  const Eigen::Matrix3d S = sp.Sigma + p.Sigma;
  if (o.track_max_chi2 > 0 && diff.dot(S.ldlt().solve(diff)) > o.track_max_chi2) return false;
  x->P_prev = f.P;
  // The reference's left error is repeated by this match (VO-6 cut the template there),
  // so the two points share it; the residual sees only what it does not repeat.
  x->Sigma_prev = f.Sigma_uncarried;
  x->P_curr = sp.P;
  x->Sigma_curr = sp.Sigma;
  x->left = m.position;
  x->right = right;
  // The right match follows the left one (its template is cut at the left match), so a
  // shift of the match moves both; a disparity offset moves the right one only.
  x->dPcurr_dshift.col(0) = J.col(0) + J.col(2);
  x->dPcurr_dshift.col(1) = J.col(1) + J.col(3);
  x->dPcurr_ddisparity = J.col(2);
  x->dPprev_ddisparity = f.dP_ddisparity;
  if (seen) {
    *seen = MakeFeature(m.position, m.covariance, right, Sigma_right, sp, J, TrackCarry(), StereoCarry());
    seen->track_id = f.track_id;
    seen->age = f.age + 1;
  }
  *fixed = (m.position - f.left).norm() < o.shadow_fixed_px &&
           (p.u - f.left).norm() > o.shadow_min_predicted_px;
  return true;
}

// The feature's template searched for in the new left image around its prediction.
bool VisualOdometry::State::SearchTracked(const Feature& f, const Pair& from, const Pair& to,
                                          const Prediction& p, int levels, MatchResult* out) {
  int L = 0;
  while (L + 1 < levels && p.radius > o.track_coarse_radius_px * (1 << L)) ++L;
  // Coarse to fine: search the whole window at level L, then +-2 px at each finer one.
  int bx = 0, by = 0;
  float score = 0;
  bool ok = true;
  for (int l = L; l >= 0 && ok; --l) {
    const int tx = static_cast<int>(std::lround(ToLevel(f.left.x(), l)));
    const int ty = static_cast<int>(std::lround(ToLevel(f.left.y(), l)));
    const int side = l == 0 ? o.match_template_px : o.track_coarse_template_px;
    // A track's position is sub-pixel: its template is cut at the nearest pixel (not
    // resampled, which would blur it a little more every pair) and the match moved by
    // the same sub-pixel offset afterwards; a warped one is resampled at the position.
    const bool warp = l == 0 && p.warped;
    if (!(warp ? tmpl.ExtractWarped(from.left_band[0], f.left.x(), f.left.y(), p.warp, side)
               : tmpl.Extract(from.left_band[l], tx, ty, side))) {
      ok = false;
      break;
    }
    int cx, cy, r;
    if (l == L) {
      cx = static_cast<int>(std::lround(ToLevel(p.u.x(), l)));
      cy = static_cast<int>(std::lround(ToLevel(p.u.y(), l)));
      r = (p.radius + (1 << l) - 1) >> l;
    } else {
      cx = 2 * bx;
      cy = 2 * by;
      r = 2;
    }
    ok = correlator.SearchWindow(tmpl, to.left_band[l], cx - r, cx + r, cy - r, cy + r, &bx, &by, &score);
  }
  if (!ok || score < o.track_min_score) return false;
  MatchResult m = Correlator::Refine(tmpl, to.left_band[0], bx, by, o.match_covariance_scale, o.match_min_sigma_px);
  if (!m.ok || m.score < o.track_min_score) return false;
  correlator.Iterate(tmpl, to.left_band[0], o.match_subpixel_iterations, o.match_covariance_scale,
                     o.match_min_sigma_px, &m);
  if (!p.warped) m.position += f.left - Eigen::Vector2d(std::lround(f.left.x()), std::lround(f.left.y()));
  *out = m;
  return true;
}

// Stereo match of a tracked feature, its disparity narrowed by the known 3-D position
// (VO-6). Times itself into *stereo_ms once the template is cut.
bool VisualOdometry::State::MatchTrackedStereo(const Pair& c, const Prediction& p,
                                               const Eigen::Vector2d& left, double* stereo_ms,
                                               Eigen::Vector2d* right, Eigen::Matrix2d* Sigma_right) {
  const auto t0 = Clock::now();
  if (!tmpl.ExtractSubpixel(c.left_band[0], left.x(), left.y(), o.match_template_px)) return false;
  Eigen::Vector3d C1, r1;
  c.rig.left->BackProject(left, &C1, &r1);
  const double range = (p.P - C1).dot(r1);
  const double sigma_range = std::sqrt(std::max(0.0, r1.dot(p.Sigma * r1)));
  const double near = std::max(o.stereo_min_range_m, range - o.track_window_sigmas * sigma_range);
  const double far = std::min(c.far_range, range + o.track_window_sigmas * sigma_range);
  const bool matched =
      far > near && MatchRight(c, C1, r1, near, far, o.track_stereo_margin_px, nullptr, right, Sigma_right);
  *stereo_ms += Ms(t0, Clock::now());
  return matched;
}

bool VisualOdometry::State::CheckTracks(Step* st) {
  const double overlap = double(st->predicted_inside) / double(st->ref->features.size());
  if (overlap < o.motion_min_overlap) {
    return st->Stop(VoStatus::kMotionTooLarge,
                    Format("prior leaves %.0f %% of features in view (need %.0f %%); re-initialised",
                           100 * overlap, 100 * o.motion_min_overlap));
  }
  if (st->res.num_tracked < o.min_tracked) {
    return st->Stop(VoStatus::kTooFewMatches,
                    Format("%.0f features tracked (need %.0f)", st->res.num_tracked, o.min_tracked));
  }
  return true;
}

}  // namespace rover::vo
