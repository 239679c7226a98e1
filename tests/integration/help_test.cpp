// Every program the build makes answers --help with a usage text and exit code 0: the
// processes, the tools, the benchmarks and the test binaries alike (a new user's first
// try). The list is whatever is in build/bin, so a new program is covered when it is
// added; a few that must exist guard against an empty folder passing.
#include "integration/run_support.hpp"

#include <gtest/gtest.h>

#include <sys/stat.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

std::vector<std::string> Programs() {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(std::string(ROVER_BINARY_DIR) + "/bin")) {
    struct stat st {};
    if (!entry.is_regular_file() || stat(entry.path().c_str(), &st) != 0 || !(st.st_mode & S_IXUSR)) continue;
    names.push_back(entry.path().filename().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

TEST(Help, EveryProgramAnswersHelpWithExitCode0) {
  const auto names = Programs();
  for (const char* must : {"rover_sim", "sequence_executor", "launcher", "scenario_runner", "rover_seq",
                           "seq_check", "rover_plot", "rover_console", "vo_eval", "render_benchmark"}) {
    EXPECT_TRUE(std::find(names.begin(), names.end(), must) != names.end())
        << must << " is not in " << ROVER_BINARY_DIR << "/bin (build everything first)";
  }
  for (const auto& name : names) {
    const auto r = rover::test::RunCommand("timeout 20 " + rover::test::Bin(name) + " --help </dev/null");
    EXPECT_EQ(r.exit_code, 0) << name << " --help exited " << r.exit_code << ":\n"
                              << r.output.substr(0, 400);
    // A usage text; a test binary prints Google Test's own.
    std::string text = r.output;
    std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return std::tolower(c); });
    EXPECT_TRUE(text.find("usage") != std::string::npos || text.find("google test") != std::string::npos)
        << name << " --help printed no usage:\n" << r.output.substr(0, 400);
  }
}

}  // namespace
