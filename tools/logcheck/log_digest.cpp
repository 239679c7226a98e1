#include "logcheck/log_digest.hpp"

#include "bus/channels.hpp"
#include "logcheck/log_reader.hpp"

#include <lcm/lcm-cpp.hpp>
#include <rover_msgs/vo_update_t.hpp>
#include <sodium.h>

#include <cstdint>
#include <cstdio>
#include <vector>

namespace rover::logcheck {

namespace {

void AddInt64(crypto_hash_sha256_state* st, std::int64_t v) {
  unsigned char b[8];
  for (int i = 0; i < 8; ++i) b[i] = static_cast<unsigned char>((static_cast<std::uint64_t>(v) >> (56 - 8 * i)) & 0xff);
  crypto_hash_sha256_update(st, b, sizeof b);
}

}  // namespace

LogDigest DigestLog(const std::string& path) {
  LogDigest out;
  if (sodium_init() < 0) {
    out.error = "libsodium did not initialise";
    return out;
  }
  rover::logcheck::LogReader log(path);
  if (!log.good()) {
    out.error = path + ": cannot open the log";
    return out;
  }
  crypto_hash_sha256_state st;
  crypto_hash_sha256_init(&st);
  while (const lcm::LogEvent* e = log.readNextEvent()) {
    ++out.events;
    AddInt64(&st, e->timestamp);
    AddInt64(&st, static_cast<std::int64_t>(e->channel.size()));
    crypto_hash_sha256_update(&st, reinterpret_cast<const unsigned char*>(e->channel.data()), e->channel.size());
    const auto* data = static_cast<const unsigned char*>(e->data);
    std::vector<unsigned char> zeroed;
    if (e->channel == channels::kVoUpdate) {
      rover_msgs::vo_update_t m;
      if (m.decode(e->data, 0, e->datalen) == e->datalen) {
        m.ms_detect = m.ms_stereo = m.ms_track = m.ms_ransac = m.ms_ml = m.ms_total = 0;
        zeroed.resize(static_cast<std::size_t>(m.getEncodedSize()));
        m.encode(zeroed.data(), 0, static_cast<int>(zeroed.size()));
        data = zeroed.data();
      }
    }
    const std::size_t size = zeroed.empty() ? static_cast<std::size_t>(e->datalen) : zeroed.size();
    AddInt64(&st, static_cast<std::int64_t>(size));
    crypto_hash_sha256_update(&st, data, size);
  }
  unsigned char hash[crypto_hash_sha256_BYTES];
  crypto_hash_sha256_final(&st, hash);
  char hex[2 * crypto_hash_sha256_BYTES + 1];
  for (std::size_t i = 0; i < sizeof hash; ++i) std::snprintf(hex + 2 * i, 3, "%02x", hash[i]);
  out.sha256_hex = hex;
  return out;
}

}  // namespace rover::logcheck
