// The gstreamer source on videotestsrc pipelines (no camera, no network).
#include "camera_hw/sources.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>

using namespace rover::camera_hw;

namespace {

std::string Caps(const std::string& format) {
  return "video/x-raw,format=" + format + ",width=64,height=48,framerate=10/1";
}

// A source for the two pipelines, or "" and a skip reason.
std::unique_ptr<StereoSource> Make(const std::string& left, const std::string& right, std::string& skip,
                                   double tolerance_ms = 1.0, int max_advances = 3, double timeout_ms = 2000) {
  if (!GstreamerAvailable()) {
    skip = "built without GStreamer (libgstreamer1.0-dev, libgstreamer-plugins-base1.0-dev)";
    return nullptr;
  }
  GstreamerOptions o;
  o.left_pipeline = left;
  o.right_pipeline = right;
  o.pairing_tolerance_ms = tolerance_ms;
  o.max_advances = max_advances;
  o.timeout_ms = timeout_ms;
  try {
    return MakeGstreamerSource(o);
  } catch (const CaptureError& e) {
    const std::string what = e.what();
    if (what.find("no element \"videotestsrc\"") != std::string::npos ||
        what.find("no element \"appsink\"") != std::string::npos) {
      skip = "GStreamer's base plugins are missing (gstreamer1.0-plugins-base): " + what;
      return nullptr;
    }
    throw;
  }
}

}  // namespace

// Non-live sources run frame by frame (appsink without drop blocks them), so both
// pipelines deliver frame n at n * 100 ms on the shared clock: every pair agrees exactly.
TEST(Gstreamer, NonLivePipelinesPairFrameByFrame) {
  const std::string p = "videotestsrc pattern=white ! " + Caps("GRAY8") + " ! appsink sync=false max-buffers=1";
  std::string skip;
  auto source = Make(p, p, skip);
  if (!source) GTEST_SKIP() << skip;
  std::int64_t previous = -1;
  for (int i = 0; i < 3; ++i) {
    const auto pair = source->Capture();
    for (const auto* f : {&pair.left, &pair.right}) {
      ASSERT_EQ(f->image.cols, 64);
      ASSERT_EQ(f->image.rows, 48);
      ASSERT_EQ(f->image.type(), CV_8UC1);
      double lo = 0, hi = 0;
      cv::minMaxLoc(f->image, &lo, &hi);
      EXPECT_EQ(lo, 235.0);  // videotestsrc's white in GRAY8 (video range, 16 to 235)
      EXPECT_EQ(hi, 235.0);
      EXPECT_EQ(f->frame_id, static_cast<std::uint64_t>(i));
    }
    EXPECT_EQ(pair.left.timestamp_ns, pair.right.timestamp_ns);
    EXPECT_EQ(pair.advances, 0);
    if (previous >= 0) {
      EXPECT_EQ(pair.left.timestamp_ns - previous, 100'000'000);  // 10 frames/s
    }
    previous = pair.left.timestamp_ns;
  }
}

TEST(Gstreamer, Gray16AndRowPadding) {
  // 6 pixels of 1 byte make a 6-byte row that GStreamer pads to 8: the image must still be
  // the picture, not shifted rows.
  const std::string p = "videotestsrc pattern=black ! video/x-raw,format=GRAY8,width=6,height=4,framerate=10/1 "
                        "! appsink sync=false max-buffers=1";
  const std::string q = "videotestsrc pattern=white ! video/x-raw,format=GRAY16_LE,width=6,height=4,framerate=10/1 "
                        "! appsink sync=false max-buffers=1";
  std::string skip;
  auto source = Make(p, q, skip);
  if (!source) GTEST_SKIP() << skip;
  const auto pair = source->Capture();
  ASSERT_EQ(pair.left.image.type(), CV_8UC1);
  ASSERT_EQ(pair.right.image.type(), CV_16UC1);
  EXPECT_EQ(pair.left.image.size(), cv::Size(6, 4));
  EXPECT_EQ(pair.right.image.size(), cv::Size(6, 4));
  double lo = 0, hi = 0;
  cv::minMaxLoc(pair.left.image, &lo, &hi);
  EXPECT_EQ(lo, 16.0);  // black, video range
  EXPECT_EQ(hi, 16.0);
  cv::minMaxLoc(pair.right.image, &lo, &hi);
  EXPECT_EQ(lo, 235.0 * 257);  // white, video range, 16 bits
  EXPECT_EQ(hi, 235.0 * 257);
}

TEST(Gstreamer, PairsApartBeyondToleranceAreRejected) {
  // The right pipeline's frames are stamped 50 ms late: never within 1 ms of a left one.
  const std::string p = "videotestsrc ! " + Caps("GRAY8") + " ! appsink sync=false max-buffers=1";
  const std::string q = "videotestsrc timestamp-offset=50000000 ! " + Caps("GRAY8") + " ! appsink sync=false max-buffers=1";
  std::string skip;
  auto source = Make(p, q, skip);
  if (!source) GTEST_SKIP() << skip;
  try {
    source->Capture();
    FAIL() << "a pair 50 ms apart was accepted";
  } catch (const CaptureError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("gstreamer: pair rejected: left and right timestamps differ by 50.000 ms (tolerance 1.000 ms"),
              std::string::npos)
        << what;
    EXPECT_EQ(what.find('\n'), std::string::npos);
  }
}

TEST(Gstreamer, LivePipelinesPairWithinTolerance) {
  // Two live 30 frames/s sources start up to one frame apart; advancing the older side
  // brings them within half a frame (16.7 ms), plus the scheduling jitter of a busy
  // machine: 25 ms, still under the 33 ms a frame behind would be.
  const std::string p = "videotestsrc is-live=true ! video/x-raw,format=GRAY8,width=64,height=48,framerate=30/1 "
                        "! appsink max-buffers=1 drop=true";
  std::string skip;
  auto source = Make(p, p, skip, 25.0, 5);
  if (!source) GTEST_SKIP() << skip;
  std::int64_t previous = 0;
  for (int i = 0; i < 5; ++i) {
    const auto pair = source->Capture();
    EXPECT_LE(std::llabs(pair.left.timestamp_ns - pair.right.timestamp_ns), 25'000'000);
    EXPECT_GT(pair.left.timestamp_ns, previous);  // each capture is a newer pair
    previous = pair.left.timestamp_ns;
  }
}

TEST(Gstreamer, StalledPipelineTimesOutInOneLine) {
  // appsrc never pushes: the capture must give up after its timeout, not hang.
  const std::string p = "videotestsrc ! " + Caps("GRAY8") + " ! appsink sync=false max-buffers=1";
  const std::string q = "appsrc caps=" + Caps("GRAY8") + " ! appsink";
  std::string skip;
  auto source = Make(p, q, skip, 1.0, 3, 300);
  if (!source) GTEST_SKIP() << skip;
  const auto start = std::chrono::steady_clock::now();
  try {
    source->Capture();
    FAIL() << "a pair from a silent pipeline";
  } catch (const CaptureError& e) {
    EXPECT_STREQ(e.what(), "gstreamer: right pipeline: no frame within 300 ms");
  }
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(2));
}

TEST(Gstreamer, PipelineThatCannotStartFailsEachCaptureInOneLine) {
  // Its source cannot open (as a camera not plugged in): the source is made all the same,
  // and each capture tries again and fails in one line, never hanging.
  const std::string p = "videotestsrc ! " + Caps("GRAY8") + " ! appsink sync=false max-buffers=1";
  std::string skip;
  auto source = Make(p, "filesrc location=/nonexistent/camera ! appsink", skip);
  if (!source) GTEST_SKIP() << skip;
  for (int i = 0; i < 2; ++i) {
    const auto start = std::chrono::steady_clock::now();
    try {
      source->Capture();
      FAIL() << "a pair from a pipeline that cannot start";
    } catch (const CaptureError& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind("gstreamer: right pipeline: cannot start", 0), 0u) << what;
      EXPECT_NE(what.find("filesrc0: "), std::string::npos) << what;  // the element that failed
      std::printf("%s\n", what.c_str());
      EXPECT_EQ(what.find('\n'), std::string::npos);
    }
    EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(2));
  }
}

TEST(Gstreamer, EndOfStreamAndBadPipelinesAreOneLine) {
  const std::string p = "videotestsrc num-buffers=1 ! " + Caps("GRAY8") + " ! appsink sync=false max-buffers=1";
  std::string skip;
  auto source = Make(p, p, skip);
  if (!source) GTEST_SKIP() << skip;
  EXPECT_NO_THROW(source->Capture());
  try {
    source->Capture();
    FAIL() << "a pair after the end of stream";
  } catch (const CaptureError& e) {
    EXPECT_STREQ(e.what(), "gstreamer: left pipeline: ended (end of stream)");
  }
  // Both pipelines start again at the next capture (as after a camera came back).
  EXPECT_NO_THROW(source->Capture());
  try {
    Make("nosuchsrc ! appsink", p, skip);
    FAIL() << "a pipeline with an unknown element";
  } catch (const CaptureError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("gstreamer: left pipeline: ", 0), 0u) << what;
    EXPECT_NE(what.find("nosuchsrc"), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos);
  }
  try {
    Make(p, "videotestsrc ! video/x-raw,format=RGB,width=8,height=8 ! appsink sync=false", skip)->Capture();
    FAIL() << "a colour pipeline";
  } catch (const CaptureError& e) {
    EXPECT_STREQ(e.what(), "gstreamer: right pipeline: frames in format RGB (expected GRAY8 or GRAY16_LE: end the "
                           "pipeline with videoconvert ! video/x-raw,format=GRAY8 ! appsink)");
  }
}
