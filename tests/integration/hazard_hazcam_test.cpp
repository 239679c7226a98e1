// hazard_monitor maps the front HAZCAM pair (HAZCAM_FRAME) as it maps STEREO_FRAME: on a
// private bus, a lone hazard_monitor (configs/rover.yaml, real clock) is sent a HAZCAM pair
// rendered over a 0.3 m rock against the body's front, where the mast's NAVCAMs never look,
// and at once a query for a step onto it. The query is held until the pair is mapped and
// refused on the map; the map it publishes has the rock unsafe, and its last frame id stays
// the NAVCAM pairs' (-1: the executor waits for a capture's NAVCAM pair, which comes after
// its HAZCAM pair). A HAZCAM_FRAME whose images are not its models' size is dropped with
// one line naming the channel, and the monitor runs on.
#include "bus/bus.hpp"
#include "bus/channels.hpp"
#include "bus/convert.hpp"
#include "bus/image_encode.hpp"
#include "config/yaml_config.hpp"
#include "geometry/camera_io.hpp"
#include "geometry/pose.hpp"
#include "integration/run_support.hpp"
#include "launch/process_set.hpp"
#include "render/stereo_renderer.hpp"
#include "terrain/world.hpp"
#include "traversability/traversability_map.hpp"

#include <rover_msgs/hazard_query_t.hpp>
#include <rover_msgs/hazard_reply_t.hpp>
#include <rover_msgs/heartbeat_t.hpp>
#include <rover_msgs/pose_t.hpp>
#include <rover_msgs/stereo_frame_t.hpp>
#include <rover_msgs/traversability_map_t.hpp>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>
#include <yaml-cpp/yaml.h>

#include <chrono>
#include <cmath>
#include <functional>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>

namespace rover::test {
namespace {

using Clock = std::chrono::steady_clock;

std::int64_t NowUs() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

const char* kWorld = R"(
name: rock_at_the_front
seed: 4
map: {center: [4, 0], size_m: [24, 20], resolution_m: 0.02}
roughness: {amplitude_m: 0.005, min_wavelength_m: 0.2, max_wavelength_m: 3.0}
soil: {default: packed_soil}
rocks:
  placed:
    - {name: Front, position: [1.0, 0.25], diameter_m: 0.4, height_m: 0.3}
albedo:
  packed_soil: {mean: 0.28, contrast: 0.25}
sun: {azimuth_deg: 30, elevation_deg: 55}
)";

rover_msgs::pose_t PoseMsg(std::int64_t utime, double z) {
  rover_msgs::pose_t p{};
  p.utime = utime;
  p.position[2] = z;
  p.orientation[0] = 1.0;
  for (int k = 0; k < 6; ++k) p.covariance[k][k] = k < 3 ? 1e-4 : 1e-6;
  p.last_vo_to_frame = -1;
  return p;
}

TEST(HazardMonitorHazcam, MapsTheHazcamPairAndRefusesAStepOntoWhatItSaw) {
  const terrain::World world(terrain::WorldOptions::Load(config::ConfigNode::FromString(kWorld, "world.yaml")));
  const double z = -world.Elevation(0, 0);
  render::RenderOptions ro;
  ro.image_scale = 0.25;  // as camera_capture renders it (capture.hazcam.render)
  render::StereoRenderer renderer(ro);
  const render::StereoImages pair = renderer.RenderPair(
      world, geometry::LoadStereoRigFile(SourceDir() + "/configs/cameras/hazcam_front.yaml"),
      geometry::PoseFromXyzRpy(0, 0, z, 0, 0, 0), 1);

  const std::string url = PrivateUrl(71);
  bus::Bus bus(url);
  bool up = false;
  std::optional<rover_msgs::hazard_reply_t> reply;
  std::optional<rover_msgs::traversability_map_t> map;
  bus.Subscribe<rover_msgs::heartbeat_t>(channels::kHeartbeat, [&](const rover_msgs::heartbeat_t& h) {
    if (h.process == "hazard_monitor") up = true;
  });
  bus.Subscribe<rover_msgs::hazard_reply_t>(channels::kHazardReply, [&](const rover_msgs::hazard_reply_t& r) {
    if (r.query_id == 7) reply = r;
  });
  bus.Subscribe<rover_msgs::traversability_map_t>(
      channels::kTraversabilityMap, [&](const rover_msgs::traversability_map_t& m) { map = m; }, 4);
  const std::string dir = OutDir("hazard_hazcam");
  launch::ProcessSet set(std::string(ROVER_BINARY_DIR) + "/bin", dir, false);
  set.Start({"hazard_monitor", "hazard_monitor", {"--config", SourceDir() + "/configs/rover.yaml"}},
            {"ROVER_LCM_URL=" + url, "ROVER_TIME=real"});
  auto spin = [&](const std::function<bool()>& done, int seconds) {
    const auto t0 = Clock::now();
    while (!done() && Clock::now() - t0 < std::chrono::seconds(seconds)) {
      bus.Publish(channels::kPose, PoseMsg(NowUs(), z));
      bus.Handle(100);
    }
  };
  spin([&] { return up; }, 30);
  ASSERT_TRUE(up) << "hazard_monitor not up within 30 s";

  rover_msgs::stereo_frame_t frame{};
  frame.frame_id = 1;
  frame.purpose = "vo";
  frame.left_model = bus::CameraModelToMsg(*pair.rig.left);
  frame.right_model = bus::CameraModelToMsg(*pair.rig.right);
  frame.pose_at_capture = PoseMsg(NowUs(), z);
  // A pair at half the models' size: dropped with one line.
  cv::Mat half;
  cv::resize(pair.left, half, cv::Size(128, 128));
  frame.left = bus::EncodeImage(half, true);
  frame.right = bus::EncodeImage(half, true);
  frame.utime = frame.left_utime = frame.right_utime = NowUs();
  bus.Publish(channels::kHazcamFrame, frame);
  // The right pair, and at once a step that would put the body's front onto the rock.
  frame.frame_id = 2;
  frame.left = bus::EncodeImage(pair.left, true);
  frame.right = bus::EncodeImage(pair.right, true);
  frame.utime = frame.left_utime = frame.right_utime = NowUs();
  bus.Publish(channels::kHazcamFrame, frame);
  rover_msgs::hazard_query_t q{};
  q.utime = NowUs();
  q.query_id = 7;
  for (double x = 0.0; x <= 0.41; x += 0.1) {
    q.x.push_back(x);
    q.y.push_back(0.0);
    q.yaw.push_back(0.0);
  }
  q.num_poses = static_cast<int>(q.x.size());
  bus.Publish(channels::kHazardQuery, q);
  spin([&] { return reply.has_value(); }, 30);
  ASSERT_TRUE(reply) << "no HAZARD_REPLY within 30 s";
  EXPECT_EQ(+reply->verdict, +rover_msgs::hazard_reply_t::VERDICT_UNSAFE) << reply->detail;
  EXPECT_NE(reply->detail.find("hazard_map"), std::string::npos) << reply->detail;

  // The published map: the rock unsafe, the frame id the NAVCAM pairs' alone.
  spin([&] { return map && map->num_cells > 0; }, 5);
  ASSERT_TRUE(map);
  EXPECT_EQ(map->last_frame_id, -1);
  int unsafe_at_rock = 0;
  for (int i = 0; i < map->rows; ++i)
    for (int j = 0; j < map->cols; ++j) {
      const double x = map->origin_x + (i + 0.5) * map->cell_m, y = map->origin_y + (j + 0.5) * map->cell_m;
      if (std::hypot(x - 1.0, y - 0.25) < 0.35 && map->state[i * map->cols + j] == rover_msgs::traversability_map_t::STATE_UNSAFE)
        ++unsafe_at_rock;
    }
  EXPECT_GE(unsafe_at_rock, 1);
  // It carries the map's caution level for the vote (executor.avoid_good_enough: 0), and
  // its cells agree with it: caution and unsafe at that goodness or less, safe above it.
  const double caution_fraction =
      traversability::LoadMapOptions(YAML::LoadFile(SourceDir() + "/configs/rover.yaml")["hazards"]["map"]["traversability"],
                                     "hazards.map.traversability")
          .caution_fraction;
  EXPECT_NEAR(map->caution_goodness, 1.0 - caution_fraction, 1e-9);
  int rated = 0;
  for (int k = 0; k < map->num_cells; ++k) {
    if (map->state[k] == rover_msgs::traversability_map_t::STATE_UNKNOWN) continue;
    ++rated;
    const bool safe = map->state[k] == rover_msgs::traversability_map_t::STATE_SAFE;
    if (safe) EXPECT_GT(map->goodness[k], map->caution_goodness - 1e-6) << "cell " << k;
    else EXPECT_LE(map->goodness[k], map->caution_goodness + 1e-6) << "cell " << k;
  }
  EXPECT_GT(rated, 20);
  EXPECT_TRUE(set.Running("hazard_monitor"));
  set.StopAll();
  std::ifstream log(dir + "/hazard_monitor.log");
  std::stringstream text;
  text << log.rdbuf();
  EXPECT_NE(text.str().find("hazard_monitor: HAZCAM_FRAME 1: "), std::string::npos) << text.str();
  EXPECT_NE(text.str().find("(not mapped)"), std::string::npos) << text.str();
  EXPECT_NE(text.str().find("hazard_monitor: mapped HAZCAM frame 2"), std::string::npos) << text.str();
}

}  // namespace
}  // namespace rover::test
