// Sliding-window maximum-likelihood refinement (common/vo/README.md, "VO with memory").
//
// The window holds the last N keyframe poses T_w_i of the rig (w: the frame of the
// window's first pose) and, per keyframe, the stereo observations of the tracked features
// (tracks.hpp). Refine() minimises the covariance-weighted stereo reprojection error
//   sum_ij rho( |u_l,ij - pi_l(T_i^-1 X_j)|^2_{W_l} + |u_r,ij - pi_r(T_i^-1 X_j)|^2_{W_r} )
// over the poses 1..N-1 and the points X_j seen in at least two keyframes, W the inverse
// 2x2 match covariances of VO-3 and rho a Huber loss. The oldest pose is held fixed (the
// gauge; stereo fixes the scale).
//
// Solver: our own Levenberg-Marquardt on Eigen with the points eliminated by the Schur
// complement, not Ceres: the problem is small (at most 9 free poses, a few hundred points,
// a 54x54 reduced system), its structure is fixed, and it must run in a couple of
// milliseconds on one core with no new dependency in the flight build.
#pragma once

#include "geometry/camera_model.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <unordered_map>
#include <vector>

namespace rover::vo {

// One feature seen in one keyframe: its left and right pixels (working resolution) and
// their 2x2 covariances (VO-3), and its triangulated point in that keyframe (VO-4/VO-5),
// which starts the point's estimate.
struct WindowObservation {
  std::int64_t track_id = 0;
  Eigen::Vector2d left = Eigen::Vector2d::Zero(), right = Eigen::Vector2d::Zero();
  Eigen::Matrix2d Sigma_left = Eigen::Matrix2d::Identity();
  Eigen::Matrix2d Sigma_right = Eigen::Matrix2d::Identity();
  Eigen::Vector3d P = Eigen::Vector3d::Zero();
  Eigen::Matrix3d Sigma = Eigen::Matrix3d::Identity();
};

struct WindowOptions {
  int max_frames = 5;          // keyframes kept (>= 2)
  int max_iterations = 8;      // Levenberg-Marquardt iterations
  double huber_sigmas = 3.0;   // Huber threshold on an observation's normalised residual
  // How a track's errors relate from keyframe to keyframe (ToIndependentErrors in
  // window.cpp). VO-6 cuts each pair's template at the track's last left match, so part of
  // a match error carries into the next observation: the left errors follow
  //   l_n = track_carry * l_n-1 + w_n,
  // and the right match is cut at its own keyframe's left one:
  //   r_n = stereo_carry * l_n + s_n,
  // w_n and s_n the matches' own errors (Sigma_left, Sigma_right). 0 and 0: independent
  // errors per observation; 1 and 1: the left errors are a random walk. Taken as
  // independent when they are not, a track seen in 5 keyframes counts its first match
  // error 5 times and the refined step claims more than its data give (README "VO with
  // memory"). VisualOdometry sets both from VoOptions (window_track_carry,
  // window_stereo_carry), which are measured on rendered drives (tools/vo_carry).
  double track_carry = 0.0;
  double stereo_carry = 0.0;
  // The carry model (as above) of the errors under which the published covariance is
  // computed, apart from the weights: the estimate stays the one weighed with track_carry
  // and stereo_carry, and its covariance is the sandwich S^-1 M S^-1 (S the reduced normal
  // matrix, M the covariance of the reduced gradient when the errors follow this model;
  // README "VO with memory", "Sandwich covariance"). Negative (the default): the weights'
  // own model, and the covariance is S^-1.
  double covariance_track_carry = -1.0;
  double covariance_stereo_carry = -1.0;
  double tolerance = 1e-4;     // stop when the relative cost decrease is below this
  // One disparity offset (right x, pixels) for every observation: a disparity offset
  // scales every range. It is one drive-wide quantity: a scalar recursive filter starts
  // from a zero-mean prior of this sigma and takes in every full window's estimate from
  // that window's data alone (with 1/max_frames of its information: windows overlap);
  // 0 = not estimated.
  double disparity_offset_sigma_px = 0.0;
  // The filter's process noise: a random walk of this sigma per full window, so that a
  // drift of the calibration (temperature) can still be followed.
  double disparity_offset_drift_px = 0.0;
  // The window uses the filter's estimate only when it differs from zero by more than
  // disparity_offset_min_sigmas times sqrt(filter variance + systematic^2), else zero:
  // `systematic` is the offset that the matcher's own systematic disparity errors can
  // fake, which no number of windows averages away. min_sigmas 0 = always used.
  double disparity_offset_systematic_px = 0.0;
  double disparity_offset_min_sigmas = 0.0;
};

struct WindowSolution {
  bool ok = false;
  int iterations = 0;
  int points = 0;         // points in the problem (seen in >= 2 keyframes)
  int observations = 0;   // their observations
  double initial_cost = 0, final_cost = 0;
  // A-posteriori variance factor: final cost / (4 observations - 3 points - 6 poses).
  double variance_factor = 0;
  // The variance factor under the covariance's model: the final cost over its expectation
  // when the errors follow that model (the redundancy above when it is the weights' own).
  double covariance_variance_factor = 0;
  double disparity_offset_px = 0;  // the offset used from now on (AppliedOffset of the filter)
  // This window's offset from its data alone (flat prior) and its sigma; 0 when the
  // window did not estimate one.
  double window_offset_px = 0, window_offset_sigma_px = 0;
  // The last keyframe's pose in the one before it, and the covariance of that delta
  // (x y z roll pitch yaw of the delta, as VoResult::covariance) from the inverse of the
  // reduced (Schur) normal matrix, or the sandwich under the covariance's carry model
  // (WindowOptions::covariance_track_carry, `sandwich` below), in the units of the match covariances (not scaled by
  // the variance factor). The delta VO publishes starts from the previous keyframe's pose
  // as it was published (before this refinement moved it by c), so the covariance also
  // holds that correction's: Cov(c) = Sigma_then - Sigma_now of that pose's marginal
  // (the smoother's correction is orthogonal to its error), carried into the delta. That
  // holds only while no keyframe has left the window since pose a was published: the
  // dropped keyframe's information is lost, not marginalised, and the pose fixed in its
  // place changes the gauge. `carries_correction` says whether the covariance holds Cov(c)
  // (true) or is the delta T_prev_last's alone (false: a frame left, or the window
  // restarted), and so which delta it belongs to.
  Eigen::Isometry3d T_prev_last = Eigen::Isometry3d::Identity();
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Zero();
  bool carries_correction = false;
  // The covariance of T_prev_last alone (without Cov(c)), in the same units.
  Eigen::Matrix<double, 6, 6> step_covariance = Eigen::Matrix<double, 6, 6>::Zero();
  // The same under the weights' own model (S^-1 alone), whatever the covariance's model:
  // the pair's VO-8 covariance is under that model too, so the window's consistency test
  // against the pair (the covariance of the difference of two nested estimates, the pair's
  // minus the window's) uses this one. Equal to step_covariance without a sandwich.
  Eigen::Matrix<double, 6, 6> fit_step_covariance = Eigen::Matrix<double, 6, 6>::Zero();
  bool sandwich = false;  // covariance is S^-1 M S^-1 (WindowOptions::covariance_*_carry set)
};

class SlidingWindow {
 public:
  explicit SlidingWindow(WindowOptions options = {}) : o_(options) {}

  const WindowOptions& options() const { return o_; }
  // New options for the next Refine (the window's contents and offset estimate stay).
  void Reset();
  // Appends a keyframe with its initial pose in the window frame; the oldest keyframe
  // leaves when the window is full (its pose is then the new fixed one).
  void AddFrame(std::int64_t frame_id, const Eigen::Isometry3d& T_w_frame,
                std::vector<WindowObservation> observations);
  // Removes the newest keyframe and restores every pose to what it was before that
  // keyframe was added (a refinement that is refused leaves the window as it was).
  void PopNewest();
  // The drive-wide offset filter's estimate and sigma.
  double disparity_offset_px() const { return disparity_offset_; }
  double disparity_offset_sigma_px() const;
  int size() const { return static_cast<int>(frames_.size()); }
  const Eigen::Isometry3d& pose(int i) const { return frames_[static_cast<std::size_t>(i)].T_w; }
  std::int64_t frame_id(int i) const { return frames_[static_cast<std::size_t>(i)].id; }

  // Refines the poses 1..size-1 and the points. Needs >= 2 keyframes and enough points.
  WindowSolution Refine(const geometry::StereoRig& rig);

 private:
  struct Frame {
    std::int64_t id = 0;
    Eigen::Isometry3d T_w = Eigen::Isometry3d::Identity();
    std::vector<WindowObservation> obs;
  };
  WindowOptions o_;
  std::vector<Frame> frames_;
  // For PopNewest: the poses before the last AddFrame (and the frame that slid out).
  std::vector<Eigen::Isometry3d> saved_poses_;
  bool has_dropped_ = false;
  Frame dropped_;
  // Point estimates of the last refinement, by track id (a warm start).
  std::unordered_map<std::int64_t, Eigen::Vector3d> points_;
  // The drive-wide offset filter: its estimate and information (0: not started, the
  // prior's). Reset() keeps them: the rig is the same after a restart.
  double disparity_offset_ = 0;
  double offset_info_ = 0;
  // The newest pose's marginal covariance at the last refinement, for Cov(c).
  bool has_newest_cov_ = false;
  std::int64_t newest_id_ = 0;
  Eigen::Matrix<double, 6, 6> newest_cov_ = Eigen::Matrix<double, 6, 6>::Zero();
};

// x y z roll pitch yaw of the relative pose inv(Ta exp(da)) Tb exp(db), differentiated
// numerically with respect to (da, db) (each a body-frame perturbation: translation
// first, then rotation): the 6x12 Jacobian.
Eigen::Matrix<double, 6, 12> RelativePoseJacobian(const Eigen::Isometry3d& Ta,
                                                  const Eigen::Isometry3d& Tb);

// One track's m observations stacked 4 rows each (left x y, right x y, keyframe order),
// residuals or Jacobians, taken in place to the rows whose errors are the matches' own and
// independent, under the carry model of WindowOptions (track_carry, stereo_carry):
// row block n becomes (left_n - track_carry left_n-1, right_n - stereo_carry left_n).
void ToIndependentErrors(Eigen::Ref<Eigen::MatrixXd> rows, int m, double track_carry, double stereo_carry);

// T exp(d): rotation R Exp(w), translation t + R v (d = (v, w)).
Eigen::Isometry3d Retract(const Eigen::Isometry3d& T, const Eigen::Matrix<double, 6, 1>& d);

}  // namespace rover::vo
