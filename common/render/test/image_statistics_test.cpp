// The realism figures must describe the scene, not the exposure or the bit depth: a real
// 12-bit NAVCAM image and an 8-bit render of the same scene must measure alike.
#include "render/image_statistics.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <cstdint>
#include <stdexcept>

namespace rover::render {
namespace {

// A scene as relative radiance around 1: dim soil with blurred cm-scale texture and
// scattered bright and dark "rocks" of a few pixels to a few tens of pixels.
cv::Mat Scene(int size, std::uint64_t seed) {
  cv::RNG rng(seed);
  cv::Mat s(size, size, CV_32F);
  rng.fill(s, cv::RNG::NORMAL, 1.0, 0.08);
  cv::GaussianBlur(s, s, cv::Size(), 1.5);
  for (int k = 0; k < 1500; ++k) {
    const cv::Point c(rng.uniform(0, size), rng.uniform(0, size));
    const int r = static_cast<int>(2 + 12 * std::pow(rng.uniform(0.0, 1.0), 3.0));
    cv::circle(s, c, r, cv::Scalar(rng.uniform(0.5, 1.6)), cv::FILLED, cv::LINE_AA);
  }
  cv::GaussianBlur(s, s, cv::Size(), 0.8);
  return s;
}

// The scene as a camera at `gain` DN per unit radiance would deliver it, in `depth`.
cv::Mat Exposed(const cv::Mat& scene, double gain, int depth) {
  cv::Mat out;
  scene.convertTo(out, depth, gain);  // rounds and saturates like a sensor's ADC
  return out;
}

void ExpectAlike(const ImageStatistics& a, const ImageStatistics& b, const char* what) {
  EXPECT_NEAR(a.corners, b.corners, 0.03 * a.corners + 2) << what;
  EXPECT_NEAR(a.local_std_mean, b.local_std_mean, 0.02 * a.local_std_mean) << what;
  EXPECT_NEAR(a.local_std_spread, b.local_std_spread, 0.03 * a.local_std_spread) << what;
}

TEST(ImageStatistics, ExposureAndBitDepthDoNotChangeTheFigures) {
  const cv::Mat scene = Scene(1024, 7);
  // A 12-bit real-like image in 16 bits, a bright 8-bit render and a dim one.
  const ImageStatistics real = MeasureImage(Exposed(scene, 2000.0, CV_16U));
  const ImageStatistics bright = MeasureImage(Exposed(scene, 140.0, CV_8U));
  const ImageStatistics dim = MeasureImage(Exposed(scene, 60.0, CV_8U));
  ASSERT_GT(real.corners, 100) << "the scene must have corners for the comparison to mean something";
  ExpectAlike(real, bright, "16-bit at 2000 DN vs 8-bit at 140 DN");
  ExpectAlike(real, dim, "16-bit at 2000 DN vs 8-bit at 60 DN");
  // The median reported is the input's own.
  EXPECT_NEAR(real.median_dn / dim.median_dn, 2000.0 / 60.0, 0.05 * 2000.0 / 60.0);
}

TEST(ImageStatistics, LocalContrastIsInPercentOfTheMedian) {
  // Pixel-scale noise of 4 % of the level, then averaged 2x2 by the resize to 512: a local
  // std of about 2 %, whatever the level.
  for (const double level : {50.0, 3000.0}) {
    cv::Mat img(1024, 1024, CV_32F);
    cv::RNG rng(3);
    rng.fill(img, cv::RNG::NORMAL, level, 0.04 * level);
    const ImageStatistics st = MeasureImage(img);
    EXPECT_NEAR(st.local_std_mean, 2.0, 0.15) << "level " << level;
    EXPECT_LT(st.local_std_spread, 0.5) << "level " << level;
  }
}

TEST(ImageStatistics, NearlyFlatImageStaysFlatAtAnyGain) {
  // Featureless ground: 1 % sensor noise. A stretch to the image's own range would blow the
  // noise up into corners; scaling to the median must not.
  for (const double level : {40.0, 200.0}) {
    cv::Mat img(1024, 1024, CV_32F);
    cv::RNG rng(11);
    rng.fill(img, cv::RNG::NORMAL, level, 0.01 * level);
    const ImageStatistics flat = MeasureImage(Exposed(img, 1.0, CV_8U));
    EXPECT_LT(flat.corners, 5) << "level " << level;
  }
  const ImageStatistics textured = MeasureImage(Exposed(Scene(1024, 7), 100.0, CV_8U));
  EXPECT_GT(textured.corners, 100);
}

TEST(ImageStatistics, RejectsWhatItCannotMeasure) {
  EXPECT_THROW(MeasureImage(cv::Mat(64, 64, CV_8UC3, cv::Scalar::all(100))), std::invalid_argument);
  EXPECT_THROW(MeasureImage(cv::Mat(64, 64, CV_8U, cv::Scalar(0))), std::invalid_argument);
  EXPECT_THROW(MeasureImage(cv::Mat()), std::invalid_argument);
}

TEST(ImageStatistics, NormaliseToMedianPutsTheMedianThere) {
  const cv::Mat n = NormaliseToMedian(Exposed(Scene(256, 2), 1500.0, CV_16U), 100.0);
  ASSERT_EQ(n.type(), CV_32F);
  cv::Mat below = n < 100.0f;
  const double fraction = cv::countNonZero(below) / static_cast<double>(n.total());
  EXPECT_NEAR(fraction, 0.5, 0.01);
}

}  // namespace
}  // namespace rover::render
