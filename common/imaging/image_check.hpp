// Checks an image from a message before anything decodes it, and decodes it only when the
// check passes. Knows nothing of LCM: a process fills an ImageView from its message.
//
// Why a check before cv::imdecode: a PNG says its own size in its IHDR chunk, and libpng
// allocates what the header claims. A 778 kB PNG of zeros whose header says 29000x29000
// decodes to 850 MB before anyone can compare it with the camera model; a header that
// claims 65535x65535 makes imdecode throw. Reading the 33 header bytes first costs nothing
// and rejects both. Raw images are checked the same way: the encoding, each side against
// the camera model carried with the image and against a configured maximum, and the byte
// count against width * height * bytes per pixel (computed in 64 bits, so no product of
// two int32 sides can overflow).
//
// Every failure is one line naming what was wrong and what was expected.
#pragma once

#include <opencv2/core.hpp>

#include <cstddef>
#include <cstdint>
#include <string>

namespace rover::imaging {

// The encodings of an image (the values of rover_msgs::image_t::ENCODING_*).
enum class Encoding : int { kGray8 = 0, kGray16 = 1, kPng = 2 };

struct ImageLimits {
  // Largest width * height accepted (4 Mpx: a 2048x2048 camera; NAVCAMs are 1024x1024).
  std::int64_t max_pixels = 4 * 1024 * 1024;
  // Smallest side accepted: below it no feature fits inside a correlation template.
  int min_side = 16;
};

// An image as a message carries it: the declared encoding and size, and the bytes.
struct ImageView {
  int encoding = 0;              // Encoding, as a plain number (it may be anything)
  std::int64_t width = 0;        // as declared
  std::int64_t height = 0;
  std::int64_t declared_size = 0;  // the message's own byte count field
  const std::uint8_t* data = nullptr;
  std::size_t data_size = 0;     // bytes actually present
};

// What a PNG's IHDR chunk says (PNG 1.2, section 11.2.2).
struct PngHeader {
  std::uint32_t width = 0;
  std::uint32_t height = 0;
  int bit_depth = 0;
  int color_type = 0;        // 0 = gray, 2 = RGB, 3 = palette, 4 = gray+alpha, 6 = RGBA
  int interlace = 0;
};

// The first bytes of every PNG file: the signature (8) and the IHDR chunk (4 length,
// 4 type, 13 data, 4 CRC).
inline constexpr std::size_t kPngHeaderBytes = 33;

// Reads the signature and the IHDR chunk of a PNG file. Returns "" and fills `out`, or a
// one-line reason (not a PNG, truncated, IHDR missing or corrupt).
std::string ReadPngHeader(const std::uint8_t* data, std::size_t size, PngHeader& out);

// Checks the header of a PNG for a gray image of `width` x `height` within `limits`
// (gray colour type, bit depth 8 or 16). Returns "" or a one-line reason.
std::string CheckPngHeader(const PngHeader& header, std::int64_t width, std::int64_t height);

// Checks an image against the size of its camera model (`model_width` x `model_height`)
// and the limits, without decoding it. For a PNG this reads the IHDR; for raw encodings
// it checks the byte count. Returns "" or a one-line reason.
std::string CheckImage(const ImageView& image, std::int64_t model_width, std::int64_t model_height,
                       const ImageLimits& limits);

// CheckImage, then decode: a CV_8UC1 or CV_16UC1 image of the declared size. Returns ""
// and fills `out`, or a one-line reason; never throws for any bytes.
std::string DecodeCheckedImage(const ImageView& image, std::int64_t model_width,
                               std::int64_t model_height, const ImageLimits& limits, cv::Mat& out);

// "GRAY8", "GRAY16", "PNG" or "unknown encoding N".
std::string EncodingName(int encoding);

}  // namespace rover::imaging
