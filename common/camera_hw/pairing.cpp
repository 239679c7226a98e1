#include "camera_hw/stereo_source.hpp"

#include <algorithm>
#include <chrono>

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

std::int64_t ExposureSystemUtime(const StereoFrames& pair) {
  if (pair.left.system_ns <= 0 || pair.right.system_ns <= 0) return 0;
  // Each side rounded to microseconds first: the mean of two ns counts since 1970 would
  // not overflow, but their sum might on a later century.
  return (pair.left.system_ns / 1000 + pair.right.system_ns / 1000) / 2;
}

std::int64_t SystemNowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

std::int64_t ClockMapping::ToSystem(std::int64_t camera_ns, std::int64_t received_system_ns) {
  const std::int64_t offset = received_system_ns - camera_ns;
  const bool went_back = !offsets_.empty() && camera_ns < last_camera_ns_;
  const bool jumped = !offsets_.empty() && offset < *std::min_element(offsets_.begin(), offsets_.end()) - reset_ns_;
  if (went_back || jumped) offsets_.clear();
  last_camera_ns_ = camera_ns;
  offsets_.push_back(offset);
  if (static_cast<int>(offsets_.size()) > window_) offsets_.erase(offsets_.begin());
  return camera_ns + *std::min_element(offsets_.begin(), offsets_.end());
}

}  // namespace rover::camera_hw
