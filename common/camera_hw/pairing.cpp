#include "camera_hw/stereo_source.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace rover::camera_hw {

namespace {

std::string Ms(std::int64_t ns) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.3f", static_cast<double>(ns) / 1e6);
  return text;
}

}  // namespace

StereoFrames PairFrames(const std::function<Frame(Side)>& next, std::int64_t tolerance_ns,
                        int max_advances, const std::string& source_name) {
  StereoFrames pair;
  pair.left = next(Side::kLeft);
  pair.right = next(Side::kRight);
  for (;;) {
    const std::int64_t diff = pair.right.timestamp_ns - pair.left.timestamp_ns;
    if (std::llabs(diff) <= tolerance_ns) return pair;
    if (pair.advances >= max_advances) {
      throw CaptureError(source_name + ": pair rejected: left and right timestamps differ by " +
                         Ms(std::llabs(diff)) + " ms (tolerance " + Ms(tolerance_ns) + " ms, left frame " +
                         std::to_string(pair.left.frame_id) + ", right frame " +
                         std::to_string(pair.right.frame_id) + ", after " +
                         std::to_string(pair.advances) + " advances)");
    }
    // The older frame cannot have a partner among frames still to come on the other side.
    if (diff > 0) {
      pair.left = next(Side::kLeft);
    } else {
      pair.right = next(Side::kRight);
    }
    ++pair.advances;
  }
}

ExposureTimes ExposureUtimes(const StereoFrames& pair, std::int64_t utime) {
  const std::int64_t right_minus_left_us =
      static_cast<std::int64_t>(std::llround(static_cast<double>(pair.right.timestamp_ns - pair.left.timestamp_ns) / 1e3));
  ExposureTimes t;
  // The left one half the difference before the mean (rounded down, so that the two stay
  // exactly the difference apart).
  t.left_utime = utime - static_cast<std::int64_t>(std::floor(static_cast<double>(right_minus_left_us) / 2.0));
  t.right_utime = t.left_utime + right_minus_left_us;
  return t;
}

}  // namespace rover::camera_hw
