// YAML configuration with errors that name the file, the key and what was expected.
//
// Every options struct in the project is a plain struct with defaults. A loader reads
// it through ConfigNode, which keeps the file name and the dotted key path, so that a
// bad value produces one line such as
//   configs/vo.yaml: vo.ransac_iterations: expected an integer >= 1, got "abc"
// Unknown keys are errors too (CheckKeys), so a typo is never silently accepted.
#pragma once

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <initializer_list>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace rover::config {

// A caller mistake in a config file or argument. what() is the one-line message.
class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class ConfigNode {
 public:
  // Reads a YAML file: a regular file of at most kMaxConfigFileBytes (config/file_read.hpp).
  // Throws ConfigError "<path>: <reason>" if it cannot be read or parsed.
  static ConfigNode LoadFile(const std::string& path);
  // Parses YAML text; `source_name` stands in for the file name in messages.
  static ConfigNode FromString(const std::string& text, const std::string& source_name);

  ConfigNode() = default;
  ConfigNode(YAML::Node node, std::string source, std::string path)
      : node_(std::move(node)), source_(std::move(source)), path_(std::move(path)) {}

  bool Has(const std::string& key) const;
  bool IsMap() const { return node_.IsMap(); }
  bool IsSequence() const { return node_.IsSequence(); }
  bool IsNull() const { return !node_ || node_.IsNull(); }
  std::size_t size() const { return node_.size(); }

  // Child map entry (may be absent: then IsNull()).
  ConfigNode operator[](const std::string& key) const;
  // Sequence element.
  ConfigNode at(std::size_t index) const;
  // Keys of a map, in file order.
  std::vector<std::string> Keys() const;

  // Throws if the node holds a key not in `allowed`.
  void CheckKeys(std::initializer_list<const char*> allowed) const;
  void CheckKeys(const std::vector<std::string>& allowed) const;

  // Optional values: leave `out` untouched when the key is absent; throw when present
  // but of the wrong type or out of [lo, hi].
  void Get(const std::string& key, double& out,
           double lo = -std::numeric_limits<double>::infinity(),
           double hi = std::numeric_limits<double>::infinity()) const;
  void Get(const std::string& key, int& out, int lo = std::numeric_limits<int>::min(),
           int hi = std::numeric_limits<int>::max()) const;
  void Get(const std::string& key, std::int64_t& out) const;
  void Get(const std::string& key, std::uint64_t& out) const;
  void Get(const std::string& key, bool& out) const;
  void Get(const std::string& key, std::string& out) const;
  // A fixed-length list of numbers, e.g. a 3-vector.
  void Get(const std::string& key, std::vector<double>& out, std::size_t expected_size = 0) const;
  // One of a set of words.
  void GetEnum(const std::string& key, std::string& out,
               std::initializer_list<const char*> choices) const;

  // Required values: throw "missing key" when absent.
  double RequireDouble(const std::string& key,
                       double lo = -std::numeric_limits<double>::infinity(),
                       double hi = std::numeric_limits<double>::infinity()) const;
  std::string RequireString(const std::string& key) const;
  std::vector<double> RequireVector(const std::string& key, std::size_t expected_size = 0) const;

  // Conversions of this node itself.
  double AsDouble(double lo = -std::numeric_limits<double>::infinity(),
                  double hi = std::numeric_limits<double>::infinity()) const;
  std::string AsString() const;
  std::vector<double> AsVector(std::size_t expected_size = 0) const;

  // "<source>: <path>: <message>" as a ConfigError.
  [[noreturn]] void Fail(const std::string& message) const;

  const std::string& source() const { return source_; }
  const std::string& path() const { return path_; }
  const YAML::Node& yaml() const { return node_; }

 private:
  std::string ChildPath(const std::string& key) const;
  std::string Describe() const;  // the node's text, quoted, for messages

  YAML::Node node_;
  std::string source_;
  std::string path_;
};

}  // namespace rover::config
