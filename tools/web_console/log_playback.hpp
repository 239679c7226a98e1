// Playback of a recorded LCM log in the web console (rover_web --log FILE): the state at
// a time of the log is what the live console would have shown had it heard every message
// logged up to then. It is built by the same WebState as the live console, fed from the
// log instead of the bus, with the same field checks the Bus applies (bus/validate.hpp).
//
// Time is the log's event stamps. In virtual time (README, "Simulated time") the recorder
// stamps each message with the rover instant it was published in, so a time of the log
// is a rover time; a real-clock log's stamps are the wall times the recorder heard them.
//
// The log is read once with LCM's own reader (lcm::LogFile). The messages the console
// shows are kept in memory, except the stereo frames (up to megabytes each), of which only
// the place in the file is kept: the one in view at a time is read back when asked for.
// Moving forward feeds only the messages in between; moving back builds the state anew.
// Every member function is thread-safe (the HTTP threads share one playback).
#pragma once

#include "web_console/web_state.hpp"

#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace lcm {
class LogFile;
}

namespace rover::web {

class LogPlayback {
 public:
  // Reads the log and moves to its end. Throws std::runtime_error naming the file when it
  // cannot be read or holds no message the console shows.
  LogPlayback(std::string path, WebStateOptions options);
  ~LogPlayback();

  const std::string& path() const { return path_; }
  std::int64_t first_utime() const { return first_utime_; }
  std::int64_t last_utime() const { return last_utime_; }
  // Messages kept (on channels the console shows), and those left out because they did
  // not decode or failed the Bus's field checks.
  std::size_t messages() const { return events_.size(); }
  std::size_t rejected() const { return rejected_; }

  // The state at log time `utime` (clamped into the log; none: where the playback is),
  // with its "playback" key set.
  std::string StateJsonAt(std::optional<std::int64_t> utime);
  // The newest left image at log time `utime`, as WebState::LeftImagePng.
  std::string LeftImagePngAt(std::optional<std::int64_t> utime, int max_width, std::string* why);

 private:
  enum class Kind {
    kPose, kTruth, kMap, kZones, kStatus, kSubmit, kStep, kVo, kHazard, kHeartbeat, kStereo, kClock
  };
  struct Event {
    std::int64_t utime;
    Kind kind;
    std::string data;  // the encoded message (empty for stereo frames)
    long offset;       // where the event starts in the file (stereo frames)
  };

  void Load();
  // Feeds every event up to `utime` into state_ (anew when `utime` is before the cursor).
  void MoveTo(std::int64_t utime);
  // False when the message does not decode or fails the Bus's field checks.
  bool Feed(const Event& e);
  template <class T>
  bool Decode(const std::string& data, T* m) const;
  // Reads the stereo frame of event `index` from the file and feeds it.
  void FeedStereo(std::size_t index);

  std::string path_;
  WebStateOptions options_;
  std::vector<Event> events_;
  std::size_t rejected_ = 0, checked_ = 0;  // checked_: events counted in rejected_
  std::int64_t first_utime_ = 0, last_utime_ = 0;

  std::mutex mutex_;
  std::unique_ptr<lcm::LogFile> file_;  // for reading stereo frames back
  std::unique_ptr<WebState> state_;
  std::size_t next_ = 0;               // the first event not fed
  std::int64_t cursor_utime_ = 0;
  long latest_stereo_ = -1;            // the newest stereo event before next_
  long fed_stereo_ = -1;               // the stereo event state_ holds
};

}  // namespace rover::web
