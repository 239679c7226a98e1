// Image checks: real PNGs from OpenCV pass and decode to the same pixels; hostile ones
// (a header claiming 65535x65535, a bomb of zeros, corrupt or truncated headers, sizes
// that disagree with the camera model or the byte count) are rejected with one line, and
// the rejection comes from the header, before cv::imdecode runs.
#include "imaging/hostile_png.hpp"
#include "imaging/image_check.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <zlib.h>

#include <cstring>
#include <random>
#include <vector>

namespace rover::imaging {
namespace {

using Bytes = std::vector<std::uint8_t>;

constexpr int kGray8 = static_cast<int>(Encoding::kGray8);
constexpr int kGray16 = static_cast<int>(Encoding::kGray16);
constexpr int kPng = static_cast<int>(Encoding::kPng);

// A textured gray image (so PNG does not shrink it to nothing).
cv::Mat Texture(int w, int h, int type) {
  cv::Mat m(h, w, type);
  cv::RNG rng(7);
  rng.fill(m, cv::RNG::UNIFORM, 0, type == CV_16UC1 ? 4096 : 256);
  return m;
}

Bytes EncodePng(const cv::Mat& m) {
  Bytes out;
  EXPECT_TRUE(cv::imencode(".png", m, out));
  return out;
}

ImageView View(int encoding, std::int64_t w, std::int64_t h, const Bytes& data) {
  ImageView v;
  v.encoding = encoding;
  v.width = w;
  v.height = h;
  v.declared_size = static_cast<std::int64_t>(data.size());
  v.data = data.data();
  v.data_size = data.size();
  return v;
}

void PatchIhdr(Bytes& png, std::uint32_t w, std::uint32_t h, int bit_depth = -1, bool fix_crc = true) {
  rover::imaging::PatchPngHeader(png, w, h, bit_depth, fix_crc);
}

TEST(ImageCheck, RealPngsFromOpenCvPassAndDecodeToTheSamePixels) {
  for (int type : {CV_8UC1, CV_16UC1}) {
    const cv::Mat image = Texture(64, 48, type);
    const Bytes png = EncodePng(image);
    PngHeader header;
    ASSERT_EQ(ReadPngHeader(png.data(), png.size(), header), "");
    EXPECT_EQ(header.width, 64u);
    EXPECT_EQ(header.height, 48u);
    EXPECT_EQ(header.bit_depth, type == CV_16UC1 ? 16 : 8);
    EXPECT_EQ(header.color_type, 0);
    cv::Mat out;
    ASSERT_EQ(DecodeCheckedImage(View(kPng, 64, 48, png), 64, 48, {}, out), "");
    ASSERT_EQ(out.type(), type);
    EXPECT_EQ(cv::norm(out, image, cv::NORM_INF), 0.0);
  }
}

TEST(ImageCheck, RawGray8AndGray16PassAndDecode) {
  const cv::Mat g8 = Texture(40, 30, CV_8UC1), g16 = Texture(40, 30, CV_16UC1);
  const Bytes b8(g8.data, g8.data + g8.total()), b16(g16.data, g16.data + 2 * g16.total());
  cv::Mat out;
  ASSERT_EQ(DecodeCheckedImage(View(kGray8, 40, 30, b8), 40, 30, {}, out), "");
  EXPECT_EQ(cv::norm(out, g8, cv::NORM_INF), 0.0);
  ASSERT_EQ(DecodeCheckedImage(View(kGray16, 40, 30, b16), 40, 30, {}, out), "");
  EXPECT_EQ(out.type(), CV_16UC1);
  EXPECT_EQ(cv::norm(out, g16, cv::NORM_INF), 0.0);
}

TEST(ImageCheck, UnknownEncodingIsNamed) {
  const Bytes data(100, 0);
  EXPECT_EQ(CheckImage(View(7, 10, 10, data), 10, 10, {}),
            "unknown encoding 7 (expected 0 GRAY8, 1 GRAY16 or 2 PNG)");
  EXPECT_NE(CheckImage(View(-1, 10, 10, data), 10, 10, {}).find("unknown encoding -1"), std::string::npos);
}

TEST(ImageCheck, NegativeOrZeroSidesAreRejected) {
  const Bytes data(100, 0);
  EXPECT_EQ(CheckImage(View(kGray8, -5, 20, data), -5, 20, {}),
            "GRAY8 image is -5x20 (expected width and height > 0)");
  EXPECT_EQ(CheckImage(View(kGray8, 20, 0, data), 20, 0, {}),
            "GRAY8 image is 20x0 (expected width and height > 0)");
  cv::Mat out;
  EXPECT_NE(DecodeCheckedImage(View(kPng, -5, -5, data), -5, -5, {}, out), "");
  EXPECT_TRUE(out.empty());
}

TEST(ImageCheck, SizeMustEqualTheCameraModel) {
  const Bytes data(32 * 32, 0);
  EXPECT_EQ(CheckImage(View(kGray8, 32, 32, data), 64, 32, {}),
            "GRAY8 image is 32x32 but its camera model is 64x32 (expected the same size)");
  const Bytes png = EncodePng(Texture(32, 32, CV_8UC1));
  EXPECT_EQ(CheckImage(View(kPng, 32, 32, png), 32, 33, {}),
            "PNG image is 32x32 but its camera model is 32x33 (expected the same size)");
}

TEST(ImageCheck, LimitsOnPixelsAndSides) {
  ImageLimits limits;
  limits.max_pixels = 1000;
  limits.min_side = 16;
  const Bytes big(40 * 30, 0), thin(100 * 8, 0), ok(30 * 30, 0);
  EXPECT_EQ(CheckImage(View(kGray8, 40, 30, big), 40, 30, limits),
            "GRAY8 image is 40x30 = 1200 px (expected at most 1000 px)");
  EXPECT_EQ(CheckImage(View(kGray8, 100, 8, thin), 100, 8, limits),
            "GRAY8 image is 100x8 (expected sides of at least 16 px)");
  EXPECT_EQ(CheckImage(View(kGray8, 30, 30, ok), 30, 30, limits), "");
}

TEST(ImageCheck, HugeSidesDoNotOverflowTheByteCount) {
  // 65536 x 65536 x 2 overflows 32 bits; the limit rejects it before any product is used.
  const Bytes data(16, 0);
  EXPECT_NE(CheckImage(View(kGray16, 65536, 65536, data), 65536, 65536, {}).find("expected at most"),
            std::string::npos);
  // With no limit the byte count is still computed in 64 bits.
  ImageLimits none;
  none.max_pixels = std::int64_t{1} << 40;
  EXPECT_EQ(CheckImage(View(kGray16, 65536, 65536, data), 65536, 65536, none),
            "GRAY16 image 65536x65536 holds 16 bytes (expected width*height*2 = 8589934592)");
}

TEST(ImageCheck, RawByteCountMustMatch) {
  const Bytes short8(20 * 20 - 1, 0), odd16(20 * 20 * 2 - 1, 0);
  EXPECT_EQ(CheckImage(View(kGray8, 20, 20, short8), 20, 20, {}),
            "GRAY8 image 20x20 holds 399 bytes (expected width*height*1 = 400)");
  EXPECT_EQ(CheckImage(View(kGray16, 20, 20, odd16), 20, 20, {}),
            "GRAY16 image 20x20 holds 799 bytes (expected width*height*2 = 800)");
}

TEST(ImageCheck, DeclaredSizeMustMatchTheBytesPresent) {
  const Bytes data(20 * 20, 0);
  ImageView v = View(kGray8, 20, 20, data);
  v.declared_size = -1;
  EXPECT_EQ(CheckImage(v, 20, 20, {}), "GRAY8 image declares -1 bytes but holds 400 (expected the same)");
}

TEST(ImageCheck, PngHeaderClaiming65535SquareIsRejectedFromTheHeader) {
  Bytes png = EncodePng(Texture(32, 32, CV_8UC1));
  PatchIhdr(png, 65535, 65535);
  // Declared as the camera's 32x32: the header disagrees.
  EXPECT_EQ(CheckImage(View(kPng, 32, 32, png), 32, 32, {}),
            "PNG's header says 65535x65535 but the image is declared 32x32 (expected the same size)");
  // Declared (and modelled) as 65535x65535: the pixel limit rejects it.
  cv::Mat out;
  const std::string reason = DecodeCheckedImage(View(kPng, 65535, 65535, png), 65535, 65535, {}, out);
  EXPECT_EQ(reason, "PNG image is 65535x65535 = 4294836225 px (expected at most 4194304 px)");
  EXPECT_TRUE(out.empty());
}

TEST(ImageCheck, PngBombIsRejectedWithoutDecoding) {
  // 8192 x 8192 zeros (64 MiB decoded) deflate to about 65 kB.
  const Bytes bomb = rover::imaging::PngBomb(8192, 8192, 8192, 8192);
  EXPECT_LT(bomb.size(), 200u * 1024);
  cv::Mat out;
  // The reasons are the header's: DecodeCheckedImage returns them before cv::imdecode.
  // Declared as the camera's 512x512: the header disagrees.
  EXPECT_EQ(DecodeCheckedImage(View(kPng, 512, 512, bomb), 512, 512, {}, out),
            "PNG's header says 8192x8192 but the image is declared 512x512 (expected the same size)");
  // Declared and modelled at its own size: over the limit.
  EXPECT_EQ(DecodeCheckedImage(View(kPng, 8192, 8192, bomb), 8192, 8192, {}, out),
            "PNG image is 8192x8192 = 67108864 px (expected at most 4194304 px)");
  EXPECT_TRUE(out.empty());
}

TEST(ImageCheck, PngWhoseDataInflatesPastItsHeaderDecodesOnlyItsHeader) {
  // The header says 64x64 (the camera's size) but the IDAT holds 4096 rows of 4096 zeros:
  // libpng reads only the rows the header promises, so nothing larger is ever allocated.
  const Bytes png = rover::imaging::PngBomb(64, 64, 4096, 4096);
  cv::Mat out;
  const std::string reason = DecodeCheckedImage(View(kPng, 64, 64, png), 64, 64, {}, out);
  if (reason.empty()) {
    EXPECT_EQ(out.size(), cv::Size(64, 64));
    EXPECT_EQ(cv::countNonZero(out), 0);
  } else {
    EXPECT_TRUE(out.empty()) << reason;
  }
}

TEST(ImageCheck, CorruptPngHeadersAreNamed) {
  const Bytes good = EncodePng(Texture(32, 32, CV_8UC1));
  Bytes bad = good;
  bad[1] = 'X';
  EXPECT_EQ(CheckImage(View(kPng, 32, 32, bad), 32, 32, {}),
            "PNG signature is wrong at byte 1 (expected 89 50 4E 47 0D 0A 1A 0A)");
  bad = good;
  bad[30] ^= 0xff;  // the IHDR CRC
  EXPECT_NE(CheckImage(View(kPng, 32, 32, bad), 32, 32, {}).find("PNG's IHDR CRC is"), std::string::npos);
  bad = good;
  PatchIhdr(bad, 33, 32, -1, false);  // a flipped size without a new CRC
  EXPECT_NE(CheckImage(View(kPng, 32, 32, bad), 32, 32, {}).find("the header is corrupt"), std::string::npos);
  bad = good;
  std::memcpy(&bad[12], "IDAT", 4);
  EXPECT_EQ(CheckImage(View(kPng, 32, 32, bad), 32, 32, {}), "PNG's first chunk is 'IDAT' (expected IHDR)");
  bad = good;
  bad[11] = 12;  // IHDR length
  EXPECT_EQ(CheckImage(View(kPng, 32, 32, bad), 32, 32, {}), "PNG's IHDR is 12 bytes long (expected 13)");
  bad = good;
  PatchIhdr(bad, 32, 32, 4);
  EXPECT_EQ(CheckImage(View(kPng, 32, 32, bad), 32, 32, {}), "PNG has bit depth 4 (expected 8 or 16)");
  bad = good;
  PatchIhdr(bad, 0, 32);
  EXPECT_EQ(CheckImage(View(kPng, 32, 32, bad), 32, 32, {}),
            "PNG's IHDR says 0x32 (expected sides from 1 to 2^31-1)");
}

TEST(ImageCheck, ColourPngIsRejectedFromItsHeader) {
  cv::Mat colour(32, 32, CV_8UC3, cv::Scalar(10, 20, 30));
  const Bytes png = EncodePng(colour);
  EXPECT_EQ(CheckImage(View(kPng, 32, 32, png), 32, 32, {}), "PNG has colour type 2 (expected 0, gray)");
}

TEST(ImageCheck, TruncatedPngsAreRejected) {
  const Bytes good = EncodePng(Texture(32, 32, CV_8UC1));
  const Bytes head(good.begin(), good.begin() + 20);
  EXPECT_EQ(CheckImage(View(kPng, 32, 32, head), 32, 32, {}),
            "PNG is truncated: 20 bytes (expected at least 33 for the signature and IHDR)");
  // A valid header with half its data: the check passes, the decode fails cleanly.
  const Bytes half(good.begin(), good.begin() + static_cast<long>(good.size() / 2));
  EXPECT_EQ(CheckImage(View(kPng, 32, 32, half), 32, 32, {}), "");
  cv::Mat out;
  EXPECT_EQ(DecodeCheckedImage(View(kPng, 32, 32, half), 32, 32, {}, out),
            "PNG does not decode: the data ends inside the image (expected complete, valid image data)");
  EXPECT_TRUE(out.empty());
  const Bytes empty;
  EXPECT_EQ(CheckImage(View(kPng, 32, 32, empty), 32, 32, {}),
            "PNG is truncated: 0 bytes (expected at least 33 for the signature and IHDR)");
}

TEST(ImageCheck, PaddedPngIsRejected) {
  Bytes png = EncodePng(Texture(32, 32, CV_8UC1));
  png.resize(png.size() + 200000, 0);
  EXPECT_NE(CheckImage(View(kPng, 32, 32, png), 32, 32, {}).find("twice its raw size"), std::string::npos);
}

TEST(ImageCheck, RandomBytesNeverThrowAndNeverDecodeToAWrongSize) {
  std::mt19937 rng(42);
  const Bytes good = EncodePng(Texture(32, 32, CV_8UC1));
  int decoded = 0;
  for (int i = 0; i < 2000; ++i) {
    Bytes data;
    if (i % 100 == 0) {  // now and then the real PNG, which must decode
      data = good;
    } else if (i % 2 == 0) {  // a valid header, then random bytes (or a random flip of a real PNG)
      data = good;
      if (i % 4 == 0) {
        data.resize(33 + rng() % 2000);
        for (std::size_t k = 33; k < data.size(); ++k) data[k] = static_cast<std::uint8_t>(rng());
      } else {
        data[33 + rng() % (data.size() - 33)] ^= static_cast<std::uint8_t>(1 + rng() % 255);
      }
    } else {
      data.resize(rng() % 3000);
      for (auto& b : data) b = static_cast<std::uint8_t>(rng());
    }
    const int encoding = i % 100 == 0 ? kPng : static_cast<int>(rng() % 4);
    cv::Mat out;
    std::string reason;
    EXPECT_NO_THROW(reason = DecodeCheckedImage(View(encoding, 32, 32, data), 32, 32, {}, out));
    if (reason.empty()) {
      ++decoded;
      EXPECT_EQ(out.size(), cv::Size(32, 32));
    } else {
      EXPECT_TRUE(out.empty());
      EXPECT_EQ(reason.find('\n'), std::string::npos) << reason;
    }
  }
  EXPECT_GE(decoded, 20);  // at least the real PNGs
}

}  // namespace
}  // namespace rover::imaging
