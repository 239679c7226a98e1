// Reading input files with a bound: every config, world, deployment, sequence file and
// dataset text file goes through ReadBoundedRegularFile, so that a FIFO, a character
// device (/dev/zero), a directory or an oversized file gives one line instead of a hang
// or unbounded memory growth:
//   /tmp: not a regular file (expected a YAML file)
//   big.seq: too large: 5000000 bytes (expected a sequence file of at most 1048576 bytes)
#pragma once

#include "config/yaml_config.hpp"

#include <cstddef>
#include <string>

namespace rover::config {

// Size bounds shared by the readers (bytes).
// Every YAML file (configs, worlds, camera models, deployments, scenarios).
inline constexpr std::size_t kMaxConfigFileBytes = 1u << 20;
inline constexpr std::size_t kMaxSequenceFileBytes = 1u << 20;   // operator sequences
inline constexpr std::size_t kMaxDatasetTextBytes = 64u << 20;   // calib.txt, times.txt, poses.txt
inline constexpr std::size_t kMaxImageFileBytes = 64u << 20;     // one image of a dataset

// A file that cannot be read as asked. what() is the one line "<path>: <problem> (expected
// <expected>)"; the parts are kept for callers that format errors their own way (the
// sequence checker's file:line:col).
class FileReadError : public ConfigError {
 public:
  FileReadError(std::string path, std::string problem, std::string expected);
  const std::string& path() const { return path_; }
  const std::string& problem() const { return problem_; }
  const std::string& expected() const { return expected_; }

 private:
  std::string path_, problem_, expected_;
};

// Checks that `path` names a regular file of at most `max_bytes` (following symlinks),
// without blocking on a FIFO. `what` names the expected content without an article,
// e.g. "YAML file". Throws FileReadError.
void CheckRegularFile(const std::string& path, std::size_t max_bytes, const std::string& what);

// Reads the whole of a regular file of at most `max_bytes`. Opens without blocking (a FIFO
// is refused, not waited on), checks the opened file itself (no race with a rename), and
// never reads more than max_bytes + 1 bytes even if the file grows or lies about its size
// (/proc). Throws FileReadError:
//   "<path>: cannot open file (expected a readable <what>)"   (missing; other reasons
//                                                              such as "permission denied"
//                                                              follow "cannot open file:")
//   "<path>: not a regular file (expected a <what>)"
//   "<path>: too large: N bytes (expected a <what> of at most M bytes)"
std::string ReadBoundedRegularFile(const std::string& path, std::size_t max_bytes,
                                   const std::string& what);

}  // namespace rover::config
