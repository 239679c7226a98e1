// CommandWatch (command_watch.hpp) fed messages directly, as the bus thread feeds it: what
// the executor's heartbeats and statuses say of a command rover_web sent, and when the
// console can tell that the stack will refuse its commands.
#include "web_console/command_watch.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <thread>

namespace rover::web {
namespace {

constexpr const char* kSubmit = "SEQUENCE_SUBMIT";
constexpr const char* kControl = "SEQUENCE_CONTROL";
constexpr const char* kNoTag = "rejected: no authentication tag (a key is required on this bus)";

rover_msgs::heartbeat_t Beat(const std::string& process, std::int64_t dropped, const std::string& detail,
                             bool signed_ = true) {
  rover_msgs::heartbeat_t hb{};
  hb.process = process;
  hb.dropped = dropped;
  hb.detail = detail;
  if (signed_) {
    hb.auth.tag.assign(32, 0xab);
    hb.auth.tag_size = 32;
  }
  return hb;
}

rover_msgs::sequence_status_t Status(std::int64_t id, std::int8_t state, const std::string& detail = "") {
  rover_msgs::sequence_status_t st{};
  st.submission_id = id;
  st.state = state;
  st.detail = detail;
  return st;
}

TEST(CommandWatch, AnUnsignedSubmitOnASignedStackIsRefusedWithTheExecutorsReason) {
  CommandWatch watch(false);
  EXPECT_EQ(watch.KeyProblem(), "");
  watch.OnHeartbeat(Beat("rover_web", 0, "", false));  // its own, unsigned: says nothing
  EXPECT_EQ(watch.KeyProblem(), "");
  watch.OnHeartbeat(Beat("sequence_executor", 0, "idle"));
  // Signed heartbeats, and this console holds no key: said once.
  EXPECT_NE(watch.KeyProblem().find("a signed HEARTBEAT from sequence_executor"), std::string::npos)
      << watch.KeyProblem();
  EXPECT_NE(watch.KeyProblem().find("--key"), std::string::npos) << watch.KeyProblem();
  EXPECT_EQ(watch.TakeNewKeyProblem(), watch.KeyProblem());
  EXPECT_EQ(watch.TakeNewKeyProblem(), "");

  const auto ticket = watch.Expect(kSubmit, 42);
  EXPECT_FALSE(watch.Judge(ticket));
  // The next heartbeat counts the drop, but its detail was set before it (the executor's
  // tick lags its heartbeat): not yet a verdict.
  watch.OnHeartbeat(Beat("sequence_executor", 1, "idle"));
  EXPECT_FALSE(watch.Judge(ticket));
  watch.OnHeartbeat(Beat("sequence_executor", 1, std::string("idle; SEQUENCE_SUBMIT dropped 1: ") + kNoTag));
  const auto verdict = watch.Judge(ticket);
  ASSERT_TRUE(verdict);
  EXPECT_EQ(verdict->kind, CommandWatch::Verdict::kRefused);
  EXPECT_EQ(verdict->text, std::string("SEQUENCE_SUBMIT: ") + kNoTag);
  // A later submit is not refused by that old drop: the count has not moved since, though
  // other channels drop messages (a keyless console's heartbeats).
  const auto later = watch.Expect(kSubmit, 43);
  watch.OnHeartbeat(Beat("sequence_executor", 9, std::string("idle; SEQUENCE_SUBMIT dropped 1: ") + kNoTag +
                                                     "; SEQUENCE_CONTROL dropped 4: rejected: wrong tag"));
  EXPECT_FALSE(watch.Judge(later));
  watch.OnStatus(Status(43, rover_msgs::sequence_status_t::STATE_RUNNING));
  ASSERT_TRUE(watch.Judge(later));
  EXPECT_EQ(watch.Judge(later)->kind, CommandWatch::Verdict::kAccepted);
  EXPECT_EQ(watch.Judge(later)->text, "running");
}

TEST(CommandWatch, ASubmitIsAnsweredByItsStatusAndARejectionSaysWhy) {
  CommandWatch watch(true);
  const auto ticket = watch.Expect(kSubmit, 7);
  watch.OnStatus(Status(6, rover_msgs::sequence_status_t::STATE_RUNNING));  // another one's
  EXPECT_FALSE(watch.Judge(ticket));
  watch.OnStatus(Status(7, rover_msgs::sequence_status_t::STATE_REJECTED, "line 1: drive: expected a distance"));
  watch.OnStatus(Status(7, rover_msgs::sequence_status_t::STATE_IDLE));  // its first answer stands
  const auto verdict = watch.Judge(ticket);
  ASSERT_TRUE(verdict);
  EXPECT_EQ(verdict->kind, CommandWatch::Verdict::kRejected);
  EXPECT_EQ(verdict->text, "line 1: drive: expected a distance");
  // With a key, signed heartbeats are no problem.
  watch.OnHeartbeat(Beat("sequence_executor", 0, "idle"));
  EXPECT_EQ(watch.KeyProblem(), "");
}

TEST(CommandWatch, AControlIsTakenAfterThreeHeartbeatsAndASecondWithoutItsDrop) {
  CommandWatch watch(true, "sequence_executor", "rover_web@h:1");
  watch.OnHeartbeat(Beat("sequence_executor", 2, "running; SEQUENCE_CONTROL dropped 1: rejected: wrong tag"));
  const auto ticket = watch.Expect(kControl);
  watch.OnHeartbeat(Beat("sequence_executor", 2, "running; SEQUENCE_CONTROL dropped 1: rejected: wrong tag"));
  // Another process's drops on this channel are not the executor's.
  watch.OnHeartbeat(Beat("hazard_monitor", 9, "ok; SEQUENCE_CONTROL dropped 5: rejected: wrong tag"));
  // Drops on another channel since: not this command's.
  watch.OnHeartbeat(Beat("sequence_executor", 3,
                         "running; SEQUENCE_SUBMIT dropped 1: rejected: no authentication tag; SEQUENCE_CONTROL "
                         "dropped 1: rejected: wrong tag"));
  EXPECT_FALSE(watch.Judge(ticket)) << "two heartbeats are not enough";
  watch.OnHeartbeat(Beat("sequence_executor", 3, "paused; SEQUENCE_CONTROL dropped 1: rejected: wrong tag"));
  // Three heartbeats, but within a second of wall time (at 50x in virtual time three come
  // in 15 ms): not yet.
  EXPECT_FALSE(watch.Judge(ticket)) << "three heartbeats within a second are not enough";
  std::this_thread::sleep_for(std::chrono::milliseconds(1050));
  const auto verdict = watch.Judge(ticket);
  ASSERT_TRUE(verdict);
  EXPECT_EQ(verdict->kind, CommandWatch::Verdict::kAccepted);

  const auto refused = watch.Expect(kControl);
  watch.OnHeartbeat(Beat("sequence_executor", 4,
                         "paused; SEQUENCE_CONTROL dropped 2: rejected: wrong tag from \"rover_web@h:1\" (not signed "
                         "with this deployment's key, or altered)"));
  ASSERT_TRUE(watch.Judge(refused));
  EXPECT_EQ(watch.Judge(refused)->kind, CommandWatch::Verdict::kRefused);
  EXPECT_EQ(watch.Judge(refused)->text,
            "SEQUENCE_CONTROL: rejected: wrong tag from \"rover_web@h:1\" (not signed with this deployment's key, or "
            "altered)");
}

// Another console beside this one, whose commands the executor drops (one without the key,
// or with another key): its drops in the meantime are not this console's refusals.
TEST(CommandWatch, AnotherConsolesDropIsNotThisOnesRefusal) {
  CommandWatch keyed(true, "sequence_executor", "rover_web@h:1");
  keyed.OnHeartbeat(Beat("sequence_executor", 0, "idle"));
  const auto submit = keyed.Expect(kSubmit, 11);
  keyed.OnHeartbeat(Beat("sequence_executor", 1, std::string("idle; SEQUENCE_SUBMIT dropped 1: ") + kNoTag));
  EXPECT_FALSE(keyed.Judge(submit)) << "an unsigned submit's drop is not a signed console's";
  keyed.OnHeartbeat(Beat("sequence_executor", 2,
                         "idle; SEQUENCE_SUBMIT dropped 2: rejected: wrong tag from \"rover_web@h:2\" (not signed "
                         "with this deployment's key, or altered)"));
  EXPECT_FALSE(keyed.Judge(submit)) << "another signer's drop is not this console's";
  keyed.OnStatus(Status(11, rover_msgs::sequence_status_t::STATE_RUNNING));
  ASSERT_TRUE(keyed.Judge(submit));
  EXPECT_EQ(keyed.Judge(submit)->kind, CommandWatch::Verdict::kAccepted);

  // A console without the key: a signed console's drop is not its own; an unsigned one may be.
  CommandWatch keyless(false);
  keyless.OnHeartbeat(Beat("sequence_executor", 0, "idle"));
  const auto pause = keyless.Expect(kControl);
  keyless.OnHeartbeat(Beat("sequence_executor", 1,
                           "idle; SEQUENCE_CONTROL dropped 1: rejected: wrong tag from \"rover_web@h:2\" (...)"));
  EXPECT_FALSE(keyless.Judge(pause));
  keyless.OnHeartbeat(Beat("sequence_executor", 2, std::string("idle; SEQUENCE_CONTROL dropped 2: ") + kNoTag));
  ASSERT_TRUE(keyless.Judge(pause));
  EXPECT_EQ(keyless.Judge(pause)->kind, CommandWatch::Verdict::kRefused);
}

TEST(CommandWatch, TheExecutorsDetailIsReadPerChannel) {
  const std::string detail =
      "paused; SEQUENCE_SUBMIT dropped 12: rejected: no authentication tag (a key is required on this bus); "
      "SEQUENCE_CONTROL dropped 3: rejected: wrong tag from rover_web@h:9 (not signed with this deployment's key, "
      "or altered)";
  EXPECT_EQ(CommandWatch::DropsOn(detail, kSubmit),
            std::make_pair(std::int64_t{12}, std::string("rejected: no authentication tag (a key is required on this bus)")));
  EXPECT_EQ(CommandWatch::DropsOn(detail, kControl).first, 3);
  EXPECT_EQ(CommandWatch::DropsOn(detail, kControl).second.rfind("rejected: wrong tag from rover_web@h:9", 0), 0u);
  EXPECT_EQ(CommandWatch::DropsOn("idle", kSubmit).first, 0);
  EXPECT_EQ(CommandWatch::DropsOn("idle; SEQUENCE_SUBMIT dropped x: y", kSubmit).first, 0);
}

TEST(CommandWatch, NoAnswerSaysWhatWasHeardAndAWaitWakesOnTheAnswer) {
  CommandWatch watch(true);
  const auto none = watch.Wait(watch.Expect(kControl), 0.05);
  EXPECT_EQ(none.kind, CommandWatch::Verdict::kNoAnswer);
  EXPECT_NE(none.text.find("no sequence_executor heard"), std::string::npos) << none.text;

  watch.OnHeartbeat(Beat("sequence_executor", 0, "idle"));
  const auto silent = watch.Wait(watch.Expect(kSubmit, 5), 0.05);
  EXPECT_EQ(silent.kind, CommandWatch::Verdict::kNoAnswer);
  EXPECT_NE(silent.text.find("sequence_executor fell silent"), std::string::npos) << silent.text;

  // The answer comes from the bus thread while an HTTP thread waits.
  const auto ticket = watch.Expect(kSubmit, 9);
  std::thread bus([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    watch.OnHeartbeat(Beat("sequence_executor", 0, "idle"));
    watch.OnStatus(Status(9, rover_msgs::sequence_status_t::STATE_RUNNING));
  });
  const auto start = std::chrono::steady_clock::now();
  const auto verdict = watch.Wait(ticket, 20);
  bus.join();
  EXPECT_EQ(verdict.kind, CommandWatch::Verdict::kAccepted) << verdict.text;
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 10);
}

TEST(CommandWatch, AKeyThatDoesNotVerifyTheStackIsAProblemAndOtherRejectionsAreNot) {
  CommandWatch watch(true);
  watch.OnAuthRejection("ROVER_CLOCK: replayed or old counter 5 from rover_sim@h:1");
  EXPECT_EQ(watch.KeyProblem(), "");
  watch.OnAuthRejection("ROVER_CLOCK: wrong tag from rover_sim@h:1 (not signed with this deployment's key, or altered)");
  EXPECT_NE(watch.KeyProblem().find("rover_web's key does not verify"), std::string::npos) << watch.KeyProblem();
  EXPECT_NE(watch.KeyProblem().find("ROVER_CLOCK: wrong tag from rover_sim@h:1"), std::string::npos);
  // No key: a wrong tag is never this console's to report (it checks nothing).
  CommandWatch keyless(false);
  keyless.OnAuthRejection("ROVER_CLOCK: wrong tag from rover_sim@h:1");
  keyless.OnHeartbeat(Beat("sequence_executor", 0, "idle", false));
  EXPECT_EQ(keyless.KeyProblem(), "") << "an unsigned stack is no problem for a console without a key";
}

}  // namespace
}  // namespace rover::web
