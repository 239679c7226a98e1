// Image figures that say whether rendered terrain looks like Mars to VO: how many corners a
// Harris detector finds, and how much local contrast varies across the image. Used by
// render_benchmark to compare renders with real NAVCAM images, and by tests (sand must
// give far fewer corners than bedrock).
#pragma once

#include <opencv2/core.hpp>

namespace rover::render {

struct ImageStatistics {
  int corners = 0;                   // Harris corners above the absolute threshold
  double corners_per_mpix = 0;       // the same per million pixels
  double local_std_mean = 0;         // mean over the image of the 15x15 local std (DN)
  double local_std_spread = 0;       // std of that local std: the spread of local contrast
};

struct ImageStatisticsOptions {
  // Images are first resized to this width so that counts compare across sizes.
  int working_width = 512;
  // Harris response (k = 0.04, 5x5 block, 3x3 Sobel, intensities in [0, 1]) a corner must
  // exceed, and the minimum distance between counted corners (non-maximum suppression).
  double harris_threshold = 1e-5;
  int min_distance_px = 5;
  int window_px = 15;
};

// `image`: CV_8UC1, or CV_16UC1 which is stretched to 8 bits by its own min..max.
ImageStatistics MeasureImage(const cv::Mat& image, const ImageStatisticsOptions& options = {});

// 16-bit (or 8-bit) to 8-bit by the image's own range.
cv::Mat To8Bit(const cv::Mat& image);

}  // namespace rover::render
