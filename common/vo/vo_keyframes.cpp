// Windowed mode (README "VO with memory"): an accepted pair becomes a keyframe or is
// measured against the last one and forgotten; a keyframe's tracks live on, and the
// sliding window refines the last keyframes' poses before the delta is published.
#include "geometry/pose.hpp"
#include "vo/vo_state.hpp"

#include <Eigen/Cholesky>

#include <algorithm>

namespace rover::vo {

namespace {

// The refined delta's covariance, built as VO-13 builds a pair's: the window's own
// (WindowSolution::covariance: its inverse reduced normal matrix, with the previous pose's
// correction when it is carried, in the units of the match covariances) scaled by the
// pair's variance factor (the larger of s0^2 and the cluster factor), plus the errors the
// pair's features share, which no fit sees (SharedErrors). Before the tracker warped its
// templates (VO-6, track_warp_template) tracked features carried a lag that every pair of
// a track shared, and this covariance was overconfident on rendered sand (NEES 35); the
// pair's own covariance was published instead, and with the lag gone that one overstated
// the error (rendered NEES 2.6-3.4).
// False when the window's step disagrees with the pair's estimate of it beyond max_chi2,
// judged under the covariance of their difference (NestedDifferenceChi2: the window holds
// the pair's data, so that difference is the pair's covariance minus the window's). The
// pair's covariance alone let through windows that claimed more than their data gave:
// on rendered rock fields 4 % of the published window deltas lay beyond the 99.7 % NEES
// bound (errors that a track's observations share from pair to pair, which the window
// counts as independent). A window that holds a disparity offset (the drive-wide filter's)
// differs from the pair, which holds none, by the pair's response to it: that response
// (MotionUncertainty::disparity_sensitivity times the offset) joins the pair's covariance
// for the test. Without it KITTI 06's 0.16 px offset failed 46 of 50 windows.
bool RefinedCovariance(const WindowSolution& w, const MotionUncertainty& u,
                       const Eigen::Isometry3d& T_ref_cur, const Matrix6d& pair_cov, double max_chi2,
                       double min_fraction, bool carried_errors, bool covariance_carried,
                       double min_published_factor, double factor_alpha, Matrix6d* out) {
  // When the window models errors carried along a track (window_track_carry or
  // window_stereo_carry above 0) its fit is scaled by the larger of the pair's factors and
  // its own (the variance factor of the window's residuals under that model: the pair's
  // s0^2 sees two keyframes, the window's every keyframe a track was seen in). VO-8 takes
  // the same carries (MakeFeature, TriangulateStereo); replayed over 8 navbench runs with
  // carries 0 and 1, 1.8 % of the updates lay beyond the 99.7 % bound without the window's
  // factor, 0.7 % with it.
  // The published covariance may be under a carry model of its own (a sandwich,
  // window_covariance_track_carry, window_covariance_stereo_carry): it is scaled the same
  // way, by the window's variance factor under that model (the cost over its expectation
  // when the errors follow it), since the sandwich is linear in the matches' covariances
  // and that factor is what scales them. The consistency test below stays under the
  // weights' model, as the pair's VO-8 covariance is.
  const double factor =
      std::max({u.variance_factor, u.cluster_factor, carried_errors ? w.variance_factor : 0.0});
  const double published_factor = PublishedWindowFactor(u, w, covariance_carried, min_published_factor, factor_alpha);
  Matrix6d cov = published_factor * w.covariance + u.shared;
  cov = 0.5 * (cov + cov.transpose()).eval();
  const geometry::Vector6d a = geometry::XyzRpyFromPose(w.T_prev_last);
  const geometry::Vector6d b = geometry::XyzRpyFromPose(T_ref_cur);
  geometry::Vector6d d = a - b;
  for (int i = 3; i < 6; ++i) d(i) = geometry::WrapAngle(d(i));
  const geometry::Vector6d offset_response = u.disparity_sensitivity * w.disparity_offset_px;
  const Matrix6d pair_with_offset = pair_cov + offset_response * offset_response.transpose();
  const double chi2 =
      NestedDifferenceChi2(d, factor * w.fit_step_covariance + u.shared, pair_with_offset, min_fraction);
  if (cov.allFinite() && (max_chi2 <= 0 || chi2 <= max_chi2)) {
    *out = cov;
    return true;
  }
  return false;
}

}  // namespace

double PublishedWindowFactor(const MotionUncertainty& pair, const WindowSolution& window,
                             bool covariance_carried, double min_factor, double factor_alpha) {
  return std::max({VarianceFactorUpperBound(pair.variance_factor, pair.redundancy, factor_alpha), pair.cluster_factor,
                   covariance_carried ? window.covariance_variance_factor : 0.0, min_factor});
}

std::vector<WindowObservation> Observations(const Pair& pair) {
  std::vector<WindowObservation> obs;
  obs.reserve(pair.features.size());
  for (const Feature& f : pair.features) {
    obs.push_back({f.track_id, f.left, f.right, f.Sigma_left, f.Sigma_right, f.P, f.Sigma});
  }
  return obs;
}

void VisualOdometry::State::RestartWindow(Pair* pair) {
  window.Reset();
  window.AddFrame(pair->frame_id, Eigen::Isometry3d::Identity(), Observations(*pair));
  T_w_last = Eigen::Isometry3d::Identity();
  last_ref_cov.setZero();
}

// An accepted measurement of the new pair against the reference pair (res.T_prev_curr,
// covariance res.covariance): keyframe or not, the window's refinement, and the delta
// from the last call's pair.
void VisualOdometry::State::Accept(Step* st) {
  VoResult* res = &st->res;
  const std::vector<int>& inliers = st->inliers;
  const auto track = [&](int k) -> const Feature& {
    return st->carried[static_cast<std::size_t>(st->corr_source[static_cast<std::size_t>(k)])];
  };
  const Eigen::Isometry3d T_ref_cur = res->T_prev_curr;
  const Matrix6d pair_cov = res->covariance;
  double age_sum = 0;
  for (int k : inliers) {
    age_sum += track(k).age;
    res->track_length_max = std::max(res->track_length_max, track(k).age);
  }
  res->track_length_mean = inliers.empty() ? 0.0 : age_sum / double(inliers.size());
  const double moved = T_ref_cur.translation().norm();
  const double turned = Eigen::AngleAxisd(T_ref_cur.linear()).angle();
  // A pair that moved too little is measured against the reference and forgotten; one
  // that kept too few of the reference's features becomes a keyframe anyway.
  const bool keyframe = moved >= o.keyframe_min_translation_m || turned >= o.keyframe_min_rotation_deg * kDeg ||
                        2 * static_cast<int>(inliers.size()) < static_cast<int>(st->ref->features.size());
  res->keyframe = keyframe;
  const Eigen::Isometry3d T_w_ref = window.pose(window.size() - 1);
  if (!keyframe) {
    const Eigen::Isometry3d T_w_cur = T_w_ref * T_ref_cur;
    res->T_prev_curr = T_w_last.inverse() * T_w_cur;
    T_w_last = T_w_cur;
    // Both pairs are measured against the reference: the delta holds both errors. Their
    // sum bounds it (the reference's share cancels), which keeps the NEES honest.
    res->covariance = pair_cov + last_ref_cov;
    last_ref_cov = pair_cov;
    prev = std::move(st->ref);
    spare = std::move(st->cur);
    res->window_frames = window.size();
    return;
  }
  // The tracks VO-8 used live on; detection tops them up.
  std::vector<Feature> tracks;
  tracks.reserve(inliers.size());
  for (int k : inliers) tracks.push_back(track(k));
  CompleteFeatures(st->cur.get(), std::move(tracks), res);
  RefineWindow(st, T_w_ref, T_ref_cur, pair_cov);
}

// A keyframe joins the window, which is refined; its delta is published if it agrees with
// the pair's, else the pair's own and the window restarts on the new pair.
void VisualOdometry::State::RefineWindow(Step* st, const Eigen::Isometry3d& T_w_ref,
                                         const Eigen::Isometry3d& T_ref_cur, const Matrix6d& pair_cov) {
  VoResult* res = &st->res;
  Pair* cur = st->cur.get();
  const auto t0 = Clock::now();
  window.AddFrame(st->images.frame_id, T_w_ref * T_ref_cur, Observations(*cur));
  const WindowSolution w = window.Refine(cur->rig);
  res->window_frames = window.size();
  res->window_points = w.points;
  res->window_iterations = w.iterations;
  res->disparity_offset_px = w.disparity_offset_px;
  res->window_variance_factor = w.variance_factor;
  res->window_covariance_variance_factor = w.covariance_variance_factor;
  Matrix6d cov;
  const bool used = w.ok && RefinedCovariance(w, st->u, T_ref_cur, pair_cov, o.window_max_chi2,
                                               o.window_consistency_min_fraction,
                                               o.window_track_carry > 0 || o.window_stereo_carry > 0,
                                               CovarianceTrackCarry(o) > 0 || CovarianceStereoCarry(o) > 0,
                                               o.window_covariance_min_variance_factor,
                                               o.window_covariance_factor_alpha, &cov);
  // Published: the window's estimate of this pair against the last call's pair as it
  // was published, so that the deltas compose to the window's latest estimate and its
  // corrections of the poses before reach the user (the window's oldest pose is fixed).
  // When the window's covariance does not carry that correction (a keyframe left the
  // window since the previous pose was published: WindowSolution::carries_correction),
  // the window's estimate of the last step alone is published, with its own covariance,
  // from the reference pose as it stood before this refinement (T_w_ref, from which the
  // last call's pair was measured when it was not a keyframe).
  if (used) {
    res->covariance = cov;
    const Eigen::Isometry3d T_w_cur = window.pose(window.size() - 1);
    res->T_prev_curr = w.carries_correction ? T_w_last.inverse() * T_w_cur
                                            : T_w_last.inverse() * T_w_ref * w.T_prev_last;
    T_w_last = T_w_cur;
  } else {
    // Refused: the pair's own estimate is published and the window restarts on this pair.
    window.PopNewest();
    res->T_prev_curr = T_w_last.inverse() * window.pose(window.size() - 1) * T_ref_cur;
    RestartWindow(cur);
  }
  res->covariance += last_ref_cov;
  last_ref_cov.setZero();
  res->window_used = used;
  res->times.window_ms = Ms(t0, Clock::now());
  prev = std::move(st->cur);
}

}  // namespace rover::vo
