// Dense stereo for the traversability map: rectify a stereo pair (NAVCAM, HAZCAM) through its camera
// models, match it with OpenCV's StereoSGBM and triangulate into the rover frame.
//
// Rectification, as JPL's tools do for CAHVOR: both images are resampled into a pair of
// ideal pinhole (linear, CAHV-equivalent) cameras with parallel optical axes, the same
// focal length and principal point, the x axes along the baseline, centred on the
// original camera centres and looking along the mean of the two original axes. Each
// rectified pixel's ray is projected through the original model (CAHV, CAHVOR, pinhole
// with distortion, ...) to get the cv::remap maps, cached per rig. A disparity d then gives
// depth z = f B / d along the common axis, and the point follows from the rectified left
// camera's ray.
#pragma once

#include "geometry/camera_model.hpp"
#include "traversability/traversability_map.hpp"

#include <Eigen/Core>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include <memory>
#include <vector>

namespace rover::traversability {

struct StereoPoints {
  std::vector<Eigen::Vector3d> points_rover;  // rover frame (X forward, Y right, Z down)
  // One standard deviation of each point's stereo error, along its ray (rover frame): the
  // range error of its matching error (DisparitySigmaPx, on the source image, times
  // SourceStretch), which the map turns into a height sigma in the site frame at the
  // capture attitude.
  std::vector<Eigen::Vector3d> error_rover;
};

// The rectified pair's geometry at the matching scale.
struct RectifiedRig {
  int width = 0, height = 0;
  double f = 0, cx = 0, cy = 0;   // pixels
  double baseline_m = 0;
  int pyramid_levels = 0;  // 2x reductions of the source images before remapping
  Eigen::Matrix3d R_rover_rect = Eigen::Matrix3d::Identity();  // rectified optical frame
  Eigen::Vector3d left_centre = Eigen::Vector3d::Zero();       // rover frame
  cv::Mat map_lx, map_ly, map_rx, map_ry;  // CV_32FC1: rectified pixel -> source pixel
  // Mean squared horizontal Sobel gradient of the rectified left image per unit variance
  // of its estimated noise, for read noise alone (12 for independent pixels; the reduction
  // and resampling correlate them). Measured on synthetic noise.
  double texture_noise_gain = 12.0;
};

// Builds the rectification for `rig` with images scaled by `scale` (in (0, 1]). The
// rectified focal length is the models' at their image centre (times the scale), so the
// centre keeps its resolution; the rectified image is the scaled size, or, with
// `fov_deg` > 0, as many columns more as span that field across (along the baseline; at
// most 4 times the scaled width): a fish-eye's field is wider than a pinhole of its centre
// focal length covers at its width (124 deg against 94 deg for the HAZCAM). Throws
// std::invalid_argument on a degenerate rig (zero baseline, axes far from parallel) or a
// field outside [0, 170) deg.
RectifiedRig Rectify(const geometry::StereoRig& rig, double scale, double fov_deg = 0.0);

// How many rectified pixels along the row one source pixel spans at rectified pixel (u, v)
// (at least 1): the factor by which disparity_sigma_px (a matching error on the source
// image) grows there. A rectified pinhole oversamples a fish-eye's periphery: the pinhole's
// f / cos^2(theta) against the equidistant lens's f, 4 rectified pixels per source pixel at
// 60 deg off the axis.
double SourceStretch(const RectifiedRig& r, int u, int v);

// Matches a rectified pair (8-bit grey, the same size): the left image's disparities in
// 1/16 px (CV_16S), <= 0 where unmatched. Uses StereoSGBM (MODE_SGBM_3WAY) on the pair
// padded on the left so that the whole left image is matched; with options.lr_max_diff_px
// > 0, also the right image against the left (RightViewMatcher), and a left pixel whose
// match's right-view disparity differs by more than that is unmatched.
cv::Mat MatchDisparity(const cv::Mat& rectL, const cv::Mat& rectR, const MapOptions& options);

// The matcher of the right view against the left for a left-right check: the settings
// cv::ximgproc::createRightMatcher gives an SGBM matcher (the disparity range mirrored,
// no uniqueness, disp12 or speckle filtering; the same block, penalties, mode and
// pre-filter cap). Written here so that hazard_monitor need not link ximgproc, which
// loads imgcodecs and its ~120 libraries (~0.12 s of CPU at every start);
// traversability_test checks it against ximgproc's.
cv::Ptr<cv::StereoSGBM> RightViewMatcher(const cv::StereoSGBM& left);

// Texture along the rows against the image's noise, per pixel of a rectified left image
// (8-bit grey): the mean squared horizontal Sobel gradient over the block_size block around
// it, over what read noise alone gives there (`texture_noise_gain`, RectifiedRig's, times
// the image's own noise variance, estimated from the image). CV_32F: the texture SNR
// squared, 1 for noise alone. min_texture_snr drops pixels under its square;
// texture_sigma_px reads it for each point's disparity sigma.
cv::Mat TextureSnr2(const cv::Mat& rect_left, double texture_noise_gain, int block_size);

// A match's disparity sigma (px on the source image at the matching scale) for a block of
// texture SNR squared `snr2` (TextureSnr2): disparity_sigma_px, and with texture_sigma_px
// the image noise's share, sqrt(disparity_sigma_px^2 + texture_sigma_px^2 / rho) with
// rho = max(snr2 - 1, 0.01), the texture's own gradient energy over the noise's.
double DisparitySigmaPx(double snr2, const MapOptions& options);

// Rectifies, matches and triangulates one pair. Throws std::invalid_argument with a
// one-line message when an image is empty, not 8-bit grey, or not the models' size.
// `stats` (optional) gets the rectify and match times. Caches the rectifications of the
// last 4 rigs seen (per thread: a NAVCAM and a HAZCAM pair in turn are not rebuilt).
StereoPoints DenseStereo(const cv::Mat& left, const cv::Mat& right,
                         const geometry::StereoRig& rig, const MapOptions& options,
                         UpdateStats* stats = nullptr);

// One pair's points as the map takes them (AddStereoPair): in the site frame at the capture
// pose `T_site_rover`, each with its height sigma (the stereo error along its ray, turned
// into the site's vertical, plus the pose's z and roll/pitch variances from `pose_cov`).
// Dropped: points beyond `stereo.max_range_m` (horizontal, rover frame) and, with
// `stereo.min_depression_deg`, those whose ray from `lens` (the left camera's centre, rover
// frame) runs less than that far below the site's horizontal or the rover's own plane.
void PlaceStereoPoints(const StereoPoints& sp, const Eigen::Vector3d& lens, const geometry::Pose& T_site_rover,
                       const geometry::Matrix6d& pose_cov, const MapOptions& stereo,
                       std::vector<Eigen::Vector3d>* points_site, std::vector<double>* sigma_m);

// The rectification DenseStereo uses for a pair of `image_width` columns from `rig` with
// `options` (the same cached one).
std::shared_ptr<const RectifiedRig> PairRectification(const geometry::StereoRig& rig, int image_width,
                                                      const MapOptions& options);

// Whether a rover-frame point could be matched and kept by DenseStereo with `options`:
// it lies in front of the rectified pair, inside both rectified images away from their
// edges by half a block (and the pixel of SGBM's prefilter), on the source images, within
// the disparity search and the stereo range, and not behind min_x_m. Occlusion by nearer
// ground is not judged.
bool PairFrames(const RectifiedRig& r, const Eigen::Vector3d& p_rover, const MapOptions& options);

// How many rectifications DenseStereo has built on this thread (its cache's misses).
std::size_t RectificationsBuilt();

}  // namespace rover::traversability
