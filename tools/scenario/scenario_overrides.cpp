#include "scenario/scenario_overrides.hpp"

#include <filesystem>
#include <fstream>

namespace rover::tools {

namespace fs = std::filesystem;
using config::ConfigError;

namespace {

std::vector<std::string> SplitKey(const std::string& key) {
  std::vector<std::string> parts;
  std::size_t start = 0;
  while (true) {
    const std::size_t dot = key.find('.', start);
    parts.push_back(key.substr(start, dot == std::string::npos ? std::string::npos : dot - start));
    if (dot == std::string::npos) break;
    start = dot + 1;
  }
  return parts;
}

bool IsIndex(const std::string& s) {
  return !s.empty() && s.size() < 7 && s.find_first_not_of("0123456789") == std::string::npos;
}

void WriteYaml(const YAML::Node& root, const std::string& path) {
  std::ofstream out(path);
  out << YAML::Dump(root) << "\n";
  if (!out) throw ConfigError(path + ": cannot write the overridden copy");
}

}  // namespace

std::vector<ConfigOverride> LoadOverrides(const config::ConfigNode& node) {
  std::vector<ConfigOverride> out;
  if (node.IsNull()) return out;
  if (!node.IsMap()) node.Fail("expected a mapping of dotted keys to values, e.g. mobility.seed: 7");
  for (const std::string& key : node.Keys()) {
    for (const std::string& part : SplitKey(key)) {
      if (part.empty()) node[key].Fail("empty component in the dotted key (expected e.g. mobility.seed)");
    }
    out.push_back({key, YAML::Clone(node.yaml()[key])});
  }
  return out;
}

void ApplyOverrides(YAML::Node& root, const std::vector<ConfigOverride>& overrides, const std::string& what) {
  for (const ConfigOverride& o : overrides) {
    const std::vector<std::string> parts = SplitKey(o.key);
    // yaml-cpp nodes are handles: assigning through a copy writes into the tree, but
    // rebinding one with `=` would not, hence the explicit stack of handles.
    std::vector<YAML::Node> path{root};
    for (std::size_t i = 0; i < parts.size(); ++i) {
      YAML::Node here = path.back();
      const std::string& part = parts[i];
      const bool last = i + 1 == parts.size();
      if (here.IsSequence()) {
        if (!IsIndex(part) || std::stoul(part) >= here.size()) {
          throw ConfigError(what + ": " + o.key + ": '" + part + "' is not an index of the list of " +
                            std::to_string(here.size()) + " (expected 0 to " +
                            std::to_string(here.size() == 0 ? 0 : here.size() - 1) + ")");
        }
        if (last) {
          here[std::stoul(part)] = YAML::Clone(o.value);
        } else {
          path.push_back(here[std::stoul(part)]);
        }
        continue;
      }
      if (here.IsScalar()) {
        throw ConfigError(what + ": " + o.key + ": '" + parts[i - 1] + "' is a value, not a section (expected a key that exists as a section)");
      }
      if (last) {
        here[part] = YAML::Clone(o.value);
      } else {
        if (!here[part] || here[part].IsNull()) here[part] = YAML::Node(YAML::NodeType::Map);
        path.push_back(here[part]);
      }
    }
  }
}

RunConfigs PrepareRunConfigs(const std::string& rover_config, const std::vector<ConfigOverride>& overrides,
                             const std::string& world, const std::vector<ConfigOverride>& world_overrides,
                             const std::string& out_dir) {
  RunConfigs r{rover_config, world};
  auto load = [](const std::string& path) {
    try {
      return YAML::LoadFile(path);
    } catch (const YAML::Exception& e) {
      throw ConfigError(path + ": cannot read (" + e.msg + ")");
    }
  };
  if (!overrides.empty()) {
    YAML::Node root = load(rover_config);
    ApplyOverrides(root, overrides, rover_config + " (scenario overrides)");
    // The rigs (NAVCAM and HAZCAM) are named relative to the config file; the copy lives
    // elsewhere. An empty HAZCAM rig (none) stays empty.
    auto absolute_rig = [&rover_config](YAML::Node section) {
      if (!section || !section.IsMap() || !section["rig"] || !section["rig"].IsScalar()) return;
      const fs::path rig = section["rig"].as<std::string>();
      if (!rig.empty() && rig.is_relative()) {
        section["rig"] = fs::absolute(fs::path(rover_config).parent_path() / rig).lexically_normal().string();
      }
    };
    if (root["capture"]) {
      absolute_rig(root["capture"]);
      absolute_rig(root["capture"]["hazcam"]);
    }
    r.rover_config = (fs::path(out_dir) / "rover.yaml").string();
    WriteYaml(root, r.rover_config);
  }
  if (!world_overrides.empty()) {
    YAML::Node root = load(world);
    ApplyOverrides(root, world_overrides, world + " (scenario world_overrides)");
    r.world = (fs::path(out_dir) / "world.yaml").string();
    WriteYaml(root, r.world);
  }
  return r;
}

}  // namespace rover::tools
