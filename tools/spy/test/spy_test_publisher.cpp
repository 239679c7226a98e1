// spy_test_publisher --lcm-url URL [--seconds S] [--period-ms MS]
// For tools/spy/test/spy_test.sh: publishes a few of the project's messages, with known
// field values, on their real channels (HEARTBEAT, POSE, IMU, WHEEL_ODOMETRY), plus one
// packet on SPY_TEST_UNKNOWN whose fingerprint no project type has, until S seconds pass.
// lcm-spy must name and decode the first four and show the last as unknown.
#include "rover_msgs/heartbeat_t.hpp"
#include "rover_msgs/imu_t.hpp"
#include "rover_msgs/pose_t.hpp"
#include "rover_msgs/wheel_odometry_t.hpp"

#include <lcm/lcm-cpp.hpp>

#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <iostream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace {

struct Args {
  std::string url;
  double seconds = 90.0;
  int period_ms = 50;
};

double ParseNumber(const std::string& flag, const std::string& text, double lo, double hi) {
  std::size_t used = 0;
  double v = 0.0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || !(v >= lo && v <= hi)) {
    throw std::invalid_argument("argument " + flag + " '" + text + "': expected a number in [" +
                                std::to_string(lo) + ", " + std::to_string(hi) + "]");
  }
  return v;
}

Args Parse(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw std::invalid_argument("argument " + arg + ": missing value");
      return argv[++i];
    };
    if (arg == "--help" || arg == "-h") {
      std::cout << "usage: spy_test_publisher --lcm-url URL [--seconds S] [--period-ms MS]\n"
                   "  publishes HEARTBEAT, POSE, IMU and WHEEL_ODOMETRY with known values, and one\n"
                   "  packet of an unknown type, for the lcm-spy test (tools/spy/test)\n";
      std::exit(0);
    } else if (arg == "--lcm-url") {
      a.url = value();
    } else if (arg == "--seconds") {
      a.seconds = ParseNumber(arg, value(), 0.1, 3600.0);
    } else if (arg == "--period-ms") {
      a.period_ms = static_cast<int>(ParseNumber(arg, value(), 1.0, 10000.0));
    } else {
      throw std::invalid_argument("argument " + arg +
                                  ": unexpected (expected --lcm-url URL [--seconds S] [--period-ms MS])");
    }
  }
  if (a.url.empty()) throw std::invalid_argument("missing --lcm-url URL (the test's private bus)");
  return a;
}

}  // namespace

int main(int argc, char** argv) {
  Args args;
  try {
    args = Parse(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "spy_test_publisher: " << e.what() << "\n";
    return 2;
  }
  lcm::LCM lcm(args.url);
  if (!lcm.good()) {
    std::cerr << "spy_test_publisher: cannot open the LCM bus " << args.url
              << " (expected a working udpm:// URL with a multicast route)\n";
    return 1;
  }

  rover_msgs::heartbeat_t hb{};
  hb.process = "spy_test_publisher";
  hb.state = rover_msgs::heartbeat_t::STATE_DEGRADED;
  hb.detail = "lcm-spy test";

  rover_msgs::pose_t pose{};
  pose.position[0] = 1.5;
  pose.position[1] = -2.25;
  pose.position[2] = 0.125;
  pose.orientation[0] = 1.0;
  for (int i = 0; i < 6; ++i) pose.covariance[i][i] = 0.01;
  pose.source = rover_msgs::pose_t::SOURCE_VO;
  pose.site_index = 7;
  pose.last_vo_to_frame = -1;

  rover_msgs::imu_t imu{};
  imu.orientation[0] = 1.0;
  imu.accel[2] = -3.71;

  rover_msgs::wheel_odometry_t odo{};
  odo.num_wheels = 6;
  odo.wheel_distance_m.assign(6, 0.0);
  odo.curvature_per_m = 0.25;

  // A fingerprint no project type has, then a few bytes: lcm-spy lists it as "?? ...".
  const std::vector<std::uint8_t> unknown = {0x01, 0x23, 0x45, 0x67, 0x89, 0xab, 0xcd, 0xef, 0, 0, 0, 42};

  const auto start = std::chrono::steady_clock::now();
  const auto period = std::chrono::milliseconds(args.period_ms);
  auto next = start;
  for (std::int64_t k = 0;; ++k) {
    const auto now = std::chrono::steady_clock::now();
    if (std::chrono::duration<double>(now - start).count() >= args.seconds) break;
    const std::int64_t utime = 1'000'000 + k * args.period_ms * 1000;
    hb.utime = pose.utime = imu.utime = odo.utime = utime;
    hb.seq = k;
    pose.pub_seq = imu.pub_seq = odo.pub_seq = k;
    pose.odometer_m = 0.01 * static_cast<double>(k);
    for (double& d : odo.wheel_distance_m) d = 0.01 * static_cast<double>(k);
    odo.distance_m = 0.01 * static_cast<double>(k);
    if (lcm.publish("HEARTBEAT", &hb) != 0 || lcm.publish("POSE", &pose) != 0 ||
        lcm.publish("IMU", &imu) != 0 || lcm.publish("WHEEL_ODOMETRY", &odo) != 0 ||
        lcm.publish("SPY_TEST_UNKNOWN", unknown.data(), static_cast<unsigned int>(unknown.size())) != 0) {
      std::cerr << "spy_test_publisher: publish failed on " << args.url << "\n";
      return 1;
    }
    next += period;
    std::this_thread::sleep_until(next);
  }
  return 0;
}
