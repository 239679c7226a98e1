// Signing and verifying command messages (those with an `auth_t auth` member) with
// common/auth: the tag is HMAC-SHA256 over the message's LCM encoding, made with
// auth.sender and auth.counter filled in and auth.tag empty (lcmtypes/auth_t.lcm).
//
// Sign last: any field set after SignMessage (utime, pub_seq, ...) breaks the tag.
// The Bus signs and verifies every message type that has an `auth` member once it is
// given MakeBusAuth(...) (from the `auth:` section of a process's config,
// LoadConfiguredKey below; tools pass their --key).
#pragma once

#include "auth/auth.hpp"
#include "bus/bus.hpp"
#include "config/yaml_config.hpp"

#include <cstdint>
#include <cstdlib>
#include <memory>
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

// The Bus's authentication for a process `program` that holds `key`. It signs as
// auth::InstanceName(program) ("rover_seq@host:pid"), with counters from the wall clock; it refuses counters from before it started (less
// auth::kClockSkewAllowanceUs), so a command captured before a restart cannot be
// replayed to the restarted process. `reject_unsigned`: a command with no tag is refused
// too. Leave it true: false lets anyone on the LAN send unsigned commands that are obeyed.
inline Bus::Auth MakeBusAuth(const auth::Key& key, const std::string& program,
                             bool reject_unsigned = true) {
  auto signer = std::make_shared<auth::Signer>(key, auth::InstanceName(program));
  auto verifier = std::make_shared<auth::Verifier>(
      key, auth::WallClockMicros() - auth::kClockSkewAllowanceUs);
  Bus::Auth a;
  a.next = [signer](std::string* name, std::int64_t* counter) {
    *name = signer->sender();
    *counter = signer->NextCounter();
  };
  a.tag = [signer](const std::vector<std::uint8_t>& bytes) {
    const auth::Tag tag = signer->Sign(bytes.data(), bytes.size());
    return std::vector<std::uint8_t>(tag.begin(), tag.end());
  };
  a.verify = [verifier](const std::string& name, std::int64_t counter,
                        const std::vector<std::uint8_t>& bytes,
                        const std::vector<std::uint8_t>& tag) -> std::string {
    const auto reason = verifier->Verify(name, counter, bytes.data(), bytes.size(),
                                         tag.empty() ? nullptr : tag.data(), tag.size());
    return reason ? *reason : "";
  };
  a.required = reject_unsigned;
  return a;
}

// Where a process finds the deployment's key: `key_flag` (its --key FILE), else the
// `auth:` section of its config, else $ROVER_KEY_FILE.
//   auth:
//     key_file: /etc/rover/rover.key   # relative paths are from the working directory,
//                                      # like every path in a deployment
//     required: true                   # refuse to start without a key
// A key named in any of these places must load: an unusable one is an error, never
// "unsigned". Without a key, commands go unsigned and unchecked.
struct AuthSettings {
  std::optional<auth::Key> key;
  bool required = false;
};

// Throws config::ConfigError with one line naming where the key was named (`program`'s
// --key, the config file's auth.key_file, $ROVER_KEY_FILE) and what is wrong: a malformed
// section, required without a key, an unusable key file.
inline AuthSettings LoadAuthSettings(const config::ConfigNode& root,
                                     const std::optional<std::string>& key_flag = std::nullopt,
                                     const std::string& program = "") {
  AuthSettings settings;
  const config::ConfigNode section = root["auth"];
  std::string key_file;
  if (!section.IsNull()) {
    if (!section.IsMap()) section.Fail("expected a mapping with key_file and required");
    section.CheckKeys({"key_file", "required"});
    section.Get("key_file", key_file);
    section.Get("required", settings.required);
  }
  auto load = [&settings](const std::string& path, const std::string& where) {
    try {
      settings.key = auth::Key::LoadFile(path);
    } catch (const auth::KeyError& e) {
      throw config::ConfigError(where + e.what());
    }
  };
  const char* env = std::getenv("ROVER_KEY_FILE");
  const std::string who = program.empty() ? "" : program + ": ";
  if (key_flag) {
    load(*key_flag, who + "argument --key: ");
  } else if (!key_file.empty()) {
    load(key_file, section.source() + ": auth.key_file: ");
  } else if (env != nullptr && *env != '\0') {
    load(env, who + "$ROVER_KEY_FILE: ");
  } else if (settings.required) {
    section["key_file"].Fail(
        "missing, and no --key or $ROVER_KEY_FILE (auth.required is true: expected the "
        "deployment's key file; ./rover seq keygen FILE makes one)");
  }
  return settings;
}

}  // namespace rover::bus
