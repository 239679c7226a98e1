// fault_inject: sends hostile packets on the bus (tools/fault_inject/packets.hpp) to prove
// that no packet can stop a process. Raw bytes go out through lcm::LCM::publish, so the
// packets are exactly as crafted. Run it on a private bus only (./rover private).
#include "bus/guard.hpp"
#include "bus/process.hpp"
#include "config/yaml_config.hpp"
#include "fault_inject/packets.hpp"

#include <lcm/lcm-cpp.hpp>
#include <rover_msgs/rover_clock_t.hpp>

#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <iostream>
#include <memory>
#include <optional>
#include <set>
#include <sstream>
#include <thread>

using rover::config::ConfigError;
namespace fault = rover::fault;

namespace {

const char* kUsage =
    "usage: fault_inject [--lcm-url URL] [--group G,...|all] [--channel C,...|all]\n"
    "                    [--interval-ms N] [--now-utime U] [--seed N] [--bomb-side N]\n"
    "                    [--list] [--quiet]\n\n"
    "Sends hostile packets on every channel: malformed (bad length fields, truncated,\n"
    "oversized, wrong fingerprint, random bytes), values (NaN, inf, unknown enums), times\n"
    "(utime at now +/- 1e12 us and the int64 extremes) and images (STEREO_FRAME and\n"
    "HAZCAM_FRAME: negative sides, a PNG claiming 65535x65535, a PNG bomb, sizes against\n"
    "the camera model).\n"
    "Groups: malformed, values, times, images, spoofed (default all; spoofed sends valid\n"
    "commands, unsigned or with a made-up tag, which a deployment without keys obeys).\n"
    "Channels: default all.\n"
    "`now` is the latest ROVER_CLOCK (waited for up to 2 s) unless --now-utime is given.\n"
    "--list prints the packets without sending. Use a private bus (./rover private).\n";

std::vector<std::string> SplitList(const std::string& text, const std::vector<std::string>& all,
                                   const std::string& what) {
  if (text == "all") return all;
  std::vector<std::string> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    bool known = false;
    for (const auto& a : all) known = known || a == item;
    if (!known) {
      std::string expected;
      for (const auto& a : all) expected += (expected.empty() ? "" : ", ") + a;
      throw ConfigError("fault_inject: " + what + " \"" + item + "\" is unknown (expected all or " + expected + ")");
    }
    out.push_back(item);
  }
  return out;
}

std::int64_t ParseInt(const std::string& flag, const std::string& text, std::int64_t lo, std::int64_t hi) {
  char* end = nullptr;
  errno = 0;
  const long long v = std::strtoll(text.c_str(), &end, 10);
  if (errno != 0 || end == text.c_str() || *end != '\0' || v < lo || v > hi) {
    throw ConfigError("fault_inject: argument " + flag + ": \"" + text + "\": expected an integer in [" +
                      std::to_string(lo) + ", " + std::to_string(hi) + "]");
  }
  return v;
}

// The latest ROVER_CLOCK within `wait_s` of wall time, decoded under a guard (the bus may
// already carry hostile packets).
std::int64_t LearnRoverTime(lcm::LCM& lcm, double wait_s) {
  struct Listener {
    std::int64_t utime = 0;
    void On(const lcm::ReceiveBuffer* rbuf, const std::string&) {
      rover_msgs::rover_clock_t m;
      try {
        rover::bus::DecodeAllocationCap cap(1 << 20);
        if (m.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) >= 0 && m.utime > utime) utime = m.utime;
      } catch (const std::exception&) {
      }
    }
  } listener;
  lcm::Subscription* sub = lcm.subscribe("ROVER_CLOCK", &Listener::On, &listener);
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(wait_s);
  while (listener.utime == 0 && std::chrono::steady_clock::now() < until) lcm.handleTimeout(50);
  lcm.unsubscribe(sub);
  return listener.utime;
}

}  // namespace

int main(int argc, char** argv) {
  return rover::bus::RunMain("fault_inject", [&]() -> int {
    std::string url, groups_arg = "all", channels_arg = "all";
    std::int64_t interval_ms = 5, seed = 1;
    std::optional<std::int64_t> now_utime;
    bool list = false, quiet = false;
    fault::PacketOptions options;
    for (int i = 1; i < argc; ++i) {
      const std::string arg = argv[i];
      auto value = [&]() -> std::string {
        if (i + 1 >= argc) throw ConfigError("fault_inject: argument " + arg + ": missing value");
        return argv[++i];
      };
      if (arg == "--help" || arg == "-h") {
        std::cout << kUsage;
        return 0;
      } else if (arg == "--lcm-url") {
        url = value();
      } else if (arg == "--group") {
        groups_arg = value();
      } else if (arg == "--channel") {
        channels_arg = value();
      } else if (arg == "--interval-ms") {
        interval_ms = ParseInt(arg, value(), 0, 10000);
      } else if (arg == "--now-utime") {
        now_utime = ParseInt(arg, value(), 0, std::int64_t{1} << 62);
      } else if (arg == "--seed") {
        seed = ParseInt(arg, value(), 0, 0xffffffffLL);
      } else if (arg == "--bomb-side") {
        options.bomb_side = static_cast<int>(ParseInt(arg, value(), 64, 65535));
      } else if (arg == "--list") {
        list = true;
      } else if (arg == "--quiet") {
        quiet = true;
      } else {
        throw ConfigError("fault_inject: argument " + arg + ": unknown (see --help)");
      }
    }
    std::vector<std::string> channel_names;
    for (const auto& c : fault::AllChannels()) channel_names.push_back(c.channel);
    const auto groups = SplitList(groups_arg, fault::Groups(), "group");
    const auto channels = SplitList(channels_arg, channel_names, "channel");
    options.seed = static_cast<std::uint32_t>(seed);
    options.max_payload_bytes = [](const std::string& ch) { return rover::bus::MaxPayloadBytes(ch); };

    if (url.empty()) {
      const char* env = std::getenv("ROVER_LCM_URL");
      url = env != nullptr ? env : rover::bus::kDefaultLcmUrl;
    }
    std::unique_ptr<lcm::LCM> lcm;
    if (!list) {
      lcm = std::make_unique<lcm::LCM>(url);
      try {
        rover::bus::RequireBus(*lcm, url, "LCM bus");
      } catch (const std::runtime_error& e) {
        throw ConfigError(std::string("fault_inject: ") + e.what());
      }
    }
    if (now_utime) {
      options.now_utime = *now_utime;
    } else if (lcm) {
      options.now_utime = LearnRoverTime(*lcm, 2.0);
      if (options.now_utime == 0) std::cerr << "fault_inject: no ROVER_CLOCK within 2 s; now = 0\n";
    }

    std::int64_t sent = 0, failed = 0, bytes = 0;
    std::set<std::string> used;
    for (const auto& group : groups) {
      for (const auto& channel : channels) {
        for (const auto& p : fault::BuildPackets(group, channel, options)) {
          if (!quiet || list) std::cout << p.label << " (" << p.bytes.size() << " bytes)\n" << std::flush;
          if (list) continue;
          if (lcm->publish(p.channel, p.bytes.data(), static_cast<unsigned int>(p.bytes.size())) != 0) {
            ++failed;
            std::cerr << "fault_inject: LCM refused to send " << p.label << "\n";
          } else {
            ++sent;
            bytes += static_cast<std::int64_t>(p.bytes.size());
            used.insert(p.channel);
          }
          if (interval_ms > 0) std::this_thread::sleep_for(std::chrono::milliseconds(interval_ms));
        }
      }
    }
    if (!list) {
      std::cout << "fault_inject: sent " << sent << " packets (" << bytes << " bytes) on " << used.size()
                << " channels" << (failed ? ", " + std::to_string(failed) + " refused by LCM" : "") << "\n";
    }
    return failed == 0 ? 0 : 1;
  });
}
