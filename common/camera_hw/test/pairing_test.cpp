// The pairing rule shared by every hardware source, on made-up frame sequences.
#include "camera_hw/stereo_source.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <deque>

using namespace rover::camera_hw;

namespace {

// Frames with the given timestamps (ms) on each side; running out is a capture error.
struct Script {
  std::deque<double> left, right;
  int pulled_left = 0, pulled_right = 0;
  Frame operator()(Side side) {
    auto& q = side == Side::kLeft ? left : right;
    if (q.empty()) throw CaptureError(std::string(SideName(side)) + ": no frame");
    Frame f;
    f.timestamp_ns = std::llround(q.front() * 1e6);
    f.frame_id = static_cast<std::uint64_t>((side == Side::kLeft ? pulled_left++ : pulled_right++));
    q.pop_front();
    return f;
  }
};

}  // namespace

TEST(Pairing, AcceptsAPairWithinTolerance) {
  Script s{{100.0}, {101.5}};
  const auto pair = PairFrames(std::ref(s), 2'000'000, 0, "test");
  EXPECT_EQ(pair.left.timestamp_ns, 100'000'000);
  EXPECT_EQ(pair.right.timestamp_ns, 101'500'000);
  EXPECT_EQ(pair.advances, 0);
}

TEST(Pairing, AdvancesTheOlderSideUntilTheyAgree) {
  // Left runs two frames behind the right camera's first frame.
  Script s{{0.0, 33.3, 66.6, 100.0}, {66.7, 100.1}};
  const auto pair = PairFrames(std::ref(s), 1'000'000, 5, "test");
  EXPECT_EQ(pair.left.timestamp_ns, 66'600'000);
  EXPECT_EQ(pair.right.timestamp_ns, 66'700'000);
  EXPECT_EQ(pair.advances, 2);
  EXPECT_EQ(pair.left.frame_id, 2u);
  EXPECT_EQ(pair.right.frame_id, 0u);
}

TEST(Pairing, RejectsInOneLineNamingBothFrames) {
  Script s{{0.0, 40.0}, {20.0, 60.0}};
  try {
    PairFrames(std::ref(s), 5'000'000, 1, "gstreamer");
    FAIL() << "pair 20 ms apart accepted";
  } catch (const CaptureError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what, "gstreamer: pair rejected: left and right timestamps differ by 20.000 ms (tolerance 5.000 ms, "
                    "left frame 1, right frame 0, after 1 advances)");
    EXPECT_EQ(what.find('\n'), std::string::npos);
  }
}

TEST(Pairing, ExactToleranceIsAccepted) {
  Script s{{10.0}, {12.0}};
  EXPECT_NO_THROW(PairFrames(std::ref(s), 2'000'000, 0, "test"));
  Script t{{10.0}, {12.001}};
  EXPECT_THROW(PairFrames(std::ref(t), 2'000'000, 0, "test"), CaptureError);
}

TEST(Pairing, ASideThatStopsIsTheCapturesError) {
  Script s{{0.0}, {}};
  try {
    PairFrames(std::ref(s), 1'000'000, 3, "test");
    FAIL();
  } catch (const CaptureError& e) {
    EXPECT_STREQ(e.what(), "right: no frame");
  }
}

TEST(Pairing, ExposureTimesKeepTheDifferenceAndCentreOnTheCaptureTime) {
  StereoFrames pair;
  // Device clocks count from the camera's power-on: only the difference is carried over.
  pair.left.timestamp_ns = 987'654'321'000;
  pair.right.timestamp_ns = 987'654'321'000 + 1'500'400;  // the right 1.5004 ms later
  const ExposureTimes t = ExposureUtimes(pair, 5'000'000);
  EXPECT_EQ(t.right_utime - t.left_utime, 1500);
  EXPECT_EQ(t.left_utime, 5'000'000 - 750);
  // The right one first, by an odd number of microseconds.
  pair.right.timestamp_ns = pair.left.timestamp_ns - 3'000;
  const ExposureTimes u = ExposureUtimes(pair, 5'000'000);
  EXPECT_EQ(u.right_utime - u.left_utime, -3);
  EXPECT_LE(std::abs(u.left_utime + u.right_utime - 2 * 5'000'000), 1);
  // Equal timestamps: both at the capture time.
  pair.right.timestamp_ns = pair.left.timestamp_ns;
  const ExposureTimes e = ExposureUtimes(pair, 42);
  EXPECT_EQ(e.left_utime, 42);
  EXPECT_EQ(e.right_utime, 42);
}
