#include "logcheck/log_check.hpp"

#include "bus/bus.hpp"
#include "bus/channels.hpp"
#include "logcheck/log_reader.hpp"

#include <lcm/lcm-cpp.hpp>
#include <rover_msgs/capture_request_t.hpp>
#include <rover_msgs/hazard_query_t.hpp>
#include <rover_msgs/hazard_reply_t.hpp>
#include <rover_msgs/hazard_status_t.hpp>
#include <rover_msgs/heartbeat_t.hpp>
#include <rover_msgs/imu_t.hpp>
#include <rover_msgs/keepout_zones_t.hpp>
#include <rover_msgs/mobility_command_t.hpp>
#include <rover_msgs/mobility_status_t.hpp>
#include <rover_msgs/new_site_t.hpp>
#include <rover_msgs/pose_t.hpp>
#include <rover_msgs/rover_clock_t.hpp>
#include <rover_msgs/sequence_control_t.hpp>
#include <rover_msgs/sequence_status_t.hpp>
#include <rover_msgs/sequence_submit_t.hpp>
#include <rover_msgs/sim_truth_t.hpp>
#include <rover_msgs/step_report_t.hpp>
#include <rover_msgs/stereo_frame_t.hpp>
#include <rover_msgs/traversability_map_t.hpp>
#include <rover_msgs/vo_update_t.hpp>
#include <rover_msgs/wheel_odometry_t.hpp>

#include <sys/stat.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <sstream>
#include <stdexcept>

namespace rover::logcheck {

namespace {

using namespace rover_msgs;

constexpr std::array<ChannelType, 22> kChannels = {{
    {channels::kHeartbeat, "heartbeat_t", &heartbeat_t::getHash, Counter::kHeartbeatSeq},
    {channels::kClock, "rover_clock_t", &rover_clock_t::getHash, Counter::kPubSeq},
    {channels::kImu, "imu_t", &imu_t::getHash, Counter::kPubSeq},
    {channels::kWheelOdometry, "wheel_odometry_t", &wheel_odometry_t::getHash, Counter::kPubSeq},
    {channels::kPose, "pose_t", &pose_t::getHash, Counter::kPubSeq},
    {channels::kNewSite, "new_site_t", &new_site_t::getHash, Counter::kPubSeq},
    {channels::kMobilityCommand, "mobility_command_t", &mobility_command_t::getHash, Counter::kPubSeq},
    {channels::kMobilityStatus, "mobility_status_t", &mobility_status_t::getHash, Counter::kPubSeq},
    {channels::kCaptureRequest, "capture_request_t", &capture_request_t::getHash, Counter::kPubSeq},
    {channels::kStereoFrame, "stereo_frame_t", &stereo_frame_t::getHash, Counter::kPubSeq},
    {channels::kHazcamFrame, "stereo_frame_t", &stereo_frame_t::getHash, Counter::kPubSeq},
    {channels::kVoUpdate, "vo_update_t", &vo_update_t::getHash, Counter::kPubSeq},
    {channels::kKeepOutZones, "keepout_zones_t", &keepout_zones_t::getHash, Counter::kPubSeq},
    {channels::kHazardStatus, "hazard_status_t", &hazard_status_t::getHash, Counter::kPubSeq},
    {channels::kHazardQuery, "hazard_query_t", &hazard_query_t::getHash, Counter::kPubSeq},
    {channels::kHazardReply, "hazard_reply_t", &hazard_reply_t::getHash, Counter::kPubSeq},
    {channels::kSequenceSubmit, "sequence_submit_t", &sequence_submit_t::getHash, Counter::kPubSeq},
    {channels::kSequenceControl, "sequence_control_t", &sequence_control_t::getHash, Counter::kPubSeq},
    {channels::kSequenceStatus, "sequence_status_t", &sequence_status_t::getHash, Counter::kPubSeq},
    {channels::kStepReport, "step_report_t", &step_report_t::getHash, Counter::kPubSeq},
    {channels::kSimTruth, "sim_truth_t", &sim_truth_t::getHash, Counter::kPubSeq},
    {channels::kTraversabilityMap, "traversability_map_t", &traversability_map_t::getHash, Counter::kPubSeq},
}};

// Names for publisher ids when the log holds no heartbeat from them: the processes, and the
// operator and test tools that publish without a heartbeat.
constexpr std::array<const char*, 11> kKnownNames = {
    "rover_sim",     "camera_capture",  "visual_odometry",    "state_estimator",
    "hazard_monitor", "sequence_executor", "rover_seq",       "scenario_runner",
    "scenario_benchmark", "capture_benchmark", "rover_recorder"};

// Reads LCM's big-endian fields from the front of an encoded message, never past its end.
// Hand-written because the generated decode allocates whatever a length field claims before
// it checks the size; this reads only fixed fields and bounded strings.
class WireReader {
 public:
  WireReader(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}

  bool Int64(std::int64_t& v) { return Fixed(8, v); }
  bool Int32(std::int32_t& v) {
    std::int64_t x = 0;
    if (!Fixed(4, x)) return false;
    v = static_cast<std::int32_t>(static_cast<std::uint32_t>(x));
    return true;
  }
  bool Int8(std::int8_t& v) {
    if (pos_ + 1 > size_) return false;
    v = static_cast<std::int8_t>(data_[pos_++]);
    return true;
  }
  // An LCM string: int32 length including the NUL, the bytes, the NUL.
  bool String(std::string& s, std::int32_t max_len = 4096) {
    std::int32_t len = 0;
    if (!Int32(len) || len < 1 || len > max_len) return false;
    if (pos_ + static_cast<std::size_t>(len) > size_) return false;
    if (data_[pos_ + len - 1] != 0) return false;
    s.assign(reinterpret_cast<const char*>(data_ + pos_), static_cast<std::size_t>(len - 1));
    pos_ += static_cast<std::size_t>(len);
    return true;
  }
  bool Skip(std::size_t n) {
    if (pos_ + n > size_) return false;
    pos_ += n;
    return true;
  }

 private:
  bool Fixed(std::size_t n, std::int64_t& v) {
    if (pos_ + n > size_) return false;
    std::uint64_t x = 0;
    for (std::size_t i = 0; i < n; ++i) x = (x << 8) | data_[pos_ + i];
    pos_ += n;
    v = static_cast<std::int64_t>(x);
    return true;
  }
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
};

std::string Hex32(std::uint32_t v) {
  char buf[16];
  std::snprintf(buf, sizeof(buf), "0x%08x", v);
  return buf;
}

// The fingerprint, utime and pub_seq every non-heartbeat type starts with; the fields after
// them are the caller's to read. False when the message is not of `type`.
bool ReadHeader(WireReader& r, std::int64_t (*fingerprint)()) {
  std::int64_t fp = 0, utime = 0, pub_seq = 0;
  return r.Int64(fp) && fp == fingerprint() && r.Int64(utime) && r.Int64(pub_seq);
}

std::string IdList(const std::vector<std::int64_t>& ids) {
  std::ostringstream os;
  const std::size_t shown = std::min<std::size_t>(ids.size(), 20);
  for (std::size_t i = 0; i < shown; ++i) os << (i ? ", " : "") << ids[i];
  if (ids.size() > shown) os << " and " << ids.size() - shown << " more";
  return os.str();
}

}  // namespace

std::span<const ChannelType> KnownChannels() {
  return kChannels;
}

const ChannelType* FindChannel(std::string_view channel) {
  for (const auto& c : KnownChannels()) {
    if (channel == c.channel) return &c;
  }
  return nullptr;
}

std::uint32_t PublisherId(std::string_view name) { return bus::PublisherId(std::string(name)); }

StampRead ReadStamp(const ChannelType& type, const std::uint8_t* data, std::size_t size) {
  StampRead out;
  WireReader r(data, size);
  std::int64_t fp = 0;
  if (!r.Int64(fp)) {
    out.error = "shorter than a type fingerprint (" + std::to_string(size) + " bytes)";
    return out;
  }
  if (fp != type.fingerprint()) {
    out.error = std::string("fingerprint is not ") + type.type_name + "'s";
    return out;
  }
  Stamp s;
  if (!r.Int64(s.utime)) {
    out.error = "too short for utime";
    return out;
  }
  if (type.counter == Counter::kHeartbeatSeq) {
    if (!r.String(s.publisher, 256) || s.publisher.empty()) {
      out.error = "process name is not a string of 1 to 255 bytes";
      return out;
    }
    if (!r.Int64(s.count) || s.count < 0) {
      out.error = "no heartbeat seq (or a negative one)";
      return out;
    }
    s.publisher_id = PublisherId(s.publisher);
  } else {
    std::int64_t pub_seq = 0;
    if (!r.Int64(pub_seq)) {
      out.error = "too short for pub_seq";
      return out;
    }
    const auto bits = static_cast<std::uint64_t>(pub_seq);
    s.publisher_id = static_cast<std::uint32_t>(bits >> 32);
    s.count = static_cast<std::int64_t>(bits & 0xffffffffu);
    if (s.publisher_id == 0) {
      out.error = "pub_seq not stamped (publisher id 0)";
      return out;
    }
    s.publisher = Hex32(s.publisher_id);
  }
  out.stamp = s;
  return out;
}

std::optional<Gap> LossTracker::Observe(const std::string& channel, const std::uint8_t* data,
                                        std::size_t size, std::optional<Restart>* restart) {
  return ObserveAt(-1, channel, data, size, restart);
}

// Decided once per process, at its first message in the log: heard within the window of
// the log's first message means it was already publishing when the recording began,
// unless that first message is its count 0 (a heartbeat's seq 0, say): then it started
// after the recording did, however soon, and every count it skipped is a loss.
bool LossTracker::RunningBeforeTheLog(std::uint32_t publisher_id, std::int64_t count,
                                      std::int64_t log_timestamp_us) {
  if (!options_.detect_joined || log_timestamp_us < 0) return false;
  const auto [it, first] = running_before_.try_emplace(publisher_id, false);
  if (first) {
    it->second = count > 0 &&
                 log_timestamp_us - first_timestamp_us_ <= static_cast<std::int64_t>(options_.joined_window_s * 1e6);
  }
  return it->second;
}

std::set<std::string> LossTracker::JoinedPublishers() const {
  std::set<std::string> out;
  for (const auto& [id, before] : before_by_publisher_) {
    if (before == 0) continue;
    auto it = names_.find(id);
    out.insert(it != names_.end() ? it->second : PublisherName(Hex32(id)));
  }
  return out;
}

std::optional<Gap> LossTracker::ObserveAt(std::int64_t log_timestamp_us, const std::string& channel,
                                          const std::uint8_t* data, std::size_t size,
                                          std::optional<Restart>* restart) {
  ++messages_;
  if (first_timestamp_us_ < 0) first_timestamp_us_ = log_timestamp_us;
  ChannelReport& report = channels_[channel];
  ++report.count;
  const ChannelType* type = FindChannel(channel);
  if (type == nullptr) return std::nullopt;  // not a rover channel: counted, not checked
  report.type_name = type->type_name;
  const StampRead read = ReadStamp(*type, data, size);
  if (!read.stamp) {
    if (report.unchecked++ == 0) report.unchecked_reason = read.error;
    return std::nullopt;
  }
  const Stamp& s = *read.stamp;
  if (type->counter == Counter::kHeartbeatSeq) names_.emplace(s.publisher_id, s.publisher);
  report.publishers.insert(s.publisher);

  auto [it, first] = last_.try_emplace({channel, s.publisher}, Last{s.count, s.utime});
  std::optional<Gap> gap;
  auto make_gap = [&](Gap::Kind kind, std::int64_t lost) {
    Gap g;
    g.kind = kind;
    g.channel = channel;
    g.publisher = s.publisher;
    g.utime_before = first ? 0 : it->second.utime;
    g.utime_after = s.utime;
    g.count_before = first ? -1 : it->second.count;
    g.count_after = s.count;
    g.lost = lost;
    return g;
  };
  const bool joined = RunningBeforeTheLog(s.publisher_id, s.count, log_timestamp_us);
  if (first) {
    if (s.count > 0 && joined) {
      before_recording_ += s.count;
      before_by_publisher_[s.publisher_id] += s.count;
    } else if (s.count > 0 && options_.from_start) {
      gap = make_gap(Gap::Kind::kAtStart, s.count);
    }
  } else if (s.count > it->second.count + 1) {
    gap = make_gap(Gap::Kind::kSkipped, s.count - it->second.count - 1);
  } else if (s.count <= it->second.count) {
    Restart r{channel, s.publisher, s.utime, it->second.count};
    report.restarts.push_back(r);
    if (restart != nullptr) *restart = r;
    if (s.count > 0) gap = make_gap(Gap::Kind::kAfterRestart, s.count);
  }
  it->second = Last{s.count, s.utime};
  if (gap) {
    report.lost += gap->lost;
    report.gaps.push_back(*gap);
  }
  return gap;
}

std::int64_t LossTracker::lost() const {
  std::int64_t n = 0;
  for (const auto& [name, c] : channels_) n += c.lost;
  return n;
}

std::int64_t LossTracker::unchecked() const {
  std::int64_t n = 0;
  for (const auto& [name, c] : channels_) n += c.unchecked;
  return n;
}

std::string LossTracker::PublisherName(const std::string& key) const {
  if (key.rfind("0x", 0) != 0) return key;  // a heartbeat's process name
  const auto id = static_cast<std::uint32_t>(std::stoul(key.substr(2), nullptr, 16));
  if (auto it = names_.find(id); it != names_.end()) return it->second;
  for (const char* known : kKnownNames) {
    if (PublisherId(known) == id) return known;
  }
  return key;
}

void ConsistencyCheck::Observe(const std::string& channel, const std::uint8_t* data,
                               std::size_t size) {
  WireReader r(data, size);
  bool ok = true;
  std::int64_t id = 0;
  if (channel == channels::kCaptureRequest) {
    std::string purpose;
    ok = ReadHeader(r, &capture_request_t::getHash) && r.Int64(id) && r.String(purpose);
    if (ok) requests_[id] = purpose;
  } else if (channel == channels::kStereoFrame) {
    std::string purpose;
    ok = ReadHeader(r, &stereo_frame_t::getHash) && r.Int64(id) && r.String(purpose);
    if (ok) frames_[id] = purpose;
  } else if (channel == channels::kHazcamFrame) {
    std::string purpose;
    ok = ReadHeader(r, &stereo_frame_t::getHash) && r.Int64(id) && r.String(purpose);
    if (ok) hazcam_frames_.insert(id);
  } else if (channel == channels::kVoUpdate) {
    std::int64_t from = 0;
    ok = ReadHeader(r, &vo_update_t::getHash) && r.Int64(from) && r.Int64(id);
    if (ok) vo_frames_.insert(id);
  } else if (channel == channels::kMobilityCommand) {
    std::int8_t type = 0;
    ok = ReadHeader(r, &mobility_command_t::getHash) && r.Int64(id) && r.Int8(type);
    if (ok && type != mobility_command_t::TYPE_STOP) motions_.insert(id);
  } else if (channel == channels::kMobilityStatus) {
    std::int8_t state = 0;
    ok = ReadHeader(r, &mobility_status_t::getHash) && r.Int64(id) && r.Int8(state);
    if (ok && state == mobility_status_t::STATE_DONE) completed_.insert(id);
  } else if (channel == channels::kStepReport) {
    std::int64_t submission = 0;
    ok = ReadHeader(r, &step_report_t::getHash) && r.Int64(submission) && r.Skip(8) &&
         r.Int64(id);
    if (ok) step_commands_.push_back(id);
  } else {
    return;
  }
  if (!ok) ++undecodable_;
}

std::vector<std::string> ConsistencyCheck::Warnings() const {
  std::vector<std::string> out;
  std::vector<std::int64_t> ids;
  for (const auto& [frame, purpose] : requests_) {
    if (!frames_.count(frame)) ids.push_back(frame);
  }
  if (!ids.empty()) {
    out.push_back(std::to_string(ids.size()) + " CAPTURE_REQUEST without a STEREO_FRAME: frame " +
                  IdList(ids));
  }
  ids.clear();
  for (const auto& [frame, purpose] : frames_) {
    // Science pairs are for the operator; visual odometry answers only VO pairs.
    if ((purpose == "vo" || purpose == "vo_baseline") && !vo_frames_.count(frame)) {
      ids.push_back(frame);
    }
  }
  if (!ids.empty()) {
    out.push_back(std::to_string(ids.size()) + " STEREO_FRAME without a VO_UPDATE: frame " +
                  IdList(ids));
  }
  ids.clear();
  // A HAZCAM pair is taken with a NAVCAM pair and published with it (just before); it feeds
  // the map only, so it needs no VO_UPDATE. A NAVCAM pair without one is fine: a HAZCAM
  // render can fail, and a deployment may have no HAZCAMs.
  for (const std::int64_t frame : hazcam_frames_) {
    if (!frames_.count(frame)) ids.push_back(frame);
  }
  if (!ids.empty()) {
    out.push_back(std::to_string(ids.size()) + " HAZCAM_FRAME without a STEREO_FRAME: frame " +
                  IdList(ids));
  }
  ids.clear();
  std::int64_t completed_motions = 0;
  const std::set<std::int64_t> reported(step_commands_.begin(), step_commands_.end());
  for (const std::int64_t id : completed_) {
    if (!motions_.count(id)) continue;
    ++completed_motions;
    if (!reported.count(id)) ids.push_back(id);
  }
  const auto reports = static_cast<std::int64_t>(step_commands_.size());
  if (reports != completed_motions || !ids.empty()) {
    std::string line = std::to_string(reports) + " STEP_REPORT for " +
                       std::to_string(completed_motions) + " completed motion commands";
    if (!ids.empty()) line += "; completed without a step report: command " + IdList(ids);
    std::vector<std::int64_t> extra;
    for (const std::int64_t id : reported) {
      if (!completed_.count(id) || !motions_.count(id)) extra.push_back(id);
    }
    if (!extra.empty()) line += "; step report for no completed motion: command " + IdList(extra);
    out.push_back(line);
  }
  if (undecodable_ > 0) {
    out.push_back(std::to_string(undecodable_) +
                  " capture, frame, VO, mobility or step messages too short or of another type");
  }
  return out;
}

LogReport CheckLog(const std::string& path, TrackerOptions options) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    throw std::runtime_error(path + ": cannot read the LCM log (no such file)");
  }
  if (!S_ISREG(st.st_mode)) {
    throw std::runtime_error(path + ": not a regular file (expected an LCM log)");
  }
  rover::logcheck::LogReader log(path);
  if (!log.good()) throw std::runtime_error(path + ": cannot open the LCM log");

  LossTracker tracker(options);
  ConsistencyCheck consistency;
  std::string trailing;
  // LCM's reader skips, silently, bytes that do not start an event (it searches for the
  // next event's magic number) and stops at an event it cannot read whole. Both show in
  // the file offsets: an event must start where the previous one ended, and the last one
  // must end at the end of the file.
  std::int64_t end = 0, skipped = 0;
  for (const lcm::LogEvent* ev = log.readNextEvent(); ev != nullptr; ev = log.readNextEvent()) {
    const auto* data = static_cast<const std::uint8_t*>(ev->data);
    const auto size = static_cast<std::size_t>(std::max<std::int32_t>(ev->datalen, 0));
    tracker.ObserveAt(ev->timestamp, ev->channel, data, size);
    consistency.Observe(ev->channel, data, size);
    const std::int64_t event_end = ftello(log.getFilePtr());
    const auto event_bytes = static_cast<std::int64_t>(4 + 8 + 8 + 4 + ev->channel.size() + 4 + size);
    skipped += std::max<std::int64_t>(0, event_end - event_bytes - end);
    end = event_end;
  }
  if (skipped > 0) {
    trailing = std::to_string(skipped) + " bytes between events that are not events (corrupt)";
  }
  if (end < st.st_size) {
    trailing += std::string(trailing.empty() ? "" : "; ") +
                       std::to_string(st.st_size - end) +
                       " bytes after the last whole event at offset " + std::to_string(end) +
                       " (truncated or corrupt)";
  }
  return Summarize(path, tracker, consistency, trailing);
}

LogReport Summarize(const std::string& path, const LossTracker& tracker,
                    const ConsistencyCheck& consistency, const std::string& trailing) {
  LogReport report;
  report.path = path;
  report.trailing = trailing;
  report.messages = tracker.messages();
  report.channels = tracker.channels();
  for (const auto& [name, c] : report.channels) {
    for (const auto& p : c.publishers) report.publisher_names[p] = tracker.PublisherName(p);
  }
  report.lost = tracker.lost();
  report.unchecked = tracker.unchecked();
  report.joined = tracker.JoinedPublishers();
  report.before_recording = tracker.before_recording();
  report.joined_window_s = tracker.options().joined_window_s;
  report.warnings = consistency.Warnings();

  std::vector<std::string> why;
  if (report.messages == 0) why.push_back("the log holds no messages");
  std::int64_t gaps = 0;
  for (const auto& [name, c] : report.channels) gaps += static_cast<std::int64_t>(c.gaps.size());
  if (report.lost > 0) {
    why.push_back(std::to_string(report.lost) + (report.lost == 1 ? " message" : " messages") +
                  " lost in " + std::to_string(gaps) +
                  (gaps == 1 ? " gap" : " gaps"));
  }
  if (report.unchecked > 0) {
    why.push_back(std::to_string(report.unchecked) +
                  (report.unchecked == 1 ? " message carries" : " messages carry") +
                  " no readable count");
  }
  if (!report.trailing.empty()) why.push_back(report.trailing);
  report.complete = why.empty();
  for (std::size_t i = 0; i < why.size(); ++i) report.verdict_reason += (i ? "; " : "") + why[i];
  return report;
}

std::string FormatReport(const LogReport& r) {
  std::ostringstream os;
  os << r.path << ": " << r.messages << " messages on " << r.channels.size() << " channels\n";
  char line[256];
  std::snprintf(line, sizeof(line), "%-18s %-20s %9s %7s %5s  %s\n", "channel", "type", "count",
                "lost", "gaps", "publishers");
  os << line;
  auto name = [&r](const std::string& key) {
    auto it = r.publisher_names.find(key);
    return it == r.publisher_names.end() ? key : it->second;
  };
  for (const auto& [channel, c] : r.channels) {
    std::string pubs;
    for (const auto& p : c.publishers) pubs += (pubs.empty() ? "" : ", ") + name(p);
    std::snprintf(line, sizeof(line), "%-18s %-20s %9lld %7lld %5zu  ", channel.c_str(),
                  c.type_name.empty() ? "(not checked)" : c.type_name.c_str(),
                  static_cast<long long>(c.count), static_cast<long long>(c.lost), c.gaps.size());
    os << line << pubs << "\n";
  }
  for (const auto& [channel, c] : r.channels) {
    for (const auto& g : c.gaps) {
      os << "gap: " << channel << " from " << name(g.publisher) << ": " << g.lost << " lost";
      switch (g.kind) {
        case Gap::Kind::kSkipped:
          os << " (count " << g.count_before << " then " << g.count_after << ") between utime "
             << g.utime_before << " and " << g.utime_after;
          break;
        case Gap::Kind::kAtStart:
          os << " before its first recorded message (count " << g.count_after << ", utime "
             << g.utime_after << ")";
          break;
        case Gap::Kind::kAfterRestart:
          os << " after a restart (count " << g.count_before << " then " << g.count_after
             << ") between utime " << g.utime_before << " and " << g.utime_after;
          break;
      }
      os << "\n";
    }
    for (const auto& s : c.restarts) {
      os << "restart: " << channel << " from " << name(s.publisher) << " at utime " << s.utime
         << " (count " << s.count_before << " before)\n";
    }
    if (c.unchecked > 0) {
      os << "unchecked: " << channel << ": " << c.unchecked << " messages (" << c.unchecked_reason
         << ")\n";
    }
    // LCM 1.3.1 sends LCM_SELF_TEST to itself when a bus opens: LCM's, not the rover's.
    if (c.type_name.empty() && channel != "LCM_SELF_TEST") {
      os << "note: " << channel << " is not a rover channel; its " << c.count
         << " messages were not checked\n";
    }
  }
  for (const auto& w : r.warnings) os << "warning: " << w << "\n";
  if (r.before_recording > 0) {
    std::string names;
    for (const auto& n : r.joined) names += (names.empty() ? "" : ", ") + n;
    os << "joined: the recording began on a running bus: " << names << " (heard in the log's first "
       << r.joined_window_s << " s) had published " << r.before_recording
       << " messages before it; those are not counted as lost (logcheck --from-start counts them)\n";
  }
  os << "log complete: " << (r.complete ? "yes" : "no");
  if (!r.complete) os << " (" << r.verdict_reason << ")";
  os << "\n";
  return os.str();
}

}  // namespace rover::logcheck
