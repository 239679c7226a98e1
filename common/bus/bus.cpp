#include "bus/bus.hpp"

#include <algorithm>
#include <cerrno>
#include <iostream>

namespace rover::bus {

std::uint32_t PublisherId(const std::string& name) { return simtime::PublisherIdOf(name); }

Bus::Bus(const std::string& url) : url_(url), lcm_(url) {
  if (!lcm_.good()) {
    throw std::runtime_error("cannot open the LCM bus at " + url +
                             " (expected a working udpm:// URL; is there a multicast route? "
                             "see README, \"Operating\")");
  }
}

void Bus::set_publisher(const std::string& name) {
  publisher_ = name;
  publisher_bits_ = static_cast<std::uint64_t>(PublisherId(name)) << 32;
}

bool Bus::Handle(int timeout_ms) {
  const int status = lcm_.handleTimeout(timeout_ms);
  // A signal (SIGTERM from systemd or the launcher) interrupts the wait: not an error.
  if (status < 0 && errno == EINTR) return false;
  if (status < 0) throw std::runtime_error("LCM handle failed on " + url_);
  return status > 0;
}

void Bus::Drop(const std::string& channel, const std::string& type, const std::string& why) {
  ++dropped_;
  last_drop_ = channel + ": " + why;
  log_.Report(channel, "bus: " + channel + ": dropped a " + type + ": " + why + " (" +
                           std::to_string(dropped_) + " dropped so far)");
}

}  // namespace rover::bus

namespace rover::bus {

void Bus::NoteReceived(const std::string& channel, std::uint32_t publisher, std::int64_t count) {
  auto& seen = received_[channel][publisher];
  seen = std::max(seen, count + 1);
}

simtime::SyncReport Bus::SyncState(const std::string& process, std::int64_t utime, bool busy) const {
  simtime::SyncReport r;
  r.process = process;
  r.utime = utime;
  r.busy = busy;
  r.subscribed = subscribed_;
  for (const auto& [channel, count] : published_) r.published[channel] = count;
  r.received = received_;
  return r;
}

void Bus::set_deferred(bool on, std::set<std::string> immediate) {
  deferred_ = on;
  immediate_ = std::move(immediate);
}

std::string Bus::Hold(const std::string& channel, int queue_capacity) {
  const int limit = std::max(8 * queue_capacity, 256);
  int& held = held_count_[channel];
  if (held >= limit) {
    return "more than " + std::to_string(limit) + " messages on this channel in one instant of rover time (a flood?)";
  }
  ++held;
  return "";
}

void Bus::SealBatch(std::int64_t next_instant) {
  for (auto& h : inbox_) sealed_.push_back(std::move(h));
  inbox_.clear();
  held_count_.clear();
  instant_ = next_instant;
  std::erase_if(later_, [&](auto& entry) {
    ++held_count_[std::get<0>(entry.second.key)];
    if (entry.first > instant_) return false;
    inbox_.push_back(std::move(entry.second));
    return true;
  });
}

int Bus::DispatchBatch() {
  std::vector<Held> batch;
  batch.swap(sealed_);
  std::sort(batch.begin(), batch.end(), [](const Held& a, const Held& b) { return a.key < b.key; });
  for (auto& h : batch) h.deliver();  // Deliver catches and reports a callback's failure
  return static_cast<int>(batch.size());
}

}  // namespace rover::bus
