// Bad and hostile images at the processes that read them: visual_odometry alone on a
// private bus answers every bad STEREO_FRAME with STATUS_BAD_INPUT and a reason (or the
// Bus drops it), counts each one as a drop, and pairs the next good frame with the last
// good one; camera_capture refuses a dataset with a pair of the wrong size at start.
#include "fault/fault_rig.hpp"

#include <rover_msgs/stereo_frame_t.hpp>
#include <rover_msgs/vo_update_t.hpp>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

namespace rover::test {
namespace {

using rover_msgs::vo_update_t;
// LCM's constants are declared in the class only: copies that tests may take by reference.
constexpr int kBadInput = vo_update_t::STATUS_BAD_INPUT;

rover_msgs::stereo_frame_t Decode(const fault::Bytes& bytes) {
  rover_msgs::stereo_frame_t f;
  if (f.decode(bytes.data(), 0, static_cast<int>(bytes.size())) < 0) throw std::runtime_error("not a frame");
  return f;
}

TEST(FaultImages, VisualOdometryAnswersEveryBadFrameAndPairsTheNextGoodOneWithTheLastGood) {
  const std::string url = PrivateUrl(23);
  launch::ProcessSet set(std::string(ROVER_BINARY_DIR) + "/bin", OutDir("fault_vo_images"), false);
  set.Start({"visual_odometry", "visual_odometry", {"--config", SourceDir() + "/configs/vo.yaml"}},
            {"ROVER_LCM_URL=" + url});
  bus::Bus bus(url);
  bus.set_publisher("fault_test");
  lcm::LCM injector(url);
  std::map<std::int64_t, vo_update_t> updates;
  std::optional<Clock::time_point> heard;
  std::int64_t dropped = -1;
  bus.Subscribe<vo_update_t>(channels::kVoUpdate, [&](const vo_update_t& u) { updates[u.to_frame_id] = u; }, 100);
  bus.Subscribe<rover_msgs::heartbeat_t>(channels::kHeartbeat, [&](const rover_msgs::heartbeat_t& h) {
    if (h.process != "visual_odometry") return;
    heard = Clock::now();
    dropped = h.dropped;
  });
  auto pump_until = [&](double seconds, const std::function<bool()>& done) {
    const auto start = Clock::now();
    while (!done() && Since(start) < seconds) bus.Handle(10);
    return done();
  };
  ASSERT_TRUE(pump_until(20, [&] { return heard.has_value(); })) << "visual_odometry sent no heartbeat";

  // Rover time of the frames: the system clock's, as on a rover. VO hears no time source,
  // so 2 s after its start it takes the system clock for rover time (bus.time: auto), and a
  // frame stamped far from it would then be dropped as too old, whenever the test got there.
  const std::int64_t t0 = bus::RoverClock::SystemUtime();
  fault::PacketOptions options;
  options.now_utime = t0 + 1000;
  options.bomb_side = 8192;  // 64 MiB of zeros claimed; the header is what matters
  auto good = Decode(fault::SampleMessage("STEREO_FRAME", options));
  good.utime = t0;
  good.frame_id = 1;
  bus.Publish(channels::kStereoFrame, good);
  ASSERT_TRUE(pump_until(10, [&] { return updates.count(1) > 0; })) << "no VO_UPDATE for the first good frame";
  EXPECT_NE(updates[1].status, kBadInput) << updates[1].reason;
  const std::int64_t dropped_before = dropped;

  const auto packets = fault::BuildPackets("images", "STEREO_FRAME", options);
  ASSERT_GE(packets.size(), 20u);
  std::vector<std::int64_t> ids;
  for (const auto& p : packets) {
    ids.push_back(Decode(p.bytes).frame_id);
    ASSERT_EQ(injector.publish(p.channel, p.bytes.data(), static_cast<unsigned int>(p.bytes.size())), 0) << p.label;
    pump_until(0.05, [] { return false; });
  }
  // Every bad frame is a drop: the Bus refused it, or VO answered STATUS_BAD_INPUT.
  auto answered_or_dropped = [&] {
    std::int64_t processed = 0;  // frames VO took as good
    for (auto id : ids)
      if (updates.count(id) && updates[id].status != kBadInput) ++processed;
    return dropped - dropped_before >= static_cast<std::int64_t>(ids.size()) - processed;
  };
  EXPECT_TRUE(pump_until(10, answered_or_dropped))
      << "visual_odometry counted " << dropped - dropped_before << " drops for " << ids.size() << " bad frames";
  EXPECT_TRUE(set.Running("visual_odometry")) << "visual_odometry died on a bad frame";

  std::int64_t last_good = 1;
  for (std::size_t i = 0; i < packets.size(); ++i) {
    const auto& p = packets[i];
    const auto it = updates.find(ids[i]);
    if (it == updates.end()) {
      EXPECT_TRUE(p.expect_reason.empty()) << p.label << ": no VO_UPDATE (expected STATUS_BAD_INPUT, \""
                                           << p.expect_reason << "\")";
      continue;
    }
    const vo_update_t& u = it->second;
    if (u.status != kBadInput) {
      // Only a frame with nothing wrong that VO can see may pass (a PNG whose extra data
      // libpng ignores); it then becomes the reference.
      EXPECT_TRUE(p.expect_reason.empty()) << p.label << ": status " << int(u.status) << " " << u.reason;
      last_good = ids[i];
      continue;
    }
    EXPECT_NE(u.reason.find(p.expect_reason), std::string::npos)
        << p.label << ": reason \"" << u.reason << "\" (expected it to hold \"" << p.expect_reason << "\")";
    EXPECT_NE(u.reason.find("frame " + std::to_string(ids[i])), std::string::npos) << u.reason;
    EXPECT_EQ(u.reason.find('\n'), std::string::npos) << u.reason;
    std::cout << "  " << p.label << " -> " << u.reason << "\n";
  }

  // The next good frame pairs with the last good one: the bad frames left nothing behind.
  good.utime = t0 + 2000;
  good.frame_id = 2;
  bus.Publish(channels::kStereoFrame, good);
  ASSERT_TRUE(pump_until(10, [&] { return updates.count(2) > 0; })) << "no VO_UPDATE for the good frame after the bad ones";
  EXPECT_NE(updates[2].status, kBadInput) << updates[2].reason;
  EXPECT_EQ(updates[2].from_frame_id, last_good);
  EXPECT_TRUE(set.Running("visual_odometry"));
  set.StopAll();
}

// A KITTI-layout directory of 64x48 pairs; `bad` names a right image written 65 px wide.
std::string WriteDataset(const std::string& name, bool bad) {
  const std::string dir = OutDir(name);
  std::filesystem::create_directories(dir + "/image_0");
  std::filesystem::create_directories(dir + "/image_1");
  std::ofstream(dir + "/calib.txt") << "P0: 50 0 31.5 0 0 50 23.5 0 0 0 1 0\n"
                                       "P1: 50 0 31.5 -10 0 50 23.5 0 0 0 1 0\n";
  cv::Mat image(48, 64, CV_8UC1);
  cv::randu(image, 0, 255);
  for (const char* file : {"000000.png", "000001.png"}) {
    cv::imwrite(dir + "/image_0/" + file, image);
    cv::imwrite(dir + "/image_1/" + file, image);
  }
  if (bad) cv::imwrite(dir + "/image_1/000001.png", cv::Mat(48, 65, CV_8UC1, cv::Scalar(9)));
  return dir;
}

TEST(FaultImages, DatasetPairOfTheWrongSizeStopsCameraCaptureAtStartWithOneLine) {
  const std::string env = "ROVER_LCM_URL='" + PrivateUrl(31) + "' ";
  const std::string bad = WriteDataset("fault_dataset_bad", true);
  const auto r = RunCommand(env + "timeout 10 " + Bin("camera_capture") + " --dataset " + bad);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_EQ(r.output, bad + "/image_1/000001.png: 65x48, 8-bit (expected 64x48, 8-bit like " + bad +
                          "/image_0/000000.png)\n");
  // The same directory with the pair fixed runs until stopped.
  const std::string good = WriteDataset("fault_dataset_good", false);
  const auto g = RunCommand(env + "timeout 2 " + Bin("camera_capture") + " --dataset " + good);
  EXPECT_EQ(g.exit_code, 124) << "expected it to run until `timeout` stopped it: " << g.output;
}

}  // namespace
}  // namespace rover::test
