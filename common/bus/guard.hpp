// What the Bus checks before a message reaches a callback: its size, that it decodes
// without a lying length field allocating gigabytes, and that its utime is plausible.
//
// LCM 1.3.1's generated C++ trusts a message's length fields: it resizes an array to
// whatever count the packet claims before it checks that the bytes are there, and a
// string length of 0 or less throws std::length_error. No LCM option bounds this, so the
// Bus decodes under an allocation cap (DecodeAllocationCap) that makes any single
// allocation larger than the cap throw std::bad_alloc, which the Bus catches and reports.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <unordered_map>
#include <utility>

namespace rover::bus {

// While an instance lives, on this thread, an allocation of more than `max_bytes` throws
// std::bad_alloc instead of being attempted. Nesting keeps the tighter cap.
class DecodeAllocationCap {
 public:
  explicit DecodeAllocationCap(std::size_t max_bytes);
  ~DecodeAllocationCap();
  DecodeAllocationCap(const DecodeAllocationCap&) = delete;
  DecodeAllocationCap& operator=(const DecodeAllocationCap&) = delete;

 private:
  std::size_t previous_;
};

// The largest payload accepted on `channel`, in bytes (checked before decoding).
std::size_t MaxPayloadBytes(const std::string& channel);

// Whether messages on `channel` must carry a utime near the receiver's rover clock.
// Heartbeats (a process may not know rover time yet) and the operator's sequence
// commands (authenticated instead) are not checked.
bool TimeChecked(const std::string& channel);

// How far from the receiver's rover clock a message's utime may be.
struct TimeWindow {
  // Ahead of the clock extrapolated from the latest ROVER_CLOCK (or trusted utime) at its
  // rate: rover time runs `rate` times faster than the wall clock in simulation, so the
  // margin is in wall seconds, scaled by the rate, plus a fixed rover-time allowance.
  double max_ahead_wall_s = 1.0;
  double max_ahead_rover_s = 2.0;
  // Behind the newest rover time seen: frames wait in queues while VO works.
  double max_behind_wall_s = 60.0;
  double max_behind_rover_s = 600.0;
  // A clock that rejects everything as too old for this long (with at least
  // `resync_count` messages and none accepted) was poisoned before it had an anchor:
  // it forgets the anchor and takes the next message's time.
  double resync_wall_s = 3.0;
  int resync_count = 50;
  // Virtual time: the largest step a clock message may take past the last one (the clock
  // ticks 0.1 s); a bigger one is taken only when the next clock message confirms it.
  double max_clock_step_s = 5.0;
};

// The receiver's view of rover time, for judging a message's utime.
class RoverClock {
 public:
  using WallClock = std::chrono::steady_clock;

  explicit RoverClock(TimeWindow window = {}) : window_(window) {}
  void set_window(const TimeWindow& window) { window_ = window; }
  const TimeWindow& window() const { return window_; }

  // A ROVER_CLOCK message: the clock's anchor and rate.
  void ObserveClock(std::int64_t utime, double rate, WallClock::time_point wall);
  // A ROVER_CLOCK message from the deployment's time source (the caller checks who sent
  // it). "" when taken (ObserveClock), else why not, for the drop line. The clock never
  // goes back. In virtual time it moves at most max_clock_step_s a message, unless the
  // next message of the source (`count` + 1, at the same instant or later) confirms a
  // longer step (after a stall, when clock messages were lost: rover_sim announces the
  // instant again while such a process holds it). In real time a message Judge refuses is
  // refused, except that one ahead of the clock extrapolated at its rate is taken when the
  // source's next clock message confirms it (the receiver took the last one late).
  std::string AcceptClock(std::int64_t utime, std::int64_t count, double rate, bool virtual_mode,
                          WallClock::time_point wall);
  // The newest ROVER_CLOCK taken (0 before any).
  std::int64_t clock_utime() const { return clock_utime_; }
  // Rover seconds per wall second, from the newest ROVER_CLOCK taken (1 before any).
  double rate() const { return rate_; }
  // Virtual time: rover time moves only with the clock's messages, so nothing is judged
  // against the wall clock.
  void set_virtual(bool on) { virtual_ = on; }
  bool virtual_time() const { return virtual_; }
  // Any trusted utime (the process accepted the message that carried it).
  void Observe(std::int64_t utime, WallClock::time_point wall);

  // The newest rover time seen (0 before any); on the system clock, the system clock.
  std::int64_t now() const { return system_ ? SystemUtime() : newest_; }
  // Rover time is the system clock (CLOCK_REALTIME, microseconds since 1970): a rover with
  // no time source, or one whose time source has not been heard yet. Messages are judged
  // against it at rate 1; nothing anchors. Turning it off forgets every anchor, so the
  // time source's first clock message starts the clock afresh.
  void set_system(bool on);
  bool system() const { return system_; }
  static std::int64_t SystemUtime();
  bool anchored() const { return anchored_; }

  // "" when `utime` is plausible now, else why not (for the drop line). A rejection
  // counts toward re-anchoring a poisoned clock; an acceptance resets that count.
  std::string Judge(std::int64_t utime, WallClock::time_point wall);

 private:
  void Anchor(std::int64_t utime, WallClock::time_point wall);
  // The latest utime Judge takes in real time: the anchor extrapolated at the rate, plus
  // the window's margin.
  double AheadLimit(WallClock::time_point wall) const;
  std::string JudgeOnSystemClock(std::int64_t utime) const;
  // Whether this clock message is the source's next after the candidate and fits it.
  bool Confirms(std::int64_t utime, std::int64_t count, double rate, bool virtual_mode,
                WallClock::time_point wall) const;

  TimeWindow window_;
  bool anchored_ = false;
  std::int64_t anchor_utime_ = 0;
  WallClock::time_point anchor_wall_{};
  double rate_ = 1.0;
  std::int64_t newest_ = 0;
  int behind_streak_ = 0;
  WallClock::time_point behind_streak_start_{};
  bool virtual_ = false;
  bool system_ = false;
  bool clock_taken_ = false;
  std::int64_t clock_utime_ = 0;
  // A clock message refused as too far ahead, kept until the source's next one.
  struct Candidate {
    std::int64_t utime = 0;
    std::int64_t count = 0;
    WallClock::time_point wall{};
  };
  std::optional<Candidate> candidate_;
};

// Prints one line per problem, rate-limited per channel: the first few, then one every
// `every` seconds of wall time with the count suppressed in between, so a flood of bad
// packets cannot fill a disk.
class RateLimitedLog {
 public:
  void Report(const std::string& channel, const std::string& line);

 private:
  struct PerChannel {
    std::int64_t printed = 0;
    std::int64_t suppressed = 0;
    std::chrono::steady_clock::time_point last{};
  };
  std::int64_t budget_ = 5;
  double every_s_ = 10.0;
  std::unordered_map<std::string, PerChannel> channels_;
};

}  // namespace rover::bus
