#include "bus/kernel_filter.hpp"

#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/stat.h>

#include <cerrno>
#include <cstdint>
#include <filesystem>
#include <stdexcept>

namespace rover::bus {

namespace {

// Offsets as a UDP socket filter sees the datagram: the 8-byte UDP header first.
constexpr std::uint32_t kUdpHeader = 8;
constexpr std::uint32_t kShortMagic = 0x4c433032;  // "LC02": magic, sequence, channel NUL, data
constexpr std::uint32_t kLongMagic = 0x4c433033;   // "LC03": magic, sequence, size, offset, fragment, count, [channel NUL], data
constexpr std::uint32_t kShortChannel = kUdpHeader + 8;
constexpr std::uint32_t kFragmentNumber = kUdpHeader + 16;
constexpr std::uint32_t kLongChannel = kUdpHeader + 20;
constexpr std::uint32_t kKeep = 0xffffffffu;
constexpr std::uint32_t kDrop = 0;

sock_filter Op(std::uint16_t code, std::uint32_t k, std::uint8_t jt = 0, std::uint8_t jf = 0) {
  return sock_filter{code, jt, jf, k};
}

// One channel's test at `offset`: its bytes and NUL compared a word, a half-word or a
// byte at a time; any difference jumps to the instruction after the block (the next
// channel's), a full match keeps the datagram.
std::vector<sock_filter> ChannelBlock(const std::string& channel, std::uint32_t offset) {
  std::string bytes = channel;
  bytes.push_back('\0');
  struct Load {
    std::uint16_t size;
    std::uint32_t at, value;
  };
  std::vector<Load> loads;
  for (std::size_t i = 0; i < bytes.size();) {
    const std::size_t n = bytes.size() - i >= 4 ? 4 : bytes.size() - i >= 2 ? 2 : 1;
    std::uint32_t value = 0;
    for (std::size_t b = 0; b < n; ++b) value = (value << 8) | static_cast<std::uint8_t>(bytes[i + b]);
    loads.push_back({static_cast<std::uint16_t>(n == 4 ? BPF_W : n == 2 ? BPF_H : BPF_B),
                     offset + static_cast<std::uint32_t>(i), value});
    i += n;
  }
  const std::size_t length = 2 * loads.size() + 1;
  std::vector<sock_filter> block;
  for (const Load& l : loads) {
    block.push_back(Op(BPF_LD | l.size | BPF_ABS, l.at));
    const std::size_t after = length - block.size() - 1;  // from the jump to the next block
    block.push_back(Op(BPF_JMP | BPF_JEQ | BPF_K, l.value, 0, static_cast<std::uint8_t>(after)));
  }
  block.push_back(Op(BPF_RET | BPF_K, kKeep));
  return block;
}

std::vector<sock_filter> ChannelBlocks(const std::vector<std::string>& channels, std::uint32_t offset) {
  std::vector<sock_filter> all;
  for (const std::string& c : channels) {
    const auto block = ChannelBlock(c, offset);
    all.insert(all.end(), block.begin(), block.end());
  }
  all.push_back(Op(BPF_RET | BPF_K, kDrop));
  return all;
}

}  // namespace

int UdpmPort(const std::string& url) {
  const std::string scheme = "udpm://";
  if (url.rfind(scheme, 0) != 0) return -1;
  const std::size_t end = url.find('?', scheme.size());
  const std::string address = url.substr(scheme.size(), end == std::string::npos ? std::string::npos : end - scheme.size());
  const std::size_t colon = address.rfind(':');
  if (colon == std::string::npos) return 7667;  // LCM's default
  const std::string port = address.substr(colon + 1);
  if (port.empty() || port.size() > 5 || port.find_first_not_of("0123456789") != std::string::npos) return -1;
  const int p = std::stoi(port);
  return p >= 1 && p <= 65535 ? p : -1;
}

bool PlainChannel(const std::string& channel) {
  return !channel.empty() && channel.find_first_of(".[]()*+?{}|^$\\") == std::string::npos;
}

std::vector<sock_filter> ChannelFilterProgram(const std::vector<std::string>& channels) {
  for (const std::string& c : channels) {
    if (!PlainChannel(c)) throw std::invalid_argument("kernel filter: channel \"" + c + "\" is a pattern, not a name");
    if (c.size() > 255) throw std::invalid_argument("kernel filter: channel \"" + c.substr(0, 40) + "...\" is over 255 bytes");
  }
  const std::vector<sock_filter> short_blocks = ChannelBlocks(channels, kShortChannel);
  const std::vector<sock_filter> long_blocks = ChannelBlocks(channels, kLongChannel);
  // The head: which kind of datagram, and for a long message which fragment.
  std::vector<sock_filter> p = {
      Op(BPF_LD | BPF_W | BPF_ABS, kUdpHeader),          // 0: the magic
      Op(BPF_JMP | BPF_JEQ | BPF_K, kShortMagic, 4, 0),  // 1: short -> 6
      Op(BPF_JMP | BPF_JEQ | BPF_K, kLongMagic, 1, 0),   // 2: long -> 4
      Op(BPF_RET | BPF_K, kKeep),                        // 3: not LCM's: LCM judges it
      Op(BPF_LD | BPF_H | BPF_ABS, kFragmentNumber),     // 4
      Op(BPF_JMP | BPF_JEQ | BPF_K, 0, 2, 1),            // 5: the first fragment -> 8, a later -> 7
  };
  const auto ja = [](std::size_t from, std::size_t to) {
    return Op(BPF_JMP | BPF_JA, static_cast<std::uint32_t>(to - from - 1));
  };
  // 6: short messages' blocks begin at 9; 7: a later fragment is kept; 8: the first
  // fragment's blocks follow the short ones.
  p.push_back(ja(6, 9));
  p.push_back(Op(BPF_RET | BPF_K, kKeep));
  p.push_back(ja(8, 9 + short_blocks.size()));
  p.insert(p.end(), short_blocks.begin(), short_blocks.end());
  p.insert(p.end(), long_blocks.begin(), long_blocks.end());
  return p;
}

int FindUdpSocket(int port) {
  int found = -1, count = 0;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator("/proc/self/fd", ec)) {
    int fd = -1;
    try {
      fd = std::stoi(entry.path().filename().string());
    } catch (const std::exception&) {
      continue;
    }
    struct stat st {};
    if (fstat(fd, &st) != 0 || !S_ISSOCK(st.st_mode)) continue;
    int type = 0;
    socklen_t type_len = sizeof type;
    if (getsockopt(fd, SOL_SOCKET, SO_TYPE, &type, &type_len) != 0 || type != SOCK_DGRAM) continue;
    sockaddr_in a{};
    socklen_t len = sizeof a;
    if (getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len) != 0 || a.sin_family != AF_INET) continue;
    if (ntohs(a.sin_port) != port) continue;
    found = fd;
    ++count;
  }
  return count == 1 ? found : -1;
}

bool AttachFilter(int fd, const std::vector<sock_filter>& program) {
  if (program.empty()) {
    const int unused = 0;
    return setsockopt(fd, SOL_SOCKET, SO_DETACH_FILTER, &unused, sizeof unused) == 0 || errno == ENOENT;
  }
  sock_fprog prog{static_cast<unsigned short>(program.size()), const_cast<sock_filter*>(program.data())};
  return setsockopt(fd, SOL_SOCKET, SO_ATTACH_FILTER, &prog, sizeof prog) == 0;
}

}  // namespace rover::bus
