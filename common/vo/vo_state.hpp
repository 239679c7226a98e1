// Internal to common/vo, not part of the public API: what VisualOdometry keeps between calls
// (State), one call's work in progress (Step), and the stages of the MER method that
// Process runs in order, one file per step of common/vo/README.md:
//   vo_input.cpp     VO-1 input, working resolution and pyramid; the pair measured against
//   vo_features.cpp  VO-2 corners, and their top-up around carried tracks (windowed mode)
//   vo_stereo.cpp    VO-3 stereo match, VO-4/VO-5 triangulation of new features
//   vo_tracking.cpp  VO-6 tracking through the motion prior (and VO-10 on the prior)
//   vo_estimate.cpp  VO-7 RANSAC, VO-8 maximum likelihood, VO-13 covariance
//   vo_checks.cpp    VO-9 sanity, VO-10 motion too large, VO-11 shadow, VO-12 geometry
//   vo_keyframes.cpp windowed mode: keyframes, tracks carried on, the sliding window
#pragma once

#include "vo/correlation.hpp"
#include "vo/features.hpp"
#include "vo/motion_estimation.hpp"
#include "vo/triangulation.hpp"
#include "vo/visual_odometry.hpp"
#include "vo/window.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace rover::vo {

using Clock = std::chrono::steady_clock;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

constexpr double kDeg = M_PI / 180.0;

inline double Ms(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

// Pixel coordinate at pyramid level l (area halving keeps pixel centres as centres).
inline double ToLevel(double x, int l) { return (x + 0.5) / double(1 << l) - 0.5; }

// A status reason with up to two numbers in it.
inline std::string Format(const char* fmt, double a, double b = 0) {
  char buf[256];
  std::snprintf(buf, sizeof(buf), fmt, a, b);
  return buf;
}

// Indices 0..n-1 ordered top to bottom, then left to right, by position(i): correlation
// windows visited in this order stream through the images instead of jumping about.
// Callers keep their results in index order, on which RANSAC's draws depend.
template <class Position>
std::vector<int> TopToBottom(int n, Position position) {
  std::vector<int> order(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) order[static_cast<std::size_t>(i)] = i;
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    const Eigen::Vector2d pa = position(a), pb = position(b);
    return std::make_pair(pa.y(), pa.x()) < std::make_pair(pb.y(), pb.x());
  });
  return order;
}

struct Feature {
  Eigen::Vector2d left;  // working-resolution pixel (integer for a fresh corner)
  Eigen::Vector3d P;
  Eigen::Matrix3d Sigma;
  // The covariance of the part of P's error that the next pair's match of this feature does
  // not repeat, which is what VO-8's residual P_curr - R P_prev - T sees of this pair: the
  // next left match is found with a template cut at this one, so it carries track_carry of
  // this left match's error, which the two points then share (Sigma with Sigma_left scaled
  // by (1 - track_carry)^2). Sigma when nothing carries.
  Eigen::Matrix3d Sigma_uncarried;
  Eigen::Vector3d dP_ddisparity;  // dP / d(right x): a disparity offset (VO-13)
  // Windowed mode: the stereo match behind P, and the track (id, pairs seen so far).
  Eigen::Vector2d right = Eigen::Vector2d::Zero();
  Eigen::Matrix2d Sigma_left = Eigen::Matrix2d::Identity(), Sigma_right = Eigen::Matrix2d::Identity();
  std::int64_t track_id = 0;
  int age = 1;
};

// A feature from its stereo match (VO-3) and the point triangulated from it (VO-4, VO-5;
// J = dP / d(left x, left y, right x, right y)), with the carries of the matches' errors
// (VoOptions::window_track_carry, window_stereo_carry; 0 and 0 in frame-to-frame mode).
inline Feature MakeFeature(const Eigen::Vector2d& left, const Eigen::Matrix2d& Sigma_left,
                           const Eigen::Vector2d& right, const Eigen::Matrix2d& Sigma_right,
                           const StereoPoint& sp, const Eigen::Matrix<double, 3, 4>& J,
                           double track_carry, double stereo_carry) {
  Feature f;
  f.left = left;
  f.P = sp.P;
  f.Sigma = sp.Sigma;
  const double kept = (1.0 - track_carry) * (1.0 - track_carry);
  f.Sigma_uncarried = StereoPointCovariance(J, kept * Sigma_left, Sigma_right, stereo_carry);
  f.dP_ddisparity = J.col(2);
  f.right = right;
  f.Sigma_left = Sigma_left;
  f.Sigma_right = Sigma_right;
  return f;
}

// One stereo pair at the working resolution.
struct Pair {
  geometry::StereoRig rig;
  std::vector<cv::Mat> left_band;  // band-passed pyramid, level 0 = working resolution
  cv::Mat right_band;
  cv::Mat right_band_half;  // level 1, for coarse-to-fine stereo of new features
  // Reused buffers (a Pair is recycled every other frame, so nothing is reallocated).
  cv::Mat left, right, right_half, scratch;
  std::vector<cv::Mat> left_levels;
  std::vector<Feature> features;
  std::vector<Corner> corners;  // windowed mode: VO-2's corners, stereo-matched later
  std::int64_t frame_id = 0;
  int width = 0, height = 0;
  double pixel_angle = 1e-3;  // radians per pixel near the left image centre
  double far_range = 1e6;     // range at stereo_min_disparity_px
};

// VO-6: a feature of the reference pair predicted into the new left image through the
// motion prior.
struct Prediction {
  Eigen::Vector3d P;      // its point in the new pair's frame
  Eigen::Matrix3d Sigma;  // the point's covariance plus the prior's
  Eigen::Vector2d u;      // its pixel in the new left image
  int radius = 0;         // the search half-window (pixels at the working resolution)
  // track_warp_template: new-image pixel offsets to reference-image ones round the
  // feature, for the ground plane through it (none: the template is cut unwarped).
  bool warped = false;
  Eigen::Matrix2d warp = Eigen::Matrix2d::Identity();
};

// One call of Process: its inputs, the result being filled, and what each stage hands to
// the next. A stage that ends the call sets the status and reason (VO-10) through Stop
// or Refuse and returns false.
struct Step {
  Step(const StereoImages& images_, const Eigen::Isometry3d& prior_, const Matrix6d& prior_covariance_)
      : images(images_), prior(prior_), prior_covariance(prior_covariance_) {}

  const StereoImages& images;
  const Eigen::Isometry3d& prior;  // expected T_prev_curr against the previous call's pair
  const Matrix6d& prior_covariance;
  VoResult res;
  VoStatus status = VoStatus::kOk;
  std::string reason;
  // The call's start, and the end of the last timed stage.
  Clock::time_point start = Clock::now(), t = start;

  // The new pair and the pair it is measured against (the previous one; in windowed mode
  // the last keyframe). Frame-to-frame the new pair is State::prev from the start (every
  // outcome makes it the previous pair) and `cur` is empty; `c` is the new pair in both.
  std::unique_ptr<Pair> cur, ref;
  const Pair* c = nullptr;
  Eigen::Isometry3d prior_ref = Eigen::Isometry3d::Identity();  // the prior against `ref`

  // VO-6: the tracked features, each with the index of its feature in `ref`, whether it
  // stayed put in the image while predicted to move (VO-11), and (windowed mode) every
  // feature of `ref` as seen in the new pair, by index in `ref`.
  std::vector<Correspondence> corr;
  std::vector<int> corr_source;
  std::vector<char> fixed;
  std::vector<Feature> carried;
  int predicted_inside = 0;  // features of `ref` the prior puts inside the new image
  // VO-7, VO-8, VO-13.
  RansacOptions ransac;
  RansacOutcome rs;
  std::vector<int> inliers;  // of the ML estimate
  MlOutcome ml;
  MotionUncertainty u;

  bool Stop(VoStatus s, std::string why) {
    status = s;
    reason = std::move(why);
    return false;
  }
  // An estimate refused after it was made: the prior stays in force.
  bool Refuse(VoStatus s, std::string why) {
    res.T_prev_curr = Eigen::Isometry3d::Identity();
    res.covariance.setZero();
    return Stop(s, std::move(why));
  }
};

// The features of a pair as the sliding window observes them.
std::vector<WindowObservation> Observations(const Pair& pair);

// The factor that scales the window's published covariance (its fit part: S^-1, or the
// sandwich under the covariance's carries; the shared errors are added unscaled): the
// larger of the pair's s0^2 and cluster factor, the window's own factor under the
// covariance's model when that model carries errors (covariance_carried), and
// `min_factor` (VoOptions::window_covariance_min_variance_factor). The variance factors
// compare the residuals' scatter with VO-3's match covariances; on navbench's rock fields
// every factor sat near 0.4 while the refined deltas' errors followed the unscaled
// covariance, so there a factor below 1 did not mean smaller errors (README, "Variance
// factor floor"). With `factor_alpha` above 0 (VoOptions::window_covariance_factor_alpha)
// the pair's s0^2 enters as its upper confidence bound at 1 - factor_alpha over its
// redundancy (VarianceFactorUpperBound), not as its point estimate.
double PublishedWindowFactor(const MotionUncertainty& pair, const WindowSolution& window,
                             bool covariance_carried, double min_factor, double factor_alpha);

struct VisualOdometry::State {
  VoOptions o;
  std::unique_ptr<Pair> prev;
  std::unique_ptr<Pair> spare;  // the pair before prev, recycled for its buffers
  Correlator correlator;
  Template tmpl, coarse_tmpl;
  std::uint64_t calls = 0;
  // Windowed mode: `prev` is the last keyframe (the reference pair); the window; the
  // last call's pair as published, in the window's frame (the deltas VO publishes compose
  // to the window's latest estimate); the next track id.
  SlidingWindow window;
  Eigen::Isometry3d T_w_last = Eigen::Isometry3d::Identity();
  // The covariance of the last call's pair against the reference pair (zero when it was
  // the reference): a delta from it carries that pair's error too.
  Matrix6d last_ref_cov = Matrix6d::Zero();
  std::int64_t next_track_id = 1;
  bool Windowed() const { return o.window_size >= 2; }
  // How much of a match's error the next left match (track) and its own right match
  // (stereo) repeat (README "Carried track errors"): VoOptions' in windowed mode; the
  // frame-to-frame mode stays the paper's, with independent errors.
  double TrackCarry() const { return Windowed() ? o.window_track_carry : 0.0; }
  double StereoCarry() const { return Windowed() ? o.window_stereo_carry : 0.0; }

  // ---- The stages of Process, in order. Those returning bool return false when they
  // end the call (Step::Stop). ----
  bool CheckInput(Step* st);               // VO-1: images, camera models, prior
  void LoadPair(Step* st);                 // VO-1: working resolution, band-passed pyramid
  void DetectFeatures(Step* st);           // VO-2
  void MatchNewFeatures(Step* st);         // VO-3..VO-5 (windowed mode: after VO-6)
  void TakeReference(Step* st);            // the pair measured against; the prior to it
  bool CheckReference(Step* st);           // a previous pair with enough features
  bool CheckPriorMotion(Step* st);         // VO-10 on the prior
  void TrackFeatures(Step* st);            // VO-6
  bool CheckTracks(Step* st);              // VO-10 overlap; enough tracked features
  bool EstimateRansac(Step* st);           // VO-7, with VO-11
  bool RefineMaximumLikelihood(Step* st);  // VO-8
  bool EstimateCovariance(Step* st);       // VO-13
  bool CheckSanity(Step* st);              // VO-10 on the estimate, VO-9
  bool CheckGeometry(Step* st);            // VO-12
  void Accept(Step* st);                   // windowed mode: keyframe, window, delta
  VoResult Finish(Step* st);               // what every outcome shares

  // ---- Parts of the stages ----
  std::string InputProblem(const StereoImages& im) const;  // empty: none
  void BuildPyramid(Pair* pair);
  void StereoMatchFresh(Pair* pair, const std::vector<Corner>& corners);
  bool MatchRight(const Pair& pair, const Eigen::Vector3d& C1, const Eigen::Vector3d& r1,
                  double range_near, double range_far, double margin_px,
                  const Template* coarse, Eigen::Vector2d* right, Eigen::Matrix2d* Sigma_right);
  TriangulationLimits Limits(const Pair& pair) const {
    TriangulationLimits l;
    l.max_gap_rad = o.triangulation_max_gap_px * pair.pixel_angle;
    l.min_parallax_rad = o.stereo_min_disparity_px * pair.pixel_angle;
    l.max_range_m = o.triangulation_max_range_m;
    return l;
  }
  bool TrackFeature(const Step& st, int fi, const Prediction& p, int levels, double* stereo_ms,
                    Correspondence* x, Feature* seen, char* fixed);
  bool SearchTracked(const Feature& f, const Pair& from, const Pair& to, const Prediction& p,
                     int levels, MatchResult* m);
  bool MatchTrackedStereo(const Pair& c, const Prediction& p, const Eigen::Vector2d& left,
                          double* stereo_ms, Eigen::Vector2d* right, Eigen::Matrix2d* Sigma_right);
  bool CheckShadow(Step* st);      // VO-11
  bool CheckSiteFrame(Step* st);   // VO-9's site-frame limits
  // Windowed mode: gives `pair` the carried tracks plus fresh corners stereo-matched where
  // tracks are missing (VO-2 top-up), and counts its features in res.
  void CompleteFeatures(Pair* pair, std::vector<Feature> carried, VoResult* res);
  // Windowed mode: the window restarts on `pair` (first pair, a failure, a refused
  // refinement), which becomes the reference pair.
  void RestartWindow(Pair* pair);
  void RefineWindow(Step* st, const Eigen::Isometry3d& T_w_ref, const Eigen::Isometry3d& T_ref_cur,
                    const Matrix6d& pair_cov);
};

}  // namespace rover::vo
