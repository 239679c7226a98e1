// How much of a track's match error carries into its next observation, measured against
// truth (the window's carry model, common/vo/window.hpp: WindowOptions::track_carry and
// stereo_carry).
//
// VO-6 cuts a track's template at its last left match, so part of a match error may carry
// forward. Along a track, with l_n and r_n the left and right pixel errors of its n-th
// keyframe observation against the truth's projection of its 3-D point, the model is
//   l_n = rho l_n-1 + w_n,   r_n = rho_s l_n + s_n,
// w_n and s_n the matches' own errors. The least-squares estimates from many tracks are
//   rho   = sum l_n-1 . l_n / sum |l_n-1|^2   (consecutive observations of a track),
//   rho_s = sum l_n . r_n   / sum |l_n|^2,
// per image axis and with both axes pooled. An error made on the surface looks larger as
// the rover closes in (perspective), so rho is also estimated with l_n-1 first carried by
// the true image-to-image map of the surface round the feature (the 2x2 Jacobian A_n of
// the pixel in keyframe n with respect to the pixel in keyframe n-1):
//   rho_mapped = sum (A_n l_n-1) . l_n / sum |A_n l_n-1|^2,
// the fraction of the error that carries beyond what geometry alone makes of it. A track's first observation defines its 3-D
// point (the left pixel where it was detected, carried to the true surface by the true
// range), so l_0 = 0 by construction: it starts the chain and gives no stereo pair.
#pragma once

#include "vo/visual_odometry.hpp"
#include "vo_eval/rendered_drive.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <ostream>
#include <unordered_map>

namespace rover::vo_carry {

struct CarryEstimate {
  int tracks = 0;        // tracks with at least one observation after the defining one
  int track_pairs = 0;   // (l_n-1, l_n) pairs behind rho
  int stereo_pairs = 0;  // (l_n, r_n) pairs behind rho_s
  double track_carry = 0, stereo_carry = 0;        // both axes pooled
  double track_carry_mapped = 0;  // rho after the surface's image-to-image map (A_n)
  int mapped_pairs = 0;
  Eigen::Vector2d track_carry_xy = Eigen::Vector2d::Zero();   // x and y apart
  Eigen::Vector2d stereo_carry_xy = Eigen::Vector2d::Zero();
  // The left matches' own error (rms of w_n = l_n - rho l_n-1 per axis, px) and the
  // standard error of rho from it.
  double match_sigma_px = 0;
  double track_carry_stderr = 0;
};

// Sums behind CarryEstimate, fed with each track's errors in keyframe order.
class CarryAccumulator {
 public:
  // One observation of a track: its left and right errors (measured minus the truth's
  // projection, pixels). `defining`: the observation that defines the track's 3-D point.
  // `image_map` (optional): A_n, the map of image offsets from the track's last keyframe to
  // this one.
  void Add(std::int64_t track_id, const Eigen::Vector2d& left_error, const Eigen::Vector2d& right_error,
           bool defining, const Eigen::Matrix2d* image_map = nullptr);
  // The track's chain is broken (an observation missing or left out): it ends here.
  void Drop(std::int64_t track_id) { last_.erase(track_id); }
  // Adds another accumulator's sums (its open chains are not carried over).
  void Merge(const CarryAccumulator& other);
  CarryEstimate Estimate() const;

 private:
  struct Last {
    Eigen::Vector2d left = Eigen::Vector2d::Zero();
    bool defining = true;
  };
  std::unordered_map<std::int64_t, Last> last_;
  int tracks_ = 0, track_pairs_ = 0, stereo_pairs_ = 0, mapped_pairs_ = 0;
  double s_mapped_curr_ = 0, s_mapped_mapped_ = 0;  // sum (A l_n-1) . l_n, sum |A l_n-1|^2
  // Per axis: sum l_n-1 l_n, sum l_n-1^2, sum l_n^2 (track); sum l_n r_n, sum l_n^2 (stereo).
  Eigen::Vector2d s_prev_curr_ = Eigen::Vector2d::Zero(), s_prev_prev_ = Eigen::Vector2d::Zero(),
                  s_curr_curr_ = Eigen::Vector2d::Zero();
  Eigen::Vector2d s_left_right_ = Eigen::Vector2d::Zero(), s_left_left_ = Eigen::Vector2d::Zero();
};

struct DriveCount {
  int frames = 0, keyframes = 0;  // VO calls; accepted keyframes
  int observations = 0;           // track observations measured
  int undefined = 0;              // tracks whose point the true range could not define
};

// Runs the VO (`vo`, with an odometry prior as vo_eval's rendered drives use) over the
// drive and feeds every inlier track observation of every accepted keyframe to `acc`.
// Observations more than `max_error_px` from the truth end their track (mismatches, which
// the window's robust loss handles, are not the match error the model is about).
// `dump` (optional) gets one CSV line per observation measured (frame, track_id, age,
// range_m, left x y, right x y errors; header by the caller, kDumpHeader).
DriveCount MeasureDrive(const vo_eval::RenderedDriveSequence& drive, const vo::VoOptions& vo,
                        CarryAccumulator* acc, double max_error_px = 3.0, std::ostream* dump = nullptr);
inline constexpr const char* kDumpHeader = "world,frame,track_id,age,range_m,lx,ly,rx,ry";

}  // namespace rover::vo_carry
