// The libpng codec against OpenCV's: the same PNG bytes from the same image, level and
// strategy, and the same pixels from the same PNG; colour, truncated and foreign data get
// one line each.
#include "imaging/png_codec.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include <vector>

namespace rover::imaging {
namespace {

using Bytes = std::vector<std::uint8_t>;

// A gray image with texture and flat runs, like a rendered scene (so every zlib strategy
// has matches to find).
cv::Mat Scene(int w, int h, int type) {
  cv::Mat m(h, w, type);
  cv::RNG rng(11);
  rng.fill(m, cv::RNG::UNIFORM, 0, type == CV_16UC1 ? 4096 : 256);
  m(cv::Rect(0, 0, w / 3, h / 2)).setTo(type == CV_16UC1 ? 1000 : 90);
  return m;
}

Bytes OpenCvPng(const cv::Mat& m, int level, int strategy) {
  Bytes out;
  EXPECT_TRUE(cv::imencode(".png", m, out, {cv::IMWRITE_PNG_COMPRESSION, level, cv::IMWRITE_PNG_STRATEGY, strategy}));
  return out;
}

TEST(PngCodec, EncodesTheBytesOpenCvWritesAtEachLevelAndStrategy) {
  for (int type : {CV_8UC1, CV_16UC1}) {
    for (const cv::Size size : {cv::Size(64, 48), cv::Size(333, 211)}) {
      const cv::Mat image = Scene(size.width, size.height, type);
      for (const auto& [level, strategy] : {std::pair{1, PngStrategy::kRle}, std::pair{6, PngStrategy::kDefault},
                                            std::pair{0, PngStrategy::kDefault}, std::pair{9, PngStrategy::kFiltered}}) {
        Bytes ours;
        ASSERT_EQ(EncodeGrayPng(image, level, strategy, ours), "");
        EXPECT_EQ(ours, OpenCvPng(image, level, static_cast<int>(strategy)))
            << "type " << type << ", " << size << ", level " << level;
      }
    }
  }
}

TEST(PngCodec, EncodesARoiAndRefusesColourOrAnEmptyImage) {
  const cv::Mat big = Scene(100, 80, CV_8UC1);
  const cv::Mat roi = big(cv::Rect(7, 5, 50, 40));  // not continuous
  Bytes ours;
  ASSERT_EQ(EncodeGrayPng(roi, 1, PngStrategy::kRle, ours), "");
  EXPECT_EQ(ours, OpenCvPng(roi.clone(), 1, cv::IMWRITE_PNG_STRATEGY_RLE));
  EXPECT_NE(EncodeGrayPng(cv::Mat(4, 4, CV_8UC3), 1, PngStrategy::kRle, ours).find("expected a non-empty gray"),
            std::string::npos);
  EXPECT_TRUE(ours.empty());
  EXPECT_NE(EncodeGrayPng(cv::Mat(), 1, PngStrategy::kRle, ours), "");
  EXPECT_NE(EncodeGrayPng(big, 10, PngStrategy::kRle, ours).find("expected 0 to 9"), std::string::npos);
}

TEST(PngCodec, DecodesThePixelsOpenCvDecodes) {
  std::vector<Bytes> pngs;
  for (int type : {CV_8UC1, CV_16UC1}) {
    pngs.push_back(OpenCvPng(Scene(97, 61, type), 1, cv::IMWRITE_PNG_STRATEGY_RLE));
    pngs.push_back(OpenCvPng(Scene(97, 61, type), 9, cv::IMWRITE_PNG_STRATEGY_DEFAULT));
  }
  Bytes bilevel;  // a 1-bit gray PNG: both decoders scale it to 8 bits
  ASSERT_TRUE(cv::imencode(".png", Scene(40, 30, CV_8UC1) > 128, bilevel, {cv::IMWRITE_PNG_BILEVEL, 1}));
  pngs.push_back(bilevel);
  for (const Bytes& png : pngs) {
    cv::Mat ours;
    ASSERT_EQ(DecodeGrayPng(png.data(), png.size(), ours), "");
    const cv::Mat theirs = cv::imdecode(png, cv::IMREAD_UNCHANGED);
    ASSERT_EQ(ours.type(), theirs.type());
    ASSERT_EQ(ours.size(), theirs.size());
    EXPECT_EQ(cv::norm(ours, theirs, cv::NORM_INF), 0.0);
  }
}

TEST(PngCodec, ColourTruncatedAndForeignDataGetOneLineEach) {
  cv::Mat out;
  Bytes colour;
  ASSERT_TRUE(cv::imencode(".png", cv::Mat(8, 8, CV_8UC3, cv::Scalar(1, 2, 3)), colour));
  EXPECT_EQ(DecodeGrayPng(colour.data(), colour.size(), out), "PNG decodes to 3 channels (expected 1, gray)");
  EXPECT_TRUE(out.empty());

  const Bytes gray = OpenCvPng(Scene(64, 48, CV_8UC1), 1, cv::IMWRITE_PNG_STRATEGY_RLE);
  const std::string truncated = DecodeGrayPng(gray.data(), gray.size() / 2, out);
  EXPECT_EQ(truncated.rfind("PNG does not decode: ", 0), 0u) << truncated;
  EXPECT_EQ(truncated.find('\n'), std::string::npos);
  EXPECT_TRUE(out.empty());

  Bytes corrupt = gray;
  corrupt[corrupt.size() / 2] ^= 0xff;  // inside IDAT: a CRC or zlib error
  EXPECT_EQ(DecodeGrayPng(corrupt.data(), corrupt.size(), out).rfind("PNG does not decode: ", 0), 0u);

  const Bytes jpeg_like = {0xff, 0xd8, 0xff, 0xe0, 0, 0x10, 'J', 'F', 'I', 'F', 0};
  EXPECT_EQ(DecodeGrayPng(jpeg_like.data(), jpeg_like.size(), out), "not a PNG (expected the 8-byte PNG signature)");
}

}  // namespace
}  // namespace rover::imaging
