#include "simtime/barrier.hpp"

#include <algorithm>
#include <limits>
#include <sstream>
#include <utility>

namespace rover::simtime {

std::uint32_t PublisherIdOf(const std::string& name) {
  std::uint32_t h = 2166136261u;  // FNV-1a, 32 bits
  for (unsigned char c : name) {
    h ^= c;
    h *= 16777619u;
  }
  return h;
}

Barrier::Barrier(std::vector<std::string> members, double liveness_s, std::string clock_owner)
    : liveness_s_(liveness_s), clock_owner_(std::move(clock_owner)) {
  for (auto& name : members) members_[name].id = PublisherIdOf(name);
}

bool Barrier::CountsReceipts(const Member& m) const {
  return clock_owner_.empty() || m.last.process == clock_owner_;
}

void Barrier::Report(SyncReport report, double wall_s) {
  auto it = members_.find(report.process);
  if (it == members_.end()) return;
  Member& m = it->second;
  const bool rejoining = m.lost;
  m.last = std::move(report);
  m.heard = true;
  m.lost = false;  // a lost member that speaks again is waited for again
  m.last_wall_s = wall_s;
  if (rejoining) {
    m.excused.clear();
    ForgiveMissing(m);
  }
}

void Barrier::ForgiveMissing(Member& m) {
  for (const auto& [pub_name, pub] : members_) {
    if (!pub.heard) continue;
    for (const auto& entry : pub.last.published) {
      const std::string& channel = entry.first;
      const std::int64_t missing = Missing(m, channel, pub);
      if (missing > 0) m.excused[channel][pub.id] += missing;
    }
  }
}

std::int64_t Barrier::Missing(const Member& m, const std::string& channel, const Member& pub) const {
  if (!CountsReceipts(m)) return 0;  // it waits for them itself, by the clock's cut
  auto p = pub.last.published.find(channel);
  if (p == pub.last.published.end() || p->second <= 0) return 0;
  if (!m.last.subscribes_all && !m.last.subscribed.count(channel)) return 0;
  std::int64_t got = 0;
  if (auto c = m.last.received.find(channel); c != m.last.received.end()) {
    if (auto r = c->second.find(pub.id); r != c->second.end()) got = r->second;
  }
  if (auto c = m.excused.find(channel); c != m.excused.end()) {
    if (auto r = c->second.find(pub.id); r != c->second.end()) got += r->second;
  }
  return p->second - got;
}

bool Barrier::AllHeard() const {
  for (const auto& [name, m] : members_)
    if (!m.heard) return false;
  return true;
}

// Holds without the words: the clock's wait loop asks this on every pass, so it builds no
// strings.
bool Barrier::Waiting(const Member& m, std::int64_t utime) const {
  if (m.lost) return false;
  if (!m.heard || m.last.utime < utime || m.last.busy) return true;
  if (!CountsReceipts(m)) return false;
  for (const auto& [pub_name, pub] : members_) {
    if (!pub.heard) continue;
    for (const auto& entry : pub.last.published)
      if (Missing(m, entry.first, pub) > 0) return true;
  }
  return false;
}

std::string Barrier::Holds(const std::string& name, const Member& m, std::int64_t utime) const {
  if (m.lost) return "";
  if (!m.heard) return name + " has not reported";
  if (m.last.utime < utime) {
    return name + " has finished only " + std::to_string(m.last.utime) + " (clock " + std::to_string(utime) + ")";
  }
  if (m.last.busy) return name + " is still working";
  // Every message a live member published on a channel this member reads has reached it.
  for (const auto& [pub_name, pub] : members_) {
    if (!pub.heard) continue;
    for (const auto& [channel, count] : pub.last.published) {
      if (const std::int64_t missing = Missing(m, channel, pub); missing > 0) {
        return name + " has received " + std::to_string(count - missing) + " of " + std::to_string(count) +
               " " + channel + " from " + pub_name;
      }
    }
  }
  return "";
}

std::int64_t Barrier::QuietUntil() const {
  std::int64_t until = std::numeric_limits<std::int64_t>::max();
  for (const auto& entry : members_) {
    const Member& m = entry.second;
    if (m.lost || !m.heard) return 0;
    until = std::min(until, m.last.quiet_until);
  }
  return until;
}

bool Barrier::Finished(std::int64_t utime) const {
  for (const auto& entry : members_)
    if (Waiting(entry.second, utime)) return false;
  return true;
}

std::string Barrier::Holding(std::int64_t utime) const {
  std::ostringstream os;
  for (const auto& [name, m] : members_) {
    const std::string why = Holds(name, m, utime);
    if (why.empty()) continue;
    if (os.tellp() > 0) os << "; ";
    os << why;
  }
  return os.str();
}

std::vector<std::string> Barrier::DeclareLost(std::int64_t utime, double wall_s, double tick_wall_s,
                                              std::vector<std::string>* forgiven) {
  std::vector<std::string> lost;
  for (auto& [name, m] : members_) {
    const double since = wall_s - std::max(m.heard ? m.last_wall_s : tick_wall_s, tick_wall_s);
    const bool silent = since > liveness_s_;
    const bool missing_only = wall_s - tick_wall_s > liveness_s_ && m.heard && m.last.utime >= utime && !m.last.busy;
    if ((!silent && !missing_only) || !Waiting(m, utime)) continue;
    if (silent) {
      m.lost = true;
      lost.push_back(name);
    } else {
      if (forgiven) forgiven->push_back(Holds(name, m, utime));
      ForgiveMissing(m);
    }
  }
  return lost;
}

bool Barrier::FarBehind(std::int64_t utime, std::int64_t by_us) const {
  for (const auto& [name, m] : members_)
    if (m.heard && !m.lost && m.last.utime >= 0 && m.last.utime < utime - by_us) return true;
  return false;
}

Cut Barrier::Published() const {
  Cut cut;
  for (const auto& [name, m] : members_) {
    if (!m.heard || m.lost) continue;
    for (const auto& [channel, count] : m.last.published) cut.Set(channel, m.id, count);
    // A report lists every channel its member has published on, so a message of the
    // member's on any other channel came after it. The clock owner adds its own counts.
    if (name != clock_owner_) cut.SetComplete(m.id);
  }
  return cut;
}

std::vector<std::string> Barrier::Lost() const {
  std::vector<std::string> out;
  for (const auto& [name, m] : members_)
    if (m.lost) out.push_back(name);
  return out;
}

std::uint32_t Barrier::Id(const std::string& process) const { return PublisherIdOf(process); }

}  // namespace rover::simtime
