#include "config/file_read.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <system_error>
#include <vector>

namespace fs = std::filesystem;
using rover::config::CheckRegularFile;
using rover::config::ConfigNode;
using rover::config::FileReadError;
using rover::config::ReadBoundedRegularFile;

namespace {

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const FileReadError& e) {
    return e.what();
  }
  return "";
}

// The directories TempDir made, removed when the test process exits: each ctest entry is a
// process of its own, so nothing is left behind in the temporary folder.
struct TempDirs {
  std::vector<fs::path> dirs;
  ~TempDirs() {
    std::error_code ignored;
    for (const fs::path& d : dirs) fs::remove_all(d, ignored);
  }
};

// A fresh directory per test.
std::string TempDir(const std::string& name) {
  const fs::path dir = fs::path(testing::TempDir()) / ("file_read_" + name + "_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  static TempDirs made;
  made.dirs.push_back(dir);
  return dir.string();
}

void WriteBytes(const std::string& path, std::size_t n, char c) {
  std::ofstream(path, std::ios::binary) << std::string(n, c);
}

}  // namespace

TEST(ReadBoundedRegularFile, ReadsTheWholeFileByteForByte) {
  const std::string path = TempDir("whole") + "/a.yaml";
  const std::string text("a: 1\n\0b: 2\n", 11);
  std::ofstream(path, std::ios::binary) << text;
  EXPECT_EQ(ReadBoundedRegularFile(path, 100, "YAML file"), text);
  EXPECT_EQ(ReadBoundedRegularFile(path, text.size(), "YAML file"), text);  // exactly the bound
}

TEST(ReadBoundedRegularFile, MissingFileIsOneLine) {
  EXPECT_EQ(ErrorOf([] { ReadBoundedRegularFile("/nonexistent/x.yaml", 100, "YAML file"); }),
            "/nonexistent/x.yaml: cannot open file (expected a readable YAML file)");
}

TEST(ReadBoundedRegularFile, DirectoryIsNotARegularFile) {
  const std::string dir = TempDir("dir");
  EXPECT_EQ(ErrorOf([&] { ReadBoundedRegularFile(dir, 100, "YAML file"); }),
            dir + ": not a regular file (expected a YAML file)");
}

TEST(ReadBoundedRegularFile, FifoIsRefusedAtOnceNotWaitedOn) {
  const std::string fifo = TempDir("fifo") + "/pipe.seq";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  const auto start = std::chrono::steady_clock::now();
  EXPECT_EQ(ErrorOf([&] { ReadBoundedRegularFile(fifo, 100, "sequence file"); }),
            fifo + ": not a regular file (expected a sequence file)");
  EXPECT_EQ(ErrorOf([&] { CheckRegularFile(fifo, 100, "PNG image"); }),
            fifo + ": not a regular file (expected a PNG image)");
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 1.0);
}

TEST(ReadBoundedRegularFile, CharacterDeviceIsRefused) {
  // /dev/zero never ends: read naively it grows without bound.
  EXPECT_EQ(ErrorOf([] { ReadBoundedRegularFile("/dev/zero", 1 << 20, "YAML file"); }),
            "/dev/zero: not a regular file (expected a YAML file)");
  EXPECT_EQ(ErrorOf([] { CheckRegularFile("/dev/null", 1 << 20, "image"); }),
            "/dev/null: not a regular file (expected an image)");
}

TEST(ReadBoundedRegularFile, OversizedFileIsRefusedWithItsSize) {
  const std::string path = TempDir("big") + "/big.yaml";
  WriteBytes(path, 1001, 'x');
  EXPECT_EQ(ErrorOf([&] { ReadBoundedRegularFile(path, 1000, "YAML file"); }),
            path + ": too large: 1001 bytes (expected a YAML file of at most 1000 bytes)");
  EXPECT_EQ(ErrorOf([&] { CheckRegularFile(path, 1000, "YAML file"); }),
            path + ": too large: 1001 bytes (expected a YAML file of at most 1000 bytes)");
  EXPECT_EQ(ReadBoundedRegularFile(path, 1001, "YAML file").size(), 1001u);
}

TEST(ReadBoundedRegularFile, FileThatUnderstatesItsSizeIsStillBounded) {
  // /proc files report size 0 and are regular: the reader counts what it really gets.
  EXPECT_FALSE(ReadBoundedRegularFile("/proc/self/status", 1 << 20, "text file").empty());
  EXPECT_EQ(ErrorOf([] { ReadBoundedRegularFile("/proc/self/status", 10, "text file"); }),
            "/proc/self/status: too large: more than 10 bytes (expected a text file of at most 10 bytes)");
}

TEST(ReadBoundedRegularFile, TheErrorKeepsItsParts) {
  try {
    ReadBoundedRegularFile("/dev/zero", 10, "sequence file");
    FAIL() << "no error";
  } catch (const FileReadError& e) {
    EXPECT_EQ(e.path(), "/dev/zero");
    EXPECT_EQ(e.problem(), "not a regular file");
    EXPECT_EQ(e.expected(), "a sequence file");
  }
}

TEST(ConfigNodeLoadFile, RefusesDirectoriesDevicesAndHugeFiles) {
  const std::string dir = TempDir("config");
  EXPECT_EQ(ErrorOf([&] { ConfigNode::LoadFile(dir); }), dir + ": not a regular file (expected a YAML file)");
  EXPECT_EQ(ErrorOf([] { ConfigNode::LoadFile("/dev/zero"); }),
            "/dev/zero: not a regular file (expected a YAML file)");
  const std::string big = dir + "/big.yaml";
  WriteBytes(big, rover::config::kMaxConfigFileBytes + 1, '#');
  EXPECT_EQ(ErrorOf([&] { ConfigNode::LoadFile(big); }),
            big + ": too large: 1048577 bytes (expected a YAML file of at most 1048576 bytes)");
}
