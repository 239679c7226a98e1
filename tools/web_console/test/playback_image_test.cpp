// LogPlayback (log_playback.hpp) on a small log written here: the NAVCAM image at a time t
// is the newest frame logged at or before t, and there is none before the first frame,
// whichever way the playback moved to t (forward, back to before the log's frames, on a
// frame's own stamp). Each frame is one flat grey, so the PNG served says which it is.
#include "bus/channels.hpp"
#include "integration/run_support.hpp"
#include "web_console/log_playback.hpp"

#include <lcm/lcm-cpp.hpp>

#include <rover_msgs/pose_t.hpp>
#include <rover_msgs/stereo_frame_t.hpp>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <yaml-cpp/yaml.h>

#include <optional>
#include <vector>

namespace rover::web {
namespace {

constexpr std::int64_t kSecond = 1'000'000;

struct Frame {
  std::int64_t id, stamp;
  std::uint8_t grey;
};
// Frames at 2 s, 3 s and 4.5 s of a log that runs from 0 to 6 s.
const std::vector<Frame> kFrames = {{51, 2 * kSecond, 40}, {52, 3 * kSecond, 120}, {53, 4'500'000, 220}};

rover_msgs::camera_model_t Model() {
  rover_msgs::camera_model_t m{};
  m.width = 64;
  m.height = 48;
  return m;
}

std::string WriteLog(const std::string& path) {
  lcm::LogFile file(path, "w");
  EXPECT_TRUE(file.good());
  auto write = [&](const char* channel, const auto& msg, std::int64_t stamp) {
    std::vector<std::uint8_t> buf(msg.getEncodedSize());
    msg.encode(buf.data(), 0, static_cast<int>(buf.size()));
    lcm::LogEvent ev{};
    ev.timestamp = stamp;
    ev.channel = channel;
    ev.datalen = static_cast<std::int32_t>(buf.size());
    ev.data = buf.data();
    EXPECT_EQ(file.writeEvent(&ev), 0);
  };
  std::size_t next_frame = 0;
  for (std::int64_t t = 0; t <= 6 * kSecond; t += kSecond / 2) {
    rover_msgs::pose_t pose{};
    pose.utime = t;
    pose.orientation[0] = 1;
    write(channels::kPose, pose, t);
    if (next_frame < kFrames.size() && kFrames[next_frame].stamp == t) {
      const Frame& f = kFrames[next_frame++];
      rover_msgs::stereo_frame_t m{};
      m.utime = m.left_utime = m.right_utime = t;
      m.frame_id = f.id;
      m.purpose = "vo";
      m.left_model = m.right_model = Model();
      m.pose_at_capture.orientation[0] = 1;
      for (rover_msgs::image_t* img : {&m.left, &m.right}) {
        img->width = 64;
        img->height = 48;
        img->encoding = rover_msgs::image_t::ENCODING_GRAY8;
        img->data.assign(64 * 48, f.grey);
        img->size = static_cast<std::int32_t>(img->data.size());
      }
      write(channels::kStereoFrame, m, t);
    }
  }
  EXPECT_EQ(next_frame, kFrames.size());
  return path;
}

// The frame a playback shows at `at`: its id from the state, and the grey of its PNG;
// nullopt when it shows none (and then the PNG request says so).
std::optional<std::pair<std::int64_t, int>> Shown(LogPlayback& playback, std::int64_t at) {
  const YAML::Node state = YAML::Load(playback.StateJsonAt(at));
  std::string why;
  const std::string png = playback.LeftImagePngAt(at, 64, &why);
  if (state["image"].IsNull()) {
    EXPECT_TRUE(png.empty()) << "at " << at << ": a PNG with no image in the state";
    EXPECT_NE(why.find("no STEREO_FRAME"), std::string::npos) << why;
    return std::nullopt;
  }
  EXPECT_FALSE(png.empty()) << why;
  const cv::Mat img = cv::imdecode(std::vector<unsigned char>(png.begin(), png.end()), cv::IMREAD_UNCHANGED);
  if (img.empty()) return std::make_pair(state["image"]["frame_id"].as<std::int64_t>(), -1);
  return std::make_pair(state["image"]["frame_id"].as<std::int64_t>(), static_cast<int>(img.at<std::uint8_t>(10, 10)));
}

// The newest frame stamped at or before `at`, as Shown gives it.
std::optional<std::pair<std::int64_t, int>> Expected(std::int64_t at) {
  std::optional<std::pair<std::int64_t, int>> want;
  for (const auto& f : kFrames)
    if (f.stamp <= at) want = std::make_pair(f.id, static_cast<int>(f.grey));
  return want;
}

TEST(WebConsolePlayback, TheImageAtATimeIsTheNewestFrameAtOrBeforeItAndNoneBeforeTheFirst) {
  const std::string dir = rover::test::OutDir("web_playback_image");
  LogPlayback playback(WriteLog(dir + "/frames.lcm"), WebStateOptions{});
  // The playback opens at the end (frame 53), then goes back and forth, on frames' own
  // stamps, between them, and before the first.
  const std::vector<std::int64_t> times = {6 * kSecond, kSecond,       2 * kSecond, 2'900'000, 3 * kSecond,
                                           1'999'999,   4'600'000,     500'000,     4'500'000, 3'500'000,
                                           0,           6 * kSecond};
  for (const std::int64_t at : times) {
    EXPECT_EQ(Shown(playback, at), Expected(at)) << "at " << at * 1e-6 << " s";
  }
  // The case seen in use: at 1.0 s, after the end was shown, no frame (not frame 53).
  EXPECT_EQ(Shown(playback, 6 * kSecond), std::make_optional(std::make_pair(std::int64_t{53}, 220)));
  EXPECT_EQ(Shown(playback, kSecond), std::nullopt);
}

}  // namespace
}  // namespace rover::web
