#include "conformance/mobility_checks.hpp"

#include "bus/validate.hpp"

#include <rover_msgs/mobility_command_t.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

namespace rover::conformance {

namespace {

using rover_msgs::mobility_command_t;
using rover_msgs::mobility_status_t;
using Status = Received<mobility_status_t>;

const char* StateName(int s) {
  switch (s) {
    case mobility_status_t::STATE_IDLE: return "IDLE";
    case mobility_status_t::STATE_MOVING: return "MOVING";
    case mobility_status_t::STATE_DONE: return "DONE";
    case mobility_status_t::STATE_STOPPED: return "STOPPED";
    case mobility_status_t::STATE_FAULT: return "FAULT";
    default: return "unknown";
  }
}

std::string Describe(const Status& s) {
  std::string out = std::string(StateName(s.msg.state)) + " for command " + std::to_string(s.msg.command_id);
  if (!s.msg.detail.empty()) out += " (" + s.msg.detail + ")";
  return out;
}

const SentCommand* Sent(const MobilityTrace& trace, std::int64_t id) {
  for (const auto& c : trace.commands)
    if (c.id == id) return &c;
  return nullptr;
}

// When the probe sent its next command after `id` (or stopped listening): the window in
// which statuses about `id` are judged.
double NextCommandWall(const MobilityTrace& trace, std::int64_t id) {
  const SentCommand* c = Sent(trace, id);
  double next = trace.end_wall_s;
  if (c == nullptr) return next;
  for (const auto& other : trace.commands)
    if (other.wall_s > c->wall_s) next = std::min(next, other.wall_s);
  return next;
}

// The first status about `id` in [from, to) wall seconds whose state is in `states`.
std::optional<Status> First(const MobilityTrace& trace, std::int64_t id, std::initializer_list<int> states, double from,
                            double to) {
  for (const auto& s : trace.statuses) {
    if (s.msg.command_id != id || s.at.wall_s < from || s.at.wall_s >= to) continue;
    if (std::find(states.begin(), states.end(), s.msg.state) != states.end()) return s;
  }
  return std::nullopt;
}

// What the statuses about `id` said last before `to` (for a "seen" text).
std::string LastWord(const MobilityTrace& trace, std::int64_t id, double from, double to) {
  std::string out = "no status for command " + std::to_string(id);
  for (const auto& s : trace.statuses)
    if (s.msg.command_id == id && s.at.wall_s >= from && s.at.wall_s < to) out = Describe(s);
  return out;
}

}  // namespace

void CheckStatusStream(const MobilityTrace& trace, const MobilityLimits& limits, Report& report) {
  if (!report.Expect(!trace.statuses.empty(), "mobility.status.present", "MOBILITY_STATUS messages", "none")) return;
  std::string bad;
  for (const auto& s : trace.statuses)
    if (bad.empty()) bad = bus::Problem(s.msg);
  report.Expect(bad.empty(), "mobility.status.fields", "finite numbers and a known state", bad);

  // Gaps in the driver's rover time; while a motion runs (from a MOVING to the next status
  // that is not), the tighter limit.
  double worst_idle = 0, worst_moving = 0;
  bool moving = false;
  for (std::size_t i = 1; i < trace.statuses.size(); ++i) {
    const double gap = static_cast<double>(trace.statuses[i].msg.utime - trace.statuses[i - 1].msg.utime) * 1e-6;
    moving = trace.statuses[i - 1].msg.state == mobility_status_t::STATE_MOVING;
    (moving ? worst_moving : worst_idle) = std::max(moving ? worst_moving : worst_idle, gap);
  }
  // Silence at the end counts too (in wall time: nothing came to stamp it).
  const double tail = trace.end_wall_s - trace.statuses.back().at.wall_s;
  worst_idle = std::max(worst_idle, tail);
  report.Expect(worst_idle <= limits.idle_status_gap_s, "mobility.status.rate_idle",
                "a status at least every " + Num(limits.idle_status_gap_s, 1) + " s",
                "a gap of " + Num(worst_idle, 2) + " s");
  report.Expect(worst_moving <= limits.moving_status_gap_s, "mobility.status.rate_moving",
                "a status at least every " + Num(limits.moving_status_gap_s, 1) + " s while moving",
                "a gap of " + Num(worst_moving, 2) + " s while moving");

  std::string back;
  for (std::size_t i = 1; i < trace.statuses.size() && back.empty(); ++i) {
    if (trace.statuses[i].msg.utime < trace.statuses[i - 1].msg.utime) {
      back = "utime " + std::to_string(trace.statuses[i].msg.utime) + " after " +
             std::to_string(trace.statuses[i - 1].msg.utime);
    }
  }
  report.Expect(back.empty(), "mobility.time.monotonic", "status utimes that never go back", back);
  const auto tolerance_us = static_cast<std::int64_t>(limits.clock_tolerance_s * 1e6);
  std::string far;
  for (const auto& s : trace.statuses) {
    if (far.empty() && std::abs(s.msg.utime - s.at.clock_utime) > tolerance_us) {
      far = "utime " + std::to_string(s.msg.utime) + " when rover time was " + std::to_string(s.at.clock_utime);
    }
  }
  report.Expect(far.empty(), "mobility.time.near_clock",
                "utimes within " + Num(limits.clock_tolerance_s, 2) + " s of rover time", far);

  double worst_hb = trace.driver_heartbeats.empty() ? std::numeric_limits<double>::infinity() : 0.0;
  for (std::size_t i = 1; i < trace.driver_heartbeats.size(); ++i) {
    worst_hb = std::max(worst_hb, trace.driver_heartbeats[i].at.wall_s - trace.driver_heartbeats[i - 1].at.wall_s);
  }
  if (!trace.driver_heartbeats.empty()) worst_hb = std::max(worst_hb, trace.end_wall_s - trace.driver_heartbeats.back().at.wall_s);
  report.Expect(worst_hb <= limits.heartbeat_gap_s, "mobility.heartbeat",
                "a driver heartbeat at least every " + Num(limits.heartbeat_gap_s, 1) + " s of wall time",
                trace.driver_heartbeats.empty() ? "no heartbeat from the driver"
                                                : "a gap of " + Num(worst_hb, 2) + " s");
}

void CheckIdleStop(const MobilityTrace& trace, std::int64_t stop_id, const MobilityLimits& limits, Report& report) {
  const SentCommand* c = Sent(trace, stop_id);
  if (c == nullptr) return;
  const auto answer = First(trace, stop_id, {mobility_status_t::STATE_STOPPED}, c->wall_s, c->wall_s + limits.answer_s);
  report.Expect(answer.has_value(), "mobility.stop.idle_answer",
                "STOPPED for command " + std::to_string(stop_id) + " within " + Num(limits.answer_s, 1) + " s",
                LastWord(trace, stop_id, c->wall_s, NextCommandWall(trace, stop_id)));
}

void CheckMotion(const MobilityTrace& trace, std::int64_t id, const MobilityLimits& limits, Report& report) {
  const SentCommand* c = Sent(trace, id);
  if (c == nullptr) return;
  const bool arc = c->type == mobility_command_t::TYPE_ARC;
  const std::string kind = arc ? "mobility.arc" : "mobility.turn";
  const double until = NextCommandWall(trace, id);
  const auto moving = First(trace, id, {mobility_status_t::STATE_MOVING}, c->wall_s, c->wall_s + limits.answer_s);
  report.Expect(moving.has_value(), kind + ".moving",
                "MOVING for command " + std::to_string(id) + " within " + Num(limits.answer_s, 1) + " s",
                LastWord(trace, id, c->wall_s, c->wall_s + limits.answer_s));
  const auto end = First(trace, id,
                         {mobility_status_t::STATE_DONE, mobility_status_t::STATE_STOPPED,
                          mobility_status_t::STATE_FAULT},
                         c->wall_s, until);
  const double amount = arc ? std::abs(c->distance_m) : std::abs(c->turn_rad);
  const double rate = arc ? c->speed_mps : c->turn_rate_rps;
  const std::string unit = arc ? " m" : " rad";
  if (!report.Expect(end && end->msg.state == mobility_status_t::STATE_DONE, kind + ".done",
                     "DONE for command " + std::to_string(id) + " after " + Num(amount, 3) + unit,
                     end ? Describe(*end) : LastWord(trace, id, c->wall_s, until))) {
    return;
  }
  const double reported = std::abs(arc ? end->msg.wheel_distance_m : end->msg.wheel_turn_rad);
  report.Expect(std::abs(reported - amount) <= limits.amount_tolerance * amount,
                arc ? "mobility.units.distance" : "mobility.units.turn",
                (arc ? "wheel_distance_m " : "wheel_turn_rad ") + Num(amount, 3) + " (" +
                    Num(limits.amount_tolerance * 100, 0) + " %) at DONE",
                Num(reported, 4));
  if (moving && rate > 0) {
    const double took = static_cast<double>(end->msg.utime - moving->msg.utime) * 1e-6;
    const double expected = amount / rate;
    report.Expect(std::abs(took - expected) <= limits.duration_tolerance * expected,
                  arc ? "mobility.units.speed" : "mobility.units.turn_rate",
                  Num(expected, 2) + " s of rover time from MOVING to DONE (" + Num(amount, 3) + unit + " at " +
                      Num(rate, 3) + (arc ? " m/s" : " rad/s") + ", " + Num(limits.duration_tolerance * 100, 0) +
                      " %)",
                  Num(took, 2) + " s");
  }
}

void CheckStop(const MobilityTrace& trace, std::int64_t motion_id, std::int64_t stop_id, const MobilityLimits& limits,
               Report& report) {
  const SentCommand* motion = Sent(trace, motion_id);
  const SentCommand* stop = Sent(trace, stop_id);
  if (motion == nullptr || stop == nullptr) return;
  const auto moving = First(trace, motion_id, {mobility_status_t::STATE_MOVING}, motion->wall_s, stop->wall_s);
  if (!moving) {
    report.Fail("mobility.stop.answer", "a motion to stop (MOVING for command " + std::to_string(motion_id) + ")",
                LastWord(trace, motion_id, motion->wall_s, stop->wall_s));
    return;
  }
  const double answer_by = stop->wall_s + limits.answer_s;
  auto answer = First(trace, motion_id, {mobility_status_t::STATE_STOPPED}, stop->wall_s, answer_by);
  if (!answer) answer = First(trace, stop_id, {mobility_status_t::STATE_STOPPED}, stop->wall_s, answer_by);
  if (!report.Expect(answer.has_value(), "mobility.stop.answer",
                     "STOPPED for command " + std::to_string(motion_id) + " or " + std::to_string(stop_id) +
                         " within " + Num(limits.answer_s, 1) + " s of the STOP",
                     LastWord(trace, motion_id, stop->wall_s, answer_by) + ", " +
                         LastWord(trace, stop_id, stop->wall_s, answer_by))) {
    return;
  }
  const double until = NextCommandWall(trace, stop_id);
  std::string moved;
  for (const auto& s : trace.statuses) {
    if (s.at.wall_s > answer_by && s.at.wall_s < until && s.msg.state == mobility_status_t::STATE_MOVING) {
      moved = Describe(s) + " " + Num(s.at.wall_s - stop->wall_s, 2) + " s after the STOP";
      break;
    }
  }
  if (moved.empty()) {
    std::optional<double> first_d, last_d;
    for (const auto& o : trace.odometry) {
      if (o.at.wall_s <= answer_by || o.at.wall_s >= until) continue;
      if (!first_d) first_d = o.msg.distance_m;
      last_d = o.msg.distance_m;
    }
    if (first_d && std::abs(*last_d - *first_d) > 0.01) {
      moved = "WHEEL_ODOMETRY distance_m went on by " + Num(*last_d - *first_d, 3) + " m after the STOP";
    }
  }
  report.Expect(moved.empty(), "mobility.stop.stays", "nothing moving after the STOP was answered", moved);
}

void CheckDeadman(const MobilityTrace& trace, std::int64_t motion_id, const MobilityLimits& limits, Report& report) {
  const SentCommand* c = Sent(trace, motion_id);
  if (c == nullptr || trace.silent_from_s < 0) return;
  const double silent = trace.silent_from_s;
  const auto moving = First(trace, motion_id, {mobility_status_t::STATE_MOVING}, c->wall_s, silent);
  const auto early = First(trace, motion_id,
                           {mobility_status_t::STATE_DONE, mobility_status_t::STATE_STOPPED,
                            mobility_status_t::STATE_FAULT},
                           c->wall_s, silent);
  if (!report.Expect(moving && !early, "mobility.deadman.alive",
                     "command " + std::to_string(motion_id) + " MOVING while the commander heartbeats (" +
                         Num(silent - c->wall_s, 1) + " s)",
                     early ? Describe(*early) + " " + Num(early->at.wall_s - c->wall_s, 2) + " s after the command"
                           : LastWord(trace, motion_id, c->wall_s, silent))) {
    return;
  }
  const double until = trace.silent_until_s > 0 ? trace.silent_until_s : trace.end_wall_s;
  const auto stopped = First(trace, motion_id,
                             {mobility_status_t::STATE_STOPPED, mobility_status_t::STATE_DONE,
                              mobility_status_t::STATE_FAULT},
                             silent, until);
  const double earliest = limits.deadman_s - 0.25, latest = limits.deadman_s + limits.deadman_margin_s;
  const double after = stopped ? stopped->at.wall_s - silent : 0.0;
  if (!report.Expect(stopped && stopped->msg.state == mobility_status_t::STATE_STOPPED && after >= earliest &&
                         after <= latest,
                     "mobility.deadman.stop",
                     "STOPPED for command " + std::to_string(motion_id) + " " + Num(earliest, 2) + " to " +
                         Num(latest, 2) + " s after the commander fell silent",
                     stopped ? Describe(*stopped) + " after " + Num(after, 2) + " s"
                             : LastWord(trace, motion_id, silent, until) + " " + Num(until - silent, 2) +
                                   " s after the commander fell silent")) {
    return;
  }
  report.Expect(stopped->msg.detail.find("dead-man") != std::string::npos, "mobility.deadman.detail",
                "a detail saying dead-man", "\"" + stopped->msg.detail + "\"");
}

void CheckRefusal(const MobilityTrace& trace, std::int64_t id, const std::string& rule, bool drop_allowed,
                  const MobilityLimits& limits, Report& report) {
  const SentCommand* c = Sent(trace, id);
  if (c == nullptr) return;
  const double until = NextCommandWall(trace, id);
  if (const auto moved = First(trace, id, {mobility_status_t::STATE_MOVING}, c->wall_s, until)) {
    report.Fail(rule, "command " + std::to_string(id) + " refused, nothing moving", Describe(*moved));
    return;
  }
  const auto fault = First(trace, id, {mobility_status_t::STATE_FAULT}, c->wall_s, c->wall_s + limits.answer_s);
  if (fault && !fault->msg.detail.empty()) {
    report.Pass(rule);
    return;
  }
  // Dropped: the driver's heartbeat counts it (bus::Bus drops a message its field checks refuse).
  std::int64_t before = -1, after = -1;
  for (const auto& h : trace.driver_heartbeats) {
    if (h.at.wall_s <= c->wall_s) before = h.msg.dropped;
    if (h.at.wall_s > c->wall_s && h.at.wall_s <= until) after = std::max(after, h.msg.dropped);
  }
  const bool dropped = drop_allowed && before >= 0 && after > before;
  report.Expect(dropped, rule,
                "FAULT for command " + std::to_string(id) + " with a detail within " + Num(limits.answer_s, 1) + " s" +
                    (drop_allowed ? ", or the driver's heartbeat counting it dropped" : ""),
                fault ? "FAULT with an empty detail"
                      : LastWord(trace, id, c->wall_s, until) +
                            (drop_allowed ? ", heartbeat dropped count " + std::to_string(before) + " then " +
                                                std::to_string(after)
                                          : ""));
}

void CheckNotObeyed(const MobilityTrace& trace, std::int64_t id, const std::string& rule, const std::string& how,
                    Report& report) {
  const SentCommand* c = Sent(trace, id);
  if (c == nullptr) return;
  const double until = NextCommandWall(trace, id);
  std::string obeyed;
  if (const auto s = First(trace, id, {mobility_status_t::STATE_MOVING, mobility_status_t::STATE_DONE}, c->wall_s,
                           until)) {
    obeyed = Describe(*s) + " " + Num(s->at.wall_s - c->wall_s, 2) + " s after it";
  } else {
    std::optional<double> first_d, last_d;
    for (const auto& o : trace.odometry) {
      if (o.at.wall_s < c->wall_s || o.at.wall_s >= until) continue;
      if (!first_d) first_d = o.msg.distance_m;
      last_d = o.msg.distance_m;
    }
    if (first_d && std::abs(*last_d - *first_d) > 0.01) {
      obeyed = "WHEEL_ODOMETRY distance_m went on by " + Num(*last_d - *first_d, 3) + " m";
    }
  }
  report.Expect(obeyed.empty(), rule,
                "command " + std::to_string(id) + " (an ARC " + how + ") not obeyed: no MOVING or DONE, wheels still",
                obeyed);
}

}  // namespace rover::conformance
