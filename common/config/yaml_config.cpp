#include "config/yaml_config.hpp"

#include "config/file_read.hpp"

#include <algorithm>
#include <sstream>

namespace rover::config {

namespace {

std::string Quote(const std::string& s) {
  std::string shown = s.size() > 40 ? s.substr(0, 40) + "..." : s;
  return "\"" + shown + "\"";
}

bool ParseDouble(const std::string& text, double& value) {
  // yaml-cpp accepts ".nan"/".inf"; a config never wants them, so parse strictly.
  try {
    std::size_t used = 0;
    value = std::stod(text, &used);
    return used == text.size() && std::isfinite(value);
  } catch (const std::exception&) {
    return false;
  }
}

std::string RangeText(double lo, double hi) {
  std::ostringstream os;
  const bool has_lo = std::isfinite(lo), has_hi = std::isfinite(hi);
  if (has_lo && has_hi) {
    os << " in [" << lo << ", " << hi << "]";
  } else if (has_lo) {
    os << " >= " << lo;
  } else if (has_hi) {
    os << " <= " << hi;
  }
  return os.str();
}

}  // namespace

ConfigNode ConfigNode::LoadFile(const std::string& path) {
  return FromString(ReadBoundedRegularFile(path, kMaxConfigFileBytes, "YAML file"), path);
}

ConfigNode ConfigNode::FromString(const std::string& text, const std::string& source_name) {
  try {
    YAML::Node node = YAML::Load(text);
    if (!node || node.IsNull()) node = YAML::Node(YAML::NodeType::Map);
    if (!node.IsMap()) {
      throw ConfigError(source_name + ": expected a YAML mapping (key: value) at top level");
    }
    return ConfigNode(node, source_name, "");
  } catch (const YAML::Exception& e) {
    throw ConfigError(source_name + ":" + std::to_string(e.mark.line + 1) + ":" +
                      std::to_string(e.mark.column + 1) + ": invalid YAML: " + e.msg);
  }
}

std::string ConfigNode::ChildPath(const std::string& key) const {
  return path_.empty() ? key : path_ + "." + key;
}

std::string ConfigNode::Describe() const {
  if (!node_) return "nothing";
  if (node_.IsScalar()) return Quote(node_.Scalar());
  if (node_.IsSequence()) return "a list";
  if (node_.IsMap()) return "a mapping";
  return "null";
}

void ConfigNode::Fail(const std::string& message) const {
  throw ConfigError(source_ + ": " + (path_.empty() ? std::string("(top level)") : path_) +
                    ": " + message);
}

bool ConfigNode::Has(const std::string& key) const {
  if (!node_ || !node_.IsMap()) return false;
  const YAML::Node child = node_[key];
  return child && !child.IsNull();
}

ConfigNode ConfigNode::operator[](const std::string& key) const {
  if (node_ && node_.IsMap()) {
    const YAML::Node child = node_[key];
    if (child) return ConfigNode(child, source_, ChildPath(key));
  }
  return ConfigNode(YAML::Node(), source_, ChildPath(key));
}

ConfigNode ConfigNode::at(std::size_t index) const {
  if (!node_ || !node_.IsSequence() || index >= node_.size()) {
    Fail("expected a list with at least " + std::to_string(index + 1) + " entries");
  }
  return ConfigNode(node_[index], source_, path_ + "[" + std::to_string(index) + "]");
}

std::vector<std::string> ConfigNode::Keys() const {
  std::vector<std::string> keys;
  if (!node_ || !node_.IsMap()) return keys;
  for (const auto& kv : node_) keys.push_back(kv.first.as<std::string>());
  return keys;
}

void ConfigNode::CheckKeys(std::initializer_list<const char*> allowed) const {
  CheckKeys(std::vector<std::string>(allowed.begin(), allowed.end()));
}

void ConfigNode::CheckKeys(const std::vector<std::string>& allowed) const {
  if (!node_ || node_.IsNull()) return;
  if (!node_.IsMap()) Fail("expected a mapping (key: value), got " + Describe());
  for (const auto& key : Keys()) {
    if (std::find(allowed.begin(), allowed.end(), key) == allowed.end()) {
      std::string list;
      for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
      throw ConfigError(source_ + ": " + ChildPath(key) + ": unknown key (expected one of: " +
                        list + ")");
    }
  }
}

double ConfigNode::AsDouble(double lo, double hi) const {
  double value = 0;
  if (!node_ || !node_.IsScalar() || !ParseDouble(node_.Scalar(), value)) {
    Fail("expected a finite number" + RangeText(lo, hi) + ", got " + Describe());
  }
  if (value < lo || value > hi) {
    Fail("expected a number" + RangeText(lo, hi) + ", got " + Describe());
  }
  return value;
}

std::string ConfigNode::AsString() const {
  if (!node_ || !node_.IsScalar()) Fail("expected a text value, got " + Describe());
  return node_.Scalar();
}

std::vector<double> ConfigNode::AsVector(std::size_t expected_size) const {
  if (!node_ || !node_.IsSequence()) {
    Fail("expected a list of " +
         (expected_size ? std::to_string(expected_size) + " numbers" : std::string("numbers")) +
         ", got " + Describe());
  }
  if (expected_size != 0 && node_.size() != expected_size) {
    Fail("expected a list of " + std::to_string(expected_size) + " numbers, got " +
         std::to_string(node_.size()));
  }
  std::vector<double> out;
  for (std::size_t i = 0; i < node_.size(); ++i) out.push_back(at(i).AsDouble());
  return out;
}

void ConfigNode::Get(const std::string& key, double& out, double lo, double hi) const {
  if (Has(key)) out = (*this)[key].AsDouble(lo, hi);
}

void ConfigNode::Get(const std::string& key, int& out, int lo, int hi) const {
  if (!Has(key)) return;
  const ConfigNode child = (*this)[key];
  const std::string text = child.node_.IsScalar() ? child.node_.Scalar() : "";
  try {
    std::size_t used = 0;
    const long value = std::stol(text, &used);
    if (used == text.size() && value >= lo && value <= hi) {
      out = static_cast<int>(value);
      return;
    }
  } catch (const std::exception&) {
  }
  child.Fail("expected an integer" + RangeText(lo, hi) + ", got " + child.Describe());
}

void ConfigNode::Get(const std::string& key, std::int64_t& out) const {
  if (!Has(key)) return;
  const ConfigNode child = (*this)[key];
  const std::string text = child.node_.IsScalar() ? child.node_.Scalar() : "";
  try {
    std::size_t used = 0;
    const long long value = std::stoll(text, &used);
    if (used == text.size()) {
      out = value;
      return;
    }
  } catch (const std::exception&) {
  }
  child.Fail("expected an integer, got " + child.Describe());
}

void ConfigNode::Get(const std::string& key, std::uint64_t& out) const {
  if (!Has(key)) return;
  const ConfigNode child = (*this)[key];
  const std::string text = child.node_.IsScalar() ? child.node_.Scalar() : "";
  try {
    std::size_t used = 0;
    if (!text.empty() && text[0] != '-') {
      const unsigned long long value = std::stoull(text, &used);
      if (used == text.size()) {
        out = value;
        return;
      }
    }
  } catch (const std::exception&) {
  }
  child.Fail("expected a non-negative integer, got " + child.Describe());
}

void ConfigNode::Get(const std::string& key, bool& out) const {
  if (!Has(key)) return;
  const ConfigNode child = (*this)[key];
  const std::string text = child.node_.IsScalar() ? child.node_.Scalar() : "";
  if (text == "true" || text == "yes" || text == "on") {
    out = true;
  } else if (text == "false" || text == "no" || text == "off") {
    out = false;
  } else {
    child.Fail("expected true or false, got " + child.Describe());
  }
}

void ConfigNode::Get(const std::string& key, std::string& out) const {
  if (Has(key)) out = (*this)[key].AsString();
}

void ConfigNode::Get(const std::string& key, std::vector<double>& out,
                     std::size_t expected_size) const {
  if (Has(key)) out = (*this)[key].AsVector(expected_size);
}

void ConfigNode::GetEnum(const std::string& key, std::string& out,
                         std::initializer_list<const char*> choices) const {
  if (!Has(key)) return;
  const ConfigNode child = (*this)[key];
  const std::string value = child.AsString();
  std::string list;
  for (const char* c : choices) {
    if (value == c) {
      out = value;
      return;
    }
    list += (list.empty() ? "" : ", ") + std::string(c);
  }
  child.Fail("expected one of: " + list + ", got " + child.Describe());
}

double ConfigNode::RequireDouble(const std::string& key, double lo, double hi) const {
  if (!Has(key)) Fail("missing key \"" + key + "\" (expected a number" + RangeText(lo, hi) + ")");
  return (*this)[key].AsDouble(lo, hi);
}

std::string ConfigNode::RequireString(const std::string& key) const {
  if (!Has(key)) Fail("missing key \"" + key + "\" (expected a text value)");
  return (*this)[key].AsString();
}

std::vector<double> ConfigNode::RequireVector(const std::string& key,
                                              std::size_t expected_size) const {
  if (!Has(key)) Fail("missing key \"" + key + "\" (expected a list of numbers)");
  return (*this)[key].AsVector(expected_size);
}

}  // namespace rover::config
