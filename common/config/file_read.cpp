#include "config/file_read.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <cstring>

namespace rover::config {

namespace {

std::string WithArticle(const std::string& noun) {
  const bool vowel = !noun.empty() && std::strchr("aeiouAEIOU", noun[0]) != nullptr;
  return (vowel ? "an " : "a ") + noun;
}

[[noreturn]] void CannotOpen(const std::string& path, int error, const std::string& what) {
  const std::string reason = error == ENOENT ? "" : std::string(": ") + std::strerror(error);
  throw FileReadError(path, "cannot open file" + reason, "a readable " + what);
}

void CheckStat(const std::string& path, const struct stat& st, std::size_t max_bytes,
               const std::string& what) {
  if (!S_ISREG(st.st_mode)) throw FileReadError(path, "not a regular file", WithArticle(what));
  if (static_cast<std::uint64_t>(st.st_size) > max_bytes) {
    throw FileReadError(path, "too large: " + std::to_string(st.st_size) + " bytes",
                        WithArticle(what) + " of at most " + std::to_string(max_bytes) + " bytes");
  }
}

// Closes the descriptor on every path out of the reader.
struct Fd {
  int fd;
  ~Fd() {
    if (fd >= 0) close(fd);
  }
};

}  // namespace

FileReadError::FileReadError(std::string path, std::string problem, std::string expected)
    : ConfigError(path + ": " + problem + " (expected " + expected + ")"),
      path_(std::move(path)),
      problem_(std::move(problem)),
      expected_(std::move(expected)) {}

void CheckRegularFile(const std::string& path, std::size_t max_bytes, const std::string& what) {
  struct stat st {};
  if (stat(path.c_str(), &st) != 0) CannotOpen(path, errno, what);
  CheckStat(path, st, max_bytes, what);
}

std::string ReadBoundedRegularFile(const std::string& path, std::size_t max_bytes,
                                   const std::string& what) {
  // O_NONBLOCK: opening a FIFO with no writer would otherwise wait forever. The checks are
  // made on the opened descriptor, so a file swapped in after a path check cannot slip by.
  const Fd file{open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY)};
  if (file.fd < 0) CannotOpen(path, errno, what);
  struct stat st {};
  if (fstat(file.fd, &st) != 0) CannotOpen(path, errno, what);
  CheckStat(path, st, max_bytes, what);

  // Read at most max_bytes + 1: a file that grows after fstat, or reports size 0 (/proc),
  // is still bounded.
  std::string text;
  text.resize(std::min<std::size_t>(max_bytes + 1, static_cast<std::size_t>(st.st_size) + 4096));
  std::size_t used = 0;
  for (;;) {
    if (used == text.size()) {
      if (text.size() > max_bytes) break;
      text.resize(std::min(max_bytes + 1, text.size() * 2));
    }
    const ssize_t n = read(file.fd, text.data() + used, text.size() - used);
    if (n < 0) {
      if (errno == EINTR) continue;
      throw FileReadError(path, std::string("cannot read file: ") + std::strerror(errno),
                          "a readable " + what);
    }
    if (n == 0) break;
    used += static_cast<std::size_t>(n);
  }
  if (used > max_bytes) {
    throw FileReadError(path, "too large: more than " + std::to_string(max_bytes) + " bytes",
                        WithArticle(what) + " of at most " + std::to_string(max_bytes) + " bytes");
  }
  text.resize(used);
  return text;
}

}  // namespace rover::config
