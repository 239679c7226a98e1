// LCM's udpm datagrams built by hand for the bus's tests (kernel_filter_test,
// udpm_receiver_test): a short message (LC02) and a fragment of a long one (LC03), in
// network byte order as LCM 1.3 sends them.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace rover::bus::test {

inline void Put32(std::vector<std::uint8_t>* d, std::uint32_t v) {
  for (int s = 24; s >= 0; s -= 8) d->push_back(static_cast<std::uint8_t>(v >> s));
}

inline void Put16(std::vector<std::uint8_t>* d, std::uint16_t v) {
  d->push_back(static_cast<std::uint8_t>(v >> 8));
  d->push_back(static_cast<std::uint8_t>(v));
}

// Magic LC02, sequence number, the channel and its NUL, then the payload.
inline std::vector<std::uint8_t> ShortDatagram(const std::string& channel, const std::vector<std::uint8_t>& payload,
                                               std::uint32_t seqno = 7) {
  std::vector<std::uint8_t> d;
  Put32(&d, 0x4c433032);
  Put32(&d, seqno);
  d.insert(d.end(), channel.begin(), channel.end());
  d.push_back(0);
  d.insert(d.end(), payload.begin(), payload.end());
  return d;
}

// Magic LC03, sequence number, the whole message's size, this piece's offset, its number
// and the count; only fragment 0 names the channel. Then the piece.
inline std::vector<std::uint8_t> FragmentDatagram(const std::string& channel, std::uint32_t seqno,
                                                  std::uint32_t message_size, std::uint32_t offset,
                                                  std::uint16_t number, std::uint16_t count,
                                                  const std::vector<std::uint8_t>& piece) {
  std::vector<std::uint8_t> d;
  Put32(&d, 0x4c433033);
  Put32(&d, seqno);
  Put32(&d, message_size);
  Put32(&d, offset);
  Put16(&d, number);
  Put16(&d, count);
  if (number == 0) {
    d.insert(d.end(), channel.begin(), channel.end());
    d.push_back(0);
  }
  d.insert(d.end(), piece.begin(), piece.end());
  return d;
}

}  // namespace rover::bus::test
