#include "bus/bus.hpp"

#include "bus/kernel_filter.hpp"
#include "bus/lcm_url_check.hpp"
#include "bus/udpm_receiver.hpp"
#include "bus/channels.hpp"

#include <algorithm>
#include <cctype>
#include <optional>

#include <arpa/inet.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>
#include <netinet/in.h>
#include <cerrno>
#include <iostream>

namespace rover::bus {

std::uint32_t PublisherId(const std::string& name) { return simtime::PublisherIdOf(name); }

namespace {

// The URL itself when it is one LCM can open, else a one-line error before LCM sees it.
const std::string& CheckedUrl(const std::string& url) {
  if (const std::string problem = LcmUrlProblem(url); !problem.empty()) {
    throw std::runtime_error("LCM URL " + url + ": " + problem + " (expected " + kLcmUrlExpected + ")");
  }
  return url;
}

// A whole decimal number in [lo, hi], or nullopt.
std::optional<long> WholeNumber(const std::string& text, long lo, long hi) {
  if (text.empty() || text.size() > 10 || !std::all_of(text.begin(), text.end(), ::isdigit)) return std::nullopt;
  const long v = std::stol(text);
  if (v < lo || v > hi) return std::nullopt;
  return v;
}

}  // namespace

// udpm://GROUP:PORT?key=value&...: LCM's own grammar; the group is read with inet_pton.
std::string LcmUrlProblem(const std::string& url) {
  const std::string scheme = "udpm://";
  if (url.rfind(scheme, 0) != 0) return "";
  const std::string rest = url.substr(scheme.size());
  const std::size_t q = rest.find('?');
  const std::string address = rest.substr(0, q);
  const std::string options = q == std::string::npos ? "" : rest.substr(q + 1);
  if (!address.empty()) {
    const std::size_t colon = address.find(':');
    const std::string group = address.substr(0, colon);
    in_addr a{};
    if (inet_pton(AF_INET, group.c_str(), &a) != 1) return "group '" + group + "' is not an IPv4 address";
    if ((ntohl(a.s_addr) >> 28) != 0xE) return "group " + group + " is not a multicast address";
    if (colon != std::string::npos && !WholeNumber(address.substr(colon + 1), 1, 65535)) {
      return "port '" + address.substr(colon + 1) + "' is not in 1-65535";
    }
  }
  std::size_t start = 0;
  while (start < options.size()) {
    const std::size_t end = std::min(options.find('&', start), options.size());
    const std::string option = options.substr(start, end - start);
    const std::size_t eq = option.find('=');
    const std::string key = option.substr(0, eq), value = eq == std::string::npos ? "" : option.substr(eq + 1);
    if (key == "ttl" && !WholeNumber(value, 0, 255)) return "ttl '" + value + "' is not in 0-255";
    if (key == "recv_buf_size" && !WholeNumber(value, 1, 2147483647)) {
      return "recv_buf_size '" + value + "' is not a positive whole number of bytes";
    }
    start = end + 1;
  }
  return "";
}

std::string SmallReceiveBufferWarning(const std::string& who, const std::string& url,
                                      const std::set<std::string>& subscribed, bool all) {
  if (url.rfind("udpm://", 0) != 0) return "";
  const std::size_t q = url.find('?');
  const std::string options = q == std::string::npos ? "" : url.substr(q + 1);
  if (options.rfind("recv_buf_size=", 0) == 0 || options.find("&recv_buf_size=") != std::string::npos) return "";
  if (!all && !subscribed.count(channels::kStereoFrame) && !subscribed.count(channels::kHazcamFrame)) return "";
  return who + ": warning: the bus URL " + url +
         " names no recv_buf_size, so stereo pairs can overflow the socket's default buffer and be lost "
         "(expected &recv_buf_size=8388608 in the URL, as the default bus has; docs/DEPLOYING.md)";
}

void RequireBus(lcm::LCM& lcm, const std::string& url, const std::string& what) {
  if (!lcm.good()) {
    throw std::runtime_error("cannot open the " + what + " at " + url +
                             " (expected a working udpm:// URL; is there a multicast route? "
                             "see README, \"Operating\")");
  }
  if (url.rfind("udpm://", 0) == 0 && lcm.getFileno() < 0) {
    throw std::runtime_error("cannot receive on the " + what + " at " + url +
                             ": its UDP port is held by a socket that does not share it "
                             "(expected a port no other program has bound; choose another in the URL)");
  }
}

bool UdpPortReceivable(int port) {
  const int fd = socket(AF_INET, SOCK_DGRAM, 0);
  if (fd < 0) return true;  // cannot tell: LCM will say so itself
  const int one = 1;
  setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  a.sin_addr.s_addr = htonl(INADDR_ANY);
  const bool ok = bind(fd, reinterpret_cast<const sockaddr*>(&a), sizeof a) == 0;
  close(fd);
  return ok;
}

Bus::Bus(const std::string& url) : url_(url), lcm_(CheckedUrl(url)) { RequireBus(lcm_, url, "LCM bus"); }

void Bus::set_publisher(const std::string& name) {
  publisher_ = name;
  publisher_bits_ = static_cast<std::uint64_t>(PublisherId(name)) << 32;
}

void Bus::FilterInKernel(bool on) {
  filter_in_kernel_ = on;
  if (!on && filter_fd_ >= 0) {
    AttachFilter(filter_fd_, {});
    filter_fd_ = -1;
  }
  ApplyKernelFilter();
}

void Bus::ApplyKernelFilter() {
  if (!filter_in_kernel_ || subscribed_.empty()) return;
  const bool plain = std::all_of(subscribed_.begin(), subscribed_.end(), PlainChannel);
  const int port = UdpmPort(url_);
  const int fd = receiver_ ? receiver_->fd() : filter_fd_ >= 0 ? filter_fd_ : port > 0 ? FindUdpSocket(port) : -1;
  if (fd < 0) return;
  // A pattern, or a kernel that refuses the program: every datagram is delivered, as LCM
  // does without a filter.
  const bool attached =
      plain && AttachFilter(fd, ChannelFilterProgram(std::vector<std::string>(subscribed_.begin(), subscribed_.end())));
  if (!attached) AttachFilter(fd, {});
  filter_fd_ = attached ? fd : -1;
}

namespace {

// Takes LCM's receive socket off the bus's multicast group, so that the kernel no longer
// copies every datagram to it only for its filter to drop (Linux delivers a multicast
// datagram to each socket bound to the port that takes the group: a copy, a filter run
// and a free each). IP_MULTICAST_ALL off first: with it on (the default) a socket takes
// every group any socket of the host has joined, member or not. Best effort: where either
// option fails, the drop-all filter still keeps the datagrams from LCM's thread.
void LeaveGroup(int fd, const std::string& url) {
  const auto [group, port] = UdpmGroupAndPort(url);
  if (port < 0) return;
  const int off = 0;
  if (::setsockopt(fd, IPPROTO_IP, IP_MULTICAST_ALL, &off, sizeof off) != 0) return;
  ip_mreq membership{};
  if (inet_pton(AF_INET, group.c_str(), &membership.imr_multiaddr) != 1) return;
  membership.imr_interface.s_addr = htonl(INADDR_ANY);
  ::setsockopt(fd, IPPROTO_IP, IP_DROP_MEMBERSHIP, &membership, sizeof membership);
}

}  // namespace

void Bus::ReadOwnSocket() {
  if (receiver_) return;
  if (!subscribed_.empty()) throw std::logic_error("Bus::ReadOwnSocket after a Subscribe");
  const int port = UdpmPort(url_);
  if (port < 0) throw std::invalid_argument("Bus::ReadOwnSocket on " + url_ + " (expected a udpm:// bus)");
  // LCM's socket (opened by RequireBus), found before this bus opens its own beside it.
  const int lcm_fd = filter_fd_ >= 0 ? filter_fd_ : FindUdpSocket(port);
  receiver_ = std::make_unique<UdpmReceiver>(url_, "LCM bus");
  dispatch_ = [this](const std::string& channel, const std::uint8_t* data, std::size_t size, std::int64_t utime) {
    Dispatch(channel, data, size, utime);
  };
  if (lcm_fd >= 0) {
    AttachFilter(lcm_fd, {BPF_STMT(BPF_RET | BPF_K, 0)});  // LCM's thread sleeps
    LeaveGroup(lcm_fd, url_);
  }
  filter_fd_ = -1;
}

int Bus::fileno() { return receiver_ ? receiver_->fd() : lcm_.getFileno(); }

void Bus::HandleReady() {
  if (receiver_) {
    TakeOne();
  } else {
    ++handle_round_;
    lcm_.handle();
  }
}

bool Bus::TakeOne() { return receiver_->Drain(dispatch_, 64, 1) > 0; }

void Bus::Dispatch(const std::string& channel, const std::uint8_t* data, std::size_t size, std::int64_t recv_utime) {
  ++handle_round_;  // one datagram a round, as in LCM's Handle (Admit's replay check)
  lcm::ReceiveBuffer rbuf{const_cast<std::uint8_t*>(data), static_cast<std::uint32_t>(size), recv_utime};
  if (const auto it = own_handlers_.find(channel); it != own_handlers_.end()) {
    for (const auto& h : it->second) h(&rbuf, channel);
  }
  for (const auto& [pattern, h] : own_pattern_handlers_) {
    if (std::regex_match(channel, pattern)) h(&rbuf, channel);
  }
}

bool Bus::Handle(int timeout_ms) {
  if (receiver_) {
    if (TakeOne()) return true;
    if (timeout_ms <= 0) return false;
    pollfd p{receiver_->fd(), POLLIN, 0};
    if (::poll(&p, 1, timeout_ms) <= 0) return false;
    return TakeOne();
  }
  ++handle_round_;  // one datagram a call (Admit: the replay check runs once per datagram)
  const int status = lcm_.handleTimeout(timeout_ms);
  // A signal (SIGTERM from systemd or the launcher) interrupts the wait: not an error.
  if (status < 0 && errno == EINTR) return false;
  if (status < 0) throw std::runtime_error("LCM handle failed on " + url_);
  return status > 0;
}

std::int64_t Bus::dropped_on(const std::string& channel) const {
  const auto it = drops_by_channel_.find(channel);
  return it == drops_by_channel_.end() ? 0 : it->second.first;
}

std::string Bus::last_drop_on(const std::string& channel) const {
  const auto it = drops_by_channel_.find(channel);
  return it == drops_by_channel_.end() ? "" : it->second.second;
}

void Bus::Drop(const std::string& channel, const std::string& type, const std::string& why) {
  ++dropped_;
  last_drop_ = channel + ": " + why;
  auto& on_channel = drops_by_channel_[channel];
  ++on_channel.first;
  on_channel.second = why;
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

void Bus::SealBatch(std::int64_t next_instant) { SealBatch(next_instant, simtime::Cut{}); }

void Bus::SealBatch(std::int64_t next_instant, const simtime::Cut& cut) {
  std::vector<Held> after;
  for (auto& h : inbox_) {
    const auto& [channel, publisher, count, arrival] = h.key;
    if (cut.After(channel, publisher, count)) {
      after.push_back(std::move(h));
    } else {
      sealed_.push_back(std::move(h));
    }
  }
  inbox_ = std::move(after);
  held_count_.clear();
  for (const auto& h : inbox_) ++held_count_[std::get<0>(h.key)];
  instant_ = next_instant;
  std::erase_if(later_, [&](auto& entry) {
    ++held_count_[std::get<0>(entry.second.key)];
    if (entry.first > instant_) return false;
    inbox_.push_back(std::move(entry.second));
    return true;
  });
}

std::int64_t Bus::ReceivedById(std::uint32_t channel_id, std::uint32_t publisher) const {
  const auto name = subscribed_ids_.find(channel_id);
  if (name == subscribed_ids_.end()) return -1;
  const auto channel = received_.find(name->second);
  if (channel == received_.end()) return 0;
  const auto count = channel->second.find(publisher);
  return count == channel->second.end() ? 0 : count->second;
}

void Bus::ClockMoved(std::int64_t next_instant, simtime::Cut cut) {
  if (pending_seal_) SealWhenReady(true);  // a newer clock: the older instant is over
  pending_seal_ = PendingSeal{next_instant, std::move(cut)};
}

bool Bus::SealWhenReady(bool force, std::string* missing) {
  if (!pending_seal_) return false;
  const auto received = [this](std::uint32_t channel_id, std::uint32_t publisher) {
    return ReceivedById(channel_id, publisher);
  };
  if (!pending_seal_->cut.Reached(received)) {
    if (!force) return false;
    if (missing) {
      for (const auto& [key, count] : pending_seal_->cut.counts()) {
        const std::int64_t got = ReceivedById(key.first, key.second);
        if (got < 0 || got >= count) continue;
        if (!missing->empty()) *missing += ", ";
        *missing += std::to_string(count - got) + " on " + subscribed_ids_.at(key.first) + " from publisher id " +
                    std::to_string(key.second);
      }
    }
  }
  SealBatch(pending_seal_->next_instant, pending_seal_->cut);
  pending_seal_.reset();
  return true;
}

int Bus::DispatchBatch() {
  std::vector<Held> batch;
  batch.swap(sealed_);
  std::sort(batch.begin(), batch.end(), [](const Held& a, const Held& b) { return a.key < b.key; });
  for (auto& h : batch) h.deliver();  // Deliver catches and reports a callback's failure
  return static_cast<int>(batch.size());
}

}  // namespace rover::bus
