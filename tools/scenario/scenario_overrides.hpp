// Scenario overrides: a scenario changes its rover config and world by dotted keys, without
// copying files. The runner applies them to copies in its output directory and hands the
// copies to the deployment's processes, which check every key as usual (a misspelt key is
// an "unknown key" error from the process that reads it).
#pragma once

#include "config/yaml_config.hpp"

#include <yaml-cpp/yaml.h>

#include <string>
#include <vector>

namespace rover::tools {

// "mobility.slip.dragged_wheel.wheel" = right_front; "slopes.0.angle_deg" = 29.
struct ConfigOverride {
  std::string key;   // dotted; a whole number indexes a list
  YAML::Node value;  // a scalar, list or map
};

// A mapping of dotted keys to values. Throws config::ConfigError naming the file and key for
// an empty key or an empty key component ("a..b").
std::vector<ConfigOverride> LoadOverrides(const config::ConfigNode& node);

// Sets each key in `root`, in order: missing map keys (and maps on the way) are created; a
// list index must exist. Throws config::ConfigError "<what>: <key>: <problem>" when a key
// runs through a scalar or past the end of a list.
void ApplyOverrides(YAML::Node& root, const std::vector<ConfigOverride>& overrides,
                    const std::string& what);

// The files a run uses: the originals when nothing is overridden, otherwise copies with
// the overrides applied, written to `out_dir` as rover.yaml and world.yaml. A relative
// `capture.rig` or `capture.hazcam.rig` (relative to the rover config) is made absolute in
// the copy.
struct RunConfigs {
  std::string rover_config;
  std::string world;
};
RunConfigs PrepareRunConfigs(const std::string& rover_config, const std::vector<ConfigOverride>& overrides,
                             const std::string& world, const std::vector<ConfigOverride>& world_overrides,
                             const std::string& out_dir);

}  // namespace rover::tools
