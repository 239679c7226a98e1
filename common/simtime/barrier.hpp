// Virtual time for a simulated process set (README, "Simulated time").
//
// In simulation rover time is virtual and conservative: the clock (rover_sim) moves from
// rover time t to the next tick only when every member of the set has finished all the
// work due at t (and, see below, no message to the clock's owner is in flight). Each member says so
// with a sync report after it has handled everything it received: the rover time it has
// finished, what it has published per channel, and what it has received per channel and
// publisher (the pub_seq counts every message carries). A message is in flight while a
// subscriber of its channel has not yet counted it.
//
// This is Chandy-Misra-style conservative simulation with one global time step, chosen
// over a per-process lookahead scheme because the processes stay the deployed ones: they
// only have to report counts, not predict their own output times.
//
// One round an instant. The clock message carries the cut (simtime/cut.hpp), and every
// member but the clock's owner seals its batch by it: it waits, on its own side, for the
// messages the cut names. So the barrier need not also wait for them to be counted (a
// second sync report from every subscriber, an instant's critical path twice as long):
// given a `clock_owner`, it waits only for that member, which makes the cut and seals its
// own batch by what it has counted, to have received every message. Without one it waits
// for every member (the rule before the cut; the unit tests use both).
//
// The one wall-clock rule left: a member that holds the clock and says nothing for
// `liveness_s` of wall time (a hung or dead process) is declared lost and left out
// until it reports again, so the clock runs on and the executor finds it lost.
// No LCM here: the messages are converted in common/bus.
#pragma once

#include "simtime/cut.hpp"

#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <vector>

namespace rover::simtime {

struct SyncReport {
  std::string process;
  std::int64_t utime = 0;     // rover time whose work is finished
  bool busy = false;          // alive, still working on work due at `utime`
  // Nothing of its own to do before this rover time (0: the next tick). See QuietUntil.
  std::int64_t quiet_until = 0;
  bool subscribes_all = false;  // a recorder: counts as a subscriber of every channel
  std::set<std::string> subscribed;
  std::map<std::string, std::int64_t> published;  // channel -> messages published
  // channel -> publisher id -> messages received (the highest count seen + 1)
  std::map<std::string, std::map<std::uint32_t, std::int64_t>> received;
};

class Barrier {
 public:
  // `members`: the processes the clock waits for (names as they report themselves).
  // `clock_owner`: the member whose receipts alone are waited for (above); "" for all.
  Barrier(std::vector<std::string> members, double liveness_s, std::string clock_owner = "");

  // A report from a process; reports from non-members are ignored. Wall seconds are for
  // liveness only.
  void Report(SyncReport report, double wall_s);

  // Every member has reported at least once (the clock may start).
  bool AllHeard() const;
  // Whether the work due at `utime` is finished: every member that is not lost has
  // finished `utime` (and is not busy), and every message a member published has been
  // counted by every member subscribed to its channel (by the clock's owner only, when
  // there is one).
  bool Finished(std::int64_t utime) const;
  // One line: who holds the clock at `utime` and why (for diagnostics and the lost line).
  std::string Holding(std::int64_t utime) const;
  // Members that hold the clock at `utime` and have sent nothing for liveness_s of wall
  // time since the later of their last report and `tick_wall_s` (when the clock reached
  // `utime`): declared lost now (returned once each) until they report again.
  // A member that is alive and has finished the instant but still misses messages
  // liveness_s after the clock reached it never gets them (its socket overflowed): they
  // are forgiven, one line each in `forgiven` (when given), so the clock does not wait
  // for them forever.
  std::vector<std::string> DeclareLost(std::int64_t utime, double wall_s, double tick_wall_s,
                                       std::vector<std::string>* forgiven = nullptr);
  // Whether a member that has started reports an instant more than `by_us` behind
  // `utime`: one that was declared lost and lost clock messages meanwhile. Only a fault
  // does this (a member is otherwise at most one instant behind).
  bool FarBehind(std::int64_t utime, std::int64_t by_us) const;
  // What the members that are not lost have published, as their last reports say: the
  // cut the next clock message carries (simtime/cut.hpp), complete for each of them but
  // the clock owner.
  Cut Published() const;
  // Members currently lost.
  std::vector<std::string> Lost() const;
  // The earliest rover time any member has something of its own to do, from the last
  // reports (0 when one is lost, or has said nothing of it): the clock may step straight
  // to it while the rover stands still (an idle stride; sim.idle_step_s).
  std::int64_t QuietUntil() const;
  std::uint32_t Id(const std::string& process) const;

 private:
  struct Member {
    std::uint32_t id = 0;
    SyncReport last;
    bool heard = false;
    bool lost = false;
    double last_wall_s = 0.0;
    // Messages a member lost while it was declared lost (its socket overflowed during a
    // freeze): forgiven when it rejoins, so that it does not hold the clock for them.
    std::map<std::string, std::map<std::uint32_t, std::int64_t>> excused;
  };
  std::int64_t Missing(const Member& m, const std::string& channel, const Member& pub) const;
  // Forgives every message `m` misses now (adds it to `excused`).
  void ForgiveMissing(Member& m);
  // Whether `m` holds the clock at `utime` (Holds is its reason in words).
  bool Waiting(const Member& m, std::int64_t utime) const;
  // "" when `name` does not hold the clock at `utime`, else why it does.
  std::string Holds(const std::string& name, const Member& m, std::int64_t utime) const;

  // Whether the barrier waits for `m` to have counted what it subscribes to.
  bool CountsReceipts(const Member& m) const;

  std::map<std::string, Member> members_;
  double liveness_s_;
  std::string clock_owner_;
};

// The publisher id Bus::Publish stamps in pub_seq's high 32 bits (FNV-1a of the name).
std::uint32_t PublisherIdOf(const std::string& name);

}  // namespace rover::simtime
