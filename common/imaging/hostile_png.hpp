// PNGs built the way an attacker would, to prove the checks in image_check.hpp: a header
// rewritten to claim another size or depth, and a decompression bomb. Used by the imaging
// tests and by tools/fault_inject; nothing in the stack's data path calls them.
#pragma once

#include <cstdint>
#include <vector>

namespace rover::imaging {

using PngBytes = std::vector<std::uint8_t>;

// Rewrites the IHDR's width and height (and bit depth when >= 0) in `png`; with
// `fix_crc` its CRC too, so that only a check of the values can reject it.
void PatchPngHeader(PngBytes& png, std::uint32_t width, std::uint32_t height, int bit_depth = -1,
                    bool fix_crc = true);

// A gray 8-bit PNG whose header says `header_w` x `header_h` over an IDAT of `rows` rows
// of `cols` zeros, deflated at level 9 (about 1000:1) and streamed, so the raw image never
// exists in memory.
PngBytes PngBomb(std::uint32_t header_w, std::uint32_t header_h, int rows, int cols);

}  // namespace rover::imaging
