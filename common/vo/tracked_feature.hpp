// A feature visual odometry tracked from the previous stereo pair into the current one
// (VO-6), kept for pictures and diagnostics (tools/plot draws them over the left image):
// its left-image pixel in each pair, and whether the maximum-likelihood motion used it.
#pragma once

#include <Eigen/Core>

#include <cstdint>

namespace rover::vo {

struct TrackedFeature {
  // Left-image pixels at the working resolution (VoOptions::working_scale; (0,0) is the
  // centre of the top-left pixel): where the feature was in the previous pair, and where
  // tracking found it in the current one.
  Eigen::Vector2d prev_left = Eigen::Vector2d::Zero();
  Eigen::Vector2d curr_left = Eigen::Vector2d::Zero();
  // The right-image pixels of the same two stereo matches, and (windowed mode) the track
  // the feature belongs to (0 in frame-to-frame mode): with these a feature's errors can
  // be followed along its track against truth (tools/vo_carry).
  Eigen::Vector2d prev_right = Eigen::Vector2d::Zero();
  Eigen::Vector2d curr_right = Eigen::Vector2d::Zero();
  std::int64_t track_id = 0;
  // Used by the maximum-likelihood motion (VO-8); false for RANSAC's outliers and for the
  // ones the ML outlier test dropped, and for every feature when VO stopped before ML.
  bool inlier = false;
};

}  // namespace rover::vo
