// PrivateUrl (run_support.hpp): test processes that ctest -j runs side by side get
// different buses. The case that collided before: a second process whose pid and offset
// point at the first one's port (pid * 7 + offset the same, modulo the range).
#include "integration/run_support.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <set>
#include <string>

#include <sys/wait.h>
#include <unistd.h>

namespace rover::test {
namespace {

TEST(PrivateUrl, SameOffsetSameUrlOtherOffsetsOtherPorts) {
  const std::string a = PrivateUrl(101);
  EXPECT_EQ(PrivateUrl(101), a);
  std::set<std::string> urls{a};
  for (int offset = 102; offset < 120; ++offset) urls.insert(PrivateUrl(offset));
  EXPECT_EQ(urls.size(), 19u);
  for (const auto& url : urls) {
    const int port = std::stoi(url.substr(std::strlen("udpm://239.255.76.67:")));
    EXPECT_EQ(port % 2, 0) << url << ": sync reports need port + 1 free";
    EXPECT_GE(port, 10000) << url;
    EXPECT_LT(port, 20000) << url;
  }
}

// A child process (another test, as ctest -j runs them) asks with the offset that points
// at the parent's port: it gets another one while the parent lives.
TEST(PrivateUrl, AnotherProcessPointedAtTheSamePortGetsAnother) {
  const std::string parent_url = PrivateUrl(7);
  const pid_t parent = getpid();
  int fds[2];
  ASSERT_EQ(pipe(fds), 0);
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    close(fds[0]);
    // pid * 7 + offset equal to the parent's, modulo the 5000 pairs.
    const long offset = ((7L * (parent - getpid()) + 7) % 5000 + 5000) % 5000;
    const std::string url = PrivateUrl(static_cast<int>(offset));
    const ssize_t n = write(fds[1], url.data(), url.size());
    _exit(n == static_cast<ssize_t>(url.size()) ? 0 : 1);
  }
  close(fds[1]);
  std::string child_url;
  char buf[256];
  for (ssize_t n; (n = read(fds[0], buf, sizeof buf)) > 0;) child_url.append(buf, static_cast<std::size_t>(n));
  close(fds[0]);
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  ASSERT_FALSE(child_url.empty());
  EXPECT_NE(child_url, parent_url) << "two test processes got the same bus";
}

}  // namespace
}  // namespace rover::test
