// Signing and verifying command messages (those with an `auth_t auth` member) with
// common/auth: the tag is HMAC-SHA256 over the message's LCM encoding, made with
// auth.sender and auth.counter filled in and auth.tag empty (lcmtypes/auth_t.lcm).
//
// Sign last: any field set after SignMessage (utime, pub_seq, ...) breaks the tag.
// The Bus does this for every message type that has an `auth` member when a key is
// configured (`auth:` in the process's config, LoadConfiguredKey below).
#pragma once

#include "auth/auth.hpp"
#include "config/yaml_config.hpp"

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace rover::bus {

// A message type that carries authentication.
template <class Msg>
concept Authenticated = requires(Msg msg) {
  msg.auth.sender;
  msg.auth.counter;
  msg.auth.tag_size;
  msg.auth.tag;
};

// The message's LCM encoding (fingerprint included, so a tag also binds the type).
template <class Msg>
std::vector<std::uint8_t> EncodeMessage(const Msg& msg) {
  const int size = msg.getEncodedSize();
  if (size < 0) throw std::runtime_error(std::string("cannot encode ") + Msg::getTypeName());
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(size));
  if (msg.encode(bytes.data(), 0, size) != size) {
    throw std::runtime_error(std::string("cannot encode ") + Msg::getTypeName());
  }
  return bytes;
}

// Sets msg.auth (sender, the signer's next counter, tag) so that receivers holding the
// same key accept it once.
template <Authenticated Msg>
void SignMessage(Msg& msg, auth::Signer& signer) {
  msg.auth.sender = signer.sender();
  msg.auth.counter = signer.NextCounter();
  msg.auth.tag.clear();
  msg.auth.tag_size = 0;
  const std::vector<std::uint8_t> bytes = EncodeMessage(msg);
  const auth::Tag tag = signer.Sign(bytes.data(), bytes.size());
  msg.auth.tag.assign(tag.begin(), tag.end());
  msg.auth.tag_size = static_cast<std::int32_t>(tag.size());
}

// nullopt when `msg` carries a right tag and a fresh counter (which the verifier then
// records); otherwise the one-line reason (missing tag, wrong tag, replayed counter...).
template <Authenticated Msg>
std::optional<std::string> VerifyMessage(const Msg& msg, auth::Verifier& verifier) {
  const auto& a = msg.auth;
  if (a.tag_size < 0 || static_cast<std::size_t>(a.tag_size) != a.tag.size()) {
    return "auth.tag_size " + std::to_string(a.tag_size) + " disagrees with the tag's " +
           std::to_string(a.tag.size()) + " bytes";
  }
  Msg unsigned_copy = msg;
  unsigned_copy.auth.tag.clear();
  unsigned_copy.auth.tag_size = 0;
  std::vector<std::uint8_t> bytes;
  try {
    bytes = EncodeMessage(unsigned_copy);
  } catch (const std::exception& e) {
    return std::string(e.what()) + " to check its tag";
  }
  return verifier.Verify(a.sender, a.counter, bytes.data(), bytes.size(),
                         a.tag.empty() ? nullptr : a.tag.data(), a.tag.size());
}

// The `auth:` section of a process's config:
//   auth:
//     key_file: /etc/rover/rover.key   # the deployment's key (configs/systemd/README.md)
//     required: true                   # refuse to start without a key
// Returns the key, or nullopt when no key_file is set (commands go unsigned and
// unchecked). Throws config::ConfigError with one line naming the file and key when the
// section is malformed, required without a key_file, or the key file is unusable.
inline std::optional<auth::Key> LoadConfiguredKey(const config::ConfigNode& root) {
  const config::ConfigNode section = root["auth"];
  if (section.IsNull()) return std::nullopt;
  if (!section.IsMap()) section.Fail("expected a mapping with key_file and required");
  section.CheckKeys({"key_file", "required"});
  std::string key_file;
  bool required = false;
  section.Get("key_file", key_file);
  section.Get("required", required);
  if (key_file.empty()) {
    if (required) {
      section["key_file"].Fail(
          "missing (auth.required is true: expected the deployment's key file)");
    }
    return std::nullopt;
  }
  try {
    return auth::Key::LoadFile(key_file);
  } catch (const auth::KeyError& e) {
    section["key_file"].Fail(e.what());
  }
  return std::nullopt;  // not reached: Fail throws
}

}  // namespace rover::bus
