// Running the project's executables from integration tests.
#pragma once

#include <array>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <map>
#include <mutex>
#include <stdexcept>
#include <string>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

namespace rover::test {

inline std::string SourceDir() { return ROVER_SOURCE_DIR; }
inline std::string Bin(const std::string& name) { return std::string(ROVER_BINARY_DIR) + "/bin/" + name; }

// A fresh output directory under the build tree.
inline std::string OutDir(const std::string& name) {
  const std::string dir = std::string(ROVER_BINARY_DIR) + "/test-out/" + name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

struct CommandResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr
};

// Runs a shell command from the source root (configs are relative to it).
inline CommandResult RunCommand(const std::string& command) {
  CommandResult r;
  const std::string full = "cd '" + SourceDir() + "' && " + command + " 2>&1";
  FILE* pipe = popen(full.c_str(), "r");
  if (pipe == nullptr) return r;
  std::array<char, 4096> buf;
  while (fgets(buf.data(), buf.size(), pipe) != nullptr) r.output += buf.data();
  const int status = pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

namespace detail {

// Binds TCP port `port` and keeps the socket open for the rest of this process: a
// reservation the kernel ends when the process ends, however it ends. False when another
// process holds the port.
inline bool ReserveTcpPort(int port) {
  const int fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return false;
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  a.sin_addr.s_addr = htonl(INADDR_ANY);
  if (bind(fd, reinterpret_cast<const sockaddr*>(&a), sizeof a) != 0) {
    close(fd);
    return false;
  }
  return true;  // fd stays open on purpose: it is the reservation
}

// Whether LCM could receive on UDP `port` (it binds with SO_REUSEADDR, so only a socket
// that does not share the port stops it).
inline bool UdpPortFree(int port) {
  const int fd = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return true;
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

}  // namespace detail

// A private LCM URL for one test: two buses on LCM 1.3.1 must differ by port. Even ports:
// virtual time's sync reports use port + 1 (bus/virtual_time.hpp). Below Linux's ephemeral
// range (32768 up), where an outgoing socket could hold the port, and below
// scenario_runner's own 20000-31999.
//
// Unique across the test processes `ctest -j` runs side by side: a port computed from the
// pid and `offset` alone collided (consecutive pids with offsets 7 apart got the same
// one), and LCM's UDP sockets share a port without complaint, so two tests then heard
// each other's traffic. So each port is reserved for the life of this process by binding
// the same number over TCP, which, unlike LCM's UDP sockets, one process at a time can
// hold: the search starts where the pid and `offset` point and takes the first port no
// other test process holds. The same `offset` gives the same URL again in one process.
inline std::string PrivateUrl(int offset) {
  static std::mutex mutex;
  static std::map<int, int> taken;  // offset -> port, this process's reservations
  std::lock_guard<std::mutex> lock(mutex);
  auto url = [](int port) {
    return "udpm://239.255.76.67:" + std::to_string(port) + "?ttl=0&recv_buf_size=8388608";
  };
  if (const auto it = taken.find(offset); it != taken.end()) return url(it->second);
  constexpr int kPairs = 5000;  // ports 10000 to 19999
  const long spread = static_cast<long>(getpid()) * 7 + offset;
  const int start = static_cast<int>((spread % kPairs + kPairs) % kPairs);
  for (int i = 0; i < kPairs; ++i) {
    const int port = 10000 + 2 * ((start + i) % kPairs);
    // A port this process reserved already fails the TCP bind too.
    if (!detail::UdpPortFree(port) || !detail::UdpPortFree(port + 1) || !detail::ReserveTcpPort(port)) continue;
    taken[offset] = port;
    return url(port);
  }
  throw std::runtime_error("PrivateUrl: every port pair from 10000 to 19999 is held (expected a free one)");
}

}  // namespace rover::test
