// Virtual time on LCM (common/simtime/barrier.hpp has the rule): the sync reports.
//
// Sync reports go to the bus's port + 1 (SyncUrl), not to the bus itself: every process
// sends a few per tick, and on one multicast port each of them would wake every process
// of the set. Only the clock (rover_sim) listens there.
#pragma once

#include "simtime/barrier.hpp"

#include <lcm/lcm-cpp.hpp>
#include <rover_msgs/rover_clock_t.hpp>
#include <rover_msgs/sim_sync_t.hpp>

#include <cstdint>
#include <memory>
#include <string>

namespace rover::bus {

inline constexpr const char* kSimSyncChannel = "SIM_SYNC";

// The URL of the sync reports: the same bus on the next port (udpm://); other providers
// (memq://, file://) are used as they are.
std::string SyncUrl(const std::string& bus_url);

rover_msgs::sim_sync_t ToMsg(const simtime::SyncReport& r, std::int64_t seq);
simtime::SyncReport FromMsg(const rover_msgs::sim_sync_t& m);

// The cut a clock message carries (simtime/cut.hpp), both ways.
void SetCut(const simtime::Cut& cut, rover_msgs::rover_clock_t* m);
simtime::Cut CutOf(const rover_msgs::rover_clock_t& m);

// Publishes sync reports (opened on the first Send).
class SyncSender {
 public:
  explicit SyncSender(std::string bus_url) : url_(SyncUrl(bus_url)) {}
  void Send(const simtime::SyncReport& report);

 private:
  std::string url_;
  std::unique_ptr<lcm::LCM> lcm_;
  std::int64_t seq_ = 0;
};

}  // namespace rover::bus
