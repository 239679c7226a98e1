#include "auth/auth.hpp"

#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using rover::auth::ComputeTag;
using rover::auth::Key;
using rover::auth::KeyError;
using rover::auth::Signer;
using rover::auth::Tag;
using rover::auth::Verifier;

namespace {

std::vector<std::uint8_t> Bytes(const std::string& s) { return {s.begin(), s.end()}; }

std::string Hex(const Tag& tag) {
  static const char* digits = "0123456789abcdef";
  std::string out;
  for (std::uint8_t b : tag) {
    out += digits[b >> 4];
    out += digits[b & 15];
  }
  return out;
}

Tag TagOf(const Key& key, const std::string& data) {
  return ComputeTag(key, reinterpret_cast<const std::uint8_t*>(data.data()), data.size());
}

// A fixed 32-byte key (not all the same byte).
Key TestKey(std::uint8_t seed = 1) {
  std::vector<std::uint8_t> bytes(32);
  for (std::size_t i = 0; i < bytes.size(); ++i) bytes[i] = static_cast<std::uint8_t>(seed + 7 * i);
  return Key::FromBytes(bytes, "test key");
}

// A fresh directory for key files under the build tree.
fs::path TempDir(const std::string& name) {
  const fs::path dir = fs::path(ROVER_BINARY_DIR) / "test-out" / "auth_test" / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string WriteFile(const fs::path& path, const std::string& content, mode_t mode) {
  std::ofstream(path, std::ios::binary) << content;
  ::chmod(path.c_str(), mode);
  return path.string();
}

std::string KeyErrorOf(const std::string& path) {
  try {
    Key::LoadFile(path);
  } catch (const KeyError& e) {
    return e.what();
  }
  return "(no error)";
}

// Signs `data` as the signer would, returning counter and tag.
struct Signed {
  std::int64_t counter;
  Tag tag;
};
Signed SignData(Signer& signer, const std::string& data) {
  const std::int64_t counter = signer.NextCounter();
  const std::string with_counter = data + "#" + std::to_string(counter);
  return {counter, signer.Sign(reinterpret_cast<const std::uint8_t*>(with_counter.data()),
                               with_counter.size())};
}
std::optional<std::string> VerifyData(Verifier& v, const std::string& sender, const std::string& data,
                                      const Signed& s) {
  const std::string with_counter = data + "#" + std::to_string(s.counter);
  return v.Verify(sender, s.counter, reinterpret_cast<const std::uint8_t*>(with_counter.data()),
                  with_counter.size(), s.tag.data(), s.tag.size());
}

}  // namespace

// RFC 4231, section 4: HMAC-SHA-256 test cases 1, 2, 6 and 7 (short, text, and keys
// longer than the 64-byte block, which HMAC hashes first).
TEST(Hmac, Rfc4231TestVectors) {
  EXPECT_EQ(Hex(TagOf(Key::FromBytes(std::vector<std::uint8_t>(20, 0x0b), "tc1", true), "Hi There")),
            "b0344c61d8db38535ca8afceaf0bf12b881dc200c9833da726e9376c2e32cff7");
  EXPECT_EQ(Hex(TagOf(Key::FromBytes(Bytes("Jefe"), "tc2", true), "what do ya want for nothing?")),
            "5bdcc146bf60754e6a042426089575c75a003f089d2739839dec58b964ec3843");
  const Key long_key = Key::FromBytes(std::vector<std::uint8_t>(131, 0xaa), "tc6", true);
  EXPECT_EQ(Hex(TagOf(long_key, "Test Using Larger Than Block-Size Key - Hash Key First")),
            "60e431591ee0b67f0d8a26aacbf5b77f8e0bc6213728c5140546040f0ee37f54");
  EXPECT_EQ(Hex(TagOf(long_key,
                      "This is a test using a larger than block-size key and a larger than "
                      "block-size data. The key needs to be hashed before being used by the "
                      "HMAC algorithm.")),
            "9b09ffa71b942fcb27635fbcd5b0e944bfdc63644f0713938a7f51535c3a35e2");
}

TEST(Hmac, CopiedAndMovedKeysGiveTheSameTag) {
  const Key key = TestKey();
  const Key copy = key;
  Key moved_from = TestKey();
  const Key moved = std::move(moved_from);
  EXPECT_EQ(TagOf(key, "abc"), TagOf(copy, "abc"));
  EXPECT_EQ(TagOf(key, "abc"), TagOf(moved, "abc"));
  EXPECT_NE(TagOf(key, "abc"), TagOf(TestKey(2), "abc"));
  EXPECT_NE(TagOf(key, "abc"), TagOf(key, "abd"));
}

TEST(Signer, CounterIsStrictlyIncreasingAndFollowsTheWallClock) {
  std::int64_t wall = 1000;
  Signer signer(TestKey(), "rover_seq", [&] { return wall; });
  EXPECT_EQ(signer.NextCounter(), 1000);
  EXPECT_EQ(signer.NextCounter(), 1001);  // the clock did not move: last + 1
  wall = 5000;
  EXPECT_EQ(signer.NextCounter(), 5000);
  wall = 10;  // the clock stepped back: the counter still goes up
  EXPECT_EQ(signer.NextCounter(), 5001);
}

TEST(Signer, RejectsMalformedSenderNames) {
  EXPECT_THROW(Signer(TestKey(), ""), std::invalid_argument);
  EXPECT_THROW(Signer(TestKey(), "two words"), std::invalid_argument);
  EXPECT_THROW(Signer(TestKey(), std::string(65, 'x')), std::invalid_argument);
  EXPECT_NO_THROW(Signer(TestKey(), std::string(64, 'x')));
}

TEST(Signer, InstanceNamesAreValidSenderNamesOfThisProcess) {
  const std::string name = rover::auth::InstanceName("sequence_executor");
  EXPECT_EQ(name.rfind("sequence_executor@", 0), 0u) << name;
  EXPECT_NE(name.find(":" + std::to_string(::getpid())), std::string::npos) << name;
  EXPECT_NO_THROW(Signer(TestKey(), name));
  const std::string long_name = rover::auth::InstanceName(std::string(80, 'p'));
  EXPECT_EQ(long_name.size(), rover::auth::kMaxSenderLength);
  EXPECT_NE(long_name.find(":" + std::to_string(::getpid())), std::string::npos) << long_name;
  EXPECT_NO_THROW(Signer(TestKey(), long_name));
}

TEST(Verifier, AcceptsSignedMessagesInCounterOrder) {
  Signer signer(TestKey(), "rover_seq");
  Verifier verifier(TestKey());
  for (int i = 0; i < 3; ++i) {
    const Signed s = SignData(signer, "submit " + std::to_string(i));
    EXPECT_EQ(VerifyData(verifier, "rover_seq", "submit " + std::to_string(i), s), std::nullopt);
    EXPECT_EQ(verifier.last_counter("rover_seq"), s.counter);
  }
}

TEST(Verifier, RejectsMissingWrongAndAlteredTags) {
  Signer signer(TestKey(), "rover_seq");
  Signer forger(TestKey(9), "rover_seq");
  Verifier verifier(TestKey());

  const Signed good = SignData(signer, "abort");
  const std::string data = "abort#" + std::to_string(good.counter);
  const auto* bytes = reinterpret_cast<const std::uint8_t*>(data.data());
  auto missing = verifier.Verify("rover_seq", good.counter, bytes, data.size(), nullptr, 0);
  ASSERT_TRUE(missing);
  EXPECT_NE(missing->find("missing tag from \"rover_seq\""), std::string::npos) << *missing;

  auto short_tag = verifier.Verify("rover_seq", good.counter, bytes, data.size(), good.tag.data(), 16);
  ASSERT_TRUE(short_tag);
  EXPECT_NE(short_tag->find("is 16 bytes (expected 32)"), std::string::npos) << *short_tag;

  auto forged = VerifyData(verifier, "rover_seq", "abort", SignData(forger, "abort"));
  ASSERT_TRUE(forged);
  EXPECT_NE(forged->find("wrong tag from \"rover_seq\""), std::string::npos) << *forged;

  Signed altered = good;
  altered.tag[5] ^= 0x01;
  EXPECT_TRUE(VerifyData(verifier, "rover_seq", "abort", altered));
  EXPECT_TRUE(VerifyData(verifier, "rover_seq", "abort!", good));      // other data
  // None of the rejected messages moved the sender's counter: the good one still passes.
  EXPECT_EQ(verifier.last_counter("rover_seq"), std::nullopt);
  EXPECT_EQ(VerifyData(verifier, "rover_seq", "abort", good), std::nullopt);
}

TEST(Verifier, RejectsReplayedAndOldCounters) {
  std::int64_t wall = 1'000'000;
  Signer signer(TestKey(), "sequence_executor", [&] { return wall; });
  Verifier verifier(TestKey());
  const Signed first = SignData(signer, "drive");
  const Signed second = SignData(signer, "drive");
  EXPECT_EQ(VerifyData(verifier, "sequence_executor", "drive", first), std::nullopt);
  EXPECT_EQ(VerifyData(verifier, "sequence_executor", "drive", second), std::nullopt);

  auto replay = VerifyData(verifier, "sequence_executor", "drive", second);
  ASSERT_TRUE(replay);
  EXPECT_EQ(*replay, "replayed or old counter 1000001 from \"sequence_executor\" (last accepted 1000001)");
  auto old = VerifyData(verifier, "sequence_executor", "drive", first);
  ASSERT_TRUE(old);
  EXPECT_NE(old->find("replayed or old counter 1000000"), std::string::npos) << *old;
}

TEST(Verifier, KeepsCountersPerSender) {
  std::int64_t wall = 500;
  Signer a(TestKey(), "rover_seq", [&] { return wall; });
  Signer b(TestKey(), "scenario_runner", [&] { return wall - 100; });
  Verifier verifier(TestKey());
  EXPECT_EQ(VerifyData(verifier, "rover_seq", "x", SignData(a, "x")), std::nullopt);
  // A lower counter from another sender is not a replay of rover_seq's.
  EXPECT_EQ(VerifyData(verifier, "scenario_runner", "x", SignData(b, "x")), std::nullopt);
  EXPECT_EQ(verifier.last_counter("rover_seq"), 500);
  EXPECT_EQ(verifier.last_counter("scenario_runner"), 400);
}

TEST(Verifier, RestartedSenderContinuesAboveWhatWasAccepted) {
  std::int64_t wall = 2'000'000;
  Verifier verifier(TestKey());
  std::int64_t last = 0;
  {
    // A busy sender signs faster than a microsecond each: its counter runs ahead of the clock.
    Signer before(TestKey(), "sequence_executor", [&] { return wall; });
    for (int i = 0; i < 50; ++i) {
      const Signed s = SignData(before, "m");
      ASSERT_EQ(VerifyData(verifier, "sequence_executor", "m", s), std::nullopt);
      last = s.counter;
    }
  }
  EXPECT_EQ(last, 2'000'049);
  wall += 3'000'000;  // restarted three seconds later
  Signer after(TestKey(), "sequence_executor", [&] { return wall; });
  const Signed s = SignData(after, "m");
  EXPECT_GT(s.counter, last);
  EXPECT_EQ(VerifyData(verifier, "sequence_executor", "m", s), std::nullopt);
}

TEST(Verifier, RefusesCountersFromBeforeItStarted) {
  // A message captured before the receiver (re)started is refused even though this
  // receiver has no record of its sender.
  std::int64_t wall = 1'000;
  Signer signer(TestKey(), "rover_seq", [&] { return wall; });
  const Signed captured = SignData(signer, "submit");
  Verifier restarted(TestKey(), 2'000);
  auto reason = VerifyData(restarted, "rover_seq", "submit", captured);
  ASSERT_TRUE(reason);
  EXPECT_NE(reason->find("predates this receiver's start"), std::string::npos) << *reason;
  wall = 2'500;
  EXPECT_EQ(VerifyData(restarted, "rover_seq", "submit", SignData(signer, "submit")), std::nullopt);
}

TEST(Verifier, HostileSenderNamesArePrintedSafely) {
  Verifier verifier(TestKey());
  const std::string sender = std::string("evil\n\x1b[2J") + std::string(100, 'x');
  const std::string data = "d";
  auto reason = verifier.Verify(sender, 1, reinterpret_cast<const std::uint8_t*>(data.data()),
                                data.size(), nullptr, 0);
  ASSERT_TRUE(reason);
  EXPECT_EQ(reason->find('\n'), std::string::npos);
  EXPECT_EQ(reason->find('\x1b'), std::string::npos);
  EXPECT_LT(reason->size(), 200u);
}

TEST(KeyFile, HexAndRawFilesHoldingTheSameBytesAreTheSameKey) {
  const fs::path dir = TempDir("same");
  std::string raw(32, '\0');
  std::string hex;
  for (int i = 0; i < 32; ++i) {
    raw[i] = static_cast<char>(i * 37 + 11);
    char buf[3];
    std::snprintf(buf, sizeof buf, "%02x", static_cast<unsigned>(static_cast<unsigned char>(raw[i])));
    hex += buf;
  }
  const Key from_hex = Key::LoadFile(WriteFile(dir / "hex.key", "  " + hex + "\n", 0600));
  const Key from_upper_hex = Key::LoadFile(WriteFile(dir / "HEX.key", [&] {
    std::string h = hex;
    for (char& c : h) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    return h;
  }(), 0640));
  const Key from_raw = Key::LoadFile(WriteFile(dir / "raw.key", raw, 0600));
  EXPECT_EQ(from_hex.size(), 32u);
  EXPECT_EQ(TagOf(from_hex, "m"), TagOf(from_raw, "m"));
  EXPECT_EQ(TagOf(from_upper_hex, "m"), TagOf(from_raw, "m"));
}

TEST(KeyFile, BadFilesGetOneClearLine) {
  const fs::path dir = TempDir("bad");
  const std::string hex64(64, 'a');
  std::string good_hex;
  for (int i = 0; i < 32; ++i) {
    good_hex += "0123456789abcdef"[i % 16];
    good_hex += "fedcba9876543210"[i % 16];
  }

  const std::string world = WriteFile(dir / "world.key", good_hex, 0644);
  EXPECT_EQ(KeyErrorOf(world), world + ": mode 0644 gives other users access to the key "
                                        "(expected none: chmod o-rwx " + world + ")");
  EXPECT_NE(KeyErrorOf(WriteFile(dir / "wwrite.key", good_hex, 0602)).find("mode 0602"), std::string::npos);
  EXPECT_NE(KeyErrorOf((dir / "absent.key").string()).find("cannot open key file: No such file"),
            std::string::npos);
  EXPECT_NE(KeyErrorOf(dir.string()).find("not a regular file"), std::string::npos);
  const fs::path fifo = dir / "fifo.key";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_NE(KeyErrorOf(fifo.string()).find("not a regular file"), std::string::npos);  // no hang
  EXPECT_NE(KeyErrorOf("/dev/zero").find("not a regular file"), std::string::npos);

  const std::string short_hex = WriteFile(dir / "short.key", good_hex.substr(0, 62), 0600);
  EXPECT_EQ(KeyErrorOf(short_hex), short_hex + ": key is 31 bytes (expected at least 32 random "
                                               "bytes, raw or as 64 or more hex digits)");
  EXPECT_NE(KeyErrorOf(WriteFile(dir / "short.raw", "password", 0600)).find("key is 8 bytes"),
            std::string::npos);
  EXPECT_NE(KeyErrorOf(WriteFile(dir / "empty.key", "", 0600)).find("key is 0 bytes"), std::string::npos);
  EXPECT_NE(KeyErrorOf(WriteFile(dir / "odd.key", good_hex + "a", 0600)).find("odd number of hex digits"),
            std::string::npos);
  EXPECT_NE(KeyErrorOf(WriteFile(dir / "zero.key", std::string(64, '0'), 0600))
                .find("every byte of the key is 0x00"),
            std::string::npos);
  EXPECT_NE(KeyErrorOf(WriteFile(dir / "same.key", hex64, 0600)).find("every byte of the key is 0xaa"),
            std::string::npos);
  EXPECT_NE(KeyErrorOf(WriteFile(dir / "huge.key", std::string(5000, 'k'), 0600))
                .find("5000 bytes (expected a key file of at most 4096 bytes)"),
            std::string::npos);
}

TEST(KeyFile, GeneratedKeyIsPrivateRandomAndNeverOverwritten) {
  const fs::path dir = TempDir("gen");
  const std::string a = (dir / "a.key").string(), b = (dir / "b.key").string();
  ::umask(022);
  rover::auth::GenerateKeyFile(a);
  rover::auth::GenerateKeyFile(b);
  struct stat st {};
  ASSERT_EQ(::stat(a.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 07777, 0600u);
  EXPECT_EQ(fs::file_size(a), 65u);  // 64 hex digits and a newline
  const Key ka = Key::LoadFile(a), kb = Key::LoadFile(b);
  EXPECT_EQ(ka.size(), 32u);
  EXPECT_NE(TagOf(ka, "m"), TagOf(kb, "m"));
  const Tag before = TagOf(ka, "m");
  try {
    rover::auth::GenerateKeyFile(a);
    ADD_FAILURE() << "an existing key file was overwritten";
  } catch (const KeyError& e) {
    EXPECT_NE(std::string(e.what()).find("File exists (remove it first to replace the key)"),
              std::string::npos) << e.what();
  }
  EXPECT_EQ(TagOf(Key::LoadFile(a), "m"), before);
}

TEST(KeyFile, GenerateKeyFileMakesAMissingFolderTheUsersAlone) {
  const fs::path dir = TempDir("folder");
  const std::string key = (dir / "keys" / "rover.key").string();
  rover::auth::GenerateKeyFile(key);
  EXPECT_EQ(Key::LoadFile(key).size(), 32u);
  struct stat st {};
  ASSERT_EQ(::stat((dir / "keys").c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 07777, 0700u);
}
