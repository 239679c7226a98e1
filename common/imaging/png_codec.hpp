// Gray PNG encode and decode with libpng, for the processes that move camera images over
// the bus (camera_capture encodes, visual_odometry and hazard_monitor decode).
//
// Why libpng by hand rather than cv::imencode / cv::imdecode: OpenCV's imgcodecs module
// links GDAL, GDCM, libheif and about 120 more libraries, and loading them costs each
// process about 0.12 s of CPU at start (`/usr/bin/time` on a program that only links
// it). Three processes of every run paid it for PNG alone. libpng is what imgcodecs
// itself calls for PNG, so these two functions make the same bytes and the same pixels
// (png_codec_test compares them with OpenCV's, byte for byte and pixel for pixel).
//
// Only gray images: 8-bit, or 16-bit (as OpenCV does, 16-bit samples are swapped to the
// machine's order). Every failure is one line naming what was wrong.
#pragma once

#include <opencv2/core.hpp>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace rover::imaging {

// zlib's strategies (Z_DEFAULT_STRATEGY .. Z_FIXED; OpenCV's IMWRITE_PNG_STRATEGY_*).
enum class PngStrategy : int { kDefault = 0, kFiltered = 1, kHuffmanOnly = 2, kRle = 3, kFixed = 4 };

// Encodes a CV_8UC1 or CV_16UC1 image into `out` at zlib `level` (0..9) with `strategy`:
// the bytes cv::imencode(".png", img, out, {IMWRITE_PNG_COMPRESSION, level,
// IMWRITE_PNG_STRATEGY, strategy}) writes. Returns "" or why it could not.
std::string EncodeGrayPng(const cv::Mat& img, int level, PngStrategy strategy, std::vector<std::uint8_t>& out);

// Decodes a gray PNG (bit depth 1, 2, 4 and 8 give CV_8UC1, as OpenCV scales them; 16
// gives CV_16UC1) into `out`. Returns "" or one line: not a PNG, truncated or corrupt
// data, or a colour image ("PNG decodes to N channels (expected 1, gray)").
std::string DecodeGrayPng(const std::uint8_t* data, std::size_t size, cv::Mat& out);

}  // namespace rover::imaging
