// Runs configs/scenarios/NAME.yaml through scenario_runner (no pictures: they cost wall time
// and the assertions read summary.json) and returns its summary.json. The runner exits 0
// only when the run met every entry of the scenario's `expect:`.
#pragma once

#include "integration/run_support.hpp"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <string>

namespace rover::test {

// `prefix` keeps each test file's output folders apart under build/test-out/.
inline YAML::Node RunScenarioSummary(const std::string& prefix, const std::string& name) {
  const std::string out = OutDir(prefix + name);
  const auto result = RunCommand(Bin("scenario_runner") + " configs/scenarios/" + name +
                                 ".yaml --out " + out + " --quiet --no-plot");
  EXPECT_EQ(result.exit_code, 0) << result.output;
  EXPECT_TRUE(std::filesystem::exists(out + "/log.lcm")) << "no log written";
  return YAML::LoadFile(out + "/summary.json");
}

inline std::string Detail(const YAML::Node& s) { return s["detail"].as<std::string>(""); }

}  // namespace rover::test
