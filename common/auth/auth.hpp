// Authenticated commands: HMAC-SHA256 tags and per-sender counters over message bytes.
//
// A deployment shares one secret key (a file of 32 or more random bytes). A sender signs
// the bytes of a message that already carries its name and a counter; a receiver checks
// the tag and accepts each sender's counters only in strictly increasing order, so a
// forged message (no key) and a replayed one (a counter already seen) are both refused.
// This library knows nothing of LCM: common/bus/signing.hpp applies it to messages.
//
// The cryptography is libsodium's (Debian libsodium-dev): its HMAC-SHA256, its
// constant-time comparison (sodium_memcmp) and its memory wiping, rather than a
// hand-written HMAC, so that nothing here is home-made cryptography. libsodium is a
// smaller dependency than OpenSSL and has one obvious call for each of these.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace rover::auth {

inline constexpr std::size_t kTagSize = 32;         // HMAC-SHA256
inline constexpr std::size_t kMinKeyBytes = 32;     // 256 bits of secret
inline constexpr std::size_t kMaxKeyFileBytes = 4096;
inline constexpr std::size_t kMaxSenderLength = 64;

using Tag = std::array<std::uint8_t, kTagSize>;

// A key file that cannot be used. what() is one line naming the file and what was expected.
class KeyError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The deployment's secret. The bytes are wiped from memory when the Key is destroyed.
class Key {
 public:
  // Reads a key file: a regular file, with no access for other users (mode o-rwx),
  // holding at least 32 bytes, either as hex digits (64 or more, surrounding white space
  // ignored) or raw. Throws KeyError with one line otherwise.
  static Key LoadFile(const std::string& path);
  // A key from bytes (tests, tools); `source` names it in messages. Throws KeyError when
  // shorter than kMinKeyBytes or every byte is the same, unless `unchecked` (the RFC 4231
  // test vectors use keys such as twenty 0x0b bytes).
  static Key FromBytes(std::vector<std::uint8_t> bytes, std::string source,
                       bool unchecked = false);

  Key(const Key& other);
  Key& operator=(const Key& other);
  Key(Key&& other) noexcept;
  Key& operator=(Key&& other) noexcept;
  ~Key();

  const std::string& source() const { return source_; }
  std::size_t size() const { return bytes_.size(); }

 private:
  Key() = default;
  friend Tag ComputeTag(const Key& key, const std::uint8_t* data, std::size_t size);
  void Wipe();

  std::vector<std::uint8_t> bytes_;
  std::string source_;
};

// HMAC-SHA256 of `data` under `key`.
Tag ComputeTag(const Key& key, const std::uint8_t* data, std::size_t size);

// Writes a fresh random key (32 bytes, as 64 hex digits and a newline) to `path` with
// mode 0600. Refuses to overwrite an existing file. Throws KeyError with one line.
void GenerateKeyFile(const std::string& path);

// Microseconds since the Unix epoch, from the wall clock.
std::int64_t WallClockMicros();

// Signs as one sender. Its counter is strictly increasing and never below the wall clock
// in microseconds, so a sender that restarts continues above every counter receivers
// have accepted from it (as long as the wall clock did not step back).
class Signer {
 public:
  // Throws std::invalid_argument when `sender` is empty, longer than kMaxSenderLength or
  // not printable ASCII.
  Signer(Key key, std::string sender, std::function<std::int64_t()> clock = WallClockMicros);

  const std::string& sender() const { return sender_; }
  // max(last + 1, clock()).
  std::int64_t NextCounter();
  // The tag over bytes that already hold this sender's name and counter.
  Tag Sign(const std::uint8_t* data, std::size_t size) const;

 private:
  Key key_;
  std::string sender_;
  std::function<std::int64_t()> clock_;
  std::int64_t last_counter_ = 0;
};

// A receiver's check of tags and counters.
class Verifier {
 public:
  // Counters below `not_before` are refused from every sender: pass the wall clock at
  // the receiver's start (less kClockSkewAllowanceUs) so that a message captured before
  // a receiver restarted cannot be replayed to it. 0 accepts any positive counter.
  explicit Verifier(Key key, std::int64_t not_before = 0);

  // Checks, in order: a tag is present and kTagSize long, the sender name is well formed,
  // the tag is right (constant-time compare), the counter is above `not_before` and
  // above the last one accepted from this sender. On success records the counter and
  // returns nullopt; otherwise returns the reason, one line (e.g. "wrong tag from
  // \"rover_seq\" (not signed with this deployment's key)").
  std::optional<std::string> Verify(const std::string& sender, std::int64_t counter,
                                    const std::uint8_t* data, std::size_t size,
                                    const std::uint8_t* tag, std::size_t tag_size);

  // The last counter accepted from `sender`, if any.
  std::optional<std::int64_t> last_counter(const std::string& sender) const;

 private:
  Key key_;
  std::int64_t not_before_;
  std::map<std::string, std::int64_t> last_counter_;
};

// How far apart the wall clocks of the rover's computers may be (chrony or NTP keeps a
// LAN within milliseconds): a receiver's `not_before` is its start time less this.
inline constexpr std::int64_t kClockSkewAllowanceUs = 2'000'000;

// `program` + "@" + host name + ":" + process id, cut to kMaxSenderLength: the sender
// name of one running instance. Each instance then has counters of its own, so two
// operators whose wall clocks disagree, or a process restarted after its clock stepped
// back, are never refused as replays of each other.
std::string InstanceName(const std::string& program);

// A name for messages: printable ASCII, at most kMaxSenderLength characters; anything
// else is replaced so that a hostile name cannot garble a log line.
std::string PrintableName(const std::string& name);

}  // namespace rover::auth
