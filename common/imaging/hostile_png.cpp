#include "imaging/hostile_png.hpp"

#include <zlib.h>

#include <cstring>
#include <stdexcept>

namespace rover::imaging {

namespace {

void PutBigEndian32(std::uint8_t* p, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<std::uint8_t>(v >> (24 - 8 * i));
}

void AppendChunk(PngBytes& png, const char* type, const PngBytes& data) {
  std::uint8_t head[8];
  PutBigEndian32(head, static_cast<std::uint32_t>(data.size()));
  std::memcpy(head + 4, type, 4);
  png.insert(png.end(), head, head + 8);
  png.insert(png.end(), data.begin(), data.end());
  uLong crc = crc32(0L, head + 4, 4);
  crc = crc32(crc, data.data(), static_cast<uInt>(data.size()));
  std::uint8_t tail[4];
  PutBigEndian32(tail, static_cast<std::uint32_t>(crc));
  png.insert(png.end(), tail, tail + 4);
}

}  // namespace

void PatchPngHeader(PngBytes& png, std::uint32_t width, std::uint32_t height, int bit_depth, bool fix_crc) {
  if (png.size() < 33) throw std::invalid_argument("PatchPngHeader: not a PNG with an IHDR");
  PutBigEndian32(&png[16], width);
  PutBigEndian32(&png[20], height);
  if (bit_depth >= 0) png[24] = static_cast<std::uint8_t>(bit_depth);
  if (fix_crc) PutBigEndian32(&png[29], static_cast<std::uint32_t>(crc32(0L, &png[12], 17)));
}

PngBytes PngBomb(std::uint32_t header_w, std::uint32_t header_h, int rows, int cols) {
  PngBytes png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  PngBytes ihdr(13, 0);
  PutBigEndian32(&ihdr[0], header_w);
  PutBigEndian32(&ihdr[4], header_h);
  ihdr[8] = 8;  // bit depth; colour type 0 (gray)
  AppendChunk(png, "IHDR", ihdr);
  z_stream z{};
  if (deflateInit(&z, 9) != Z_OK) throw std::runtime_error("zlib deflateInit failed");
  const PngBytes row(static_cast<std::size_t>(cols) + 1, 0);  // filter byte and zeros
  PngBytes idat;
  std::vector<std::uint8_t> buf(1 << 16);
  for (int r = 0; r <= rows; ++r) {
    const bool last = r == rows;
    z.next_in = const_cast<Bytef*>(row.data());
    z.avail_in = last ? 0 : static_cast<uInt>(row.size());
    do {
      z.next_out = buf.data();
      z.avail_out = static_cast<uInt>(buf.size());
      deflate(&z, last ? Z_FINISH : Z_NO_FLUSH);
      idat.insert(idat.end(), buf.data(), buf.data() + (buf.size() - z.avail_out));
    } while (z.avail_out == 0);
  }
  deflateEnd(&z);
  AppendChunk(png, "IDAT", idat);
  AppendChunk(png, "IEND", {});
  return png;
}

}  // namespace rover::imaging
