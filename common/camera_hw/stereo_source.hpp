// Stereo pairs from real cameras, behind one small interface. Knows nothing of LCM:
// processes/camera_capture wraps a StereoSource in its ImageSource (README, "Camera
// hardware"; docs/HARDWARE.md).
//
// Every failure (a dropped or incomplete frame, a timeout, a pair whose two timestamps do
// not agree, a camera that vanished) is a CaptureError whose what() is one line; a capture
// never waits longer than its timeout. A source that lost a camera reopens it on a later
// Capture(), so a camera that comes back is used again without restarting the process.
#pragma once

#include <opencv2/core.hpp>

#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

namespace rover::camera_hw {

class CaptureError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct Frame {
  cv::Mat image;                 // CV_8UC1 (Mono8, GRAY8) or CV_16UC1 (Mono16, GRAY16_LE)
  std::int64_t timestamp_ns = 0; // the clock the pairing compares (see the sources' options)
  std::uint64_t frame_id = 0;    // the camera's frame counter (GenICam) or sample count
  // When the image was exposed on the system clock (CLOCK_REALTIME, ns since 1970): the
  // GenICam timestamp mapped through ClockMapping, or the GStreamer buffer time moved from
  // the pipeline's clock. 0: unknown. camera_capture stamps the pair with it.
  std::int64_t system_ns = 0;
};

// The system clock now (CLOCK_REALTIME), in ns since 1970.
std::int64_t SystemNowNs();

// A camera's own clock (a GenICam device timestamp: its own epoch, its own drift) mapped
// onto the system clock. Each frame gives one pair (its timestamp, the system time the host
// received it); received minus exposed is the transfer latency plus the clocks' offset, and
// the smallest such difference over the last `window` frames is the best estimate of the
// offset (the frame that waited least), as in network time synchronisation. A camera clock
// that goes back, or jumps ahead by more than `reset_ns` (a camera restarted), starts the
// window anew.
class ClockMapping {
 public:
  explicit ClockMapping(int window = 64, std::int64_t reset_ns = 1'000'000'000)
      : window_(window), reset_ns_(reset_ns) {}
  // The exposure on the system clock of a frame stamped `camera_ns`, received at `system_ns`.
  std::int64_t ToSystem(std::int64_t camera_ns, std::int64_t received_system_ns);
  int samples() const { return static_cast<int>(offsets_.size()); }

 private:
  int window_;
  std::int64_t reset_ns_;
  std::int64_t last_camera_ns_ = 0;
  std::vector<std::int64_t> offsets_;  // received - exposed, the newest last
};

struct StereoFrames {
  Frame left, right;
  int advances = 0;  // frames skipped on the older side before the two agreed
};

class StereoSource {
 public:
  virtual ~StereoSource() = default;
  // One pair taken at once. Throws CaptureError (one line) and never hangs.
  virtual StereoFrames Capture() = 0;
};

enum class Side { kLeft, kRight };
inline const char* SideName(Side s) { return s == Side::kLeft ? "left" : "right"; }

// The pairing rule every source shares: a pair is accepted only when the two timestamps
// agree within `tolerance_ns`. When they do not, the side that is behind takes its next
// frame (free-running cameras and pipelines drift in and out of step), at most
// `max_advances` times; then the capture fails with one line naming both timestamps.
// `next(side)` returns that side's next frame or throws CaptureError.
StereoFrames PairFrames(const std::function<Frame(Side)>& next, std::int64_t tolerance_ns,
                        int max_advances, const std::string& source_name);

// When each image of `pair` was exposed, in rover time: the two timestamps keep their
// difference (rounded to microseconds) and their mean becomes `utime`, the pair's capture
// time in rover time. A camera's clock (host or device, see the sources' options) has its
// own epoch; only the difference between the two is carried over, so that a
// STEREO_FRAME says how far apart its images were taken (stereo_frame_t left_utime,
// right_utime).
struct ExposureTimes {
  std::int64_t left_utime = 0, right_utime = 0;
};
ExposureTimes ExposureUtimes(const StereoFrames& pair, std::int64_t utime);

// The pair's exposure on the system clock in microseconds (the mean of its two images'
// system_ns), or 0 when a side does not know it.
std::int64_t ExposureSystemUtime(const StereoFrames& pair);

}  // namespace rover::camera_hw
