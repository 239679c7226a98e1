// rover_recorder's hand-off between its receive thread and its writer thread: a queue of
// log events bounded in bytes per channel and in all.
#pragma once

#include <algorithm>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace rover::recorder {

// Our own queue, in memory: bounded per channel and in all, so that a flood on one channel
// (copies of a 250 kB STEREO_FRAME, say) costs that channel's messages only, never another's,
// and never more than kMaxQueuedBytes of memory. A stereo pair every rover second at 50x is
// 12 MB a wall second, well inside a channel's share while the writer keeps up.
inline constexpr std::size_t kMaxQueuedBytes = 256ull << 20;
inline constexpr std::size_t kMaxChannelBytes = 48ull << 20;

struct Event {
  std::int64_t timestamp;  // receive time, us since the epoch (as lcm-logger records)
  std::string channel;
  std::vector<std::uint8_t> data;
};

// The hand-off between the receive thread and the writer, bounded in bytes per channel and
// in all: a message that would pass either bound is dropped and counted against its channel.
// (The writer's loss tracker then names each dropped message by publisher and count.)
class EventQueue {
 public:
  explicit EventQueue(std::size_t max_bytes = kMaxQueuedBytes, std::size_t max_channel_bytes = kMaxChannelBytes)
      : max_total_(max_bytes), max_channel_(max_channel_bytes) {}
  bool Push(Event&& e) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!Add(std::move(e))) return false;
    }
    ready_.notify_one();
    return true;
  }
  // Each event as Push would take it, in order, under one lock and with one wake-up of the
  // writer: an instant's batch of a dozen messages, handed over as one. Returns how many
  // were dropped.
  std::size_t PushAll(std::vector<Event>&& events) {
    std::size_t dropped = 0;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      for (Event& e : events) dropped += Add(std::move(e)) ? 0 : 1;
    }
    if (dropped < events.size()) ready_.notify_one();
    return dropped;
  }
  // Messages dropped per channel because its share (or the whole queue) was full.
  std::map<std::string, std::int64_t> dropped() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return dropped_;
  }
  // The next event; nullopt once closed and empty.
  std::optional<Event> Pop() {
    std::unique_lock<std::mutex> lock(mutex_);
    ready_.wait(lock, [this] { return closed_ || !events_.empty(); });
    if (events_.empty()) return std::nullopt;
    Event e = std::move(events_.front());
    events_.pop_front();
    bytes_ -= e.data.size();
    channel_bytes_[e.channel] -= e.data.size();
    return e;
  }
  void Close() {
    std::lock_guard<std::mutex> lock(mutex_);
    closed_ = true;
    ready_.notify_all();
  }
  std::size_t max_events() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return max_events_;
  }
  std::size_t max_bytes() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return max_bytes_;
  }

 private:
  // Push's bounds and bookkeeping; the caller holds the lock.
  bool Add(Event&& e) {
    std::size_t& channel_bytes = channel_bytes_[e.channel];
    if (bytes_ + e.data.size() > max_total_ || channel_bytes + e.data.size() > max_channel_) {
      ++dropped_[e.channel];
      return false;
    }
    bytes_ += e.data.size();
    channel_bytes += e.data.size();
    max_bytes_ = std::max(max_bytes_, bytes_);
    events_.push_back(std::move(e));
    max_events_ = std::max(max_events_, events_.size());
    return true;
  }

  std::size_t max_total_, max_channel_;
  mutable std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<Event> events_;
  std::size_t bytes_ = 0, max_bytes_ = 0, max_events_ = 0;
  std::map<std::string, std::size_t> channel_bytes_;
  std::map<std::string, std::int64_t> dropped_;
  bool closed_ = false;
};

}  // namespace rover::recorder
