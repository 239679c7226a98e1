#include "web_console/command_watch.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <utility>

namespace rover::web {
namespace {

// Executor heartbeats after a control command with no drop of it: the command was taken.
// The detail is set on the executor's tick, so the first heartbeat after a drop may
// still carry the detail from before it; three are past any such lag.
constexpr std::int64_t kHeartbeatsToTake = 3;
// ... and this much wall time: heartbeats come every 0.25 s of rover time, which in virtual
// time at a high rate is a few milliseconds, less than a command takes to be judged.
constexpr double kWallSecondsToTake = 1.0;

std::string StateName(int state) {
  static const char* names[] = {"idle", "running", "paused", "completed", "aborted", "rejected"};
  return state >= 0 && state < 6 ? names[state] : "state " + std::to_string(state);
}

}  // namespace

std::pair<std::int64_t, std::string> CommandWatch::DropsOn(const std::string& detail, const std::string& channel) {
  const std::string key = "; " + channel + " dropped ";
  const std::size_t at = detail.find(key);
  if (at == std::string::npos) return {0, ""};
  std::size_t end = at + key.size();
  std::int64_t n = 0;
  while (end < detail.size() && detail[end] >= '0' && detail[end] <= '9' && n < (1LL << 50)) {
    n = n * 10 + (detail[end++] - '0');
  }
  if (detail.compare(end, 2, ": ") != 0) return {0, ""};
  // The reason runs to the next channel's entry, or to the end.
  const std::size_t next = detail.find("; SEQUENCE_", end);
  return {n, detail.substr(end + 2, next == std::string::npos ? std::string::npos : next - end - 2)};
}

CommandWatch::CommandWatch(bool holds_key, std::string executor, std::string sender)
    : holds_key_(holds_key), executor_(std::move(executor)), sender_(std::move(sender)) {}

bool CommandWatch::DropCouldBeOurs(const std::string& reason) const {
  const bool unsigned_drop = reason.find("no authentication tag") != std::string::npos;
  if (!holds_key_) return unsigned_drop;
  if (unsigned_drop) return false;
  // A signed command's refusal names its sender ("wrong tag from \"rover_web@host:pid\"").
  return sender_.empty() || reason.find("\"" + sender_ + "\"") != std::string::npos;
}

void CommandWatch::OnHeartbeat(const rover_msgs::heartbeat_t& hb) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!holds_key_ && key_problem_.empty() && hb.auth.tag_size > 0) {
    key_problem_ = "this stack signs its messages (a signed HEARTBEAT from " + hb.process +
                   ") and rover_web holds no key, so the executor refuses its commands (expected the "
                   "deployment's key: start rover_web with --key FILE or $ROVER_KEY_FILE)";
  }
  if (hb.process != executor_) return;
  ++heartbeats_;
  last_ = hb;
  changed_.notify_all();
}

void CommandWatch::OnStatus(const rover_msgs::sequence_status_t& st) {
  std::lock_guard<std::mutex> lock(mutex_);
  for (const auto& s : statuses_)
    if (s.submission_id == st.submission_id) return;  // its first answer is the one kept
  statuses_.push_back(st);
  while (statuses_.size() > 32) statuses_.pop_front();
  changed_.notify_all();
}

void CommandWatch::OnAuthRejection(const std::string& what) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!holds_key_ || !key_problem_.empty() || what.find("wrong tag") == std::string::npos) return;
  // Another console beside this one, signing with another key, is not the stack: its
  // executor's and its processes' messages are what this key must verify.
  if (what.find("wrong tag from \"rover_web") != std::string::npos) return;
  key_problem_ = "rover_web's key does not verify this bus's messages (" + what +
                 "): if the stack signs with another key, its executor refuses rover_web's commands too "
                 "(expected the deployment's key in --key)";
  changed_.notify_all();
}

CommandWatch::Ticket CommandWatch::Expect(const std::string& channel, std::int64_t submission_id) const {
  std::lock_guard<std::mutex> lock(mutex_);
  Ticket t;
  t.channel = channel;
  t.submission_id = submission_id;
  t.heartbeats = heartbeats_;
  t.dropped = last_ ? DropsOn(last_->detail, channel).first : -1;
  t.sent = std::chrono::steady_clock::now();
  return t;
}

std::optional<CommandWatch::Verdict> CommandWatch::Judge(const Ticket& ticket) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return JudgeLocked(ticket);
}

std::optional<CommandWatch::Verdict> CommandWatch::JudgeLocked(const Ticket& ticket) const {
  if (ticket.submission_id >= 0) {
    for (const auto& s : statuses_) {
      if (s.submission_id != ticket.submission_id) continue;
      if (s.state == rover_msgs::sequence_status_t::STATE_REJECTED) {
        return Verdict{Verdict::kRejected, s.detail.empty() ? "rejected" : s.detail};
      }
      return Verdict{Verdict::kAccepted, StateName(s.state)};
    }
  }
  if (!last_ || heartbeats_ <= ticket.heartbeats) return std::nullopt;
  // A drop on the command's channel since it was sent.
  const auto [dropped, reason] = DropsOn(last_->detail, ticket.channel);
  if (dropped > std::max<std::int64_t>(ticket.dropped, 0) && DropCouldBeOurs(reason)) {
    return Verdict{Verdict::kRefused, ticket.channel + ": " + reason};
  }
  const double waited_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - ticket.sent).count();
  if (ticket.submission_id < 0 && heartbeats_ - ticket.heartbeats >= kHeartbeatsToTake &&
      waited_s >= kWallSecondsToTake) {
    return Verdict{Verdict::kAccepted, "taken: " + std::to_string(heartbeats_ - ticket.heartbeats) +
                                           " heartbeats of " + executor_ + " since, and it dropped none of them"};
  }
  return std::nullopt;
}

std::string CommandWatch::NoAnswerLocked(const Ticket& ticket, double timeout_s) const {
  char wait[32];
  std::snprintf(wait, sizeof wait, "%.0f s", timeout_s);
  std::string text;
  if (heartbeats_ == 0) {
    text = "no " + executor_ + " heard (no heartbeat) within " + wait + ", so nothing obeyed the command";
  } else if (heartbeats_ <= ticket.heartbeats) {
    text = executor_ + " fell silent: no heartbeat of it within " + wait + " of the command";
  } else if (ticket.submission_id >= 0) {
    text = executor_ + " is heard but did not answer submission " + std::to_string(ticket.submission_id) +
           " within " + wait;
    text += " (its state: " + last_->detail + ")";
  } else {
    text = executor_ + " did not say within " + wait + " whether it took the command";
  }
  if (!key_problem_.empty()) text += "; " + key_problem_;
  return text;
}

CommandWatch::Verdict CommandWatch::Wait(const Ticket& ticket, double timeout_s) const {
  std::unique_lock<std::mutex> lock(mutex_);
  std::optional<Verdict> verdict;
  changed_.wait_for(lock, std::chrono::duration<double>(timeout_s), [&] {
    verdict = JudgeLocked(ticket);
    return verdict.has_value();
  });
  if (verdict) return *verdict;
  return Verdict{Verdict::kNoAnswer, NoAnswerLocked(ticket, timeout_s)};
}

std::string CommandWatch::KeyProblem() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return key_problem_;
}

std::string CommandWatch::TakeNewKeyProblem() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (key_problem_.empty() || key_problem_said_) return "";
  key_problem_said_ = true;
  return key_problem_;
}

}  // namespace rover::web
