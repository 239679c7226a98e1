#include "imaging/image_check.hpp"

#include "imaging/png_codec.hpp"

#include <zlib.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <exception>

namespace rover::imaging {
namespace {

constexpr std::array<std::uint8_t, 8> kPngSignature = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};

std::uint32_t ReadBigEndian32(const std::uint8_t* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) |
         std::uint32_t{p[3]};
}

std::string Hex32(std::uint32_t v) {
  char buf[16];
  std::snprintf(buf, sizeof(buf), "0x%08x", v);
  return buf;
}

// A chunk type as text, with anything unprintable shown as '?'.
std::string ChunkName(const std::uint8_t* p) {
  std::string name;
  for (int i = 0; i < 4; ++i) name += (p[i] >= 0x20 && p[i] < 0x7f) ? static_cast<char>(p[i]) : '?';
  return name;
}

std::string Size(std::int64_t w, std::int64_t h) { return std::to_string(w) + "x" + std::to_string(h); }

int BytesPerPixel(Encoding e) { return e == Encoding::kGray16 ? 2 : 1; }

// The largest PNG of a w x h gray image worth reading. A PNG stores its filtered rows
// (one filter byte per row) deflated; even stored uncompressed, zlib adds 5 bytes per
// 64 KiB block and PNG 12 bytes per chunk. Twice the raw size plus 64 KiB for ancillary
// chunks bounds any real encoder's output; more is padding that only makes work.
std::int64_t MaxPngBytes(std::int64_t w, std::int64_t h, int bit_depth) {
  const std::int64_t raw = h * (1 + w * (bit_depth == 16 ? 2 : 1));
  return 2 * raw + 64 * 1024;
}

std::string FirstLine(const std::string& text) {
  const auto end = text.find('\n');
  return end == std::string::npos ? text : text.substr(0, end);
}

}  // namespace

std::string EncodingName(int encoding) {
  switch (encoding) {
    case static_cast<int>(Encoding::kGray8): return "GRAY8";
    case static_cast<int>(Encoding::kGray16): return "GRAY16";
    case static_cast<int>(Encoding::kPng): return "PNG";
    default: return "unknown encoding " + std::to_string(encoding);
  }
}

std::string ReadPngHeader(const std::uint8_t* data, std::size_t size, PngHeader& out) {
  const std::size_t signature_bytes = std::min(size, kPngSignature.size());
  for (std::size_t i = 0; i < signature_bytes; ++i) {
    if (data[i] != kPngSignature[i]) {
      return "PNG signature is wrong at byte " + std::to_string(i) +
             " (expected 89 50 4E 47 0D 0A 1A 0A)";
    }
  }
  if (size < kPngHeaderBytes) {
    return "PNG is truncated: " + std::to_string(size) + " bytes (expected at least " +
           std::to_string(kPngHeaderBytes) + " for the signature and IHDR)";
  }
  const std::uint8_t* chunk = data + 8;
  if (ChunkName(chunk + 4) != "IHDR") {
    return "PNG's first chunk is '" + ChunkName(chunk + 4) + "' (expected IHDR)";
  }
  const std::uint32_t length = ReadBigEndian32(chunk);
  if (length != 13) return "PNG's IHDR is " + std::to_string(length) + " bytes long (expected 13)";
  // The CRC covers the chunk type and data (PNG 1.2, section 5.3); zlib computes it.
  const std::uint32_t stored_crc = ReadBigEndian32(chunk + 8 + 13);
  const std::uint32_t crc = static_cast<std::uint32_t>(crc32(0L, chunk + 4, 4 + 13));
  if (crc != stored_crc) {
    return "PNG's IHDR CRC is " + Hex32(stored_crc) + " (expected " + Hex32(crc) +
           "; the header is corrupt)";
  }
  const std::uint8_t* ihdr = chunk + 8;
  PngHeader h;
  h.width = ReadBigEndian32(ihdr);
  h.height = ReadBigEndian32(ihdr + 4);
  h.bit_depth = ihdr[8];
  h.color_type = ihdr[9];
  h.interlace = ihdr[12];
  if (h.width == 0 || h.height == 0 || h.width > 0x7fffffffu || h.height > 0x7fffffffu) {
    return "PNG's IHDR says " + std::to_string(h.width) + "x" + std::to_string(h.height) +
           " (expected sides from 1 to 2^31-1)";
  }
  if (ihdr[10] != 0 || ihdr[11] != 0) {
    return "PNG's IHDR has compression " + std::to_string(ihdr[10]) + ", filter " +
           std::to_string(ihdr[11]) + " (expected 0 and 0)";
  }
  if (h.interlace > 1) return "PNG's IHDR has interlace " + std::to_string(h.interlace) + " (expected 0 or 1)";
  out = h;
  return "";
}

std::string CheckPngHeader(const PngHeader& header, std::int64_t width, std::int64_t height) {
  if (header.width != width || header.height != height) {
    return "PNG's header says " + Size(header.width, header.height) + " but the image is declared " +
           Size(width, height) + " (expected the same size)";
  }
  if (header.color_type != 0) {
    return "PNG has colour type " + std::to_string(header.color_type) + " (expected 0, gray)";
  }
  if (header.bit_depth != 8 && header.bit_depth != 16) {
    return "PNG has bit depth " + std::to_string(header.bit_depth) + " (expected 8 or 16)";
  }
  return "";
}

std::string CheckImage(const ImageView& image, std::int64_t model_width, std::int64_t model_height,
                       const ImageLimits& limits) {
  if (image.encoding != static_cast<int>(Encoding::kGray8) &&
      image.encoding != static_cast<int>(Encoding::kGray16) &&
      image.encoding != static_cast<int>(Encoding::kPng)) {
    return EncodingName(image.encoding) + " (expected 0 GRAY8, 1 GRAY16 or 2 PNG)";
  }
  const Encoding encoding = static_cast<Encoding>(image.encoding);
  const std::string what = EncodingName(image.encoding) + " image";
  if (image.width <= 0 || image.height <= 0) {
    return what + " is " + Size(image.width, image.height) + " (expected width and height > 0)";
  }
  if (image.width != model_width || image.height != model_height) {
    return what + " is " + Size(image.width, image.height) + " but its camera model is " +
           Size(model_width, model_height) + " (expected the same size)";
  }
  if (std::min(image.width, image.height) < limits.min_side) {
    return what + " is " + Size(image.width, image.height) + " (expected sides of at least " +
           std::to_string(limits.min_side) + " px)";
  }
  // Both sides are now equal to the model's int32 sides: the product fits in 64 bits.
  const std::int64_t pixels = image.width * image.height;
  if (pixels > limits.max_pixels) {
    return what + " is " + Size(image.width, image.height) + " = " + std::to_string(pixels) +
           " px (expected at most " + std::to_string(limits.max_pixels) + " px)";
  }
  if (image.declared_size != static_cast<std::int64_t>(image.data_size)) {
    return what + " declares " + std::to_string(image.declared_size) + " bytes but holds " +
           std::to_string(image.data_size) + " (expected the same)";
  }
  if (image.data_size > 0 && image.data == nullptr) return what + " has no data (expected bytes)";
  if (encoding != Encoding::kPng) {
    const std::int64_t expected = pixels * BytesPerPixel(encoding);
    if (static_cast<std::int64_t>(image.data_size) != expected) {
      return what + " " + Size(image.width, image.height) + " holds " +
             std::to_string(image.data_size) + " bytes (expected width*height*" +
             std::to_string(BytesPerPixel(encoding)) + " = " + std::to_string(expected) + ")";
    }
    return "";
  }
  PngHeader header;
  if (std::string bad = ReadPngHeader(image.data, image.data_size, header); !bad.empty()) return bad;
  if (std::string bad = CheckPngHeader(header, image.width, image.height); !bad.empty()) return bad;
  const std::int64_t max_bytes = MaxPngBytes(image.width, image.height, header.bit_depth);
  if (static_cast<std::int64_t>(image.data_size) > max_bytes) {
    return "PNG of " + Size(image.width, image.height) + " holds " + std::to_string(image.data_size) +
           " bytes (expected at most " + std::to_string(max_bytes) + ", twice its raw size)";
  }
  return "";
}

std::string DecodeCheckedImage(const ImageView& image, std::int64_t model_width,
                               std::int64_t model_height, const ImageLimits& limits, cv::Mat& out) {
  if (std::string bad = CheckImage(image, model_width, model_height, limits); !bad.empty()) return bad;
  const int w = static_cast<int>(image.width), h = static_cast<int>(image.height);
  auto* bytes = const_cast<std::uint8_t*>(image.data);  // cv::Mat wraps, clone() copies
  const auto encoding = static_cast<Encoding>(image.encoding);
  try {
    if (encoding == Encoding::kGray8) {
      out = cv::Mat(h, w, CV_8UC1, bytes).clone();
      return "";
    }
    if (encoding == Encoding::kGray16) {
      out = cv::Mat(h, w, CV_16UC1, bytes).clone();
      return "";
    }
    if (std::string bad = DecodeGrayPng(image.data, image.data_size, out); !bad.empty()) return bad;
  } catch (const std::exception& e) {
    out.release();
    return EncodingName(image.encoding) + " image does not decode: " + FirstLine(e.what());
  }
  if (out.cols != w || out.rows != h) {
    const std::string got = Size(out.cols, out.rows);
    out.release();
    return "PNG decodes to " + got + " (expected " + Size(w, h) + ")";
  }
  return "";
}

}  // namespace rover::imaging
