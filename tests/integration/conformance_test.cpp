// The conformance kit (tools/conformance) against real processes on a real bus: it passes
// rover_sim (mobility, imu, wheel_odometry), the sample mobility driver, and camera_capture
// on the simulator source; it fails, naming the broken rule, against drivers made here
// with one fault each: a wheel distance in millimetres, no dead-man, no answer to STOP, an
// IMU with Z up, a driver that obeys commands not signed with the key, a camera that fails
// in silence, a camera whose two images are taken too far apart.
#include "bus/bus.hpp"
#include "bus/convert.hpp"
#include "bus/image_encode.hpp"
#include "bus/channels.hpp"
#include "bus/signing.hpp"
#include "config/yaml_config.hpp"
#include "geometry/camera_io.hpp"
#include "integration/run_support.hpp"
#include "launch/process_set.hpp"
#include "mobility/deadman.hpp"
#include "sample_driver/sample_mobility.hpp"

#include <rover_msgs/capture_request_t.hpp>
#include <rover_msgs/heartbeat_t.hpp>
#include <rover_msgs/imu_t.hpp>
#include <rover_msgs/mobility_command_t.hpp>
#include <rover_msgs/mobility_status_t.hpp>
#include <rover_msgs/stereo_frame_t.hpp>
#include <rover_msgs/wheel_odometry_t.hpp>

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <thread>

namespace rover::test {
namespace {

CommandResult Kit(const std::string& url, const std::string& args) {
  const auto r = RunCommand("ROVER_LCM_URL='" + url + "' ROVER_TIME=real " + Bin("rover_conformance") + " " + args);
  std::cout << r.output;
  return r;
}

bool Has(const CommandResult& r, const std::string& text) { return r.output.find(text) != std::string::npos; }

// Wall-clock microseconds: the hand-made drivers below run on a real clock.
std::int64_t Now() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// rover_sim on a real clock at rate 1, as a rover's mobility runs.
class SimRig {
 public:
  // `key`: the deployment's key file (keys on), or "" (keys off).
  explicit SimRig(const std::string& name, int offset, bool cameras = false, const std::string& key = "")
      : url_(PrivateUrl(offset)), set_(std::string(ROVER_BINARY_DIR) + "/bin", OutDir(name), false) {
    const std::string world = SourceDir() + "/configs/worlds/featureless_sand.yaml";
    const std::vector<std::string> env = {"ROVER_LCM_URL=" + url_, "ROVER_TIME=real"};
    std::vector<std::string> args = {"--config", SourceDir() + "/configs/rover.yaml", "--world", world,
                                     "--start", "0,0,0", "--rate", "1"};
    if (!key.empty()) args.insert(args.end(), {"--key", key});
    set_.Start({"rover_sim", "rover_sim", args}, env);
    if (cameras) {
      set_.Start({"camera_capture", "camera_capture", {"--config", SourceDir() + "/configs/rover.yaml", "--world", world}},
                 env);
    }
  }
  ~SimRig() { set_.StopAll(); }
  const std::string& url() const { return url_; }
  bool Running(const std::string& name) const { return set_.Running(name); }

 private:
  std::string url_;
  launch::ProcessSet set_;
};

TEST(ConformanceKit, RoverSimPassesMobilityImuAndWheelOdometry) {
  SimRig rig("conformance_sim", 41);
  const auto mobility = Kit(rig.url(), "mobility --config configs/rover.yaml");
  EXPECT_EQ(mobility.exit_code, 0);
  EXPECT_TRUE(Has(mobility, "ok   mobility.deadman.stop"));
  EXPECT_TRUE(Has(mobility, "conformance mobility: PASS (25 held, 0 failed, 2 not checked)"));
  EXPECT_TRUE(Has(mobility, "--   mobility.auth.unsigned (not checked: needs --key)"));
  const auto imu = Kit(rig.url(), "imu --config configs/rover.yaml --listen-s 3 --drive");
  EXPECT_EQ(imu.exit_code, 0);
  EXPECT_TRUE(Has(imu, "ok   imu.frame.gravity"));
  EXPECT_TRUE(Has(imu, "conformance imu: PASS (11 held, 0 failed, 0 not checked)"));
  const auto odometry = Kit(rig.url(), "wheel_odometry --listen-s 3 --drive");
  EXPECT_EQ(odometry.exit_code, 0);
  EXPECT_TRUE(Has(odometry, "ok   wheel_odometry.frame.turn"));
  EXPECT_TRUE(Has(odometry, "conformance wheel_odometry: PASS (9 held, 0 failed, 0 not checked)"));
  // With Earth's gravity the IMU is wrong by a factor of 2.6: the kit says so.
  const auto earth = Kit(rig.url(), "imu --gravity 9.81 --listen-s 2");
  EXPECT_EQ(earth.exit_code, 1);
  EXPECT_TRUE(Has(earth, "FAIL imu.units.accel: expected |accel| 9.81 m/s^2 at rest (10 %); seen |accel| 3.7"));
  EXPECT_TRUE(rig.Running("rover_sim"));
}

TEST(ConformanceKit, WithKeysOnRoverSimPassesAKitThatSignsAndRefusesOneThatDoesNot) {
  // The deployment's key, made as docs/HARDWARE.md says (./rover seq keygen).
  const std::string key = OutDir("conformance_keys") + "/rover.key";
  std::filesystem::remove(key);
  ASSERT_EQ(RunCommand(Bin("rover_seq") + " keygen " + key).exit_code, 0);
  SimRig rig("conformance_sim_keys", 49, false, key);
  const auto signed_kit = Kit(rig.url(), "mobility --config configs/rover.yaml --key " + key);
  EXPECT_EQ(signed_kit.exit_code, 0);
  EXPECT_TRUE(Has(signed_kit, "conformance mobility: PASS (27 held, 0 failed, 0 not checked)"));
  EXPECT_TRUE(Has(signed_kit, "ok   mobility.auth.unsigned"));
  EXPECT_TRUE(Has(signed_kit, "ok   mobility.auth.wrong_key"));
  // Without the key its commands are refused, and the kit sees a driver that does not
  // answer: it fails, naming the rules.
  const auto unsigned_kit = Kit(rig.url(), "mobility --config configs/rover.yaml");
  EXPECT_EQ(unsigned_kit.exit_code, 1);
  EXPECT_TRUE(Has(unsigned_kit, "FAIL mobility.arc.moving: expected MOVING"));
  EXPECT_TRUE(Has(unsigned_kit, "FAIL mobility.stop.answer"));
  EXPECT_TRUE(rig.Running("rover_sim"));
}

TEST(ConformanceKit, SampleDriverPasses) {
  const std::string url = PrivateUrl(42);
  launch::ProcessSet set(std::string(ROVER_BINARY_DIR) + "/bin", OutDir("conformance_sample"), false);
  set.Start({"mobility_driver", "sample_mobility_driver", {}}, {"ROVER_LCM_URL=" + url, "ROVER_TIME=real"});
  const auto mobility = Kit(url, "mobility");
  EXPECT_EQ(mobility.exit_code, 0);
  EXPECT_TRUE(Has(mobility, "conformance mobility: PASS (25 held, 0 failed, 2 not checked)"));
  EXPECT_EQ(Kit(url, "imu --listen-s 2 --drive").exit_code, 0);
  EXPECT_EQ(Kit(url, "wheel_odometry --listen-s 2 --drive").exit_code, 0);
  set.StopAll();
}

// A mobility driver on this test's thread: the sample driver's logic, wired to the bus
// with one fault.
// kIgnoresKey: no key at all, so it obeys anyone; kObeysUnsigned: it holds the key and
// checks the tags it is given, but obeys a command with none (bus::MakeBusAuth's
// reject_unsigned false).
enum class Fault { kMillimetres, kNoDeadman, kIgnoresStop, kImuZUp, kIgnoresKey, kObeysUnsigned };

class BrokenDriver {
 public:
  BrokenDriver(const std::string& url, Fault fault, const std::string& key = "")
      : url_(url), fault_(fault), key_(key), thread_([this] { Loop(); }) {}
  ~BrokenDriver() {
    stop_ = true;
    thread_.join();
  }

 private:
  static double Wall() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
  }
  void Publish(bus::Bus& bus, const sample_driver::Status& s) {
    rover_msgs::mobility_status_t m{};
    m.utime = Now();
    m.command_id = s.command_id;
    m.state = static_cast<std::int8_t>(s.state);
    m.wheel_distance_m = s.wheel_distance_m * (fault_ == Fault::kMillimetres ? 1000.0 : 1.0);
    m.wheel_turn_rad = s.wheel_turn_rad;
    m.detail = s.detail;
    bus.Publish(channels::kMobilityStatus, m);
  }
  void Loop() {
    bus::Bus bus(url_);
    bus.set_publisher("mobility_driver");
    if (fault_ == Fault::kObeysUnsigned) {
      bus.set_auth(bus::MakeBusAuth(auth::Key::LoadFile(key_), "mobility_driver", /*reject_unsigned=*/false));
    }
    sample_driver::SampleMobility drive;
    mobility::Deadman deadman;
    bus.Subscribe<rover_msgs::mobility_command_t>(channels::kMobilityCommand, [&](const rover_msgs::mobility_command_t& m) {
      deadman.OnCommanderMessage(Wall());
      if (fault_ == Fault::kIgnoresStop && m.type == rover_msgs::mobility_command_t::TYPE_STOP) return;
      sample_driver::Command c;
      c.id = m.command_id;
      c.type = m.type;
      c.distance_m = m.distance_m;
      c.curvature_per_m = m.curvature_per_m;
      c.turn_rad = m.turn_rad;
      c.speed_mps = m.speed_mps;
      c.turn_rate_rps = m.turn_rate_rps;
      for (const auto& s : drive.Execute(c)) Publish(bus, s);
    });
    bus.Subscribe<rover_msgs::heartbeat_t>(channels::kHeartbeat, [&](const rover_msgs::heartbeat_t& hb) {
      deadman.OnHeartbeat(hb.process, Wall());
    }, 1000);
    double last = Wall(), next_status = 0, next_heartbeat = 0, next_imu = 0;
    std::int64_t seq = 0;
    while (!stop_) {
      bus.Handle(10);
      const double now = Wall();
      if (fault_ != Fault::kNoDeadman) {
        if (const auto why = deadman.Check(drive.moving(), now)) {
          if (const auto s = drive.Halt(*why)) Publish(bus, *s);
        }
      }
      if (const auto s = drive.Advance(now - last)) Publish(bus, *s);
      last = now;
      if (now >= next_status) {
        Publish(bus, drive.status());
        next_status = now + 0.25;
      }
      if (now >= next_imu) {
        rover_msgs::imu_t m{};
        m.utime = Now();
        m.orientation[0] = 1;
        m.accel[2] = fault_ == Fault::kImuZUp ? 9.80665 : -9.80665;
        bus.Publish(channels::kImu, m);
        next_imu = now + 0.05;
      }
      if (now >= next_heartbeat) {
        rover_msgs::heartbeat_t hb{};
        hb.utime = Now();
        hb.process = "mobility_driver";
        hb.seq = seq++;
        hb.dropped = bus.dropped();
        bus.Publish(channels::kHeartbeat, hb);
        next_heartbeat = now + 0.25;
      }
    }
  }

  std::string url_;
  Fault fault_;
  std::string key_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

std::string FreshKey(const std::string& name) {
  const std::string key = OutDir(name) + "/rover.key";
  std::filesystem::remove(key);
  EXPECT_EQ(RunCommand(Bin("rover_seq") + " keygen " + key).exit_code, 0);
  return key;
}

TEST(ConformanceKit, WithKeysOnADriverThatObeysUnsignedOrForeignCommandsFailsTheAuthRules) {
  const std::string key = FreshKey("conformance_ignores_key");
  {
    // No key at all: it obeys the kit's signed commands (every other rule holds), and the
    // unsigned and the foreign ones too.
    const std::string url = PrivateUrl(51);
    BrokenDriver driver(url, Fault::kIgnoresKey);
    const auto r = Kit(url, "mobility --key " + key);
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_TRUE(Has(r, "FAIL mobility.auth.unsigned: expected command "));
    EXPECT_TRUE(Has(r, " (an ARC unsigned) not obeyed: no MOVING or DONE, wheels still; seen MOVING for command "));
    EXPECT_TRUE(Has(r, "FAIL mobility.auth.wrong_key: expected command "));
    // The signed ones it obeys as it should (the dead-man's timing, on a loaded machine, is
    // not this test's business).
    EXPECT_TRUE(Has(r, "ok   mobility.arc.done"));
    EXPECT_TRUE(Has(r, "ok   mobility.stop.answer"));
  }
  {
    // The key, checked when a tag comes, but an untagged command obeyed.
    const std::string url = PrivateUrl(52);
    BrokenDriver driver(url, Fault::kObeysUnsigned, key);
    const auto r = Kit(url, "mobility --key " + key);
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_TRUE(Has(r, "FAIL mobility.auth.unsigned: expected command "));
    EXPECT_TRUE(Has(r, "ok   mobility.auth.wrong_key"));
    EXPECT_TRUE(Has(r, "ok   mobility.arc.done"));
  }
}

TEST(ConformanceKit, WheelDistanceInMillimetresFailsTheDistanceUnit) {
  const std::string url = PrivateUrl(43);
  BrokenDriver driver(url, Fault::kMillimetres);
  const auto r = Kit(url, "mobility");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(Has(r, "FAIL mobility.units.distance: expected wheel_distance_m 0.100 (10 %) at DONE; seen 100."));
  EXPECT_TRUE(Has(r, "ok   mobility.deadman.stop"));
  EXPECT_TRUE(Has(r, "ok   mobility.units.turn"));
}

TEST(ConformanceKit, NoDeadmanFailsTheDeadmanStop) {
  const std::string url = PrivateUrl(44);
  BrokenDriver driver(url, Fault::kNoDeadman);
  const auto r = Kit(url, "mobility");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(Has(r, "FAIL mobility.deadman.stop: expected STOPPED for command "));
  EXPECT_TRUE(Has(r, "s after the commander fell silent; seen MOVING for command "));
  EXPECT_TRUE(Has(r, "ok   mobility.units.distance"));
  EXPECT_TRUE(Has(r, "ok   mobility.stop.answer"));
}

TEST(ConformanceKit, NoAnswerToStopFailsTheStopRules) {
  const std::string url = PrivateUrl(45);
  BrokenDriver driver(url, Fault::kIgnoresStop);
  const auto r = Kit(url, "mobility");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(Has(r, "FAIL mobility.stop.answer: expected STOPPED for command "));
  EXPECT_TRUE(Has(r, "FAIL mobility.stop.idle_answer: expected STOPPED for command "));
  EXPECT_TRUE(Has(r, "ok   mobility.deadman.stop"));
}

TEST(ConformanceKit, ImuWithZUpFailsTheGravityFrame) {
  const std::string url = PrivateUrl(46);
  BrokenDriver driver(url, Fault::kImuZUp);
  const auto r = Kit(url, "imu --listen-s 2");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(Has(r, "FAIL imu.frame.gravity: expected accel along R^T (0, 0, -1) of the orientation within 5.0 deg; "
                     "seen 180.0 deg apart"));
  EXPECT_TRUE(Has(r, "ok   imu.units.accel"));
}

TEST(ConformanceKit, CameraCapturePassesAndASilentFailureDoesNot) {
  {
    SimRig rig("conformance_camera", 47, true);
    const auto r = Kit(rig.url(), "camera --requests 2 --timeout-s 60");
    EXPECT_EQ(r.exit_code, 0);
    EXPECT_TRUE(Has(r, "ok   camera.pairing"));
    EXPECT_TRUE(Has(r, "ok   camera.time.capture"));
    EXPECT_TRUE(Has(r, "ok   camera.time.pair"));
    EXPECT_TRUE(rig.Running("camera_capture"));
  }
  // A capture process that heartbeats OK and never answers.
  const std::string url = PrivateUrl(48);
  bus::Bus bus(url);
  bus.set_publisher("camera_capture");
  std::atomic<bool> stop{false};
  std::thread silent([&] {
    std::int64_t seq = 0;
    while (!stop) {
      rover_msgs::heartbeat_t hb{};
      hb.utime = std::chrono::duration_cast<std::chrono::microseconds>(
                     std::chrono::system_clock::now().time_since_epoch()).count();
      hb.process = "camera_capture";
      hb.seq = seq++;
      bus.Publish(channels::kHeartbeat, hb);
      std::this_thread::sleep_for(std::chrono::milliseconds(250));
    }
  });
  const auto r = Kit(url, "camera --requests 1 --timeout-s 2");
  stop = true;
  silent.join();
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(Has(r, "FAIL camera.answer: expected STEREO_FRAME "));
  EXPECT_TRUE(Has(r, "FAIL camera.frames: expected at least one STEREO_FRAME; seen none for 1 requests"));
}

// A capture process on this test's thread that answers every request with a well-formed
// frame whose right image was exposed `skew_us` after its left one.
class SkewedCamera {
 public:
  SkewedCamera(const std::string& url, std::int64_t skew_us)
      : url_(url), skew_us_(skew_us), thread_([this] { Loop(); }) {}
  ~SkewedCamera() {
    stop_ = true;
    thread_.join();
  }

 private:
  void Loop() {
    const auto rig = geometry::LoadStereoRig(config::ConfigNode::FromString(
        "left: {type: pinhole, width: 64, height: 48, fx: 60, fy: 60, cx: 31.5, cy: 23.5, position: [0, -0.1, -1], rpy_deg: [0, 0, 0]}\n"
        "right: {type: pinhole, width: 64, height: 48, fx: 60, fy: 60, cx: 31.5, cy: 23.5, position: [0, 0.1, -1], rpy_deg: [0, 0, 0]}\n",
        "rig"));
    bus::Bus bus(url_);
    bus.set_publisher("camera_capture");
    bus.Subscribe<rover_msgs::capture_request_t>(channels::kCaptureRequest, [&](const rover_msgs::capture_request_t& r) {
      rover_msgs::stereo_frame_t f{};
      f.utime = Now();
      f.frame_id = r.frame_id;
      f.purpose = r.purpose;
      f.left = bus::EncodeImage(cv::Mat(48, 64, CV_8UC1, cv::Scalar(128)), false);
      f.right = bus::EncodeImage(cv::Mat(48, 64, CV_8UC1, cv::Scalar(128)), false);
      f.left_model = bus::CameraModelToMsg(*rig.left);
      f.right_model = bus::CameraModelToMsg(*rig.right);
      f.pose_at_capture.orientation[0] = 1;
      f.left_utime = f.utime - skew_us_ / 2;
      f.right_utime = f.left_utime + skew_us_;
      bus.Publish(channels::kStereoFrame, f);
    });
    std::int64_t seq = 0;
    double next_heartbeat = 0;
    while (!stop_) {
      bus.Handle(10);
      const double now = std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
      if (now >= next_heartbeat) {
        rover_msgs::heartbeat_t hb{};
        hb.utime = Now();
        hb.process = "camera_capture";
        hb.seq = seq++;
        bus.Publish(channels::kHeartbeat, hb);
        next_heartbeat = now + 0.25;
      }
    }
  }

  std::string url_;
  std::int64_t skew_us_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

TEST(ConformanceKit, APairTakenFurtherApartThanTheToleranceFailsThePairTime) {
  const std::string url = PrivateUrl(50);
  SkewedCamera camera(url, 7500);  // the right image 7.5 ms after the left
  // Within a tolerance of 10 ms it passes (so the frames are otherwise good) ...
  const auto loose = Kit(url, "camera --requests 2 --timeout-s 5 --pair-tolerance-ms 10");
  EXPECT_EQ(loose.exit_code, 0);
  EXPECT_TRUE(Has(loose, "ok   camera.time.pair"));
  // ... and against genicam's 2 ms, from the config the capture process runs with.
  const auto r = Kit(url, "camera --requests 2 --timeout-s 5 --config configs/cameras/capture_genicam.yaml");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(Has(r, "FAIL camera.time.pair: expected left_utime and right_utime within 2.000 ms of each other, "
                     "both within 0.50 s of utime; seen frame "));
  EXPECT_TRUE(Has(r, ": right exposed 7.500 ms after left"));
  EXPECT_TRUE(Has(r, "ok   camera.pairing"));
  EXPECT_TRUE(Has(r, "ok   camera.time.capture"));
  EXPECT_TRUE(Has(r, "conformance camera: FAIL (9 held, 1 failed, 0 not checked)"));
}

}  // namespace
}  // namespace rover::test
