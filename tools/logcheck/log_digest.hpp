// A digest of a run's log, to compare two runs at a glance (README, "Simulated time").
//
// SHA-256 (libsodium) over every event's timestamp, channel and bytes, in order. The only
// fields left out are the ones that must carry wall time: VO_UPDATE's ms_detect, ms_stereo,
// ms_track, ms_ransac, ms_ml and ms_total (how long VO took on this machine), which are
// zeroed before hashing. Two virtual-time runs of the same scenario and seeds give the
// same digest on any load and at any rate.
#pragma once

#include <string>

namespace rover::logcheck {

struct LogDigest {
  std::string sha256_hex;  // empty when the log could not be read (see error)
  long long events = 0;
  std::string error;
};

LogDigest DigestLog(const std::string& path);

}  // namespace rover::logcheck
