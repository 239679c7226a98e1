// The dense stereo's left-right consistency check on a synthetic rectified pair with a
// known occlusion: a textured square at 24 px of disparity in front of a textured
// background at 8 px. The background just left of the square (16 px, the disparities'
// difference) is seen by the left camera only; it has no match in the right image.
#include "traversability/dense_stereo.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>
#include <opencv2/ximgproc/disparity_filter.hpp>

namespace rover::traversability {
namespace {

constexpr int kWidth = 220, kHeight = 120;
constexpr int kBackground = 8, kForeground = 24;     // disparities (px)
constexpr int kSquareLeft = 110, kSquareRight = 150;  // left-image columns of the square
constexpr int kSquareTop = 30, kSquareBottom = 90;

cv::Mat Texture(int width, std::uint64_t seed) {
  cv::Mat t(kHeight, width, CV_8UC1), blurred;
  cv::RNG rng(seed);
  rng.fill(t, cv::RNG::UNIFORM, 0, 256);
  cv::GaussianBlur(t, blurred, cv::Size(3, 3), 0.8);
  return blurred;
}

struct Pair {
  cv::Mat left, right, truth;  // truth: the left pixel's disparity, 0 where it has no match
};

Pair OccludingSquare() {
  const cv::Mat bg = Texture(kWidth + kForeground + 1, 11), fg = Texture(kWidth + kForeground + 1, 12);
  Pair p{cv::Mat(kHeight, kWidth, CV_8UC1), cv::Mat(kHeight, kWidth, CV_8UC1), cv::Mat(kHeight, kWidth, CV_32S)};
  auto in_square_rows = [](int v) { return v >= kSquareTop && v < kSquareBottom; };
  for (int v = 0; v < kHeight; ++v)
    for (int u = 0; u < kWidth; ++u) {
      const bool square = in_square_rows(v) && u >= kSquareLeft && u < kSquareRight;
      p.left.at<std::uint8_t>(v, u) = square ? fg.at<std::uint8_t>(v, u) : bg.at<std::uint8_t>(v, u);
      // The right camera sees the square kForeground px to the left, over the background.
      const int s = u + kForeground;  // the left column the square shows here
      const bool square_r = in_square_rows(v) && s >= kSquareLeft && s < kSquareRight;
      p.right.at<std::uint8_t>(v, u) = square_r ? fg.at<std::uint8_t>(v, s) : bg.at<std::uint8_t>(v, u + kBackground);
      // The truth: background pixels whose right-image position the square covers are occluded.
      const int ur = u - kBackground;
      const bool occluded = !square && in_square_rows(v) && ur + kForeground >= kSquareLeft && ur + kForeground < kSquareRight;
      p.truth.at<int>(v, u) = square ? kForeground : (occluded || ur < 0 ? 0 : kBackground);
    }
  return p;
}

struct Count {
  int occluded = 0, occluded_matched = 0;  // pixels with no true match, and those given a disparity
  int visible = 0, visible_right = 0;      // pixels with one, and those matched within 1 px of it
  int visible_wrong = 0;                   // and those matched further from it
};

Count Score(const Pair& p, const cv::Mat& disp16) {
  Count c;
  // Away from the image's borders, where the blocks are whole (and the left columns the
  // right image never sees).
  for (int v = 5; v < kHeight - 5; ++v)
    for (int u = kBackground + 5; u < kWidth - 5; ++u) {
      const int truth = p.truth.at<int>(v, u);
      const int d16 = disp16.at<std::int16_t>(v, u);
      if (truth == 0) {
        ++c.occluded;
        c.occluded_matched += d16 > 0;
      } else {
        ++c.visible;
        c.visible_right += d16 > 0 && std::abs(d16 / 16.0 - truth) <= 1.0;
        c.visible_wrong += d16 > 0 && std::abs(d16 / 16.0 - truth) > 1.0;
      }
    }
  return c;
}

TEST(LeftRightCheck, DropsTheOccludedBandAndKeepsTheRest) {
  const Pair p = OccludingSquare();
  MapOptions o;
  o.num_disparities = 32;
  o.uniqueness_ratio = 0;
  o.speckle_window = 0;
  const Count plain = Score(p, MatchDisparity(p.left, p.right, o));
  o.lr_max_diff_px = 1.0;
  const Count checked = Score(p, MatchDisparity(p.left, p.right, o));
  const int band = (kForeground - kBackground) * (kSquareBottom - kSquareTop);
  ASSERT_EQ(checked.occluded, band);
  // SGBM alone (its uniqueness and speckle filters off, so the check is seen alone) gives
  // some of the occluded band a disparity ...
  EXPECT_GT(plain.occluded_matched, band / 20) << plain.occluded_matched << " of " << band;
  // ... the check drops most of them ...
  EXPECT_LT(checked.occluded_matched, plain.occluded_matched / 2) << checked.occluded_matched << " of " << band;
  EXPECT_LT(checked.occluded_matched, band / 10);
  // ... keeps the correct matches elsewhere, and adds no wrong ones.
  EXPECT_GT(checked.visible_right, 0.99 * plain.visible_right) << checked.visible_right << " vs " << plain.visible_right;
  EXPECT_GT(checked.visible_right, 0.95 * checked.visible);
  EXPECT_LE(checked.visible_wrong, plain.visible_wrong);
}

// RightViewMatcher stands in for cv::ximgproc::createRightMatcher (so that the process
// need not link ximgproc): the same settings, and the same right-view disparities.
TEST(LeftRightCheck, TheRightViewMatcherIsXimgprocsRightMatcher) {
  const Pair p = OccludingSquare();
  cv::Ptr<cv::StereoSGBM> left = cv::StereoSGBM::create(-3, 48, 7, 8 * 49, 32 * 49, 2, 31, 10, 100, 2,
                                                        cv::StereoSGBM::MODE_SGBM_3WAY);
  const cv::Ptr<cv::StereoSGBM> ours = RightViewMatcher(*left);
  const cv::Ptr<cv::StereoSGBM> theirs = cv::ximgproc::createRightMatcher(left).dynamicCast<cv::StereoSGBM>();
  ASSERT_FALSE(theirs.empty());
  EXPECT_EQ(ours->getMinDisparity(), theirs->getMinDisparity());
  EXPECT_EQ(ours->getMinDisparity(), -(-3 + 48) + 1);
  EXPECT_EQ(ours->getNumDisparities(), theirs->getNumDisparities());
  EXPECT_EQ(ours->getBlockSize(), theirs->getBlockSize());
  EXPECT_EQ(ours->getP1(), theirs->getP1());
  EXPECT_EQ(ours->getP2(), theirs->getP2());
  EXPECT_EQ(ours->getMode(), theirs->getMode());
  EXPECT_EQ(ours->getPreFilterCap(), theirs->getPreFilterCap());
  EXPECT_EQ(ours->getUniquenessRatio(), theirs->getUniquenessRatio());
  EXPECT_EQ(ours->getDisp12MaxDiff(), theirs->getDisp12MaxDiff());
  EXPECT_EQ(ours->getSpeckleWindowSize(), theirs->getSpeckleWindowSize());
  EXPECT_EQ(ours->getSpeckleRange(), theirs->getSpeckleRange());
  cv::Mat ours16, theirs16;
  ours->compute(p.right, p.left, ours16);
  theirs->compute(p.right, p.left, theirs16);
  ASSERT_EQ(ours16.type(), CV_16S);
  EXPECT_GT(cv::countNonZero(ours16 < 0), kWidth * kHeight / 2);  // the mirrored range: negative disparities
  EXPECT_EQ(cv::norm(ours16, theirs16, cv::NORM_INF), 0.0);
}

TEST(LeftRightCheck, RejectsBadInput) {
  const Pair p = OccludingSquare();
  MapOptions o;
  o.lr_max_diff_px = 1.0;
  EXPECT_THROW(MatchDisparity(p.left, p.right.colRange(0, kWidth - 1).clone(), o), std::invalid_argument);
  EXPECT_THROW(TraversabilityMap([] {
                 MapOptions bad;
                 bad.lr_max_diff_px = -1;
                 return bad;
               }()),
               std::invalid_argument);
}

}  // namespace
}  // namespace rover::traversability
