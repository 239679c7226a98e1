// Log completeness: which messages a recording lost, found from the publishers' own counts.
//
// Every rover message type except heartbeat_t starts the same way on the wire (LCM encodes
// big-endian): an 8-byte type fingerprint, `int64 utime`, `int64 pub_seq`. The high 32 bits
// of pub_seq name the publisher (FNV-1a of its process name), the low 32 bits count that
// publisher's messages on that channel from 0 (Bus::Publish stamps it). A heartbeat names
// its process and counts in `seq`. So, per channel and publisher:
//   - a count that skips ahead is a gap: the skipped messages were lost;
//   - a count that falls back to 0 is the publisher restarting, not a loss;
//   - a count that falls back to N > 0 is a restart whose first N messages were lost;
//   - a publisher whose first recorded count is N > 0 lost its first N messages, when the
//     recording started before the publisher did (TrackerOptions::from_start);
//   - unless the publisher was already running when the recording began, which a log
//     shows by itself (TrackerOptions::detect_joined): every process heartbeats once a
//     second, so a process heard in the log's first `joined_window_s` was publishing before
//     the recording started, and its earlier messages are before the log, not lost. A
//     process first heard later, or first heard at its count 0 (it started after the
//     recording, however soon), must count from 0 on every channel.
// Only those first bytes are read, so a check costs nothing per image and needs no decode of
// the message body. A message whose bytes cannot say (too short, another type's fingerprint,
// no pub_seq stamped) is "unchecked", and an unchecked message means completeness is unknown.
//
// The consistency check is separate: it decodes the few messages of one drive (captures,
// frames, VO updates, mobility commands and status, step reports) and says which capture
// has no frame, which VO frame no VO update, and which completed motion no step report.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace rover::logcheck {

// How a channel's messages count themselves.
enum class Counter { kPubSeq, kHeartbeatSeq };

struct ChannelType {
  const char* channel;
  const char* type_name;
  std::int64_t (*fingerprint)();  // the generated type's getHash()
  Counter counter;
};

// Every rover channel and the type it carries (common/bus/channels.hpp).
std::span<const ChannelType> KnownChannels();
const ChannelType* FindChannel(std::string_view channel);

// The publisher id in pub_seq's high 32 bits: 32-bit FNV-1a of the process name
// (bus::PublisherId, the one Bus::Publish stamps).
std::uint32_t PublisherId(std::string_view process_name);

// Where one message came from.
struct Stamp {
  std::int64_t utime = 0;
  std::string publisher;  // the process name (heartbeat) or "0x" + the 32-bit id in hex
  std::uint32_t publisher_id = 0;
  std::int64_t count = 0;  // that publisher's count on this channel
};

// The stamp of an encoded message, or why it cannot be read (`error`).
struct StampRead {
  std::optional<Stamp> stamp;
  std::string error;
};
StampRead ReadStamp(const ChannelType& type, const std::uint8_t* data, std::size_t size);

struct Gap {
  enum class Kind {
    kSkipped,        // the count jumped ahead
    kAtStart,        // the publisher's first recorded count was not 0
    kAfterRestart,   // the count fell back, but not to 0
  };
  Kind kind = Kind::kSkipped;
  std::string channel;
  std::string publisher;
  std::int64_t utime_before = 0;  // the last message before the gap (0 for kAtStart)
  std::int64_t utime_after = 0;   // the first message after it
  std::int64_t count_before = -1; // -1 for kAtStart
  std::int64_t count_after = 0;
  std::int64_t lost = 0;
};

struct Restart {
  std::string channel;
  std::string publisher;
  std::int64_t utime = 0;         // the first message of the new run
  std::int64_t count_before = 0;  // the last count of the old run
};

struct ChannelReport {
  std::string type_name;          // empty: not a rover channel (not checked)
  std::int64_t count = 0;         // messages in the log
  std::int64_t lost = 0;
  std::vector<Gap> gaps;
  std::vector<Restart> restarts;
  std::set<std::string> publishers;
  std::int64_t unchecked = 0;     // messages whose stamp could not be read
  std::string unchecked_reason;   // the first reason
};

struct TrackerOptions {
  // The recording started before its publishers, so each publisher's first count must be
  // 0 (a scenario log). False for a recording that joined a running bus.
  bool from_start = true;
  // With from_start: a publisher (process) heard within joined_window_s of the log's first
  // message was running before the recording began; its first counts are not losses
  // (`logcheck` and the recorder; a scenario, whose recorder starts first, checks strictly).
  bool detect_joined = false;
  double joined_window_s = 2.0;  // > the 1 s heartbeat period
};

// Follows every (channel, publisher) count, message by message: the recorder runs it live,
// the checker over a file.
class LossTracker {
 public:
  explicit LossTracker(TrackerOptions options = {}) : options_(options) {}

  // Takes one message; returns the gap it reveals, if any. A restart is recorded in the
  // channel's report (and returned through `restart` when given).
  std::optional<Gap> Observe(const std::string& channel, const std::uint8_t* data,
                             std::size_t size, std::optional<Restart>* restart = nullptr);
  // The same, with the message's log timestamp (microseconds), which detect_joined needs.
  std::optional<Gap> ObserveAt(std::int64_t log_timestamp_us, const std::string& channel,
                               const std::uint8_t* data, std::size_t size,
                               std::optional<Restart>* restart = nullptr);

  const std::map<std::string, ChannelReport>& channels() const { return channels_; }
  std::int64_t messages() const { return messages_; }
  std::int64_t lost() const;
  std::int64_t unchecked() const;
  // A readable name for a publisher key: heartbeats name their processes, and each name's
  // FNV-1a id maps a pub_seq id back to it.
  std::string PublisherName(const std::string& key) const;
  // detect_joined: the processes that had published before the recording began, and how
  // many of their messages (all channels) were published before it.
  std::set<std::string> JoinedPublishers() const;
  std::int64_t before_recording() const { return before_recording_; }
  const TrackerOptions& options() const { return options_; }

 private:
  bool RunningBeforeTheLog(std::uint32_t publisher_id, std::int64_t count, std::int64_t log_timestamp_us);
  struct Last {
    std::int64_t count;
    std::int64_t utime;
  };
  TrackerOptions options_;
  std::map<std::string, ChannelReport> channels_;
  std::map<std::pair<std::string, std::string>, Last> last_;  // (channel, publisher)
  std::map<std::uint32_t, std::string> names_;                // publisher id -> process name
  std::int64_t messages_ = 0;
  std::int64_t first_timestamp_us_ = -1;                      // the log's first message
  std::map<std::uint32_t, bool> running_before_;              // publisher id -> joined?
  std::map<std::uint32_t, std::int64_t> before_by_publisher_; // its messages before the log
  std::int64_t before_recording_ = 0;
};

// Captures, frames, VO updates and steps that do not add up.
class ConsistencyCheck {
 public:
  void Observe(const std::string& channel, const std::uint8_t* data, std::size_t size);
  // One line per finding, naming the ids.
  std::vector<std::string> Warnings() const;

 private:
  std::map<std::int64_t, std::string> requests_;  // frame id -> purpose
  std::map<std::int64_t, std::string> frames_;    // frame id -> purpose
  std::set<std::int64_t> hazcam_frames_;          // HAZCAM_FRAME frame ids
  std::set<std::int64_t> vo_frames_;              // VO_UPDATE to_frame_id
  std::set<std::int64_t> motions_;                // ARC and TURN command ids
  std::set<std::int64_t> completed_;              // command ids with a DONE status
  std::vector<std::int64_t> step_commands_;       // STEP_REPORT mobility_command_id
  std::int64_t undecodable_ = 0;
};

struct LogReport {
  std::string path;
  std::int64_t messages = 0;
  std::map<std::string, ChannelReport> channels;
  std::map<std::string, std::string> publisher_names;  // key -> readable name
  std::int64_t lost = 0;
  std::int64_t unchecked = 0;
  std::set<std::string> joined;         // processes running before the recording (detect_joined)
  std::int64_t before_recording = 0;    // their messages published before it (not lost)
  double joined_window_s = 0;
  std::string trailing;                 // non-empty: bytes after the last whole event
  std::vector<std::string> warnings;    // consistency
  bool complete = false;
  std::string verdict_reason;           // why not complete (empty when complete)
};

// The report of what `tracker` and `consistency` have seen (the recorder's, live).
// `trailing` is the file's own defect, if any (see CheckLog).
LogReport Summarize(const std::string& path, const LossTracker& tracker,
                    const ConsistencyCheck& consistency, const std::string& trailing = "");

// Reads an LCM log (lcm::LogFile). Throws std::runtime_error naming the file when it is not
// a readable regular file.
LogReport CheckLog(const std::string& path, TrackerOptions options = {});

// The report as text: a table per channel, one line per gap, restart and warning, and the
// verdict line "log complete: yes" or "log complete: no (...)".
std::string FormatReport(const LogReport& report);

}  // namespace rover::logcheck
