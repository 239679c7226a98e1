// The MER visual odometry (common/vo/README.md) as a sequence of stages, one per step of
// the method; each stage lives in the file named for it (vo_state.hpp lists them).
#include "vo/visual_odometry.hpp"

#include "vo/vo_state.hpp"

namespace rover::vo {

VisualOdometry::VisualOdometry(VoOptions options) : state_(std::make_unique<State>()) {
  ValidateVoOptions(options);
  state_->o = options;
  WindowOptions w;
  w.max_frames = std::max(2, options.window_size);
  w.max_iterations = options.window_max_iterations;
  w.huber_sigmas = options.window_huber_sigmas;
  w.track_carry = options.window_track_carry;
  w.stereo_carry = options.window_stereo_carry;
  w.covariance_track_carry = options.window_covariance_track_carry;
  w.covariance_stereo_carry = options.window_covariance_stereo_carry;
  w.disparity_offset_sigma_px = options.window_disparity_offset_sigma_px;
  w.disparity_offset_drift_px = options.window_disparity_offset_drift_px;
  w.disparity_offset_systematic_px = options.window_disparity_offset_systematic_px;
  w.disparity_offset_min_sigmas = options.window_disparity_offset_min_sigmas;
  state_->window = SlidingWindow(w);
}
VisualOdometry::~VisualOdometry() = default;
VisualOdometry::VisualOdometry(VisualOdometry&&) noexcept = default;
VisualOdometry& VisualOdometry::operator=(VisualOdometry&&) noexcept = default;

void VisualOdometry::Reset() {
  state_->prev.reset();
  state_->spare.reset();
  state_->calls = 0;
  state_->window = SlidingWindow(state_->window.options());
  state_->T_w_last = Eigen::Isometry3d::Identity();
  state_->last_ref_cov.setZero();
}

const VoOptions& VisualOdometry::options() const { return state_->o; }

VoResult VisualOdometry::Process(const StereoImages& images,
                                 const Eigen::Isometry3d& prior_T_prev_curr,
                                 const Eigen::Matrix<double, 6, 6>& prior_covariance) {
  State& s = *state_;
  // A stage returning false has ended the call with a status and reason (VO-10); Finish
  // then does what every outcome shares.
  Step st(images, prior_T_prev_curr, prior_covariance);
  if (!s.CheckInput(&st)) return s.Finish(&st);  // VO-1: images, camera models, prior
  s.LoadPair(&st);                                // VO-1: working resolution, pyramid
  s.DetectFeatures(&st);                          // VO-2: corners
  s.MatchNewFeatures(&st);                        // VO-3..VO-5: stereo, triangulation
  s.TakeReference(&st);                           // the pair measured against
  if (!s.CheckReference(&st) || !s.CheckPriorMotion(&st)) return s.Finish(&st);
  s.TrackFeatures(&st);                                    // VO-6: tracking by correlation
  const bool accepted = s.CheckTracks(&st) &&              // VO-10: overlap, enough tracks
                        s.EstimateRansac(&st) &&           // VO-7 RANSAC, VO-11 shadow
                        s.RefineMaximumLikelihood(&st) &&  // VO-8
                        s.EstimateCovariance(&st) &&       // VO-13
                        s.CheckSanity(&st) &&              // VO-10, VO-9 sanity
                        s.CheckGeometry(&st);              // VO-12 degenerate geometry
  if (accepted && s.Windowed()) s.Accept(&st);  // keyframes, tracks, the sliding window
  return s.Finish(&st);
}

// What every outcome shares: the status, the total time, and the pairs kept for the next call.
VoResult VisualOdometry::State::Finish(Step* st) {
  if (Windowed() && st->cur) {
    // Every outcome but an accepted measurement restarts the tracks and the window on
    // the new pair, which becomes the reference (as VO-10 makes it the previous pair).
    CompleteFeatures(st->cur.get(), {}, &st->res);
    RestartWindow(st->cur.get());
    prev = std::move(st->cur);
  }
  st->res.status = st->status;
  st->res.reason = std::move(st->reason);
  st->res.times.total_ms = Ms(st->start, Clock::now());
  // The old pair's buffers serve the next call's pair.
  if (st->ref) spare = std::move(st->ref);
  return std::move(st->res);
}

}  // namespace rover::vo
