// Typed publish/subscribe over LCM 1.3.1, which has no lambda subscribe (it came in 1.4).
//
// Messages are decoded here rather than by LCM's typed subscribe, so that a corrupt
// message gets one clear line naming the channel and the expected type, instead of
// LCM's bare "error decoding". A callback must not throw: the Bus records the first
// error and Handle() re-raises it in the loop (the Drake habit).
#pragma once

#include <lcm/lcm-cpp.hpp>

#include <cstdint>
#include <exception>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace rover::bus {

// The default bus: loopback-only multicast (ttl=0) with a socket buffer large enough for
// stereo frames. On a rover spread over a LAN use ttl=1 (see README, "Deploying").
inline constexpr const char* kDefaultLcmUrl =
    "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=8388608";

class Bus {
 public:
  explicit Bus(const std::string& url);
  Bus(const Bus&) = delete;
  Bus& operator=(const Bus&) = delete;

  // Subscribes `callback(msg)` to `channel`. `queue_capacity` bounds LCM's queue.
  template <class Msg>
  void Subscribe(const std::string& channel, std::function<void(const Msg&)> callback,
                 int queue_capacity = 30);

  template <class Msg>
  void Publish(const std::string& channel, const Msg& msg) {
    if (lcm_.publish(channel, &msg) != 0) {
      throw std::runtime_error("LCM publish failed on channel " + channel);
    }
  }

  // Dispatches messages for at most `timeout_ms`. Returns true if any was handled.
  // Re-raises the first exception thrown by a callback.
  bool Handle(int timeout_ms);

  // Number of messages dropped because they did not decode.
  std::int64_t corrupt_count() const { return corrupt_count_; }
  const std::string& url() const { return url_; }
  lcm::LCM& lcm() { return lcm_; }

 private:
  struct Handler {
    virtual ~Handler() = default;
  };
  template <class Msg>
  struct TypedHandler : Handler {
    Bus* bus;
    std::function<void(const Msg&)> callback;
    void OnMessage(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
      Msg msg;
      if (msg.decode(rbuf->data, 0, rbuf->data_size) < 0) {
        bus->ReportCorrupt(channel, Msg::getTypeName(), rbuf->data_size);
        return;
      }
      if (bus->pending_error_) return;  // the loop will stop; drop the rest
      try {
        callback(msg);
      } catch (...) {
        bus->pending_error_ = std::current_exception();
      }
    }
  };

  void ReportCorrupt(const std::string& channel, const char* type, std::uint32_t size);

  std::string url_;
  lcm::LCM lcm_;
  std::vector<std::unique_ptr<Handler>> handlers_;
  std::exception_ptr pending_error_;
  std::int64_t corrupt_count_ = 0;
};

template <class Msg>
void Bus::Subscribe(const std::string& channel, std::function<void(const Msg&)> callback,
                    int queue_capacity) {
  auto handler = std::make_unique<TypedHandler<Msg>>();
  handler->bus = this;
  handler->callback = std::move(callback);
  lcm::Subscription* sub =
      lcm_.subscribe(channel, &TypedHandler<Msg>::OnMessage, handler.get());
  if (sub == nullptr) throw std::runtime_error("LCM subscribe failed on channel " + channel);
  sub->setQueueCapacity(queue_capacity);
  handlers_.push_back(std::move(handler));
}

}  // namespace rover::bus
