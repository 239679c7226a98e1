#include "bus/guard.hpp"

#include "bus/channels.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <new>

namespace rover::bus {

namespace {
// 0 = no cap. Thread-local, so a decode on one thread never limits another.
thread_local std::size_t t_allocation_cap = 0;

std::string Seconds(double s) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f s", s);
  return buf;
}

void* Allocate(std::size_t size) {
  if (t_allocation_cap != 0 && size > t_allocation_cap) throw std::bad_alloc();
  if (size == 0) size = 1;
  if (void* p = std::malloc(size)) return p;
  throw std::bad_alloc();
}

void* AllocateAligned(std::size_t size, std::align_val_t align) {
  if (t_allocation_cap != 0 && size > t_allocation_cap) throw std::bad_alloc();
  const std::size_t a = static_cast<std::size_t>(align);
  std::size_t rounded = (size + a - 1) / a * a;
  if (rounded == 0) rounded = a;
  if (void* p = std::aligned_alloc(a, rounded)) return p;
  throw std::bad_alloc();
}
}  // namespace

DecodeAllocationCap::DecodeAllocationCap(std::size_t max_bytes) : previous_(t_allocation_cap) {
  if (previous_ == 0 || max_bytes < previous_) t_allocation_cap = max_bytes;
}

DecodeAllocationCap::~DecodeAllocationCap() { t_allocation_cap = previous_; }

std::size_t MaxPayloadBytes(const std::string& channel) {
  constexpr std::size_t kKiB = 1024, kMiB = 1024 * kKiB;
  // Two 16-bit 2048x2048 raw images and their models fit; anything larger is not a NAVCAM
  // (or HAZCAM) pair this stack can use.
  if (channel == channels::kStereoFrame || channel == channels::kHazcamFrame) return 48 * kMiB;
  // A sequence file is at most 1 MiB (common/config file limits); zones and queries are
  // lists an operator writes.
  if (channel == channels::kSequenceSubmit || channel == channels::kSequenceStatus ||
      channel == channels::kKeepOutZones || channel == channels::kHazardQuery)
    return 2 * kMiB;
  // A traversability map: 9 bytes a cell, up to 400x400 cells (common/traversability).
  if (channel == channels::kTraversabilityMap) return 2 * kMiB;
  return 64 * kKiB;
}

bool TimeChecked(const std::string& channel) {
  return channel != channels::kHeartbeat && channel != channels::kSequenceSubmit &&
         channel != channels::kSequenceControl;
}

std::int64_t RoverClock::SystemUtime() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

void RoverClock::set_system(bool on) {
  system_ = on;
  anchored_ = false;
  newest_ = 0;
  behind_streak_ = 0;
  rate_ = 1.0;
  candidate_.reset();
}

void RoverClock::Anchor(std::int64_t utime, WallClock::time_point wall) {
  anchored_ = true;
  anchor_utime_ = utime;
  anchor_wall_ = wall;
}

void RoverClock::ObserveClock(std::int64_t utime, double rate, WallClock::time_point wall) {
  if (rate > 0 && std::isfinite(rate)) rate_ = rate;
  Anchor(utime, wall);
  Observe(utime, wall);
}

void RoverClock::Observe(std::int64_t utime, WallClock::time_point wall) {
  if (system_) return;  // the system clock needs no anchor
  if (!anchored_) Anchor(utime, wall);
  if (utime > newest_) newest_ = utime;
  // A trusted time ahead of the extrapolated anchor moves the anchor (no ROVER_CLOCK on
  // this bus, or it lags).
  const double extrapolated =
      anchor_utime_ + std::chrono::duration<double>(wall - anchor_wall_).count() * rate_ * 1e6;
  if (utime > extrapolated) Anchor(utime, wall);
}

double RoverClock::AheadLimit(WallClock::time_point wall) const {
  const double since_anchor_s = std::chrono::duration<double>(wall - anchor_wall_).count();
  return anchor_utime_ + since_anchor_s * rate_ * 1e6 +
         (window_.max_ahead_wall_s * rate_ + window_.max_ahead_rover_s) * 1e6;
}

bool RoverClock::Confirms(std::int64_t utime, std::int64_t count, double rate, bool virtual_mode,
                          WallClock::time_point wall) const {
  if (!candidate_ || count != candidate_->count + 1 || utime < candidate_->utime) return false;
  const double step = static_cast<double>(utime - candidate_->utime);
  if (virtual_mode) return step <= window_.max_clock_step_s * 1e6;
  // Real time: the step from the candidate fits the candidate's own clock extrapolated at
  // its rate, with the same margin Judge allows.
  const double r = rate > 0 && std::isfinite(rate) ? rate : rate_;
  const double since_s = std::chrono::duration<double>(wall - candidate_->wall).count();
  return step <= (since_s * r + window_.max_ahead_wall_s * r + window_.max_ahead_rover_s) * 1e6;
}

std::string RoverClock::AcceptClock(std::int64_t utime, std::int64_t count, double rate,
                                    bool virtual_mode, WallClock::time_point wall) {
  if (clock_taken_ && utime < clock_utime_) {
    return "utime " + std::to_string(utime) + " is " + Seconds((clock_utime_ - utime) * 1e-6) +
           " behind the rover clock (a clock never goes back)";
  }
  // A clock message too far ahead is held as a candidate and taken only when the source's
  // next clock message (`count` + 1, consistent with it) confirms it. In virtual time the
  // clock's step is too large after a stall in which clock messages were lost. In real
  // time the receiver extrapolates from when it took the last message: one taken late (the
  // process starved, its socket overflowing) and the next on time puts every later message
  // ahead of the extrapolation by the difference, and without this the clock would stay
  // wedged behind for good. A forged future clock stands alone and is never confirmed.
  std::string why;
  if (clock_taken_ && virtual_mode && utime - clock_utime_ > window_.max_clock_step_s * 1e6) {
    why = "utime " + std::to_string(utime) + " is " + Seconds((utime - clock_utime_) * 1e-6) +
          " ahead of the rover clock (expected at most " + Seconds(window_.max_clock_step_s) +
          " a clock message, unless the next one confirms it)";
  } else if (clock_taken_ && !virtual_mode) {
    why = Judge(utime, wall);
    if (!why.empty() && utime > AheadLimit(wall)) why += ", unless the next clock message confirms it";
  }
  if (!why.empty()) {
    const bool ahead = virtual_mode || utime > AheadLimit(wall);
    if (!ahead) return why;
    if (!Confirms(utime, count, rate, virtual_mode, wall)) {
      candidate_ = Candidate{utime, count, wall};
      return why;
    }
  }
  candidate_.reset();
  clock_taken_ = true;
  clock_utime_ = utime;
  ObserveClock(utime, rate, wall);
  return "";
}

std::string RoverClock::Judge(std::int64_t utime, WallClock::time_point wall) {
  if (system_) return JudgeOnSystemClock(utime);
  if (!anchored_) {
    behind_streak_ = 0;
    return "";
  }
  const double t = static_cast<double>(utime);
  if (virtual_) {  // rover time only: the wall clock says nothing about a virtual clock
    const double ahead = t - std::max(newest_, clock_utime_);
    if (ahead > window_.max_ahead_rover_s * 1e6) {
      return "utime " + std::to_string(utime) + " is " + Seconds(ahead * 1e-6) +
             " ahead of the rover clock (expected within " + Seconds(window_.max_ahead_rover_s) + " of rover time)";
    }
    if (t < newest_ - window_.max_behind_rover_s * 1e6) {
      return "utime " + std::to_string(utime) + " is " + Seconds((newest_ - t) * 1e-6) +
             " behind the rover clock (expected within " + Seconds(window_.max_behind_rover_s) + " of rover time)";
    }
    return "";
  }
  const double since_anchor_s = std::chrono::duration<double>(wall - anchor_wall_).count();
  const double ahead_limit = AheadLimit(wall);
  const double behind_limit =
      newest_ - (window_.max_behind_wall_s * rate_ + window_.max_behind_rover_s) * 1e6;
  if (t > ahead_limit) {
    return "utime " + std::to_string(utime) + " is " +
           Seconds((t - anchor_utime_) * 1e-6 - since_anchor_s * rate_) +
           " ahead of the rover clock (expected within " +
           Seconds(window_.max_ahead_wall_s * rate_ + window_.max_ahead_rover_s) + ")";
  }
  if (t < behind_limit) {
    if (behind_streak_ == 0) behind_streak_start_ = wall;
    ++behind_streak_;
    if (behind_streak_ >= window_.resync_count &&
        std::chrono::duration<double>(wall - behind_streak_start_).count() >= window_.resync_wall_s) {
      std::cerr << "bus: rover clock re-anchored at " << utime << " after " << behind_streak_
                << " messages older than it (it was poisoned before it had an anchor)\n";
      anchored_ = false;
      newest_ = 0;
      behind_streak_ = 0;
      return "";
    }
    return "utime " + std::to_string(utime) + " is " + Seconds((newest_ - t) * 1e-6) +
           " behind the rover clock (expected within " +
           Seconds(window_.max_behind_wall_s * rate_ + window_.max_behind_rover_s) + ")";
  }
  behind_streak_ = 0;
  return "";
}

std::string RoverClock::JudgeOnSystemClock(std::int64_t utime) const {
  // 0 is "not stamped" (a tool that does not know rover time, e.g. a bare capture request),
  // not a message from 1970: taken as now, as an unanchored clock takes its first message.
  if (utime == 0) return "";
  const double now = static_cast<double>(SystemUtime()), t = static_cast<double>(utime);
  const double ahead_s = window_.max_ahead_wall_s + window_.max_ahead_rover_s;
  const double behind_s = window_.max_behind_wall_s + window_.max_behind_rover_s;
  if (t > now + ahead_s * 1e6) {
    return "utime " + std::to_string(utime) + " is " + Seconds((t - now) * 1e-6) +
           " ahead of the system clock (expected within " + Seconds(ahead_s) + ")";
  }
  if (t < now - behind_s * 1e6) {
    return "utime " + std::to_string(utime) + " is " + Seconds((now - t) * 1e-6) +
           " behind the system clock (expected within " + Seconds(behind_s) + ")";
  }
  return "";
}

void RateLimitedLog::Report(const std::string& channel, const std::string& line) {
  auto& c = channels_[channel];
  const auto now = std::chrono::steady_clock::now();
  const bool in_budget = c.printed < budget_;
  const bool due = std::chrono::duration<double>(now - c.last).count() >= every_s_;
  if (!in_budget && !due) {
    ++c.suppressed;
    return;
  }
  std::cerr << line;
  if (c.suppressed > 0) std::cerr << " (" << c.suppressed << " more on " << channel << " not shown)";
  std::cerr << "\n";
  c.suppressed = 0;
  ++c.printed;
  c.last = now;
}

}  // namespace rover::bus

// The replaceable global allocation functions, so that DecodeAllocationCap applies to the
// allocations inside LCM's generated decode (std::vector::resize, std::string::assign).
void* operator new(std::size_t size) { return rover::bus::Allocate(size); }
void* operator new[](std::size_t size) { return rover::bus::Allocate(size); }
void* operator new(std::size_t size, std::align_val_t a) { return rover::bus::AllocateAligned(size, a); }
void* operator new[](std::size_t size, std::align_val_t a) { return rover::bus::AllocateAligned(size, a); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
