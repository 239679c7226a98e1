// The genicam source on Aravis's simulated cameras: the in-process Fake interface
// (FakeInterface.*) and arv-fake-gv-camera-0.8 speaking GigE Vision over the loopback
// (FakeGv.*). Run by ctest through in_netns.sh: a private network namespace holding only
// lo with 127.0.0.1 and 127.0.0.2, so Aravis's discovery broadcasts stay on this machine.
//
// What the fake camera draws (arvfakecamera.c, Aravis 0.8): a diagonal ramp,
// ramp(x, y) = (x + y + frame id) mod 255 in region coordinates, times
// scale = 1 + gain + log10(exposure_us / 10000), clipped to 255 (Mono8); Mono16 holds
// ramp * 256 + 255. Its sensor is 2048 x 2048.
#include "camera_hw/sources.hpp"
#include "fake_gv_camera.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <thread>

using namespace rover::camera_hw;
using rover::camera_hw::test::FakeGvCamera;
using Clock = std::chrono::steady_clock;

namespace {

// Why a test cannot run here, or "".
std::string SkipReason() {
  if (!GenicamAvailable()) return "built without Aravis (libaravis-dev)";
  const char* netns = std::getenv("ROVER_CAMERA_NETNS");
  if (netns == nullptr || std::string(netns) != "1") {
    return "run through ctest: Aravis broadcasts discoveries, so this test runs only in the private "
           "network namespace made by common/camera_hw/test/in_netns.sh";
  }
  return "";
}

GenicamOptions FakeInterfaceOptions() {
  GenicamOptions o;
  // Each opening of Fake_1 is its own simulated camera, so two openings make a pair. The
  // in-process fake has no software trigger (it runs free whatever the trigger), so it is
  // used free-running, at 25 frames/s: its frames fall on one 40 ms grid of the monotonic
  // clock, but are stamped when its thread wakes, which on a loaded machine has been seen
  // 190 ms late. These tests are about what the cameras deliver (pixels, sizes, formats,
  // gain); the pairing rule is tested in pairing_test.cpp and on the GigE fakes below.
  o.left.device_id = "Fake_1";
  o.right.device_id = "Fake_1";
  o.fake_interface = true;
  o.trigger = "free";
  o.frame_rate_hz = 25.0;
  o.max_advances = 3;
  o.timestamps = "device";
  o.pairing_tolerance_ms = 500.0;
  o.roi_width = 320;
  o.roi_height = 240;
  o.timeout_ms = 1000;
  return o;
}

constexpr double kFakeGvTriggerTolerance_ms = 110.0;

GenicamOptions FakeGvOptions() {
  GenicamOptions o;
  o.left.serial = "GV01";
  o.right.serial = "GV02";
  // Both fake cameras stamp frames with this computer's monotonic clock, so the device
  // timestamps of a pair are comparable (as with PTP-synchronised cameras).
  o.timestamps = "device";
  // The fake looks at its trigger register every 100 ms until its first frame after an
  // acquisition start, then every 40 ms: two triggers sent back to back may be answered up
  // to one such tick apart. (A real camera answers in microseconds; free-running, the
  // fakes' frames agree within microseconds: see PairsAgreeWithinTolerance.)
  o.pairing_tolerance_ms = kFakeGvTriggerTolerance_ms;
  o.roi_width = 256;
  o.roi_height = 192;
  o.timeout_ms = 1000;
  return o;
}

// Pixels that differ from the fake camera's Mono8 ramp for this frame.
int RampMismatches8(const Frame& f, double scale) {
  int bad = 0;
  for (int y = 0; y < f.image.rows; ++y) {
    for (int x = 0; x < f.image.cols; ++x) {
      const double ramp = static_cast<double>((x + y + f.frame_id) % 255);
      const int expected = static_cast<int>(std::clamp(ramp * scale, 0.0, 255.0));
      if (f.image.at<std::uint8_t>(y, x) != expected) ++bad;
    }
  }
  return bad;
}

int RampMismatches16(const Frame& f) {
  int bad = 0;
  for (int y = 0; y < f.image.rows; ++y) {
    for (int x = 0; x < f.image.cols; ++x) {
      const int ramp = static_cast<int>((x + y + f.frame_id) % 255);
      if (f.image.at<std::uint16_t>(y, x) != ramp * 256 + 255) ++bad;
    }
  }
  return bad;
}

std::string CaptureErrorOf(StereoSource& source) {
  try {
    source.Capture();
  } catch (const CaptureError& e) {
    return e.what();
  }
  return "";
}

double Seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

// Two fake GigE Vision cameras, GV01 on 127.0.0.1 and GV02 on 127.0.0.2.
class FakeGv : public ::testing::Test {
 protected:
  void SetUp() override {
    const std::string skip = SkipReason();
    if (!skip.empty()) GTEST_SKIP() << skip;
    if (!FakeGvCamera::Installed()) GTEST_SKIP() << FakeGvCamera::kProgram << " is not installed (aravis-tools)";
    ASSERT_TRUE(left_.Start()) << "fake camera GV01 did not answer on 127.0.0.1";
    ASSERT_TRUE(right_.Start()) << "fake camera GV02 did not answer on 127.0.0.2";
  }
  FakeGvCamera left_{"127.0.0.1", "GV01"};
  FakeGvCamera right_{"127.0.0.2", "GV02"};
};

}  // namespace

TEST(FakeInterface, PairHasTheFakeCamerasRampAndSize) {
  const std::string skip = SkipReason();
  if (!skip.empty()) GTEST_SKIP() << skip;
  auto source = MakeGenicamSource(FakeInterfaceOptions());
  for (int i = 0; i < 3; ++i) {
    const auto pair = source->Capture();
    for (const auto* f : {&pair.left, &pair.right}) {
      ASSERT_EQ(f->image.cols, 320);
      ASSERT_EQ(f->image.rows, 240);
      ASSERT_EQ(f->image.type(), CV_8UC1);
      EXPECT_EQ(RampMismatches8(*f, 1.0), 0) << "frame " << f->frame_id;
    }
    EXPECT_LE(std::llabs(pair.left.timestamp_ns - pair.right.timestamp_ns), 500'000'000);
  }
}

TEST(FakeInterface, GainIsSharedByThePair) {
  const std::string skip = SkipReason();
  if (!skip.empty()) GTEST_SKIP() << skip;
  auto options = FakeInterfaceOptions();
  options.gain = 1.0;  // scale 2: the ramp doubles, clipped at 255
  auto source = MakeGenicamSource(options);
  const auto pair = source->Capture();
  EXPECT_EQ(RampMismatches8(pair.left, 2.0), 0);
  EXPECT_EQ(RampMismatches8(pair.right, 2.0), 0);
  EXPECT_GT(RampMismatches8(pair.right, 1.0), 0);  // the check can tell the gains apart
  // Exposure 100 ms: scale 1 + log10(10) = 2 as well.
  options.gain = 0.0;
  options.exposure_us = 100000;
  auto longer = MakeGenicamSource(options);
  const auto pair2 = longer->Capture();
  EXPECT_EQ(RampMismatches8(pair2.left, 2.0), 0);
  EXPECT_EQ(RampMismatches8(pair2.right, 2.0), 0);
}

TEST(FakeInterface, Mono16AndRegion) {
  const std::string skip = SkipReason();
  if (!skip.empty()) GTEST_SKIP() << skip;
  auto options = FakeInterfaceOptions();
  options.pixel_format = "Mono16";
  options.roi_x = 10;
  options.roi_y = 20;
  options.roi_width = 64;
  options.roi_height = 32;
  options.binning = 2;  // the fake accepts binning (and draws the same ramp)
  auto source = MakeGenicamSource(options);
  const auto pair = source->Capture();
  for (const auto* f : {&pair.left, &pair.right}) {
    ASSERT_EQ(f->image.type(), CV_16UC1);
    EXPECT_EQ(f->image.size(), cv::Size(64, 32));
    EXPECT_EQ(RampMismatches16(*f), 0);
  }
  // The whole sensor when no region is given.
  options.roi_width = options.roi_height = 0;
  options.binning = 1;
  options.pixel_format = "Mono8";
  const auto whole = MakeGenicamSource(options)->Capture();
  EXPECT_EQ(whole.left.image.size(), cv::Size(2048, 2048));
}

TEST(FakeInterface, MissingCameraIsOneLineAndNeverHangs) {
  const std::string skip = SkipReason();
  if (!skip.empty()) GTEST_SKIP() << skip;
  auto options = FakeInterfaceOptions();
  options.right.device_id.clear();
  options.right.serial = "NOPE";
  auto source = MakeGenicamSource(options);
  const auto start = Clock::now();
  const std::string error = CaptureErrorOf(*source);
  EXPECT_EQ(error.rfind("genicam: right camera (serial NOPE): not found (cameras seen: ", 0), 0u) << error;
  EXPECT_NE(error.find("Fake_1 (serial 1)"), std::string::npos) << error;
  EXPECT_EQ(error.find('\n'), std::string::npos);
  EXPECT_LT(Seconds(Clock::now() - start), 10.0);
  // A feature the camera lacks: one line naming the camera and the key.
  options = FakeInterfaceOptions();
  options.exposure_auto = true;
  EXPECT_EQ(CaptureErrorOf(*MakeGenicamSource(options)),
            "genicam: left camera (device Fake_1): exposure_us: auto asked but the camera has no ExposureAuto");
}

TEST_F(FakeGv, SoftwareTriggerTakesOnePairPerRequest) {
  auto source = MakeGenicamSource(FakeGvOptions());
  std::uint64_t last_left = 0, last_right = 0;
  for (int i = 0; i < 4; ++i) {
    const auto pair = source->Capture();
    for (const auto* f : {&pair.left, &pair.right}) {
      ASSERT_EQ(f->image.size(), cv::Size(256, 192));
      EXPECT_EQ(RampMismatches8(*f, 1.0), 0) << "frame " << f->frame_id;
    }
    // Free-running, the fakes make 25 frames/s: 200 ms between requests would skip about
    // five. Triggered, each request makes exactly one frame per camera.
    if (i > 0) {
      EXPECT_EQ(pair.left.frame_id, last_left + 1);
      EXPECT_EQ(pair.right.frame_id, last_right + 1);
    }
    last_left = pair.left.frame_id;
    last_right = pair.right.frame_id;
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
}

TEST_F(FakeGv, PairsAgreeWithinTolerance) {
  // Free-running at 50 frames/s, each fake on its own 20 ms clock: the side behind
  // advances until the two are within one frame period. (The fakes' frame times jitter by
  // milliseconds on a loaded machine, and a late frame makes the other side advance more.)
  auto options = FakeGvOptions();
  options.trigger = "free";
  options.frame_rate_hz = 50.0;
  options.max_advances = 12;
  options.timeout_ms = 2000;
  for (const char* clock : {"device", "host"}) {
    options.timestamps = clock;
    // Device stamps are the fill instants; host stamps add the transfer over loopback.
    options.pairing_tolerance_ms = 20.0;
    auto source = MakeGenicamSource(options);
    std::int64_t worst = 0;
    double slowest = 0;
    int advances = 0;
    std::int64_t previous = 0;
    for (int i = 0; i < 10; ++i) {
      const auto start = Clock::now();
      const auto pair = source->Capture();
      if (i > 0) slowest = std::max(slowest, Seconds(Clock::now() - start));  // (the first opens the cameras)
      worst = std::max<std::int64_t>(worst, std::llabs(pair.left.timestamp_ns - pair.right.timestamp_ns));
      advances += pair.advances;
      EXPECT_EQ(RampMismatches8(pair.left, 1.0), 0);
      EXPECT_EQ(RampMismatches8(pair.right, 1.0), 0);
      // A new pair each time. (Not by frame id: GigE Vision's 16-bit block ids wrap, and
      // the fake starts them at 65400 to show it.)
      EXPECT_GT(pair.left.timestamp_ns, previous);
      previous = pair.left.timestamp_ns;
    }
    EXPECT_LE(worst, options.pairing_tolerance_ms * 1e6);
    std::printf("%s timestamps, free-running: largest left-right difference over 10 pairs %.3f ms, %d advances, "
                "slowest capture %.1f ms\n", clock, worst / 1e6, advances, slowest * 1e3);
  }
}

TEST_F(FakeGv, TightToleranceRejectsPairs) {
  // Two processes fill their frames microseconds apart: with no tolerance and no advance,
  // pairs are rejected with one line naming both frames.
  auto options = FakeGvOptions();
  options.pairing_tolerance_ms = 0.0;
  options.max_advances = 0;
  auto source = MakeGenicamSource(options);
  int rejected = 0;
  for (int i = 0; i < 3; ++i) {
    const std::string error = CaptureErrorOf(*source);
    if (error.empty()) continue;
    ++rejected;
    EXPECT_EQ(error.rfind("genicam: pair rejected: left and right timestamps differ by ", 0), 0u) << error;
    EXPECT_NE(error.find("(tolerance 0.000 ms, left frame "), std::string::npos) << error;
  }
  EXPECT_GE(rejected, 1);
}

TEST_F(FakeGv, KilledCameraFailsInOneLineAndRecovers) {
  auto options = FakeGvOptions();
  options.timeout_ms = 500;
  auto source = MakeGenicamSource(options);
  ASSERT_NO_THROW(source->Capture());

  right_.Kill();  // the right camera loses power mid-run
  auto start = Clock::now();
  const std::string lost = CaptureErrorOf(*source);
  const double lost_s = Seconds(Clock::now() - start);
  EXPECT_EQ(lost.rfind("genicam: right camera (serial GV02): ", 0), 0u) << lost;
  EXPECT_EQ(lost.find('\n'), std::string::npos);
  EXPECT_LT(lost_s, 15.0) << lost;
  start = Clock::now();
  const std::string absent = CaptureErrorOf(*source);
  const double absent_s = Seconds(Clock::now() - start);
  EXPECT_EQ(absent.rfind("genicam: right camera (serial GV02): not found (cameras seen: ", 0), 0u) << absent;
  EXPECT_LT(absent_s, 15.0);

  ASSERT_TRUE(right_.Start());  // power back
  start = Clock::now();
  int failures = 0;
  bool recovered = false;
  for (int i = 0; i < 10 && !recovered; ++i) {
    try {
      const auto pair = source->Capture();
      recovered = true;
      EXPECT_EQ(RampMismatches8(pair.right, 1.0), 0);
      EXPECT_EQ(pair.right.image.size(), cv::Size(256, 192));
    } catch (const CaptureError& e) {
      ++failures;
      EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
    }
  }
  EXPECT_TRUE(recovered);
  std::printf("camera killed: failed capture after %.2f s (\"%s\"); while absent: %.2f s; after restart: "
              "%d failed captures, first pair after %.2f s\n",
              lost_s, lost.c_str(), absent_s, failures, Seconds(Clock::now() - start));
}

TEST_F(FakeGv, LostPacketsFailTheCaptureInOneLine) {
  ASSERT_TRUE(right_.Start(500));  // half of the right camera's packets never arrive
  auto options = FakeGvOptions();
  options.timeout_ms = 1000;
  auto source = MakeGenicamSource(options);
  int failed = 0;
  for (int i = 0; i < 3; ++i) {
    const auto start = Clock::now();
    const std::string error = CaptureErrorOf(*source);
    EXPECT_LT(Seconds(Clock::now() - start), 5.0);
    if (error.empty()) continue;
    ++failed;
    std::printf("%s\n", error.c_str());
    EXPECT_EQ(error.rfind("genicam: right camera (serial GV02): ", 0), 0u) << error;
    EXPECT_TRUE(error.find(" dropped: ") != std::string::npos || error.find("no frame within 1000 ms") != std::string::npos)
        << error;
    EXPECT_EQ(error.find('\n'), std::string::npos);
  }
  EXPECT_EQ(failed, 3);
  // Whole again: the next capture works.
  ASSERT_TRUE(right_.Start());
  bool recovered = false;
  for (int i = 0; i < 5 && !recovered; ++i) recovered = CaptureErrorOf(*source).empty();
  EXPECT_TRUE(recovered);
}

TEST_F(FakeGv, HardwareTriggerWithoutPulseTimesOut) {
  auto options = FakeGvOptions();
  options.trigger = "hardware";
  options.trigger_line = "Line0";
  options.timeout_ms = 500;
  auto source = MakeGenicamSource(options);
  const auto start = Clock::now();
  const std::string error = CaptureErrorOf(*source);
  EXPECT_EQ(error, "genicam: left camera (serial GV01): no frame within 500 ms (trigger hardware); reopening at the next capture");
  EXPECT_LT(Seconds(Clock::now() - start), 10.0);
}
