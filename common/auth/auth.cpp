#include "auth/auth.hpp"

#include <sodium.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <utility>

namespace rover::auth {

namespace {

// sodium_init() once per process (it is safe to call again; it picks the CPU's fastest
// implementations and seeds the random generator).
void EnsureSodium() {
  static const bool ready = sodium_init() >= 0;
  if (!ready) throw std::runtime_error("libsodium could not be initialised");
}

std::string Octal(mode_t mode) {
  char buf[8];
  std::snprintf(buf, sizeof buf, "%04o", static_cast<unsigned>(mode & 07777));
  return buf;
}

// Closes a file descriptor on every path out.
struct Fd {
  int fd;
  ~Fd() {
    if (fd >= 0) ::close(fd);
  }
};

// Reads a key file's bytes after checking what the file is. O_NONBLOCK: a FIFO must not
// hang the open; the type is then checked on the open descriptor, not on the name.
std::string ReadKeyFile(const std::string& path) {
  Fd file{::open(path.c_str(), O_RDONLY | O_NOCTTY | O_NONBLOCK | O_CLOEXEC)};
  if (file.fd < 0) {
    throw KeyError(path + ": cannot open key file: " + std::strerror(errno) +
                   " (expected a file of 32 or more random bytes)");
  }
  struct stat st {};
  if (::fstat(file.fd, &st) != 0) {
    throw KeyError(path + ": cannot stat key file: " + std::strerror(errno));
  }
  if (!S_ISREG(st.st_mode)) {
    throw KeyError(path + ": not a regular file (expected a key file of 32 or more random bytes)");
  }
  if ((st.st_mode & S_IRWXO) != 0) {
    throw KeyError(path + ": mode " + Octal(st.st_mode) +
                   " gives other users access to the key (expected none: chmod o-rwx " + path +
                   ")");
  }
  if (static_cast<std::uint64_t>(st.st_size) > kMaxKeyFileBytes) {
    throw KeyError(path + ": " + std::to_string(st.st_size) + " bytes (expected a key file of at most " +
                   std::to_string(kMaxKeyFileBytes) + " bytes)");
  }
  std::string content;
  char buf[512];
  for (;;) {
    const ssize_t n = ::read(file.fd, buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw KeyError(path + ": cannot read key file: " + std::strerror(errno));
    if (n == 0) break;
    content.append(buf, static_cast<std::size_t>(n));
    if (content.size() > kMaxKeyFileBytes) {
      throw KeyError(path + ": more than " + std::to_string(kMaxKeyFileBytes) +
                     " bytes (expected a key file of at most that size)");
    }
  }
  sodium_memzero(buf, sizeof buf);
  return content;
}

bool IsHexText(const std::string& text) {
  if (text.empty()) return false;
  for (char c : text) {
    if (std::isxdigit(static_cast<unsigned char>(c)) == 0) return false;
  }
  return true;
}

std::string TrimWhiteSpace(const std::string& text) {
  const char* space = " \t\r\n";
  const auto first = text.find_first_not_of(space);
  if (first == std::string::npos) return {};
  const auto last = text.find_last_not_of(space);
  return text.substr(first, last - first + 1);
}

// A file of hex digits (surrounding white space ignored) is hex: two digits a byte. Any
// other content is the key as it is (32 random bytes are all hex digits with
// probability (22/256)^32, so raw keys are not mistaken for hex).
std::vector<std::uint8_t> KeyBytes(const std::string& content, const std::string& path) {
  const std::string trimmed = TrimWhiteSpace(content);
  std::vector<std::uint8_t> bytes;
  if (IsHexText(trimmed)) {
    if (trimmed.size() % 2 != 0) {
      throw KeyError(path + ": odd number of hex digits (" + std::to_string(trimmed.size()) +
                     "; expected two per byte)");
    }
    bytes.resize(trimmed.size() / 2);
    std::size_t decoded = 0;
    if (sodium_hex2bin(bytes.data(), bytes.size(), trimmed.data(), trimmed.size(), nullptr,
                       &decoded, nullptr) != 0 ||
        decoded != bytes.size()) {
      throw KeyError(path + ": malformed hex key");
    }
  } else {
    bytes.assign(content.begin(), content.end());
  }
  return bytes;
}

void CheckKeyBytes(const std::vector<std::uint8_t>& bytes, const std::string& source) {
  if (bytes.size() < kMinKeyBytes) {
    throw KeyError(source + ": key is " + std::to_string(bytes.size()) +
                   " bytes (expected at least " + std::to_string(kMinKeyBytes) +
                   " random bytes, raw or as 64 or more hex digits)");
  }
  bool all_same = true;
  for (std::uint8_t b : bytes) all_same = all_same && b == bytes.front();
  if (all_same) {
    char hex[8];
    std::snprintf(hex, sizeof hex, "0x%02x", static_cast<unsigned>(bytes.front()));
    throw KeyError(source + ": every byte of the key is " + hex + " (expected random bytes)");
  }
}

bool IsPrintableName(const std::string& name) {
  if (name.empty() || name.size() > kMaxSenderLength) return false;
  for (char c : name) {
    if (c < 0x21 || c > 0x7e) return false;
  }
  return true;
}

}  // namespace

// ---- Key ----

Key Key::LoadFile(const std::string& path) {
  EnsureSodium();
  std::string content = ReadKeyFile(path);
  Key key;
  key.source_ = path;
  try {
    key.bytes_ = KeyBytes(content, path);
  } catch (...) {
    sodium_memzero(content.data(), content.size());
    throw;
  }
  sodium_memzero(content.data(), content.size());
  CheckKeyBytes(key.bytes_, path);
  return key;
}

Key Key::FromBytes(std::vector<std::uint8_t> bytes, std::string source, bool unchecked) {
  EnsureSodium();
  Key key;
  key.bytes_ = std::move(bytes);
  key.source_ = std::move(source);
  if (key.bytes_.empty()) throw KeyError(key.source_ + ": empty key (expected random bytes)");
  if (!unchecked) CheckKeyBytes(key.bytes_, key.source_);
  return key;
}

Key::Key(const Key& other) : bytes_(other.bytes_), source_(other.source_) {}

Key& Key::operator=(const Key& other) {
  if (this != &other) {
    Wipe();
    bytes_ = other.bytes_;
    source_ = other.source_;
  }
  return *this;
}

Key::Key(Key&& other) noexcept
    : bytes_(std::move(other.bytes_)), source_(std::move(other.source_)) {
  other.bytes_.clear();
}

Key& Key::operator=(Key&& other) noexcept {
  if (this != &other) {
    Wipe();
    bytes_ = std::move(other.bytes_);
    source_ = std::move(other.source_);
    other.bytes_.clear();
  }
  return *this;
}

Key::~Key() { Wipe(); }

void Key::Wipe() {
  if (!bytes_.empty()) sodium_memzero(bytes_.data(), bytes_.size());
  bytes_.clear();
}

Tag ComputeTag(const Key& key, const std::uint8_t* data, std::size_t size) {
  EnsureSodium();
  if (key.bytes_.empty()) throw std::logic_error("ComputeTag: empty key (moved from?)");
  // The init/update/final form takes a key of any length, as HMAC does (RFC 2104);
  // crypto_auth_hmacsha256() itself takes exactly 32 bytes.
  crypto_auth_hmacsha256_state state;
  crypto_auth_hmacsha256_init(&state, key.bytes_.data(), key.bytes_.size());
  crypto_auth_hmacsha256_update(&state, data, size);
  Tag tag{};
  crypto_auth_hmacsha256_final(&state, tag.data());
  sodium_memzero(&state, sizeof state);
  return tag;
}

void GenerateKeyFile(const std::string& path) {
  EnsureSodium();
  std::uint8_t bytes[kMinKeyBytes];
  randombytes_buf(bytes, sizeof bytes);
  char hex[2 * kMinKeyBytes + 1];
  sodium_bin2hex(hex, sizeof hex, bytes, sizeof bytes);
  sodium_memzero(bytes, sizeof bytes);
  const std::string text = std::string(hex) + "\n";
  sodium_memzero(hex, sizeof hex);
  // The guide's `./rover seq keygen build/keys/rover.key` names a folder no build makes:
  // a missing folder is made, and only the user may enter it (0700).
  const std::filesystem::path folder = std::filesystem::path(path).parent_path();
  if (!folder.empty() && !std::filesystem::exists(folder)) {
    std::error_code ec;
    std::filesystem::create_directories(folder, ec);
    if (!ec) std::filesystem::permissions(folder, std::filesystem::perms::owner_all, ec);
    if (ec) throw KeyError(path + ": cannot make its folder " + folder.string() + ": " + ec.message());
  }
  // O_EXCL: never replace a key (receivers holding the old one would refuse everything);
  // mode 0600 from the start, so the key is never readable by others, even briefly.
  Fd file{::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0600)};
  if (file.fd < 0) {
    throw KeyError(path + ": cannot create key file: " + std::strerror(errno) +
                   (errno == EEXIST ? " (remove it first to replace the key)" : ""));
  }
  // The umask may have taken bits away, never added them; make the mode exact anyway.
  if (::fchmod(file.fd, 0600) != 0 ||
      ::write(file.fd, text.data(), text.size()) != static_cast<ssize_t>(text.size())) {
    const std::string why = std::strerror(errno);
    ::unlink(path.c_str());
    throw KeyError(path + ": cannot write key file: " + why);
  }
}

std::int64_t WallClockMicros() {
  return std::chrono::duration_cast<std::chrono::microseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

std::string InstanceName(const std::string& program) {
  char host[256] = {};
  if (::gethostname(host, sizeof host - 1) != 0) host[0] = '\0';
  std::string name = program + "@" + host;
  for (char& c : name) {
    if (c < 0x21 || c > 0x7e) c = '_';
  }
  std::string pid(":");
  pid.append(std::to_string(::getpid()));
  if (name.size() + pid.size() > kMaxSenderLength) name.resize(kMaxSenderLength - pid.size());
  return name.append(pid);
}

std::string PrintableName(const std::string& name) {
  std::string out;
  for (char c : name.substr(0, kMaxSenderLength)) out += (c >= 0x20 && c <= 0x7e) ? c : '?';
  if (name.size() > kMaxSenderLength) out += "...";
  return out;
}

// ---- Signer ----

Signer::Signer(Key key, std::string sender, std::function<std::int64_t()> clock)
    : key_(std::move(key)), sender_(std::move(sender)), clock_(std::move(clock)) {
  if (!IsPrintableName(sender_)) {
    throw std::invalid_argument("auth::Signer: sender \"" + PrintableName(sender_) +
                                "\": expected 1 to " + std::to_string(kMaxSenderLength) +
                                " printable characters without spaces");
  }
}

std::int64_t Signer::NextCounter() {
  last_counter_ = std::max(last_counter_ + 1, clock_());
  return last_counter_;
}

Tag Signer::Sign(const std::uint8_t* data, std::size_t size) const {
  return ComputeTag(key_, data, size);
}

// ---- Verifier ----

Verifier::Verifier(Key key, std::int64_t not_before)
    : key_(std::move(key)), not_before_(not_before) {}

std::optional<std::string> Verifier::Verify(const std::string& sender, std::int64_t counter,
                                            const std::uint8_t* data, std::size_t size,
                                            const std::uint8_t* tag, std::size_t tag_size) {
  // Appended piece by piece: `"\"" + name` trips GCC 12's -Wrestrict false positive.
  std::string who(1, '"');
  who.append(PrintableName(sender)).push_back('"');
  if (tag_size == 0 || tag == nullptr) {
    return "missing tag from " + who + " (expected a message signed with this deployment's key)";
  }
  if (tag_size != kTagSize) {
    return "tag from " + who + " is " + std::to_string(tag_size) + " bytes (expected " +
           std::to_string(kTagSize) + ")";
  }
  if (!IsPrintableName(sender)) {
    return "sender " + who + ": expected 1 to " + std::to_string(kMaxSenderLength) +
           " printable characters without spaces";
  }
  const Tag expected = ComputeTag(key_, data, size);
  if (sodium_memcmp(expected.data(), tag, kTagSize) != 0) {
    return "wrong tag from " + who + " (not signed with this deployment's key, or altered)";
  }
  // Counters are compared only once the tag proved the sender holds the key, so that a
  // forger can neither fill the table nor move a sender's counter.
  if (counter <= 0) {
    return "counter " + std::to_string(counter) + " from " + who + " (expected a positive counter)";
  }
  if (counter < not_before_) {
    return "counter " + std::to_string(counter) + " from " + who +
           " predates this receiver's start (" + std::to_string(not_before_) +
           "): a replay, or the sender's clock is behind";
  }
  if (auto it = last_counter_.find(sender); it != last_counter_.end() && counter <= it->second) {
    return "replayed or old counter " + std::to_string(counter) + " from " + who +
           " (last accepted " + std::to_string(it->second) + ")";
  }
  last_counter_[sender] = counter;
  return std::nullopt;
}

std::optional<std::int64_t> Verifier::last_counter(const std::string& sender) const {
  if (auto it = last_counter_.find(sender); it != last_counter_.end()) return it->second;
  return std::nullopt;
}

}  // namespace rover::auth
