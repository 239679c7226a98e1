// Hostile packets for every channel of the bus (tools/fault_inject, tests/fault).
//
// Each channel gets a plausible, valid message of its type (never sent as it is); every
// packet is that message's encoding with one thing wrong:
//   malformed  a string length or an array count of 0, -1, one past the data, 50 million
//              or 2^31-1; truncated; grown past the channel's size bound; a wrong type
//              fingerprint or another channel's type; random bytes behind the right
//              fingerprint
//   values     NaN, +inf or -inf in each double field; an unknown value in each enum
//   times      each utime field at now +/- 10^12 us, and at the int64 extremes
//   images     (STEREO_FRAME, HAZCAM_FRAME) bad and hostile images: negative or zero sides, a PNG whose
//              header claims 65535x65535, a PNG bomb, sizes that disagree with the camera
//              model or the byte count, unknown encodings, colour, truncated PNGs, bad
//              camera models
//   spoofed    (command channels) commands that would change what the rover does: a
//              STOP, a turn, an abort, a zone around the rover, a new site, a submit;
//              unsigned, and with a made-up tag (a deployment with keys refuses them all;
//              one without keys obeys them)
// Labels name the channel, the field and the fault, so a death can be traced to a packet.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace rover::fault {

using Bytes = std::vector<std::uint8_t>;

struct Packet {
  std::string channel;
  std::string label;  // "HEARTBEAT malformed process: string length 0"
  Bytes bytes;
  // Images only: a phrase visual_odometry's VO_UPDATE reason must hold for this frame
  // ("" when the Bus's own field checks may drop the frame before VO sees it). The same
  // on HAZCAM_FRAME, whose reader (the map) drops a bad frame with its reason.
  std::string expect_reason;
};

struct ChannelInfo {
  std::string channel;
  std::string type;  // rover_msgs type name, e.g. "heartbeat_t"
};

// Every channel of the bus and its type (common/bus/channels.hpp).
const std::vector<ChannelInfo>& AllChannels();
const ChannelInfo& Channel(const std::string& channel);  // throws when unknown

struct PacketOptions {
  std::int64_t now_utime = 0;  // rover time the packets are built around
  std::uint32_t seed = 1;      // random payloads; same seed, same packets
  // The largest payload a receiver accepts on a channel (common/bus MaxPayloadBytes).
  std::function<std::size_t(const std::string& channel)> max_payload_bytes;
  // Side of the PNG bomb's square image of zeros (its header claims it).
  int bomb_side = 16384;
};

// The groups, in the order "all" runs them: malformed, values, times, images, spoofed.
const std::vector<std::string>& Groups();

// The valid message a channel's packets start from, encoded.
Bytes SampleMessage(const std::string& channel, const PacketOptions& options);

// The packets of one group for one channel ("images" has packets only for STEREO_FRAME and
// HAZCAM_FRAME, "spoofed" only for the five command channels).
// Throws std::invalid_argument for an unknown group or channel.
std::vector<Packet> BuildPackets(const std::string& group, const std::string& channel,
                                 const PacketOptions& options);

// The publisher id fault_inject stamps into pub_seq (FNV-1a of "fault_inject", as the
// Bus stamps a process's name), so that a reader can tell injected messages apart.
std::uint32_t InjectorPublisherId();

}  // namespace rover::fault
