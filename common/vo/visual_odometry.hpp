// Stereo visual odometry, the MER algorithm (Cheng, Maimone and Matthies 2005), as a
// library that knows nothing of LCM. Requirements VO-1..VO-13 of common/vo/README.md.
//
// One call per stereo pair:
//   detect (VO-2) -> stereo match (VO-3) -> triangulate (VO-4, VO-5) for the new pair,
//   track the previous pair's features through the motion prior (VO-6),
//   weighted least squares inside RANSAC (VO-7), maximum likelihood (VO-8),
//   sanity constraints (VO-9), degenerate geometry (VO-12), shadow (VO-11).
// Any failure returns a status, a reason, counts and stage times; the caller keeps its
// prior (VO-10). Every call (except kBadInput) makes the given pair the new "previous"
// pair, so T_prev_curr always relates two consecutive calls.
//
// Frames: all 3-D quantities are in the stereo rig's reference frame (the rover frame for
// CAHV/CAHVOR models, the left camera frame for a KITTI rig).
#pragma once

#include "config/yaml_config.hpp"
#include "geometry/camera_model.hpp"
#include "vo/tracked_feature.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace rover::vo {

// Numbers equal vo_update_t STATUS_* in lcmtypes/vo_update_t.lcm.
enum class VoStatus {
  kOk = 0,
  kBaseline = 1,         // first pair (or after Reset): kept, no motion yet
  kTooFewFeatures = 2,   // VO-10: too few corners / stereo matches in the previous pair
  kTooFewMatches = 3,    // VO-10: too few features tracked into the new pair
  kTooFewInliers = 4,    // VO-7: RANSAC consensus too small
  kNoConvergence = 5,    // VO-8: ML did not converge within the iteration limit
  kSanityFailed = 6,     // VO-9: a sanity constraint was broken
  kMotionTooLarge = 7,   // VO-10: too little overlap; tracking re-initialised on this pair
  kShadowAmbiguous = 8,  // VO-11: features fixed in the image compete with the scene
  kDegenerate = 9,       // VO-12: inliers too clustered / motion poorly determined
  kBadInput = 10,        // empty images, wrong type or size, missing camera models
};

const char* ToString(VoStatus status);

// Every parameter of the VO. Pixel quantities are at the WORKING resolution (after
// `working_scale`), so that one set of values serves 1024x1024 NAVCAM pairs at 1/2 scale
// and 1226x370 KITTI pairs at full scale alike.
struct VoOptions {
  // ---- VO-1 input ----
  // Working resolution: 1.0 (full), 0.5 or 0.25. Images are area-averaged and the camera
  // models rescaled with CameraModel::Scaled.
  double working_scale = 1.0;

  // ---- VO-2 features ----
  // Harris corner response: k, and the side (odd, <= 63) of the binomial (Gaussian-like)
  // window over which the structure tensor of 3x3 Sobel gradients is summed.
  double feature_harris_k = 0.04;
  int feature_harris_block = 5;
  // Grid cell (pixels); each cell keeps its strongest local maximum. Must be smaller than
  // feature_min_distance_px (the paper's rule).
  int feature_grid_cell_px = 8;
  // Minimum distance between kept features. On Opportunity (sols 137, 141) too small a
  // value let features cluster on one small planar patch and VO converged to wrong
  // answers: 20 px keeps at most ~1 feature per 20x20 patch, so 400 features must span
  // at least 0.6 of a 512x512 or 0.35 of a 1226x370 image.
  double feature_min_distance_px = 20.0;
  // The fixed number of features kept (strongest first). 400, not 300: with the window,
  // more tracks tie the poses (KITTI 06 0.0121 -> 0.0116 deg/m), and the synthetic
  // terrain's first pair, tracked through a weak prior, no longer fails (38/39 -> 39/39
  // pairs); rendered NAVCAM scenes rarely hold 300 corners, so they do not change.
  int feature_count = 400;
  // Response floor, with intensities scaled to [0, 1] and gradients per pixel: below it a
  // "corner" is sensor noise (2 grey levels of noise give ~1e-9; a 10-level corner ~1e-6).
  double feature_min_response = 1e-7;
  // Features closer than this to the image border are not used (template must fit).
  int feature_border_px = 12;

  // ---- VO-3 stereo matching ----
  // Correlation template side (odd, pixels).
  int match_template_px = 11;
  // Band-pass prefilter before correlation: Gaussian sigma (noise) minus a box mean of
  // this side (illumination). Pseudo-normalized correlation is not mean-invariant, so
  // the box must be on (>= 3); the Gaussian may be 0 (off).
  double match_prefilter_sigma = 0.8;
  int match_prefilter_box_px = 9;
  // Rows searched above and below the epipolar line.
  int stereo_epipolar_band_px = 1;
  // New features search the epipolar segment at half resolution first, then +-2 px at
  // the working resolution. Off: on KITTI 06 it lost accuracy (1.04 % against 0.999 %)
  // and saved no time there; it may pay on long disparity ranges (NAVCAM at full size).
  bool stereo_coarse_to_fine = false;
  // Nearest range searched (metres): sets the disparity range from the rig.
  double stereo_min_range_m = 2.0;
  // Smallest disparity (pixels) kept: a point beyond this carries no range.
  double stereo_min_disparity_px = 1.0;
  // Pseudo-normalized correlation score needed to accept a match (1 = perfect).
  double match_min_score = 0.75;
  // Match location covariance = scale * (-Hessian of the biquadratic score surface)^-1,
  // floored at min_sigma^2 per axis (VO-3, VO-5).
  double match_covariance_scale = 0.01;
  double match_min_sigma_px = 0.05;
  // Iterations of a re-centred biquadratic fit (bilinear resampling around the estimate).
  // Off by default: on KITTI 06 it did not help (1.03 % against 0.999 % without).
  int match_subpixel_iterations = 0;

  // ---- VO-4 triangulation ----
  // Largest gap between the two rays, in pixels of angle at the feature's range.
  double triangulation_max_gap_px = 1.5;
  // Farthest range kept (metres); 0 = no limit.
  double triangulation_max_range_m = 0.0;

  // ---- VO-6 tracking ----
  // Search half-window = k * sigma of the predicted pixel (prior + point covariance),
  // clamped to [min, max] pixels.
  double track_window_sigmas = 3.0;
  int track_min_radius_px = 3;
  int track_max_radius_px = 64;
  // Coarse-to-fine: pyramid levels (1 = none) and the largest radius searched directly
  // at one level.
  int track_pyramid_levels = 4;
  int track_coarse_radius_px = 4;
  // Template side at the coarse pyramid levels (cheaper; the finest level uses
  // match_template_px).
  int track_coarse_template_px = 7;
  // Score needed at the working resolution.
  double track_min_score = 0.75;
  // Stereo search margin around the disparity predicted from the known 3-D position.
  double track_stereo_margin_px = 3.0;
  // Chi-square gate (3 dof) on |Pc - prior(Pp)| against Sigma_c + R Sigma_p R^T + prior.
  double track_max_chi2 = 16.27;
  // Warp the finest level's template by the change of perspective the prior predicts for
  // the ground round the feature (the plane of the reference rover's x and y axes), so
  // that a tracked point does not lag the true one as the rover nears it. Off: the
  // template is cut unwarped, and a point tracked over several pairs drifts (measured on
  // rendered drives: -0.07 px at age 3, -0.22 px at age 7), which the window reads as a
  // disparity offset. On by default (configs/vo.yaml has the figures).
  bool track_warp_template = true;
  // Minimum tracked features for an estimate.
  int min_tracked = 12;
  // Minimum stereo-matched features in a pair for it to be used.
  int min_features = 12;

  // ---- VO-7 RANSAC ----
  int ransac_iterations = 100;
  int ransac_sample_size = 6;
  // Reprojection gap (pixels, largest of left and right) under which a feature counts.
  // 1.5, not 1: the gap ignores the range uncertainty of the previous point, which the
  // step's parallax turns into pixels, so a tight gate keeps, on long steps, the features
  // whose errors agree with the hypothesis and the ML inherits the hypothesis' error
  // unseen (rendered drives of 0.6 m steps: inlier share 0.70 at 1 px, NEES 13-20 against
  // 8-10 at 1.5 px; KITTI 06 0.984 % -> 0.982 %).
  double ransac_inlier_px = 1.5;
  std::uint64_t ransac_seed = 42;
  int min_inliers = 10;

  // ---- VO-8 maximum likelihood ----
  int ml_max_iterations = 20;
  // Converged when the step is below this (metres and radians).
  double ml_tolerance = 1e-9;
  // After convergence, drop inliers whose Mahalanobis residual exceeds this chi-square
  // (3 dof) and re-run once; 0 = off.
  double ml_outlier_chi2 = 16.27;

  // ---- VO-9 sanity constraints (0 = off) ----
  double sanity_max_translation_m = 0.0;
  // Site-frame X and Y components: need StereoImages::R_site_ref.
  double sanity_max_site_dx_m = 0.0;
  double sanity_max_site_dy_m = 0.0;
  double sanity_max_roll_deg = 0.0;
  double sanity_max_pitch_deg = 0.0;
  double sanity_max_yaw_deg = 0.0;
  // Angle between the update and pure downslope (needs R_site_ref; skipped on slopes
  // under 2 deg or updates under 1 cm).
  double sanity_max_downslope_angle_deg = 0.0;

  // ---- VO-10 motion too large ----
  // These refuse what VO cannot measure; they must not refuse a step the executor
  // commands at its own limits plus slip. The executor plans for 60 % overlap (the
  // paper's rule: steps <= 75 cm, turns <= 18 deg); VO's limits sit 1.5x beyond that.
  // Fraction of the previous features predicted (through the prior) inside the new image
  // below which the step re-initialises: 0.4 (an 18 deg NAVCAM turn leaves about 60 %
  // of the features in view, a 27 deg one about 40 %).
  double motion_min_overlap = 0.4;
  // Limits on the prior motion (0 = off): 27 deg = 1.5 x the executor's 18 deg turn per
  // step. No translation limit: the overlap check covers it (KITTI frames move 1.2 m).
  double motion_max_translation_m = 0.0;
  double motion_max_rotation_deg = 27.0;

  // ---- VO-11 shadow ----
  bool shadow_check = true;
  // A tracked feature is "fixed" when it moved less than this (pixels) while the prior
  // predicted more than shadow_min_predicted_px.
  double shadow_fixed_px = 1.0;
  double shadow_min_predicted_px = 5.0;

  // ---- VO-12 degenerate geometry ----
  // Refuse when sqrt(smallest eigenvalue) of the inliers' image scatter is below this
  // fraction of the smaller image side (Mars lesson: clustered features): a line or a
  // thin band of features. Features spread evenly over the whole image give 0.29.
  double degenerate_min_spread = 0.05;
  // Refuse when the geometric mean of the two (the side of the patch they cover, over
  // sqrt 12) is below this: one compact patch. 0.11 is a patch 0.38 of the image across.
  // Below that a lone patch's shared errors (templates that deform alike as the rover
  // nears it) move the whole estimate more than VO-13's covariance carries: with the
  // narrow spread alone, the 65 cm patch of clustered_features gave NEES up to 25
  // (vo_eval --world configs/worlds/clustered_features.yaml --step-m 0.3 --frames 7,
  // seeds 1-16: 1 of 47 accepted pairs beyond the 99.7 % bound, and 1 of 2 in a CI run of
  // the scenario), at geometric means of 0.061-0.115; with this check 6 are accepted, NEES
  // at most 13.5. A band of lit ground beside the rover's shadow (0.062 by 0.27, mean 0.13)
  // is measured well (tests/vo_scenes/shadow_test.cpp); rendered drives over whole fields
  // of view give 0.17 and more.
  double degenerate_min_patch_spread = 0.11;
  // Refuse when the covariance (VO-13) leaves the motion poorly determined (0 = off).
  double degenerate_max_translation_sigma_m = 0.1;
  double degenerate_max_rotation_sigma_deg = 1.0;

  // ---- VO-13 honest uncertainty (motion_estimation.hpp, EstimateMotionUncertainty) ----
  // covariance = max(s0^2, k) H^-1 + shared errors. s0^2: the ML residuals against the
  // match covariances; k: the same with the features grouped in the cells of a
  // grid x grid partition of the image, so that errors shared by neighbours count
  // (< 2 = off).
  int covariance_cluster_grid = 4;
  // Errors shared by every feature of a pair, which the fit absorbs (SharedErrors): a
  // smooth error field over the matches (shift, rotation and scale modes; pixels) and a
  // disparity offset common to both pairs (the rig's calibration; pixels). Learned on
  // rendered truth only (tools/vo_eval/README.md): 0.02 and 0.05 px.
  double covariance_field_sigma_px = 0.02;
  double covariance_disparity_sigma_px = 0.05;
  // Errors the features of one cluster-grid cell share (motion_estimation.hpp,
  // SharedErrors): a shift of the current matches, and a disparity error in each pair.
  double covariance_cell_shift_sigma_px = 0.04;
  double covariance_cell_disparity_sigma_px = 0.04;

  // ---- VO with memory: feature tracks and a sliding window (README "VO with memory") ----
  // Keyframes in the sliding-window maximum-likelihood refinement (window.hpp); < 2 = off:
  // the MER frame-to-frame VO above, unchanged (fresh features every pair, no keyframes).
  // On: features that VO-8 used live on as tracks (tracks.hpp), detection (VO-2) only
  // tops up the image where tracks are missing, and after each keyframe's VO-8 estimate
  // the last window_size poses and the points tracked through them are refined together.
  int window_size = 5;
  // Levenberg-Marquardt iterations of the refinement, and its Huber threshold (sigmas of
  // an observation's normalised stereo reprojection residual).
  int window_max_iterations = 8;
  double window_huber_sigmas = 3.0;
  // WindowOptions::track_carry and stereo_carry: the fraction of a track's left match
  // error that carries into its next keyframe's left match (each template is cut at the
  // last match, VO-6), and into its own keyframe's right match; 0 = independent errors,
  // 1 = a random walk. Measured on rendered drives with truth by tools/vo_carry
  // (common/vo/README.md, "Carried track errors").
  double window_track_carry = 0.0;
  double window_stereo_carry = 0.0;
  // The carries under which the window's published covariance is computed, apart from the
  // weights (WindowOptions::covariance_track_carry, covariance_stereo_carry): the estimate
  // stays the one weighed with window_track_carry and window_stereo_carry, its covariance
  // is the sandwich S^-1 M S^-1 under these. -1 = the weights' own (S^-1, as before): no
  // pair measured was both honest on navbench's rock fields and above tilt_slope's NEES
  // limit (common/vo/README.md, "Sandwich covariance").
  double window_covariance_track_carry = -1.0;
  double window_covariance_stereo_carry = -1.0;
  // The least factor that scales the window's published covariance (its fit part: S^-1 or
  // the sandwich; the shared errors are not scaled). The variance factors (the pair's s0^2
  // and cluster factor, the window's own) compare the residuals' scatter with VO-3's match
  // covariances; on navbench's rock fields they sat near 0.4 while the refined deltas'
  // errors followed the unscaled covariance, but on tilt_slope the errors are as small as
  // its factors (0.11) say, and no floor suits both (tools/vo_replay/learn_factor_floor.py,
  // README "Variance factor floor"). 0 = none (the default: a factor may shrink the
  // covariance as far as it says).
  double window_covariance_min_variance_factor = 0.0;
  // Above 0: the pair's s0^2 scales the window's published covariance as its upper
  // confidence bound, s0^2 * r / chi^2_alpha(r) with r = 3n - 6 its redundancy, rather than
  // as its point estimate (a factor from few inliers is uncertain, and RANSAC's selection
  // truncates their residuals). 0 = the point estimate; configs/vo.yaml sets 1e-4 (README
  // "Variance factor floor" has the replays that decided it).
  double window_covariance_factor_alpha = 0.0;
  // The refined delta must agree with the pair's VO-8 estimate: chi-square (6 dof) of
  // their difference under its covariance, the pair's minus the window's (the window holds
  // the pair's data; NestedDifferenceChi2 in motion_estimation.hpp), each whitened
  // eigenvalue floored at window_consistency_min_fraction of the pair's variance. Beyond
  // it the pair estimate is used and the window restarts (20.06: the 99.7 % bound). A
  // window that claims more than its data give (errors a track shares from pair to pair)
  // fails it; under the pair's covariance alone, 4 % of the window deltas on rendered rock
  // fields lay beyond the 99.7 % NEES bound.
  double window_max_chi2 = 20.06;
  double window_consistency_min_fraction = 0.15;
  // The window also estimates one disparity offset of the rig (right x, pixels), which
  // scales every range and so every step: one drive-wide estimate, a scalar filter fed by
  // every full window (window.hpp), starting from a zero-mean prior of this sigma; 0 = not
  // estimated. It may drift by window_disparity_offset_drift_px per full window, and is
  // used only when it differs from zero by more than window_disparity_offset_min_sigmas
  // sigmas, its sigma including window_disparity_offset_systematic_px (what the matcher's
  // systematic disparity errors fake); else the window holds it at zero.
  double window_disparity_offset_sigma_px = 0.5;
  double window_disparity_offset_drift_px = 0.0;
  double window_disparity_offset_systematic_px = 0.05;
  double window_disparity_offset_min_sigmas = 2.0;
  // Carried tracks closer than this to an older track are dropped (older tracks win), so
  // tracks stay spread; fresh corners keep feature_min_distance_px from every track.
  double track_min_distance_px = 10.0;
  // Keyframes: a pair that moved less than both of these from the last keyframe (a short
  // step, standing still) is measured against that keyframe, so noise does not add up
  // frame after frame; it joins neither the window nor the tracks.
  double keyframe_min_translation_m = 0.1;
  double keyframe_min_rotation_deg = 2.0;
};

// Reads the node of the `vo:` section. Unknown keys and out-of-range values throw
// config::ConfigError naming the key.
VoOptions LoadVoOptions(const config::ConfigNode& node);
// Throws std::invalid_argument naming the first inconsistent value.
// The carries of the window's covariance model: window_covariance_*_carry, or the
// weights' (window_track_carry, window_stereo_carry) when that is negative.
double CovarianceTrackCarry(const VoOptions& o);
double CovarianceStereoCarry(const VoOptions& o);
void ValidateVoOptions(const VoOptions& options);

struct StereoImages {
  cv::Mat left, right;  // CV_8UC1 or CV_16UC1, full size (the rig's size)
  geometry::StereoRig rig;
  std::int64_t utime = 0;
  std::int64_t frame_id = 0;
  // Optional attitude of the rig's reference frame in the site frame at capture (IMU);
  // needed only by the site-frame sanity checks of VO-9.
  std::optional<Eigen::Matrix3d> R_site_ref;
};

struct StageTimes {
  double detect_ms = 0, stereo_ms = 0, track_ms = 0, ransac_ms = 0, ml_ms = 0, total_ms = 0;
  double window_ms = 0;  // sliding-window refinement (0 when off)
};

struct VoResult {
  VoStatus status = VoStatus::kBadInput;
  std::string reason;
  // Pose of the current reference frame in the previous one (the motion).
  Eigen::Isometry3d T_prev_curr = Eigen::Isometry3d::Identity();
  // Of the delta: x y z roll pitch yaw (roll, pitch, yaw of T_prev_curr's rotation,
  // R = Rz(yaw) Ry(pitch) Rx(roll)).
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Zero();
  int num_detected = 0;  // corners kept in the current left image
  int num_matched = 0;   // of those, stereo-matched and triangulated
  int num_tracked = 0;   // previous features found again in the current pair
  int num_inliers = 0;   // used by the ML estimate
  int iterations = 0;    // ML iterations
  // VO-13: the a-posteriori variance factor of the ML fit (weighted residual sum over its
  // degrees of freedom) and the cluster variance factor (EstimateMotionUncertainty);
  // `covariance` already includes the larger.
  double variance_factor = 0;
  double cluster_factor = 0;
  StageTimes times;
  // Windowed mode (VoOptions::window_size): whether this pair became a keyframe, the
  // lengths (pairs seen, this one included) of the tracks VO-8 used, the window's
  // keyframes, points and iterations, and whether the refined delta was published
  // (false: the pair's VO-8 estimate was).
  bool keyframe = true;
  double track_length_mean = 0;
  int track_length_max = 0;
  int window_frames = 0, window_points = 0, window_iterations = 0;
  bool window_used = false;
  double disparity_offset_px = 0;  // the window's estimate of the rig's disparity offset
  // The window's variance factors (WindowSolution): under its weights' model, and under
  // the published covariance's model; 0 when no window was refined.
  double window_variance_factor = 0, window_covariance_variance_factor = 0;
  // The features tracked from the previous pair (VO-6), in the order of the
  // correspondences, with the ones the ML motion used marked (tracked_feature.hpp).
  std::vector<TrackedFeature> tracks;
};

class VisualOdometry {
 public:
  // Throws std::invalid_argument on inconsistent options.
  explicit VisualOdometry(VoOptions options);
  ~VisualOdometry();
  VisualOdometry(VisualOdometry&&) noexcept;
  VisualOdometry& operator=(VisualOdometry&&) noexcept;

  // First call (or after Reset/MotionTooLarge): returns kBaseline and keeps the frame.
  // prior: the expected motion T_prev_curr and its covariance (x y z roll pitch yaw),
  // from wheel odometry + IMU, or constant velocity.
  VoResult Process(const StereoImages& images, const Eigen::Isometry3d& prior_T_prev_curr,
                   const Eigen::Matrix<double, 6, 6>& prior_covariance);
  void Reset();

  const VoOptions& options() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace rover::vo
