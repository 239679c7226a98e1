#include "fake_gv_camera.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <cstring>
#include <thread>
#include <vector>

extern char** environ;

namespace rover::camera_hw::test {

namespace {

// One GVCP DISCOVERY_CMD (GigE Vision 2.0, section 16.1) to address:3956; true when the
// camera answers with a DISCOVERY_ACK. Sent to the loopback address only.
bool Discovered(const std::string& address) {
  const int fd = socket(AF_INET, SOCK_DGRAM, 0);
  if (fd < 0) return false;
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(3956);
  inet_pton(AF_INET, address.c_str(), &to.sin_addr);
  const unsigned char command[8] = {0x42, 0x11, 0x00, 0x02, 0x00, 0x00, 0x00, 0x01};
  bool answered = false;
  if (sendto(fd, command, sizeof(command), 0, reinterpret_cast<sockaddr*>(&to), sizeof(to)) == sizeof(command)) {
    pollfd p{fd, POLLIN, 0};
    unsigned char reply[600];
    if (poll(&p, 1, 200) == 1) {
      const ssize_t n = recv(fd, reply, sizeof(reply), 0);
      answered = n >= 8 && reply[2] == 0x00 && reply[3] == 0x03;  // DISCOVERY_ACK
    }
  }
  close(fd);
  return answered;
}

}  // namespace

bool FakeGvCamera::Installed() {
  const char* path = std::getenv("PATH");
  std::string dirs = path ? path : "/usr/bin:/bin";
  std::size_t start = 0;
  while (start <= dirs.size()) {
    const std::size_t end = dirs.find(':', start);
    const std::string dir = dirs.substr(start, end == std::string::npos ? std::string::npos : end - start);
    if (!dir.empty() && access((dir + "/" + kProgram).c_str(), X_OK) == 0) return true;
    if (end == std::string::npos) break;
    start = end + 1;
  }
  return false;
}

bool FakeGvCamera::Start(int lost_per_thousand) {
  Kill();
  std::vector<std::string> args = {kProgram, "-i", address_, "-s", serial_};
  if (lost_per_thousand > 0) {
    args.push_back("-r");
    args.push_back(std::to_string(lost_per_thousand));
  }
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  if (posix_spawnp(&pid_, kProgram, nullptr, nullptr, argv.data(), environ) != 0) {
    pid_ = -1;
    return false;
  }
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (std::chrono::steady_clock::now() < until) {
    if (Discovered(address_)) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return false;
}

void FakeGvCamera::Kill() {
  if (pid_ <= 0) return;
  kill(pid_, SIGKILL);
  waitpid(pid_, nullptr, 0);
  pid_ = -1;
}

}  // namespace rover::camera_hw::test
