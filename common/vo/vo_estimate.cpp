// The motion from the tracked features: VO-7 weighted least squares inside RANSAC (with
// VO-11's shadow check on its consensus), VO-8 maximum likelihood, VO-13 its covariance
// from what the data shows.
#include "vo/vo_state.hpp"

namespace rover::vo {

bool VisualOdometry::State::EstimateRansac(Step* st) {
  RansacOptions& ro = st->ransac;
  ro.iterations = o.ransac_iterations;
  ro.sample_size = o.ransac_sample_size;
  ro.inlier_px = o.ransac_inlier_px;
  ro.seed = o.ransac_seed + 0x9E3779B97F4A7C15ull * calls;
  st->rs = RansacMotion(st->corr, st->c->rig, ro);
  if (o.shadow_check && !CheckShadow(st)) return false;
  const auto now = Clock::now();
  st->res.times.ransac_ms = Ms(st->t, now);
  st->t = now;
  const int inliers = static_cast<int>(st->rs.inliers.size());
  if (inliers < o.min_inliers) {
    st->res.num_inliers = inliers;
    return st->Stop(VoStatus::kTooFewInliers,
                    Format("%.0f RANSAC inliers (need %.0f)", inliers, o.min_inliers));
  }
  return true;
}

bool VisualOdometry::State::RefineMaximumLikelihood(Step* st) {
  const std::vector<Correspondence>& corr = st->corr;
  std::vector<int>& inliers = st->inliers;
  MlOutcome& ml = st->ml;
  inliers = st->rs.inliers;
  ml = MaximumLikelihoodMotion(corr, inliers, st->rs.T_curr_prev.inverse(), o.ml_max_iterations,
                               o.ml_tolerance);
  int iterations = ml.iterations;
  // Once, the inliers whose residual the fit cannot explain are dropped and it runs again.
  if (ml.converged && o.ml_outlier_chi2 > 0) {
    std::vector<int> kept;
    for (int k : inliers) {
      if (MahalanobisSquared(corr[k], ml.T_prev_curr) <= o.ml_outlier_chi2) kept.push_back(k);
    }
    if (kept.size() < inliers.size() && static_cast<int>(kept.size()) >= o.min_inliers) {
      inliers = std::move(kept);
      ml = MaximumLikelihoodMotion(corr, inliers, ml.T_prev_curr, o.ml_max_iterations, o.ml_tolerance);
      iterations += ml.iterations;
    }
  }
  VoResult& res = st->res;
  res.iterations = iterations;
  res.num_inliers = static_cast<int>(inliers.size());
  for (int k : inliers) res.tracks[k].inlier = true;
  res.times.ml_ms = Ms(st->t, Clock::now());
  if (!ml.converged) {
    return st->Stop(VoStatus::kNoConvergence,
                    Format("maximum likelihood did not converge in %.0f iterations", o.ml_max_iterations));
  }
  res.T_prev_curr = ml.T_prev_curr;
  return true;
}

// Timed with the ML.
bool VisualOdometry::State::EstimateCovariance(Step* st) {
  const auto t0 = Clock::now();
  const Pair& c = *st->c;
  const int grid = o.covariance_cluster_grid;
  std::vector<int> cluster;
  if (grid >= 2) {
    cluster.assign(st->corr.size(), 0);
    for (int k : st->inliers) {
      const Eigen::Vector2d& left = st->corr[k].left;
      const int gx = std::clamp(static_cast<int>(left.x() * grid / c.width), 0, grid - 1);
      const int gy = std::clamp(static_cast<int>(left.y() * grid / c.height), 0, grid - 1);
      cluster[k] = gy * grid + gx;
    }
  }
  SharedErrors shared;
  shared.field_sigma_px = o.covariance_field_sigma_px;
  shared.disparity_sigma_px = o.covariance_disparity_sigma_px;
  shared.cell_shift_sigma_px = o.covariance_cell_shift_sigma_px;
  shared.cell_disparity_sigma_px = o.covariance_cell_disparity_sigma_px;
  shared.centre_px = Eigen::Vector2d(0.5 * (c.width - 1), 0.5 * (c.height - 1));
  shared.half_size_px = 0.5 * std::max(c.width, c.height);
  const MotionUncertainty& u = st->u =
      EstimateMotionUncertainty(st->corr, st->inliers, st->ml.T_prev_curr, cluster, grid * grid, shared);
  if (!u.ok) {
    st->res.T_prev_curr = Eigen::Isometry3d::Identity();
    return st->Stop(VoStatus::kDegenerate, "motion undetermined: the normal matrix is singular");
  }
  st->res.covariance = u.covariance;
  st->res.variance_factor = u.variance_factor;
  st->res.cluster_factor = u.cluster_factor;
  st->res.times.ml_ms += Ms(t0, Clock::now());
  return true;
}

}  // namespace rover::vo
