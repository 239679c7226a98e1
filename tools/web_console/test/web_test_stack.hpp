// What the web console's process tests share: the signed simulated stack
// (configs/deploy/sim_vo_auth.yaml with a key made for the test) and rover_web on a
// private bus, and a listener that records what the bus carries, to compare the
// console's picture with.
#pragma once

#include "bus/bus.hpp"
#include "bus/channels.hpp"
#include "integration/run_support.hpp"
#include "launch/process_set.hpp"

#include <rover_msgs/heartbeat_t.hpp>
#include <rover_msgs/keepout_zones_t.hpp>
#include <rover_msgs/pose_t.hpp>
#include <rover_msgs/rover_clock_t.hpp>
#include <rover_msgs/sequence_status_t.hpp>
#include <rover_msgs/step_report_t.hpp>

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <sys/stat.h>
#include <unistd.h>

namespace rover::test {

using WebClock = std::chrono::steady_clock;

inline double SecondsSince(WebClock::time_point since) {
  return std::chrono::duration<double>(WebClock::now() - since).count();
}

inline std::string ReadText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// What the test itself hears on the bus, on its own thread (HTTP calls and the browser
// block the test's).
struct Listener {
  explicit Listener(const std::string& url) : bus(url) {
    using rover_msgs::sequence_status_t;
    bus.Subscribe<rover_msgs::heartbeat_t>(channels::kHeartbeat, [this](const rover_msgs::heartbeat_t& hb) {
      std::lock_guard<std::mutex> lock(mutex);
      alive.insert(hb.process);
    }, 100);
    bus.Subscribe<rover_msgs::pose_t>(channels::kPose, [this](const rover_msgs::pose_t& p) {
      std::lock_guard<std::mutex> lock(mutex);
      pose = p;
      ++poses;
      pose_at[p.utime] = p;
    }, 100);
    bus.Subscribe<sequence_status_t>(channels::kSequenceStatus, [this](const sequence_status_t& s) {
      std::lock_guard<std::mutex> lock(mutex);
      statuses[s.submission_id].push_back(s);
    }, 100);
    bus.Subscribe<rover_msgs::step_report_t>(channels::kStepReport, [this](const rover_msgs::step_report_t& s) {
      std::lock_guard<std::mutex> lock(mutex);
      ++steps;
      ++steps_of[s.submission_id];
    }, 100);
    bus.Subscribe<rover_msgs::keepout_zones_t>(channels::kKeepOutZones, [this](const rover_msgs::keepout_zones_t& z) {
      std::lock_guard<std::mutex> lock(mutex);
      zones = z;
    }, 10);
    bus.Subscribe<rover_msgs::rover_clock_t>(channels::kClock, [this](const rover_msgs::rover_clock_t& c) {
      std::lock_guard<std::mutex> lock(mutex);
      rover_utime = std::max(rover_utime, c.utime);
    }, 100);
    thread = std::thread([this] {
      while (!stop) bus.Handle(20);
    });
  }
  ~Listener() {
    stop = true;
    thread.join();
  }
  bool HasState(std::int64_t id, std::int8_t state) {
    std::lock_guard<std::mutex> lock(mutex);
    for (const auto& s : statuses[id])
      if (s.state == state) return true;
    return false;
  }
  std::int8_t LastState(std::int64_t id) {
    std::lock_guard<std::mutex> lock(mutex);
    return statuses[id].empty() ? -1 : statuses[id].back().state;
  }
  std::optional<rover_msgs::sequence_status_t> LastStatus(std::int64_t id) {
    std::lock_guard<std::mutex> lock(mutex);
    if (statuses[id].empty()) return std::nullopt;
    return statuses[id].back();
  }
  int StepsOf(std::int64_t id) {
    std::lock_guard<std::mutex> lock(mutex);
    return steps_of[id];
  }
  rover_msgs::pose_t LastPose() {
    std::lock_guard<std::mutex> lock(mutex);
    return pose;
  }
  std::optional<rover_msgs::pose_t> PoseAt(std::int64_t utime) {
    std::lock_guard<std::mutex> lock(mutex);
    const auto it = pose_at.find(utime);
    if (it == pose_at.end()) return std::nullopt;
    return it->second;
  }
  std::int64_t RoverUtime() {
    std::lock_guard<std::mutex> lock(mutex);
    return rover_utime;
  }
  std::size_t Alive() {
    std::lock_guard<std::mutex> lock(mutex);
    return alive.size();
  }

  bus::Bus bus;
  std::mutex mutex;
  std::set<std::string> alive;
  rover_msgs::pose_t pose{};
  std::map<std::int64_t, rover_msgs::pose_t> pose_at;  // every POSE heard, by its utime
  int poses = 0, steps = 0;
  std::map<std::int64_t, int> steps_of;  // STEP_REPORTs per submission
  std::map<std::int64_t, std::vector<rover_msgs::sequence_status_t>> statuses;
  rover_msgs::keepout_zones_t zones{};
  std::int64_t rover_utime = 0;
  std::atomic<bool> stop{false};
  std::thread thread;
};

// The committed signed deployment with its key path pointed at `key`.
inline std::string DeploymentWithKey(const std::string& dir, const std::string& key) {
  std::string text = ReadText(SourceDir() + "/configs/deploy/sim_vo_auth.yaml");
  const std::string placeholder = "build/keys/rover.key";
  for (auto at = text.find(placeholder); at != std::string::npos; at = text.find(placeholder, at + key.size()))
    text.replace(at, placeholder.size(), key);
  const std::string path = dir + "/sim_vo_auth.yaml";
  std::ofstream(path) << text;
  return path;
}

// The signed simulated stack and rover_web (an operator secret and the key, any free port)
// on a private bus, in virtual time. `sim_args`: more arguments for rover_sim (--rate).
// Fatal failures leave port 0.
struct WebStack {
  WebStack(const std::string& out_name, int url_offset, std::vector<std::string> sim_args = {})
      : dir(OutDir(out_name)),
        key(dir + "/rover.key"),
        secret("s3cret-operator-token-" + std::to_string(getpid())),
        url(PrivateUrl(url_offset)),
        heard(url),
        set(std::string(ROVER_BINARY_DIR) + "/bin", dir, false) {
    Start(sim_args);
  }


  void Start(const std::vector<std::string>& sim_args) {
    const auto r = RunCommand(Bin("rover_seq") + " keygen " + key);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const std::string secret_file = dir + "/secret";
    std::ofstream(secret_file) << secret << "\n";
    ASSERT_EQ(chmod(secret_file.c_str(), 0600), 0);
    deployment = launch::LoadDeployment(DeploymentWithKey(dir, key));
    std::filesystem::current_path(SourceDir());

    std::string others = "rover_web";
    for (const auto& p : deployment.processes)
      if (p.name != "rover_sim") others += "," + p.name;
    const std::vector<std::string> env = {"ROVER_LCM_URL=" + url, "ROVER_TIME=" + deployment.time};
    for (auto p : deployment.processes) {
      if (p.name == "rover_sim") {
        p.args.push_back("--hold-for");
        p.args.push_back(others);
        p.args.insert(p.args.end(), sim_args.begin(), sim_args.end());
      }
      set.Start(p, env);  // virtual time: load cannot change what the rover does
    }
    launch::ProcessSpec web;
    web.name = "rover_web";
    web.program = "rover_web";
    web.args = {"--port", "0", "--secret-file", secret_file, "--key", key};
    set.Start(web, env);

    const auto start = WebClock::now();
    while (heard.Alive() < deployment.processes.size() + 1 && SecondsSince(start) < 90) set.Poll(100);
    ASSERT_EQ(heard.Alive(), deployment.processes.size() + 1) << "not every process sent a heartbeat";

    // The port rover_web chose, from its first line.
    const std::string listening = "listening on http://127.0.0.1:";
    const auto t_listen = WebClock::now();
    int found = 0;
    while (found == 0 && SecondsSince(t_listen) < 30) {
      set.Poll(100);
      const std::string log = ReadText(dir + "/rover_web.log");
      if (const auto at = log.find(listening); at != std::string::npos) found = std::atoi(log.c_str() + at + listening.size());
    }
    ASSERT_GT(found, 0) << "rover_web did not say where it listens:\n" << ReadText(dir + "/rover_web.log");
    port = found;
  }

  // Polls the processes (their output goes to their logs) until `done` or `timeout_s`.
  template <typename Done>
  bool WaitFor(Done done, double timeout_s, int poll_ms = 100) {
    const auto start = WebClock::now();
    while (!done()) {
      if (SecondsSince(start) > timeout_s) return false;
      set.Poll(poll_ms);
    }
    return true;
  }

  std::string dir, key, secret, url;
  Listener heard;
  launch::ProcessSet set;
  launch::Deployment deployment;
  int port = 0;
};

}  // namespace rover::test
