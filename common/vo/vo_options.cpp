#include "vo/visual_odometry.hpp"

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace rover::vo {

const char* ToString(VoStatus status) {
  switch (status) {
    case VoStatus::kOk: return "ok";
    case VoStatus::kBaseline: return "baseline";
    case VoStatus::kTooFewFeatures: return "too_few_features";
    case VoStatus::kTooFewMatches: return "too_few_matches";
    case VoStatus::kTooFewInliers: return "too_few_inliers";
    case VoStatus::kNoConvergence: return "no_convergence";
    case VoStatus::kSanityFailed: return "sanity_failed";
    case VoStatus::kMotionTooLarge: return "motion_too_large";
    case VoStatus::kShadowAmbiguous: return "shadow_ambiguous";
    case VoStatus::kDegenerate: return "degenerate";
    case VoStatus::kBadInput: return "bad_input";
  }
  return "unknown";
}

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
}

VoOptions LoadVoOptions(const config::ConfigNode& node) {
  VoOptions o;
  if (node.IsNull()) return o;
  if (!node.IsMap()) node.Fail("expected a mapping of VO options");
  node.CheckKeys({"working_scale",
                  "feature_harris_k", "feature_harris_block", "feature_grid_cell_px",
                  "feature_min_distance_px", "feature_count", "feature_min_response",
                  "feature_border_px",
                  "match_template_px", "match_prefilter_sigma", "match_prefilter_box_px",
                  "stereo_epipolar_band_px", "stereo_coarse_to_fine", "stereo_min_range_m", "stereo_min_disparity_px",
                  "match_min_score", "match_covariance_scale", "match_min_sigma_px",
                  "match_subpixel_iterations",
                  "triangulation_max_gap_px", "triangulation_max_range_m",
                  "track_window_sigmas", "track_min_radius_px", "track_max_radius_px",
                  "track_pyramid_levels", "track_coarse_radius_px", "track_coarse_template_px",
                  "track_min_score",
                  "track_stereo_margin_px", "track_max_chi2", "track_warp_template", "min_tracked", "min_features",
                  "ransac_iterations", "ransac_sample_size", "ransac_inlier_px", "ransac_seed",
                  "min_inliers",
                  "ml_max_iterations", "ml_tolerance", "ml_outlier_chi2",
                  "sanity_max_translation_m", "sanity_max_site_dx_m", "sanity_max_site_dy_m",
                  "sanity_max_roll_deg", "sanity_max_pitch_deg", "sanity_max_yaw_deg",
                  "sanity_max_downslope_angle_deg",
                  "motion_min_overlap", "motion_max_translation_m", "motion_max_rotation_deg",
                  "shadow_check", "shadow_fixed_px", "shadow_min_predicted_px",
                  "degenerate_min_spread", "degenerate_min_patch_spread", "degenerate_max_translation_sigma_m",
                  "degenerate_max_rotation_sigma_deg",
                  "covariance_cluster_grid", "covariance_field_sigma_px",
                  "covariance_disparity_sigma_px", "covariance_cell_shift_sigma_px",
                  "covariance_cell_disparity_sigma_px",
                  "window_size", "window_max_iterations", "window_huber_sigmas", "window_track_carry", "window_stereo_carry",
                  "window_covariance_track_carry", "window_covariance_stereo_carry",
                  "window_covariance_min_variance_factor", "window_covariance_factor_alpha",
                  "window_max_chi2",
                  "window_consistency_min_fraction",
                  "window_disparity_offset_sigma_px", "window_disparity_offset_drift_px",
                  "window_disparity_offset_systematic_px", "window_disparity_offset_min_sigmas",
                  "track_min_distance_px", "keyframe_min_translation_m", "keyframe_min_rotation_deg"});
  node.Get("working_scale", o.working_scale, 0.0625, 1.0);
  node.Get("feature_harris_k", o.feature_harris_k, 0.0, 0.25);
  node.Get("feature_harris_block", o.feature_harris_block, 3, 31);
  node.Get("feature_grid_cell_px", o.feature_grid_cell_px, 1, 1000);
  node.Get("feature_min_distance_px", o.feature_min_distance_px, 1.0, 1000.0);
  node.Get("feature_count", o.feature_count, 3, 100000);
  node.Get("feature_min_response", o.feature_min_response, 0.0, kInf);
  node.Get("feature_border_px", o.feature_border_px, 1, 1000);
  node.Get("match_template_px", o.match_template_px, 3, 63);
  node.Get("match_prefilter_sigma", o.match_prefilter_sigma, 0.0, 10.0);
  node.Get("match_prefilter_box_px", o.match_prefilter_box_px, 0, 101);
  node.Get("stereo_epipolar_band_px", o.stereo_epipolar_band_px, 0, 20);
  node.Get("stereo_coarse_to_fine", o.stereo_coarse_to_fine);
  node.Get("stereo_min_range_m", o.stereo_min_range_m, 1e-3, kInf);
  node.Get("stereo_min_disparity_px", o.stereo_min_disparity_px, 0.0, 1000.0);
  node.Get("match_min_score", o.match_min_score, -1.0, 1.0);
  node.Get("match_covariance_scale", o.match_covariance_scale, 1e-9, kInf);
  node.Get("match_min_sigma_px", o.match_min_sigma_px, 0.0, 100.0);
  node.Get("match_subpixel_iterations", o.match_subpixel_iterations, 0, 20);
  node.Get("triangulation_max_gap_px", o.triangulation_max_gap_px, 0.0, 1000.0);
  node.Get("triangulation_max_range_m", o.triangulation_max_range_m, 0.0, kInf);
  node.Get("track_window_sigmas", o.track_window_sigmas, 0.0, 100.0);
  node.Get("track_min_radius_px", o.track_min_radius_px, 1, 10000);
  node.Get("track_max_radius_px", o.track_max_radius_px, 1, 10000);
  node.Get("track_pyramid_levels", o.track_pyramid_levels, 1, 8);
  node.Get("track_coarse_radius_px", o.track_coarse_radius_px, 1, 1000);
  node.Get("track_coarse_template_px", o.track_coarse_template_px, 3, 63);
  node.Get("track_min_score", o.track_min_score, -1.0, 1.0);
  node.Get("track_stereo_margin_px", o.track_stereo_margin_px, 0.0, 1000.0);
  node.Get("track_max_chi2", o.track_max_chi2, 0.0, kInf);
  node.Get("track_warp_template", o.track_warp_template);
  node.Get("min_tracked", o.min_tracked, 3, 100000);
  node.Get("min_features", o.min_features, 3, 100000);
  node.Get("ransac_iterations", o.ransac_iterations, 1, 1000000);
  node.Get("ransac_sample_size", o.ransac_sample_size, 3, 1000);
  node.Get("ransac_inlier_px", o.ransac_inlier_px, 1e-6, 1000.0);
  node.Get("ransac_seed", o.ransac_seed);
  node.Get("min_inliers", o.min_inliers, 3, 100000);
  node.Get("ml_max_iterations", o.ml_max_iterations, 1, 10000);
  node.Get("ml_tolerance", o.ml_tolerance, 0.0, 1.0);
  node.Get("ml_outlier_chi2", o.ml_outlier_chi2, 0.0, kInf);
  node.Get("sanity_max_translation_m", o.sanity_max_translation_m, 0.0, kInf);
  node.Get("sanity_max_site_dx_m", o.sanity_max_site_dx_m, 0.0, kInf);
  node.Get("sanity_max_site_dy_m", o.sanity_max_site_dy_m, 0.0, kInf);
  node.Get("sanity_max_roll_deg", o.sanity_max_roll_deg, 0.0, 180.0);
  node.Get("sanity_max_pitch_deg", o.sanity_max_pitch_deg, 0.0, 180.0);
  node.Get("sanity_max_yaw_deg", o.sanity_max_yaw_deg, 0.0, 180.0);
  node.Get("sanity_max_downslope_angle_deg", o.sanity_max_downslope_angle_deg, 0.0, 180.0);
  node.Get("motion_min_overlap", o.motion_min_overlap, 0.0, 1.0);
  node.Get("motion_max_translation_m", o.motion_max_translation_m, 0.0, kInf);
  node.Get("motion_max_rotation_deg", o.motion_max_rotation_deg, 0.0, 180.0);
  node.Get("shadow_check", o.shadow_check);
  node.Get("shadow_fixed_px", o.shadow_fixed_px, 0.0, 1000.0);
  node.Get("shadow_min_predicted_px", o.shadow_min_predicted_px, 0.0, 10000.0);
  node.Get("degenerate_min_spread", o.degenerate_min_spread, 0.0, 1.0);
  node.Get("degenerate_min_patch_spread", o.degenerate_min_patch_spread, 0.0, 1.0);
  node.Get("degenerate_max_translation_sigma_m", o.degenerate_max_translation_sigma_m, 0.0, kInf);
  node.Get("degenerate_max_rotation_sigma_deg", o.degenerate_max_rotation_sigma_deg, 0.0, 180.0);
  node.Get("covariance_cluster_grid", o.covariance_cluster_grid, 0, 16);
  node.Get("covariance_field_sigma_px", o.covariance_field_sigma_px, 0.0, 10.0);
  node.Get("covariance_disparity_sigma_px", o.covariance_disparity_sigma_px, 0.0, 10.0);
  node.Get("covariance_cell_shift_sigma_px", o.covariance_cell_shift_sigma_px, 0.0, 10.0);
  node.Get("covariance_cell_disparity_sigma_px", o.covariance_cell_disparity_sigma_px, 0.0, 10.0);
  node.Get("window_size", o.window_size, 0, 10);
  node.Get("window_max_iterations", o.window_max_iterations, 1, 100);
  node.Get("window_huber_sigmas", o.window_huber_sigmas, 0.5, 100.0);
  node.Get("window_track_carry", o.window_track_carry, 0.0, 1.0);
  node.Get("window_stereo_carry", o.window_stereo_carry, 0.0, 1.0);
  node.Get("window_covariance_track_carry", o.window_covariance_track_carry, -1.0, 1.0);
  node.Get("window_covariance_stereo_carry", o.window_covariance_stereo_carry, -1.0, 1.0);
  node.Get("window_covariance_min_variance_factor", o.window_covariance_min_variance_factor, 0.0, 10.0);
  node.Get("window_covariance_factor_alpha", o.window_covariance_factor_alpha, 0.0, 0.5);
  node.Get("window_max_chi2", o.window_max_chi2, 0.0, kInf);
  node.Get("window_consistency_min_fraction", o.window_consistency_min_fraction, 1e-6, 1.0);
  node.Get("window_disparity_offset_sigma_px", o.window_disparity_offset_sigma_px, 0.0, 10.0);
  node.Get("window_disparity_offset_drift_px", o.window_disparity_offset_drift_px, 0.0, 10.0);
  node.Get("window_disparity_offset_systematic_px", o.window_disparity_offset_systematic_px, 0.0, 10.0);
  node.Get("window_disparity_offset_min_sigmas", o.window_disparity_offset_min_sigmas, 0.0, 100.0);
  node.Get("track_min_distance_px", o.track_min_distance_px, 0.0, 1000.0);
  node.Get("keyframe_min_translation_m", o.keyframe_min_translation_m, 0.0, kInf);
  node.Get("keyframe_min_rotation_deg", o.keyframe_min_rotation_deg, 0.0, 180.0);
  try {
    ValidateVoOptions(o);
  } catch (const std::invalid_argument& e) {
    node.Fail(e.what());
  }
  return o;
}

double CovarianceTrackCarry(const VoOptions& o) {
  return o.window_covariance_track_carry < 0 ? o.window_track_carry : o.window_covariance_track_carry;
}
double CovarianceStereoCarry(const VoOptions& o) {
  return o.window_covariance_stereo_carry < 0 ? o.window_stereo_carry : o.window_covariance_stereo_carry;
}

void ValidateVoOptions(const VoOptions& o) {
  auto fail = [](const std::string& m) { throw std::invalid_argument("VoOptions: " + m); };
  // -1 (the weights' own model) or a carry in [0, 1]; one set and the other -1 would mix
  // the two models in one covariance.
  const auto carry_ok = [](double c) { return c == -1.0 || (c >= 0.0 && c <= 1.0); };
  if (!carry_ok(o.window_covariance_track_carry) || !carry_ok(o.window_covariance_stereo_carry) ||
      (o.window_covariance_track_carry < 0) != (o.window_covariance_stereo_carry < 0)) {
    fail("window_covariance_track_carry " + std::to_string(o.window_covariance_track_carry) +
         ", window_covariance_stereo_carry " + std::to_string(o.window_covariance_stereo_carry) +
         " (expected both -1, the weights' carries, or both in [0, 1])");
  }
  if (!(o.working_scale > 0 && o.working_scale <= 1)) {
    fail("working_scale " + std::to_string(o.working_scale) + " (expected in (0, 1])");
  }
  if (o.match_template_px % 2 == 0) {
    fail("match_template_px " + std::to_string(o.match_template_px) + " (expected odd)");
  }
  if (o.track_coarse_template_px % 2 == 0) {
    fail("track_coarse_template_px " + std::to_string(o.track_coarse_template_px) + " (expected odd)");
  }
  if (o.match_prefilter_box_px != 0 && (o.match_prefilter_box_px < 3 || o.match_prefilter_box_px % 2 == 0)) {
    fail("match_prefilter_box_px " + std::to_string(o.match_prefilter_box_px) +
         " (expected 0 or an odd number >= 3)");
  }
  if (o.feature_grid_cell_px >= o.feature_min_distance_px) {
    fail("feature_grid_cell_px " + std::to_string(o.feature_grid_cell_px) +
         " (expected smaller than feature_min_distance_px " +
         std::to_string(o.feature_min_distance_px) + ")");
  }
  if (o.feature_border_px < o.match_template_px / 2 + 2) {
    fail("feature_border_px " + std::to_string(o.feature_border_px) +
         " (expected >= match_template_px/2 + 2 = " + std::to_string(o.match_template_px / 2 + 2) + ")");
  }
  if (o.track_min_radius_px > o.track_max_radius_px) {
    fail("track_min_radius_px " + std::to_string(o.track_min_radius_px) +
         " (expected <= track_max_radius_px " + std::to_string(o.track_max_radius_px) + ")");
  }
  if (o.ransac_sample_size < 3) {
    fail("ransac_sample_size " + std::to_string(o.ransac_sample_size) + " (expected >= 3)");
  }
  if (o.min_inliers < o.ransac_sample_size) {
    fail("min_inliers " + std::to_string(o.min_inliers) + " (expected >= ransac_sample_size " +
         std::to_string(o.ransac_sample_size) + ")");
  }
}

}  // namespace rover::vo
