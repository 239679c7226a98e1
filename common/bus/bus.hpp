// Typed publish/subscribe over LCM 1.3.1, which has no lambda subscribe (it came in 1.4).
//
// Messages are decoded here rather than by LCM's typed subscribe, so that nothing a
// packet holds can stop a process. Before a callback sees a message, the Bus:
//   1. bounds its size per channel (MaxPayloadBytes) before decoding;
//   2. decodes it under an allocation cap, so a lying length field cannot allocate
//      gigabytes, and with every exception caught;
//   3. checks its fields (bus/validate.hpp: finite numbers, known enums, sane counts);
//   4. checks that its utime is plausible against this process's rover clock;
//   5. checks its authentication tag, for command messages when a key is configured.
// A message that fails is dropped with one line naming the channel, the type and what
// was wrong (rate-limited per channel), and counted (dropped(), sent in the heartbeat).
// An exception from a callback is reported and counted the same way; the process goes on.
//
// Publish stamps `pub_seq` (the publisher's id and its count on the channel), so a
// log checker can find every lost message, and signs command messages when a key is set.
#pragma once

#include "bus/channels.hpp"
#include "bus/guard.hpp"
#include "bus/kernel_filter.hpp"
#include "bus/udpm_receiver.hpp"
#include "bus/validate.hpp"
#include "simtime/barrier.hpp"

#include <lcm/lcm-cpp.hpp>

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <regex>
#include <set>
#include <stdexcept>
#include <tuple>
#include <string>
#include <vector>

namespace rover::bus {

// The default bus: loopback-only multicast (ttl=0) with a socket buffer large enough for
// stereo frames. On a rover spread over a LAN use ttl=1 (see README, "Deploying on a
// rover computer").
inline constexpr const char* kDefaultLcmUrl =
    "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=8388608";

// The id a publisher stamps into the high 32 bits of pub_seq: FNV-1a of its name, so the
// same process publishes the same bytes in every run (replays compare byte for byte).
std::uint32_t PublisherId(const std::string& name);

// Throws a one-line error unless `lcm` (opened on `url`, named `what` in the error) can
// both send and receive. LCM 1.3.1 binds its udpm receive socket only at the first
// subscribe; when that bind fails (the port is held by a socket that does not share it,
// e.g. another program's ephemeral port) LCM prints "bind: Address already in use" and
// hands back a subscription with nothing under it, which crashes on first use. Asking for
// the file descriptor binds now, so the process can say so and stop instead.
void RequireBus(lcm::LCM& lcm, const std::string& url, const std::string& what);

// Whether LCM could bind UDP `port` to receive: a probe socket binds it as LCM does (with
// SO_REUSEADDR), so it fails only where another program holds the port without sharing it.
bool UdpPortReceivable(int port);

// Who published a message and its count on the channel: pub_seq, or a heartbeat's process
// and seq. Virtual time counts messages in flight with these (simtime/barrier.hpp).
template <class Msg>
std::optional<std::pair<std::uint32_t, std::int64_t>> StampOf(const Msg& m) {
  if constexpr (requires { m.pub_seq; }) {
    const auto bits = static_cast<std::uint64_t>(m.pub_seq);
    return std::make_pair(static_cast<std::uint32_t>(bits >> 32), static_cast<std::int64_t>(bits & 0xffffffffu));
  } else if constexpr (requires { m.process; m.seq; }) {
    return std::make_pair(PublisherId(m.process), static_cast<std::int64_t>(m.seq));
  } else {
    return std::nullopt;
  }
}

class Bus {
 public:
  explicit Bus(const std::string& url);
  Bus(const Bus&) = delete;
  Bus& operator=(const Bus&) = delete;

  // The name this bus publishes under (pub_seq's publisher id; heartbeats).
  void set_publisher(const std::string& name);
  const std::string& publisher() const { return publisher_; }
  // The channels subscribed so far (`--channels`, bus/process.hpp).
  const std::set<std::string>& subscribed() const { return subscribed_; }

  // On: datagrams on channels this bus does not subscribe to are dropped by the kernel,
  // before they wake the process (bus/kernel_filter.hpp); the filter follows every later
  // Subscribe. bus::Process turns it on (`bus.filter_in_kernel`). Nothing is filtered while
  // a subscription is a pattern, on a provider other than udpm, or where this process has
  // more than one socket on the bus's port; nor for channels subscribed on lcm() directly,
  // so a program that does so leaves it off.
  void FilterInKernel(bool on);
  // Whether a filter is on the bus's socket now.
  bool filtered_in_kernel() const { return filter_fd_ >= 0; }

  // From now on this bus reads its udpm socket on the caller's thread (bus/udpm_receiver.hpp)
  // instead of through LCM's receive thread, whose socket then takes nothing (a filter that
  // drops every datagram): each message wakes one thread, not two. Handle still hands on
  // one message a call. Called before any Subscribe, on a udpm:// bus only (bus::Process
  // does so in virtual time); channels subscribed on lcm() directly get nothing after it.
  void ReadOwnSocket();
  bool reads_own_socket() const { return receiver_ != nullptr; }
  // The descriptor that is readable when a message may be waiting (for poll beside others),
  // and the handling of one such message without waiting (what poll found).
  int fileno();
  void HandleReady();

  // Subscribes `callback(msg)` to `channel`. `queue_capacity` bounds LCM's queue.
  template <class Msg>
  void Subscribe(const std::string& channel, std::function<void(const Msg&)> callback,
                 int queue_capacity = 30);

  // The same without the time and authentication checks (size, decoding and fields are
  // checked): for a console's diagnostics only. What it delivers may be forged, replayed or
  // stamped in another time, so nothing may act on it; rover_web reads the executor's
  // heartbeat so, to say why its commands are refused when its key does not verify them.
  template <class Msg>
  void SubscribeUnverified(const std::string& channel, std::function<void(const Msg&)> callback,
                           int queue_capacity = 30);

  template <class Msg>
  void Publish(const std::string& channel, const Msg& msg);

  // Dispatches messages for at most `timeout_ms`. Returns true if any was handled.
  bool Handle(int timeout_ms);

  // Rover time as this process sees it (bus/guard.hpp).
  RoverClock& clock() { return clock_; }
  const RoverClock& clock() const { return clock_; }

  // Messages dropped so far, for any reason, and the last reason.
  std::int64_t dropped() const { return dropped_; }
  const std::string& last_drop() const { return last_drop_; }
  // Kept for older callers: the same count.
  std::int64_t corrupt_count() const { return dropped_; }
  // Per channel: the messages dropped and the last reason (0 and "" when none). The
  // executor names its command channels' drops in its heartbeat, so a console can tell
  // that its own command was refused even while other channels drop messages too.
  std::int64_t dropped_on(const std::string& channel) const;
  std::string last_drop_on(const std::string& channel) const;
  // Of those, the messages refused for their authentication (a missing or wrong tag, a
  // replayed counter), and the last one: "CHANNEL: reason".
  std::int64_t auth_rejected() const { return auth_rejected_; }
  const std::string& last_auth_rejection() const { return last_auth_rejection_; }
  // Records a drop found by a receiver after the Bus's own checks (an image that does not
  // match its camera model, say): same line, same count.
  void Drop(const std::string& channel, const std::string& type, const std::string& why);

  const std::string& url() const { return url_; }
  lcm::LCM& lcm() { return lcm_; }

  // Virtual time: what this bus has subscribed to, published and received (counted as each
  // message arrives, before it is judged), for the sync report a simulated process sends.
  simtime::SyncReport SyncState(const std::string& process, std::int64_t utime, bool busy) const;
  // Deferred delivery (virtual time): messages are held as they arrive and handed to their
  // callbacks only by DispatchBatch, sorted by channel, publisher and count, so the order in
  // which the messages of one instant happened to arrive cannot change what a process does.
  // Channels named in `immediate` (the clock) are always delivered at once.
  void set_deferred(bool on, std::set<std::string> immediate = {});
  bool deferred() const { return deferred_; }
  // The messages held so far become the next batch (called when the clock moves on to
  // `next_instant`). A heartbeat stamped later than the instant it came in belongs to a
  // later one: on a multi-core computer it can overtake the clock message that started
  // its instant, so it is held by its stamp, not by when it came, until its instant.
  void SealBatch(std::int64_t next_instant);
  // The same, keeping back what `cut` says was published after it (simtime/cut.hpp): a
  // message that overtook the clock waits for the next batch.
  void SealBatch(std::int64_t next_instant, const simtime::Cut& cut);
  // A virtual clock message moved the clock on to `next_instant` with `cut`: the batch is
  // sealed by SealWhenReady once every message below the cut on a channel this bus takes
  // has come (the time source's last messages may come just after its clock message).
  void ClockMoved(std::int64_t next_instant, simtime::Cut cut);
  // Seals the batch ClockMoved announced when the cut is reached, or at once with `force`
  // (what is missing was lost on the way; `missing` then says what, when given). True when
  // sealed, false when nothing is pending or the cut is not reached yet.
  bool SealWhenReady(bool force, std::string* missing = nullptr);
  bool seal_pending() const { return pending_seal_.has_value(); }
  // Hands the sealed batch to the callbacks; returns how many messages it held.
  int DispatchBatch();
  // Messages held, sealed or not.
  std::size_t held() const { return inbox_.size() + sealed_.size(); }

  // Authentication: a signer for what this process publishes and a verifier for what it
  // receives, on command channels (see bus/signing.hpp). Type-erased so that the Bus does
  // not depend on the crypto library.
  struct Auth {
    // Fills sender and counter, then the tag over the message encoded with them and an
    // empty tag (the callback encodes; see Publish).
    std::function<void(std::string* sender, std::int64_t* counter)> next;
    std::function<std::vector<std::uint8_t>(const std::vector<std::uint8_t>& bytes)> tag;
    // "" when (sender, counter, tag over bytes) is acceptable, else why not. Accepting
    // records the counter.
    std::function<std::string(const std::string& sender, std::int64_t counter,
                              const std::vector<std::uint8_t>& bytes,
                              const std::vector<std::uint8_t>& tag)> verify;
    bool required = false;
  };
  void set_auth(Auth auth) { auth_ = std::move(auth); has_auth_ = true; }
  bool has_auth() const { return has_auth_; }

 private:
  struct Handler {
    virtual ~Handler() = default;
  };
  template <class Msg>
  struct TypedHandler : Handler {
    Bus* bus;
    std::function<void(const Msg&)> callback;
    int queue_capacity = 30;
    bool unverified = false;  // SubscribeUnverified
    void OnMessage(const lcm::ReceiveBuffer* rbuf, const std::string& channel);
    void Deliver(const Msg& msg, const std::string& channel);
  };
  struct Held {
    std::tuple<std::string, std::uint32_t, std::int64_t, std::uint64_t> key;  // channel, publisher, count, arrival
    std::function<void()> deliver;
  };
  void NoteReceived(const std::string& channel, std::uint32_t publisher, std::int64_t count);
  bool Defers(const std::string& channel) const { return deferred_ && !immediate_.count(channel); }
  // Deferred delivery is bounded per channel as LCM's queue is in real time: one instant may
  // hold at most this many messages of a channel subscribed with `queue_capacity` (far more
  // than any process publishes in a tick), so a flood on one channel costs that channel's
  // messages only and cannot grow a process's memory while the clock waits. "" admits.
  std::string Hold(const std::string& channel, int queue_capacity);

  template <class Msg>
  std::string Admit(const std::string& channel, const lcm::ReceiveBuffer* rbuf, Msg* msg, const void* handler,
                    bool unverified);
  template <class Msg>
  void SubscribeHandler(const std::string& channel, std::function<void(const Msg&)> callback, int queue_capacity,
                        bool unverified);
  template <class Msg>
  std::string Authenticate(const Msg& msg);
  template <class Msg>
  void Sign(Msg* msg);

  // FilterInKernel: the filter for subscribed_, attached to the bus's socket or taken off.
  void ApplyKernelFilter();
  // ReadOwnSocket: one message from the own socket to its handlers, if one is waiting.
  bool TakeOne();
  void Dispatch(const std::string& channel, const std::uint8_t* data, std::size_t size, std::int64_t recv_utime);
  using RawHandler = std::function<void(const lcm::ReceiveBuffer*, const std::string&)>;
  std::unique_ptr<UdpmReceiver> receiver_;
  UdpmReceiver::Handler dispatch_;
  std::map<std::string, std::vector<RawHandler>> own_handlers_;                // by channel
  std::vector<std::pair<std::regex, RawHandler>> own_pattern_handlers_;  // LCM's whole-name patterns
  bool filter_in_kernel_ = false;
  int filter_fd_ = -1;  // the socket a filter is on, or -1

  std::string url_;
  lcm::LCM lcm_;
  std::string publisher_;
  std::uint64_t publisher_bits_ = 0;
  std::map<std::string, std::uint32_t> published_;
  std::vector<std::unique_ptr<Handler>> handlers_;
  RoverClock clock_;
  RateLimitedLog log_;
  std::int64_t dropped_ = 0;
  std::string last_drop_;
  std::map<std::string, std::pair<std::int64_t, std::string>> drops_by_channel_;
  std::int64_t auth_rejected_ = 0;
  std::string last_auth_rejection_;
  Auth auth_;
  bool has_auth_ = false;
  std::set<std::string> subscribed_;
  // The datagram whose authentication was last accepted (Admit says why). `round`: the
  // Handle call that dispatched it; LCM dispatches one datagram a call, so a replay, which
  // is another datagram, comes in another round even where LCM reuses its buffer.
  struct Received {
    const void* data;
    std::uint32_t size;
    std::int64_t recv_utime;
    std::string channel;
    std::uint64_t round;
    bool operator==(const Received&) const = default;
  };
  std::uint64_t handle_round_ = 0;
  std::optional<Received> last_verified_;
  std::set<const void*> verified_for_;  // the subscriptions that have had it
  std::map<std::string, std::map<std::uint32_t, std::int64_t>> received_;
  bool deferred_ = false;
  std::set<std::string> immediate_;
  // Received so far on a subscribed channel, by the cut's channel id (-1: not subscribed).
  std::int64_t ReceivedById(std::uint32_t channel_id, std::uint32_t publisher) const;
  std::vector<Held> inbox_, sealed_;
  std::map<std::uint32_t, std::string> subscribed_ids_;  // cut channel id -> channel
  struct PendingSeal {
    std::int64_t next_instant;
    simtime::Cut cut;
  };
  std::optional<PendingSeal> pending_seal_;
  std::vector<std::pair<std::int64_t, Held>> later_;  // heartbeats stamped after the instant
  std::map<std::string, int> held_count_;            // per channel, inbox_ and later_
  std::int64_t instant_ = -1;
  std::uint64_t arrivals_ = 0;
};

template <class Msg>
std::string Bus::Authenticate(const Msg& msg) {
  if constexpr (requires { msg.auth.tag; }) {
    if (!has_auth_) return "";
    if (msg.auth.tag_size == 0) return auth_.required ? "no authentication tag (a key is required on this bus)" : "";
    Msg copy = msg;
    copy.auth.tag_size = 0;
    copy.auth.tag.clear();
    std::vector<std::uint8_t> bytes(static_cast<std::size_t>(copy.getEncodedSize()));
    if (copy.encode(bytes.data(), 0, static_cast<int>(bytes.size())) < 0) return "cannot re-encode to check its tag";
    return auth_.verify(msg.auth.sender, msg.auth.counter, bytes, msg.auth.tag);
  }
  return "";
}

template <class Msg>
void Bus::Sign(Msg* msg) {
  if constexpr (requires { msg->auth.tag; }) {
    if (!has_auth_ || !auth_.next) return;
    auth_.next(&msg->auth.sender, &msg->auth.counter);
    msg->auth.tag_size = 0;
    msg->auth.tag.clear();
    std::vector<std::uint8_t> bytes(static_cast<std::size_t>(msg->getEncodedSize()));
    if (msg->encode(bytes.data(), 0, static_cast<int>(bytes.size())) < 0)
      throw std::runtime_error("cannot encode a command to sign it");
    msg->auth.tag = auth_.tag(bytes);
    msg->auth.tag_size = static_cast<std::int32_t>(msg->auth.tag.size());
  }
}

template <class Msg>
void Bus::Publish(const std::string& channel, const Msg& msg) {
  int status = 0;
  if constexpr (!requires { msg.pub_seq; }) ++published_[channel];  // counted by its own seq
  if constexpr (requires { msg.pub_seq; } || requires { msg.auth; }) {
    Msg stamped = msg;
    if constexpr (requires { msg.pub_seq; }) {
      stamped.pub_seq = static_cast<std::int64_t>(publisher_bits_ | published_[channel]++);
    }
    Sign(&stamped);
    status = lcm_.publish(channel, &stamped);
  } else {
    status = lcm_.publish(channel, &msg);
  }
  if (status != 0) throw std::runtime_error("LCM publish failed on channel " + channel);
}

// The checks in order; "" admits the message into `msg`.
template <class Msg>
std::string Bus::Admit(const std::string& channel, const lcm::ReceiveBuffer* rbuf, Msg* msg, const void* handler,
                       bool unverified) {
  const std::size_t max_bytes = MaxPayloadBytes(channel);
  if (rbuf->data_size > max_bytes) {
    return std::to_string(rbuf->data_size) + " bytes is over the channel's limit of " +
           std::to_string(max_bytes);
  }
  try {
    // Decoded objects are larger than their bytes (headers of strings and vectors), but no
    // single allocation can honestly exceed a few times the payload.
    DecodeAllocationCap cap(16 * static_cast<std::size_t>(rbuf->data_size) + 65536);
    if (msg->decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) < 0)
      return "does not decode (truncated, a wrong type fingerprint or a length past the end)";
  } catch (const std::exception& e) {
    return std::string("does not decode (a length field out of bounds: ") + e.what() + ")";
  }
  if (const auto stamp = StampOf(*msg)) {
    NoteReceived(channel, stamp->first, stamp->second);
  }
  if constexpr (requires { Problem(*msg); }) {
    if (std::string p = Problem(*msg); !p.empty()) return p;
  }
  if (unverified) return "";  // SubscribeUnverified: no time, no authentication
  if constexpr (requires { msg->utime; }) {
    if (TimeChecked(channel) && channel != channels::kClock) {  // the clock: RoverClock::AcceptClock
      if (std::string p = clock_.Judge(msg->utime, RoverClock::WallClock::now()); !p.empty()) return p;
    }
  }
  // The replay check runs once per datagram, not once per subscription: LCM hands one
  // datagram to every subscription of its channel, in one Handle call and with the same
  // receive buffer, so a second subscription on this Bus takes the first one's verdict
  // instead of seeing the counter again and calling the same datagram a replay. A replay
  // is another datagram (another Handle call), so it is still checked, by every
  // subscription; so is a datagram handed again to a subscription that already had it.
  const Received same{rbuf->data, rbuf->data_size, rbuf->recv_utime, channel, handle_round_};
  if (last_verified_ && *last_verified_ == same && !verified_for_.count(handler)) {
    verified_for_.insert(handler);
    return "";
  }
  if (std::string p = Authenticate(*msg); !p.empty()) {
    ++auth_rejected_;
    last_auth_rejection_ = channel + ": " + p;
    return "rejected: " + p;
  }
  if constexpr (requires { msg->auth.tag; }) {
    last_verified_ = same;
    verified_for_ = {handler};
  }
  return "";
}

template <class Msg>
void Bus::TypedHandler<Msg>::OnMessage(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
  auto msg = std::make_shared<Msg>();
  if (std::string why = bus->Admit(channel, rbuf, msg.get(), this, unverified); !why.empty()) {
    bus->Drop(channel, Msg::getTypeName(), why);
    return;
  }
  if (bus->Defers(channel)) {
    if (std::string why = bus->Hold(channel, queue_capacity); !why.empty()) {
      bus->Drop(channel, Msg::getTypeName(), why);
      return;
    }
    const auto stamp = StampOf(*msg);
    Held h;
    h.key = {channel, stamp ? stamp->first : 0u, stamp ? stamp->second : 0, bus->arrivals_++};
    h.deliver = [this, msg, channel] { Deliver(*msg, channel); };
    if constexpr (requires { msg->process; msg->seq; msg->utime; }) {
      if (bus->instant_ >= 0 && msg->utime > bus->instant_) {
        bus->later_.emplace_back(msg->utime, std::move(h));
        return;
      }
    }
    bus->inbox_.push_back(std::move(h));
    return;
  }
  Deliver(*msg, channel);
}

template <class Msg>
void Bus::TypedHandler<Msg>::Deliver(const Msg& msg, const std::string& channel) {
  try {
    callback(msg);
  } catch (const std::exception& e) {
    bus->Drop(channel, Msg::getTypeName(), std::string("its handler failed: ") + e.what());
  } catch (...) {
    bus->Drop(channel, Msg::getTypeName(), "its handler failed");
  }
}

template <class Msg>
void Bus::Subscribe(const std::string& channel, std::function<void(const Msg&)> callback,
                    int queue_capacity) {
  SubscribeHandler<Msg>(channel, std::move(callback), queue_capacity, false);
}

template <class Msg>
void Bus::SubscribeUnverified(const std::string& channel, std::function<void(const Msg&)> callback,
                              int queue_capacity) {
  SubscribeHandler<Msg>(channel, std::move(callback), queue_capacity, true);
}

template <class Msg>
void Bus::SubscribeHandler(const std::string& channel, std::function<void(const Msg&)> callback,
                           int queue_capacity, bool unverified) {
  auto handler = std::make_unique<TypedHandler<Msg>>();
  handler->bus = this;
  handler->callback = std::move(callback);
  handler->queue_capacity = queue_capacity;
  handler->unverified = unverified;
  if (receiver_) {
    // Bounded by the kernel's socket buffer and, in virtual time, by Hold per instant.
    TypedHandler<Msg>* h = handler.get();
    RawHandler raw = [h](const lcm::ReceiveBuffer* rbuf, const std::string& c) { h->OnMessage(rbuf, c); };
    if (PlainChannel(channel)) {
      own_handlers_[channel].push_back(std::move(raw));
    } else {
      own_pattern_handlers_.emplace_back(std::regex(channel), std::move(raw));
    }
  } else {
    lcm::Subscription* sub = lcm_.subscribe(channel, &TypedHandler<Msg>::OnMessage, handler.get());
    if (sub == nullptr) throw std::runtime_error("LCM subscribe failed on channel " + channel);
    sub->setQueueCapacity(queue_capacity);
  }
  handlers_.push_back(std::move(handler));
  subscribed_.insert(channel);
  subscribed_ids_[simtime::ChannelIdOf(channel)] = channel;
  ApplyKernelFilter();
}

}  // namespace rover::bus
