#include "web_console/log_playback.hpp"

#include "bus/channels.hpp"
#include "bus/validate.hpp"

#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <map>
#include <stdexcept>

namespace rover::web {

LogPlayback::LogPlayback(std::string path, WebStateOptions options)
    : path_(std::move(path)), options_(std::move(options)) {
  Load();
  // The whole log once: the checks' count, and the picture the page opens on (the end).
  std::lock_guard<std::mutex> lock(mutex_);
  state_ = std::make_unique<WebState>(options_);
  cursor_utime_ = first_utime_;
  MoveTo(last_utime_);
}

LogPlayback::~LogPlayback() = default;

void LogPlayback::Load() {
  namespace ch = channels;
  const std::map<std::string, Kind> kinds = {
      {ch::kPose, Kind::kPose},           {ch::kSimTruth, Kind::kTruth},
      {ch::kTraversabilityMap, Kind::kMap}, {ch::kKeepOutZones, Kind::kZones},
      {ch::kSequenceStatus, Kind::kStatus}, {ch::kSequenceSubmit, Kind::kSubmit},
      {ch::kStepReport, Kind::kStep},     {ch::kVoUpdate, Kind::kVo},
      {ch::kHazardStatus, Kind::kHazard}, {ch::kHeartbeat, Kind::kHeartbeat},
      {ch::kStereoFrame, Kind::kStereo},  {ch::kClock, Kind::kClock}};
  file_ = std::make_unique<lcm::LogFile>(path_, "r");
  if (!file_->good()) throw std::runtime_error(path_ + ": cannot read the LCM log (expected a log from rover_recorder or ./rover scenario --out)");
  FILE* fp = file_->getFilePtr();
  for (;;) {
    const long offset = std::ftell(fp);
    const lcm::LogEvent* e = file_->readNextEvent();
    if (e == nullptr) break;
    const auto kind = kinds.find(e->channel);
    if (kind == kinds.end()) continue;
    Event ev{e->timestamp, kind->second, {}, offset};
    if (kind->second != Kind::kStereo) ev.data.assign(static_cast<const char*>(e->data), static_cast<std::size_t>(e->datalen));
    events_.push_back(std::move(ev));
  }
  if (events_.empty()) {
    throw std::runtime_error(path_ + ": no message the web console shows (expected POSE, SEQUENCE_STATUS, ... in an LCM log)");
  }
  // The recorder writes in the order it heard: stamps are kept as they are, and the
  // playback's span is the smallest and largest of them.
  first_utime_ = last_utime_ = events_.front().utime;
  for (const auto& e : events_) {
    first_utime_ = std::min(first_utime_, e.utime);
    last_utime_ = std::max(last_utime_, e.utime);
  }
}

template <class T>
bool LogPlayback::Decode(const std::string& data, T* m) const {
  if (m->decode(data.data(), 0, static_cast<int>(data.size())) < 0) return false;
  return bus::Problem(*m).empty();
}

bool LogPlayback::Feed(const Event& e) {
  const double t = e.utime * 1e-6;  // heartbeats age in log time
  auto feed = [&](auto msg) {
    if (!Decode(e.data, &msg)) return false;
    state_->On(msg, t);
    return true;
  };
  switch (e.kind) {
    case Kind::kPose: return feed(rover_msgs::pose_t{});
    case Kind::kTruth: return feed(rover_msgs::sim_truth_t{});
    case Kind::kMap: return feed(rover_msgs::traversability_map_t{});
    case Kind::kZones: return feed(rover_msgs::keepout_zones_t{});
    case Kind::kStatus: return feed(rover_msgs::sequence_status_t{});
    case Kind::kSubmit: return feed(rover_msgs::sequence_submit_t{});
    case Kind::kStep: return feed(rover_msgs::step_report_t{});
    case Kind::kVo: return feed(rover_msgs::vo_update_t{});
    case Kind::kHazard: return feed(rover_msgs::hazard_status_t{});
    case Kind::kHeartbeat: return feed(rover_msgs::heartbeat_t{});
    case Kind::kClock: {
      rover_msgs::rover_clock_t m{};
      if (!Decode(e.data, &m)) return false;
      state_->OnRoverClock(m.utime);
      return true;
    }
    case Kind::kStereo: return true;  // read back from the file once the cursor stops (FeedStereo)
  }
  return false;
}

void LogPlayback::FeedStereo(std::size_t index) {
  FILE* fp = file_->getFilePtr();
  if (std::fseek(fp, events_[index].offset, SEEK_SET) != 0) return;
  const lcm::LogEvent* e = file_->readNextEvent();
  if (e == nullptr) return;
  rover_msgs::stereo_frame_t m{};
  if (m.decode(e->data, 0, e->datalen) < 0 || !bus::Problem(m).empty()) return;
  state_->On(m, events_[index].utime * 1e-6);
}

void LogPlayback::MoveTo(std::int64_t utime) {
  utime = std::clamp(utime, first_utime_, last_utime_);
  if (utime < cursor_utime_) {
    state_ = std::make_unique<WebState>(options_);
    next_ = 0;
    latest_stereo_ = fed_stereo_ = -1;
  }
  for (; next_ < events_.size() && events_[next_].utime <= utime; ++next_) {
    if (events_[next_].kind == Kind::kStereo) latest_stereo_ = static_cast<long>(next_);
    const bool fed = Feed(events_[next_]);
    if (next_ >= checked_) {  // each message is counted once, however often it is fed
      if (!fed) ++rejected_;
      checked_ = next_ + 1;
    }
  }
  // WebState keeps only the newest frame: feeding the one in view is feeding them all.
  if (latest_stereo_ >= 0 && latest_stereo_ != fed_stereo_) {
    FeedStereo(static_cast<std::size_t>(latest_stereo_));
    fed_stereo_ = latest_stereo_;
  }
  cursor_utime_ = utime;
}

std::string LogPlayback::StateJsonAt(std::optional<std::int64_t> utime) {
  std::lock_guard<std::mutex> lock(mutex_);
  MoveTo(utime.value_or(cursor_utime_));
  const PlaybackInfo info{path_, first_utime_, last_utime_, cursor_utime_};
  return state_->StateJson(cursor_utime_ * 1e-6, &info);
}

std::string LogPlayback::LeftImagePngAt(std::optional<std::int64_t> utime, int max_width, std::string* why) {
  std::lock_guard<std::mutex> lock(mutex_);
  MoveTo(utime.value_or(cursor_utime_));
  return state_->LeftImagePng(max_width, why);
}

}  // namespace rover::web
