// Image figures that say whether rendered terrain looks like Mars to VO: how many corners a
// Harris detector finds, and how much local contrast varies across the image. Used by
// render_benchmark to compare renders with real NAVCAM images, and by tests (sand must
// give far fewer corners than bedrock).
//
// Normalisation, and why. Real NAVCAM products are 12-bit data in 16-bit PNGs (medians
// of about 1000 to 3000 DN); rendered images are 8-bit with an exposure of their own
// (automatic, or fixed). The Harris response grows as intensity^4, so counting corners
// above a fixed threshold compares exposures unless every image is first brought to the
// same scale. Every image, real or rendered, is therefore multiplied by the one gain that
// puts its median at `target_median_dn` on an 8-bit scale (kept in floating point: no
// clipping, no requantising), and only then measured. Consequences:
//  - the figures do not depend on exposure or bit depth (a gain cancels exactly);
//  - local contrast comes out in DN at a median of 100, i.e. in percent of the image's
//    median brightness: a relative (albedo-like) contrast that any camera gain leaves alone;
//  - a flat image stays flat. A percentile stretch (1st..99th to 0..255) was rejected
//    because it amplifies without bound: on nearly featureless sand it stretches sensor
//    noise to full range and counts noise as corners, the opposite of what featureless
//    sand does to VO. A min..max stretch has the same flaw and also hangs on one pixel.
// It assumes DN proportional to radiance (no offset). The renderer has none (sky light is
// light, not an offset); real EDRs may keep a small electronic bias, which would lower
// their relative contrast slightly.
#pragma once

#include <opencv2/core.hpp>

namespace rover::render {

struct ImageStatistics {
  int corners = 0;                   // Harris corners above the threshold (after normalising)
  double corners_per_mpix = 0;       // the same per million pixels of the working image
  double local_std_mean = 0;         // mean over the image of the 15x15 local std, in % of the median
  double local_std_spread = 0;       // std of that local std (same unit): the spread of local contrast
  double median_dn = 0;              // the input image's median, before normalising (its own units)
};

struct ImageStatisticsOptions {
  // Images are first resized to this width so that counts compare across sizes.
  int working_width = 512;
  // The median is brought to this value on an 8-bit scale (100 DN: a NAVCAM-like exposure,
  // and then local std in DN is in percent of the median).
  double target_median_dn = 100.0;
  // Harris response (k = 0.04, 5x5 block, 3x3 Sobel, intensities DN / 255 after the
  // normalisation) a corner must exceed, and the minimum distance between counted corners
  // (non-maximum suppression). The VO detector's kind of corner.
  double harris_threshold = 1e-5;
  int min_distance_px = 5;
  int window_px = 15;
};

// `image`: one channel, CV_8U, CV_16U or CV_32F, in any units proportional to radiance.
// Throws std::invalid_argument for other types or an image whose median is not positive.
ImageStatistics MeasureImage(const cv::Mat& image, const ImageStatisticsOptions& options = {});

// The image (one channel, any depth) as CV_32F multiplied so that its median is
// `target_median` (the normalisation MeasureImage applies, for looking at what it measures).
cv::Mat NormaliseToMedian(const cv::Mat& image, double target_median);

}  // namespace rover::render
