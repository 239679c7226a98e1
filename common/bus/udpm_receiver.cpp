#include "bus/udpm_receiver.hpp"

#include "bus/kernel_filter.hpp"

#include <arpa/inet.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace rover::bus {

namespace {

constexpr std::uint32_t kShortMagic = 0x4c433032;  // "LC02": a whole message in one datagram
constexpr std::uint32_t kLongMagic = 0x4c433033;   // "LC03": one fragment of a long message
constexpr std::size_t kLongHeader = 20;            // magic, seqno, size, offset, fragment no, count
constexpr std::size_t kMaxMessage = std::size_t{1} << 28;  // LCM_MAX_MESSAGE_SIZE
constexpr std::size_t kMaxChannel = 63;                    // LCM_MAX_CHANNEL_NAME_LENGTH

std::uint32_t Be32(const std::uint8_t* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) | p[3];
}
std::uint16_t Be16(const std::uint8_t* p) { return static_cast<std::uint16_t>((p[0] << 8) | p[1]); }

// The NUL-terminated channel name at the start of [p, p + n): its length, or -1 when there
// is no terminator within LCM's longest name.
int ChannelLength(const std::uint8_t* p, std::size_t n) {
  const std::size_t limit = std::min(n, kMaxChannel + 1);
  const void* nul = std::memchr(p, 0, limit);
  return nul ? static_cast<int>(static_cast<const std::uint8_t*>(nul) - p) : -1;
}

// recv_buf_size=N of a udpm URL's options, or 0 when it names none.
int ReceiveBufferOf(const std::string& url) {
  const std::size_t q = url.find('?');
  if (q == std::string::npos) return 0;
  const std::string key = "recv_buf_size=";
  std::size_t at = url.find(key, q + 1);
  while (at != std::string::npos && url[at - 1] != '?' && url[at - 1] != '&') at = url.find(key, at + 1);
  if (at == std::string::npos) return 0;
  const std::size_t begin = at + key.size(), end = url.find('&', begin);
  const std::string value = url.substr(begin, end == std::string::npos ? std::string::npos : end - begin);
  if (value.empty() || value.size() > 10 || value.find_first_not_of("0123456789") != std::string::npos) return 0;
  return static_cast<int>(std::min(std::stoll(value), 2147483647LL));
}

}  // namespace

std::pair<std::string, int> UdpmGroupAndPort(const std::string& url) {
  const int port = UdpmPort(url);
  if (port < 0) return {"", -1};
  const std::string scheme = "udpm://";
  const std::size_t end = url.find_first_of("?:", scheme.size());
  std::string group = url.substr(scheme.size(), end == std::string::npos ? std::string::npos : end - scheme.size());
  if (group.empty()) group = "239.255.76.67";  // LCM's default
  in_addr a{};
  if (inet_pton(AF_INET, group.c_str(), &a) != 1) return {"", -1};
  return {group, port};
}

UdpmReceiver::UdpmReceiver(const std::string& url, const std::string& what) : buffer_(65536) {
  const auto [group, port] = UdpmGroupAndPort(url);
  const std::string where = "cannot receive on the " + what + " at " + url;
  if (port < 0) throw std::runtime_error(where + ": expected a udpm://GROUP:PORT URL");
  const auto fail = [&](const char* step) {
    const std::string why = std::strerror(errno);
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
    throw std::runtime_error(where + ": " + step + ": " + why);
  };
  fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
  if (fd_ < 0) fail("socket");
  const int one = 1;
  if (::setsockopt(fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one) != 0) fail("SO_REUSEADDR");
  if (const int size = ReceiveBufferOf(url); size > 0) {
    ::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &size, sizeof size);  // the kernel caps it, as for LCM
  }
  sockaddr_in local{};
  local.sin_family = AF_INET;
  local.sin_port = htons(static_cast<std::uint16_t>(port));
  local.sin_addr.s_addr = htonl(INADDR_ANY);
  if (::setsockopt(fd_, SOL_SOCKET, SO_TIMESTAMP, &one, sizeof one) != 0) fail("SO_TIMESTAMP");
  if (::bind(fd_, reinterpret_cast<const sockaddr*>(&local), sizeof local) != 0) {
    fail("bind (expected a port no other program has bound; choose another in the URL)");
  }
  ip_mreq membership{};
  inet_pton(AF_INET, group.c_str(), &membership.imr_multiaddr);
  membership.imr_interface.s_addr = htonl(INADDR_ANY);
  if (::setsockopt(fd_, IPPROTO_IP, IP_ADD_MEMBERSHIP, &membership, sizeof membership) != 0) {
    fail("joining the multicast group (is there a multicast route?)");
  }
}

UdpmReceiver::~UdpmReceiver() {
  if (fd_ >= 0) ::close(fd_);
}

int UdpmReceiver::Drain(const Handler& handler, int max_datagrams, int max_messages) {
  int handed = 0;
  for (int i = 0; i < max_datagrams && handed < max_messages; ++i) {
    sockaddr_in from{};
    iovec io{buffer_.data(), buffer_.size()};
    alignas(cmsghdr) char control[CMSG_SPACE(sizeof(timeval))];
    msghdr m{};
    m.msg_name = &from;
    m.msg_namelen = sizeof from;
    m.msg_iov = &io;
    m.msg_iovlen = 1;
    m.msg_control = control;
    m.msg_controllen = sizeof control;
    const ssize_t n = ::recvmsg(fd_, &m, MSG_DONTWAIT);
    if (n < 0) break;  // EAGAIN: nothing more waits (or EINTR: the caller polls again)
    if (m.msg_flags & MSG_TRUNC) {
      ++malformed_;  // longer than any LCM datagram
      continue;
    }
    std::int64_t utime = 0;
    for (cmsghdr* c = CMSG_FIRSTHDR(&m); c != nullptr; c = CMSG_NXTHDR(&m, c)) {
      if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_TIMESTAMP) {
        timeval tv{};
        std::memcpy(&tv, CMSG_DATA(c), sizeof tv);
        utime = std::int64_t{tv.tv_sec} * 1000000 + tv.tv_usec;
      }
    }
    if (utime == 0) {
      timeval tv{};
      gettimeofday(&tv, nullptr);
      utime = std::int64_t{tv.tv_sec} * 1000000 + tv.tv_usec;
    }
    const std::uint64_t sender = (std::uint64_t{ntohl(from.sin_addr.s_addr)} << 16) | ntohs(from.sin_port);
    if (Take(buffer_.data(), static_cast<std::size_t>(n), sender, handler, utime)) ++handed;
  }
  return handed;
}

bool UdpmReceiver::Take(const std::uint8_t* data, std::size_t size, std::uint64_t sender, const Handler& handler,
                        std::int64_t utime) {
  if (size >= 4 && Be32(data) == kLongMagic) return TakeFragment(data, size, sender, handler, utime);
  if (size < 9 || Be32(data) != kShortMagic) {
    ++malformed_;
    return false;
  }
  const int length = ChannelLength(data + 8, size - 8);
  if (length <= 0) {
    ++malformed_;
    return false;
  }
  const std::string channel(reinterpret_cast<const char*>(data + 8), static_cast<std::size_t>(length));
  const std::size_t payload = 8 + static_cast<std::size_t>(length) + 1;
  handler(channel, data + payload, size - payload, utime);
  return true;
}

bool UdpmReceiver::TakeFragment(const std::uint8_t* data, std::size_t size, std::uint64_t sender,
                                const Handler& handler, std::int64_t utime) {
  if (size < kLongHeader) {
    ++malformed_;
    return false;
  }
  const std::uint32_t seqno = Be32(data + 4), total = Be32(data + 8), offset = Be32(data + 12);
  const int number = Be16(data + 16), count = Be16(data + 18);
  std::size_t at = kLongHeader;
  Partial& p = partial_[sender];
  if (number == 0) {
    const int length = ChannelLength(data + at, size - at);
    if (length <= 0 || total == 0 || total > kMaxMessage || count == 0) {
      ++malformed_;
      partial_.erase(sender);
      return false;
    }
    // A new message from this sender: whatever was missing of the last is lost, as in LCM.
    p = Partial{seqno, std::string(reinterpret_cast<const char*>(data + at), static_cast<std::size_t>(length)),
                std::vector<std::uint8_t>(total), std::vector<bool>(static_cast<std::size_t>(count), false), count, utime};
    at += static_cast<std::size_t>(length) + 1;
  }
  const std::size_t bytes = size - at;
  if (p.got.empty() || p.seqno != seqno || number >= static_cast<int>(p.got.size()) ||
      static_cast<std::size_t>(count) != p.got.size() || offset > p.data.size() || bytes > p.data.size() - offset) {
    ++malformed_;  // a fragment of a message whose first fragment never came, or one that does not fit it
    return false;
  }
  if (!p.got[static_cast<std::size_t>(number)]) {
    p.got[static_cast<std::size_t>(number)] = true;
    --p.missing;
    std::memcpy(p.data.data() + offset, data + at, bytes);
  }
  if (p.missing > 0) return false;
  const Partial whole = std::move(p);
  partial_.erase(sender);
  handler(whole.channel, whole.data.data(), whole.data.size(), whole.utime);
  return true;
}

}  // namespace rover::bus
