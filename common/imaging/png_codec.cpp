#include "imaging/png_codec.hpp"

#include <png.h>

#include <cstdio>
#include <cstring>

namespace rover::imaging {

namespace {

// libpng reports errors by longjmp back to the setjmp of the call that began the work.
// So the functions that call setjmp below hold no C++ object of their own (nothing whose
// destructor a longjmp would skip): their state lives in these plain contexts, owned by
// the caller, and the error message is copied out before the jump.
struct WriteContext {
  std::vector<std::uint8_t>* out = nullptr;
  char error[160] = {};
};

struct ReadContext {
  const std::uint8_t* data = nullptr;
  std::size_t size = 0;
  std::size_t pos = 0;
  char error[160] = {};
};

template <typename Context>
[[noreturn]] void OnError(png_structp png, png_const_charp message) {
  auto* context = static_cast<Context*>(png_get_error_ptr(png));
  std::snprintf(context->error, sizeof(context->error), "%s", message);
  png_longjmp(png, 1);
}

void OnWarning(png_structp, png_const_charp) {}  // a warning changes nothing decoded

void WriteBytes(png_structp png, png_bytep bytes, std::size_t n) {
  auto* context = static_cast<WriteContext*>(png_get_io_ptr(png));
  context->out->insert(context->out->end(), bytes, bytes + n);
}

void FlushNothing(png_structp) {}

void ReadBytes(png_structp png, png_bytep bytes, std::size_t n) {
  auto* context = static_cast<ReadContext*>(png_get_io_ptr(png));
  if (n > context->size - context->pos) png_error(png, "the data ends inside the image");
  std::memcpy(bytes, context->data + context->pos, n);
  context->pos += n;
}

bool LittleEndian() {
  const std::uint16_t one = 1;
  std::uint8_t first = 0;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

// The steps of OpenCV's PNG writer for a gray image with an explicit level and strategy.
bool WritePng(const cv::Mat& img, int level, int strategy, WriteContext* context) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, context, OnError<WriteContext>, OnWarning);
  if (png == nullptr) return false;
  png_infop info = png_create_info_struct(png);
  if (info == nullptr || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    return false;
  }
  const bool sixteen = img.depth() == CV_16U;
  png_set_write_fn(png, context, WriteBytes, FlushNothing);
  png_set_compression_level(png, level);
  png_set_compression_strategy(png, strategy);
  png_set_IHDR(png, info, static_cast<png_uint_32>(img.cols), static_cast<png_uint_32>(img.rows), sixteen ? 16 : 8,
               PNG_COLOR_TYPE_GRAY, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  if (sixteen && LittleEndian()) png_set_swap(png);  // PNG stores 16-bit samples big-endian
  for (int r = 0; r < img.rows; ++r) png_write_row(png, img.ptr<png_byte>(r));
  png_write_end(png, info);
  png_destroy_write_struct(&png, &info);
  return true;
}

// The channels cv::imdecode(IMREAD_UNCHANGED) would give a PNG of this colour type.
int OpenCvChannels(png_structp png, png_infop info, int color_type) {
  if (color_type == PNG_COLOR_TYPE_GRAY) return 1;
  if (color_type == PNG_COLOR_TYPE_GRAY_ALPHA || color_type == PNG_COLOR_TYPE_RGB_ALPHA) return 4;
  return png_get_valid(png, info, PNG_INFO_tRNS) ? 4 : 3;  // RGB or palette
}

// Largest image DecodeGrayPng allocates (64 Mpx); the bus's checks allow far less.
constexpr png_uint_32 kMaxPixels = 1u << 26;

// Reads the header, then (for a gray image) the pixels into *out. On a colour image it
// returns true with *out empty and *channels set.
bool ReadPng(ReadContext* context, cv::Mat* out, int* channels) {
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, context, OnError<ReadContext>, OnWarning);
  if (png == nullptr) return false;
  png_infop info = png_create_info_struct(png);
  if (info == nullptr || setjmp(png_jmpbuf(png))) {
    png_destroy_read_struct(&png, &info, nullptr);
    return false;
  }
  png_set_read_fn(png, context, ReadBytes);
  png_read_info(png, info);
  const png_uint_32 width = png_get_image_width(png, info), height = png_get_image_height(png, info);
  const int bit_depth = png_get_bit_depth(png, info), color_type = png_get_color_type(png, info);
  *channels = OpenCvChannels(png, info, color_type);
  if (*channels != 1) {
    png_destroy_read_struct(&png, &info, nullptr);
    return true;
  }
  if (static_cast<std::uint64_t>(width) * height > kMaxPixels) png_error(png, "the image is over 64 Mpx");
  if (bit_depth < 8) png_set_expand_gray_1_2_4_to_8(png);
  if (bit_depth == 16 && LittleEndian()) png_set_swap(png);
  const int passes = png_set_interlace_handling(png);
  png_read_update_info(png, info);
  out->create(static_cast<int>(height), static_cast<int>(width), bit_depth == 16 ? CV_16UC1 : CV_8UC1);
  for (int pass = 0; pass < passes; ++pass) {
    for (int r = 0; r < out->rows; ++r) png_read_row(png, out->ptr<png_byte>(r), nullptr);
  }
  png_read_end(png, nullptr);
  png_destroy_read_struct(&png, &info, nullptr);
  return true;
}

}  // namespace

std::string EncodeGrayPng(const cv::Mat& img, int level, PngStrategy strategy, std::vector<std::uint8_t>& out) {
  out.clear();
  if (img.empty() || img.channels() != 1 || (img.depth() != CV_8U && img.depth() != CV_16U)) {
    return "cannot encode a " + std::to_string(img.cols) + "x" + std::to_string(img.rows) + " image with " +
           std::to_string(img.channels()) + " channels of depth " + std::to_string(img.depth()) +
           " as PNG (expected a non-empty gray 8- or 16-bit image)";
  }
  if (level < 0 || level > 9) return "PNG level " + std::to_string(level) + " (expected 0 to 9)";
  WriteContext context;
  context.out = &out;
  if (!WritePng(img, level, static_cast<int>(strategy), &context)) {
    out.clear();
    return std::string("PNG encoding failed: ") + context.error;
  }
  return "";
}

std::string DecodeGrayPng(const std::uint8_t* data, std::size_t size, cv::Mat& out) {
  out.release();
  static constexpr std::uint8_t kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (size < sizeof(kSignature) || std::memcmp(data, kSignature, sizeof(kSignature)) != 0) {
    return "not a PNG (expected the 8-byte PNG signature)";
  }
  ReadContext context;
  context.data = data;
  context.size = size;
  int channels = 0;
  if (!ReadPng(&context, &out, &channels)) {
    out.release();
    return std::string("PNG does not decode: ") + context.error + " (expected complete, valid image data)";
  }
  if (channels != 1) return "PNG decodes to " + std::to_string(channels) + " channels (expected 1, gray)";
  return "";
}

}  // namespace rover::imaging
