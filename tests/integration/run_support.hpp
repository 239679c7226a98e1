// Running the project's executables from integration tests.
#pragma once

#include <array>
#include <cstdio>
#include <filesystem>
#include <string>
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

// A private LCM URL for one test: two buses on LCM 1.3.1 must differ by port. Even ports:
// virtual time's sync reports use port + 1 (bus/virtual_time.hpp).
inline std::string PrivateUrl(int offset) {
  // Below Linux's ephemeral range (32768 up), where an outgoing socket could hold the
  // port, and below scenario_runner's own 20000-31999.
  const int port = 10000 + 2 * static_cast<int>((getpid() * 7 + offset) % 5000);
  return "udpm://239.255.76.67:" + std::to_string(port) + "?ttl=0&recv_buf_size=8388608";
}

}  // namespace rover::test
