// ./rover bench capture: camera_capture over LCM with full-size stereo frames.
// Writes a KITTI-layout directory of textured 1024x1024 pairs, starts the real
// camera_capture on it (dataset source), requests N frames one at a time, and prints how
// many arrived, the latency from request to received frame, the message size, and the
// kernel's UDP receive-buffer drops (UdpRcvbufErrors, as `nstat` reports them).
// Exit 1 unless every frame arrived. Run it on a private bus (./rover bench capture).
#include "bus/bus.hpp"
#include "bus/channels.hpp"
#include "bus/process.hpp"
#include "launch/process_set.hpp"

#include <rover_msgs/capture_request_t.hpp>
#include <rover_msgs/heartbeat_t.hpp>
#include <rover_msgs/stereo_frame_t.hpp>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

long UdpRcvbufErrors() {
  std::ifstream in("/proc/net/snmp");
  std::string header, values;
  while (std::getline(in, header) && std::getline(in, values)) {
    if (header.rfind("Udp:", 0) != 0) continue;
    std::istringstream h(header), v(values);
    std::string name, value;
    while (h >> name && v >> value) {
      if (name == "RcvbufErrors") return std::stol(value);
    }
  }
  return -1;
}

// Smooth multi-scale texture, so PNG sizes are like real terrain rather than pure noise.
cv::Mat Texture(int size, int seed) {
  cv::RNG rng(seed);
  cv::Mat sum(size, size, CV_32F, cv::Scalar(0));
  for (int cell = 2; cell <= 64; cell *= 2) {
    cv::Mat coarse(size / cell + 1, size / cell + 1, CV_32F);
    rng.fill(coarse, cv::RNG::NORMAL, 0, 1);
    cv::Mat up;
    cv::resize(coarse, up, cv::Size(size, size), 0, 0, cv::INTER_CUBIC);
    sum += up;
  }
  cv::Mat out;
  sum.convertTo(out, CV_8U, 20, 128);
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  return rover::bus::RunMain("capture_benchmark", [&]() -> int {
    int frames = 100, size = 1024;
    std::string encoding = "png", dir = "out/capture_benchmark";
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      if (a == "--frames" && i + 1 < argc) frames = std::max(1, std::atoi(argv[++i]));
      else if (a == "--size" && i + 1 < argc) size = std::max(64, std::atoi(argv[++i]));
      else if (a == "--encoding" && i + 1 < argc) encoding = argv[++i];
      else if (a == "--out" && i + 1 < argc) dir = argv[++i];
      else {
        std::cout << "usage: capture_benchmark [--frames 100] [--size 1024] [--encoding png|raw] [--out DIR]\n";
        return a == "--help" ? 0 : 2;
      }
    }
    if (encoding != "png" && encoding != "raw") {
      throw rover::config::ConfigError("capture_benchmark: argument --encoding: expected png or raw");
    }
    // The dataset: two distinct pairs, linked under N names (the source reads each anew).
    fs::remove_all(dir);
    fs::create_directories(dir + "/image_0");
    fs::create_directories(dir + "/image_1");
    for (int k = 0; k < 2; ++k) {
      cv::imwrite(dir + "/image_0/pair" + std::to_string(k) + ".png", Texture(size, 2 * k + 1));
      cv::imwrite(dir + "/image_1/pair" + std::to_string(k) + ".png", Texture(size, 2 * k + 2));
    }
    for (int i = 0; i < frames; ++i) {
      char name[32];
      std::snprintf(name, sizeof(name), "%06d.png", i);
      for (const char* side : {"/image_0/", "/image_1/"}) {
        fs::create_hard_link(dir + side + "pair" + std::to_string(i % 2) + ".png", dir + side + name);
      }
    }
    const double f = size / 2.0 / std::tan(22.5 * M_PI / 180.0), c = (size - 1) / 2.0, b = 0.2;
    std::ofstream(dir + "/calib.txt") << "P0: " << f << " 0 " << c << " 0 0 " << f << " " << c
                                      << " 0 0 0 1 0\nP1: " << f << " 0 " << c << " " << -f * b
                                      << " 0 " << f << " " << c << " 0 0 0 1 0\n";
    std::ofstream(dir + "/capture.yaml") << "capture:\n  source: dataset\n  encoding: " << encoding << "\n";

    const char* env_url = std::getenv("ROVER_LCM_URL");
    const std::string url = env_url && *env_url ? env_url
        : "udpm://239.255.76.67:" + std::to_string(20000 + 2 * (getpid() % 6000)) + "?ttl=0&recv_buf_size=8388608";
    rover::bus::Bus bus(url);
    bool alive = false;
    std::int64_t got_id = -1;
    std::size_t bytes = 0;
    int wrong_size = 0;
    bus.Subscribe<rover_msgs::heartbeat_t>(rover::channels::kHeartbeat, [&](const rover_msgs::heartbeat_t& h) {
      alive = alive || h.process == "camera_capture";
    });
    bus.Subscribe<rover_msgs::stereo_frame_t>(rover::channels::kStereoFrame, [&](const rover_msgs::stereo_frame_t& m) {
      got_id = m.frame_id;
      bytes = m.left.data.size() + m.right.data.size();
      if (m.left.width != size || m.left.height != size || m.right.width != size) ++wrong_size;
    }, 4);
    rover::launch::ProcessSet set(rover::launch::BinDir(), dir, false);
    set.Start({"camera_capture", "camera_capture", {"--config", dir + "/capture.yaml", "--dataset", dir}},
              {"ROVER_LCM_URL=" + url});
    const auto start = Clock::now();
    while (!alive && Clock::now() - start < std::chrono::seconds(20)) bus.Handle(50);
    if (!alive) throw std::runtime_error("camera_capture sent no heartbeat within 20 s (see " + dir + "/camera_capture.log)");

    const long drops_before = UdpRcvbufErrors();
    std::vector<double> latency_ms;
    int delivered = 0;
    for (int i = 1; i <= frames; ++i) {
      rover_msgs::capture_request_t req{};
      req.frame_id = i;
      req.purpose = "science";  // one of the purposes receivers accept
      const auto t0 = Clock::now();
      bus.Publish(rover::channels::kCaptureRequest, req);
      while (got_id != i && Clock::now() - t0 < std::chrono::seconds(5)) bus.Handle(5);
      if (got_id == i) {
        ++delivered;
        latency_ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
      }
    }
    const long drops = UdpRcvbufErrors() - drops_before;
    set.StopAll();
    std::sort(latency_ms.begin(), latency_ms.end());
    auto pct = [&](double p) { return latency_ms.empty() ? 0.0 : latency_ms[std::min(latency_ms.size() - 1, static_cast<std::size_t>(p * latency_ms.size()))]; };
    std::printf("camera_capture, dataset source, %dx%d stereo frames, %s\n", size, size, encoding.c_str());
    std::printf("  delivered %d/%d frames (%d of the wrong size)\n", delivered, frames, wrong_size);
    std::printf("  message images %.0f kB\n", bytes / 1024.0);
    std::printf("  latency request -> frame received: median %.1f ms, p95 %.1f ms (includes reading the dataset's PNGs)\n",
                pct(0.5), pct(0.95));
    std::printf("  UdpRcvbufErrors during the run: %ld\n", drops);
    return delivered == frames && wrong_size == 0 ? 0 : 1;
  });
}
