// LCM's udpm wire format, received on the caller's own thread.
//
// LCM 1.3.1 reads its socket on a receive thread of its own and wakes the thread that
// handles messages through a pipe: every datagram costs two wake-ups. The clock (rover_sim)
// takes one sync report from every member of the set every instant, most of them while
// it waits for nothing else, so on the shared 2-core machine those wake-ups were a large
// part of what it cost (docs/SIMTIME_LOG.md, "The clock reads its sync reports itself").
// This receiver opens a socket as LCM does (the group and port of a udpm:// URL, shared
// with SO_REUSEADDR, the URL's recv_buf_size), and its owner polls fd() beside its other
// descriptors and calls Drain, which reads every datagram waiting and hands on each whole
// LCM message: a short one (LC02), or a long one (LC03) once all its fragments have come.
//
// Written here because LCM has no receive call without its thread (lcm_handle waits on
// the thread's pipe). Publishing stays LCM's. Only the sync bus uses it: its messages are
// small and come from the members of one set, and the main bus keeps LCM's own receiver.
#pragma once

#include <netinet/in.h>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace rover::bus {

class UdpmReceiver {
 public:
  // `recv_utime`: when the message's first datagram came (the kernel's stamp, wall
  // microseconds since the epoch), as LCM's ReceiveBuffer::recv_utime.
  using Handler = std::function<void(const std::string& channel, const std::uint8_t* data, std::size_t size,
                                     std::int64_t recv_utime)>;

  // Joins the group of `url` (udpm://GROUP:PORT?...; LCM's 239.255.76.67:7667 where it
  // names none) and binds its port. Throws std::runtime_error, one line naming `what` and
  // the URL, for another provider or a socket that cannot be made.
  explicit UdpmReceiver(const std::string& url, const std::string& what = "bus");
  ~UdpmReceiver();
  UdpmReceiver(const UdpmReceiver&) = delete;
  UdpmReceiver& operator=(const UdpmReceiver&) = delete;

  // For poll: readable when a datagram waits.
  int fd() const { return fd_; }
  // Reads the datagrams waiting, without blocking, up to `max_datagrams` (so a flood cannot
  // hold the caller) or until `max_messages` whole messages have been handed to `handler`.
  // Returns the messages handed.
  int Drain(const Handler& handler, int max_datagrams = 256, int max_messages = 1 << 30);
  // Datagrams that were not LCM's, or fragments that did not fit their message.
  std::int64_t malformed() const { return malformed_; }

  // One datagram as it came from `sender` (address and port) at `utime`: the parsing under
  // Drain. True when it completed a message (and `handler` was called).
  bool Take(const std::uint8_t* data, std::size_t size, std::uint64_t sender, const Handler& handler,
            std::int64_t utime = 0);

 private:
  // A long message being put together from its fragments.
  struct Partial {
    std::uint32_t seqno = 0;
    std::string channel;
    std::vector<std::uint8_t> data;
    std::vector<bool> got;
    int missing = 0;
    std::int64_t utime = 0;  // of the first fragment
  };
  bool TakeFragment(const std::uint8_t* data, std::size_t size, std::uint64_t sender, const Handler& handler,
                    std::int64_t utime);

  int fd_ = -1;
  std::vector<std::uint8_t> buffer_;
  std::map<std::uint64_t, Partial> partial_;  // by sender: LCM sends one long message at a time
  std::int64_t malformed_ = 0;
};

// The multicast group and port of a udpm:// URL, or {"", -1} for another provider or a URL
// whose address cannot be read.
std::pair<std::string, int> UdpmGroupAndPort(const std::string& url);

}  // namespace rover::bus
