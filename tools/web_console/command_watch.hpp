// What became of a command rover_web sent, as the sequence executor tells it, the way
// rover_seq finds out (tools/rover_seq/main.cpp):
//   - a submit is answered by a SEQUENCE_STATUS of its submission;
//   - a command the executor drops (unsigned on a signed stack, a wrong key) shows in the
//     executor's HEARTBEAT, whose detail counts the drops of each command channel with the
//     last reason ("idle; SEQUENCE_SUBMIT dropped 2: rejected: no authentication tag ...",
//     processes/sequence_executor): the count going up after the command, with a reason
//     that fits how this console sent it (DropCouldBeOurs), is its refusal;
//   - pause, resume and abort have no answer of their own: three executor heartbeats and a
//     second of wall time after the command with no drop of it say it was taken (in
//     virtual time at 50x three heartbeats pass in 15 ms, before the executor may have
//     taken the command's instant at all).
// And whether this console can command the stack at all: a stack whose heartbeats are
// signed while the console holds no key, or whose messages the console's key does not
// verify, refuses its commands. That is said once it is heard (KeyProblem).
//
// Knows the messages, not the bus: the bus thread feeds it, HTTP threads wait on it (every
// member function is thread-safe). The executor's heartbeats come unverified
// (Bus::SubscribeUnverified: a console whose key is wrong cannot verify them): they only
// explain a refusal, they never make a command count as obeyed by themselves.
#pragma once

#include <rover_msgs/heartbeat_t.hpp>
#include <rover_msgs/sequence_status_t.hpp>

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <mutex>
#include <optional>
#include <string>
#include <utility>

namespace rover::web {

class CommandWatch {
 public:
  struct Verdict {
    enum Kind { kAccepted, kRefused, kRejected, kNoAnswer } kind = kNoAnswer;
    std::string text;  // the executor's answer or reason, or what was (not) heard
  };
  // What was known when a command was sent, to judge what comes after it.
  struct Ticket {
    std::string channel;            // SEQUENCE_SUBMIT or SEQUENCE_CONTROL
    std::int64_t submission_id = -1;  // a submit's
    std::int64_t heartbeats = 0;    // executor heartbeats heard before
    std::int64_t dropped = -1;      // the executor's count of drops on `channel` then (-1: not heard yet)
    std::chrono::steady_clock::time_point sent{};  // when it was sent
  };

  // `holds_key`: this console signs its commands, as `sender` (its auth::InstanceName).
  // `executor`: the process that obeys them.
  explicit CommandWatch(bool holds_key, std::string executor = "sequence_executor", std::string sender = "");

  // Whether a drop whose last reason is `reason` can be this console's command: an
  // unsigned command is dropped for having no tag; a signed one for its tag, naming its
  // sender. Another console's drop in the meantime (one without the key, or with another
  // key) is not this one's refusal.
  bool DropCouldBeOurs(const std::string& reason) const;

  // The bus thread: every heartbeat (unverified), every sequence status, and each message
  // the console's own bus refused for its authentication ("CHANNEL: reason").
  void OnHeartbeat(const rover_msgs::heartbeat_t& hb);
  void OnStatus(const rover_msgs::sequence_status_t& st);
  void OnAuthRejection(const std::string& what);

  // Before the command is published.
  Ticket Expect(const std::string& channel, std::int64_t submission_id = -1) const;
  // The verdict once it is known, or nullopt.
  std::optional<Verdict> Judge(const Ticket& ticket) const;
  // Waits up to `timeout_s` for the verdict; then kNoAnswer, saying what was heard.
  Verdict Wait(const Ticket& ticket, double timeout_s) const;

  // What an executor heartbeat's detail says of `channel`: its count of drops there and
  // the last reason; 0 and "" when it names none.
  static std::pair<std::int64_t, std::string> DropsOn(const std::string& detail, const std::string& channel);

  // Why this console's commands are refused by the stack, once heard; "" until then.
  std::string KeyProblem() const;
  // The key problem the first time it is asked for after it became known, else "" (the
  // one line rover_web prints on stderr).
  std::string TakeNewKeyProblem();

 private:
  std::optional<Verdict> JudgeLocked(const Ticket& ticket) const;
  std::string NoAnswerLocked(const Ticket& ticket, double timeout_s) const;

  const bool holds_key_;
  const std::string executor_;
  const std::string sender_;
  mutable std::mutex mutex_;
  mutable std::condition_variable changed_;
  std::int64_t heartbeats_ = 0;  // the executor's, heard so far
  std::optional<rover_msgs::heartbeat_t> last_;  // its newest
  std::deque<rover_msgs::sequence_status_t> statuses_;  // the newest few, one per submission
  std::string key_problem_;
  bool key_problem_said_ = false;
};

}  // namespace rover::web
