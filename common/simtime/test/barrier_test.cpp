// The barrier of virtual time: the clock may move on only when every member has finished
// the current instant and nothing a member published is still on its way to a subscriber.
#include "simtime/barrier.hpp"
#include "simtime/compute_profile.hpp"

#include <gtest/gtest.h>

namespace rover::simtime {
namespace {

SyncReport Report(const std::string& name, std::int64_t utime, std::set<std::string> subscribed = {}) {
  SyncReport r;
  r.process = name;
  r.utime = utime;
  r.subscribed = std::move(subscribed);
  return r;
}

TEST(Barrier, WaitsUntilEveryMemberHasFinishedTheInstant) {
  Barrier b({"a", "b"}, 3.0);
  EXPECT_FALSE(b.AllHeard());
  EXPECT_FALSE(b.Finished(100));
  b.Report(Report("a", 100), 0.0);
  EXPECT_FALSE(b.Finished(100));
  EXPECT_NE(b.Holding(100).find("b has not reported"), std::string::npos);
  b.Report(Report("b", 90), 0.0);
  EXPECT_TRUE(b.AllHeard());
  EXPECT_FALSE(b.Finished(100));
  b.Report(Report("b", 100), 0.0);
  EXPECT_TRUE(b.Finished(100));
  EXPECT_FALSE(b.Finished(200));
}

TEST(Barrier, AMessageInFlightHoldsTheClock) {
  Barrier b({"estimator", "executor"}, 3.0);
  auto est = Report("estimator", 100);
  est.published["POSE"] = 3;
  auto exe = Report("executor", 100, {"POSE"});
  exe.received["POSE"][PublisherIdOf("estimator")] = 2;
  b.Report(est, 0.0);
  b.Report(exe, 0.0);
  EXPECT_FALSE(b.Finished(100));
  EXPECT_NE(b.Holding(100).find("received 2 of 3 POSE from estimator"), std::string::npos);
  exe.received["POSE"][PublisherIdOf("estimator")] = 3;
  b.Report(exe, 0.0);
  EXPECT_TRUE(b.Finished(100));
}

TEST(Barrier, AChannelNobodyReadsHoldsNothingAndARecorderReadsEverything) {
  Barrier b({"sim", "recorder"}, 3.0);
  auto sim = Report("sim", 100);
  sim.published["SIM_TRUTH"] = 5;
  auto rec = Report("recorder", 100);
  b.Report(sim, 0.0);
  b.Report(rec, 0.0);
  EXPECT_TRUE(b.Finished(100));  // the recorder says it reads nothing
  rec.subscribes_all = true;
  b.Report(rec, 0.0);
  EXPECT_FALSE(b.Finished(100));
  rec.received["SIM_TRUTH"][PublisherIdOf("sim")] = 5;
  b.Report(rec, 0.0);
  EXPECT_TRUE(b.Finished(100));
}

TEST(Barrier, ABusyMemberHoldsTheClockButIsAlive) {
  Barrier b({"camera"}, 3.0);
  auto r = Report("camera", 100);
  r.busy = true;
  b.Report(r, 0.0);
  EXPECT_FALSE(b.Finished(100));
  b.Report(r, 2.5);  // a keepalive
  EXPECT_TRUE(b.DeclareLost(100, 5.0, 0.0).empty());
  r.busy = false;
  b.Report(r, 5.1);
  EXPECT_TRUE(b.Finished(100));
}

TEST(Barrier, ASilentMemberIsDeclaredLostOnceAndRejoinsWhenItSpeaks) {
  Barrier b({"a", "b"}, 3.0);
  b.Report(Report("a", 100), 0.0);
  b.Report(Report("b", 100), 0.0);
  ASSERT_TRUE(b.Finished(100));
  // The clock moves to 200 at wall 10 s; a answers, b is frozen.
  b.Report(Report("a", 200), 10.1);
  EXPECT_TRUE(b.DeclareLost(200, 12.9, 10.0).empty());  // under the limit since the tick
  const auto lost = b.DeclareLost(200, 13.1, 10.0);
  ASSERT_EQ(lost.size(), 1u);
  EXPECT_EQ(lost[0], "b");
  EXPECT_TRUE(b.DeclareLost(200, 20.0, 10.0).empty());  // once
  EXPECT_TRUE(b.Finished(200));                           // the clock runs on without it
  b.Report(Report("b", 200), 21.0);                       // SIGCONT: it reports again
  EXPECT_TRUE(b.Lost().empty());
  EXPECT_FALSE(b.Finished(300));
}

TEST(Barrier, ReportsFromStrangersAreIgnored) {
  Barrier b({"a"}, 3.0);
  b.Report(Report("a", 100), 0.0);
  auto stranger = Report("mallory", 0);
  stranger.published["POSE"] = 1000;
  b.Report(stranger, 0.0);
  EXPECT_TRUE(b.Finished(100));
}

TEST(ComputeProfile, NamedProfilesAndAnUnknownName) {
  EXPECT_EQ(NamedProfile("instant").vo_s, 0.0);
  EXPECT_GT(NamedProfile("mer").vo_s, 100.0);
  EXPECT_GT(NamedProfile("embedded").map_s, 0.0);
  // A HAZCAM pair (256x256) costs a third of a NAVCAM pair in every profile that charges.
  EXPECT_EQ(NamedProfile("instant").hazcam_map_s, 0.0);
  for (const char* name : {"embedded", "mer"})
    EXPECT_NEAR(NamedProfile(name).hazcam_map_s, NamedProfile(name).map_s / 3.0, 1e-9) << name;
  try {
    NamedProfile("cray");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("expected one of: instant, embedded, mer"), std::string::npos);
  }
}

}  // namespace
}  // namespace rover::simtime

namespace rover::simtime {
namespace {

TEST(Barrier, MessagesLostDuringAFreezeAreForgivenWhenTheMemberRejoins) {
  Barrier b({"sim", "frozen"}, 3.0);
  auto sim = Report("sim", 100);
  sim.published["IMU"] = 10;
  auto frozen = Report("frozen", 100, {"IMU"});
  frozen.received["IMU"][PublisherIdOf("sim")] = 10;
  b.Report(sim, 0.0);
  b.Report(frozen, 0.0);
  ASSERT_TRUE(b.Finished(100));
  sim.utime = 200;
  sim.published["IMU"] = 500;
  b.Report(sim, 1.0);
  ASSERT_EQ(b.DeclareLost(200, 5.0, 1.0).size(), 1u);
  // It wakes having lost 90 of the 490 sent meanwhile (its socket overflowed).
  frozen.utime = 200;
  frozen.received["IMU"][PublisherIdOf("sim")] = 410;
  b.Report(frozen, 6.0);
  EXPECT_TRUE(b.Finished(200));
  // Later messages are waited for as before.
  sim.utime = 300;
  sim.published["IMU"] = 502;
  b.Report(sim, 7.0);
  frozen.utime = 300;
  frozen.received["IMU"][PublisherIdOf("sim")] = 411;
  b.Report(frozen, 7.0);
  EXPECT_FALSE(b.Finished(300));
  frozen.received["IMU"][PublisherIdOf("sim")] = 412;
  b.Report(frozen, 7.1);
  EXPECT_TRUE(b.Finished(300));
}

}  // namespace
}  // namespace rover::simtime

namespace rover::simtime {
namespace {

TEST(Barrier, MessagesThatNeverCameAreForgivenOnceTheLimitHasPassed) {
  Barrier b({"estimator", "monitor"}, 3.0);
  auto est = Report("estimator", 100);
  est.published["POSE"] = 10;
  auto mon = Report("monitor", 100, {"POSE"});
  mon.received["POSE"][PublisherIdOf("estimator")] = 8;  // two lost in an overflowing socket
  b.Report(est, 0.0);
  b.Report(mon, 0.0);
  std::vector<std::string> forgiven;
  // Alive and reporting, so never lost; under the limit, still waited for.
  b.Report(mon, 2.0);
  EXPECT_TRUE(b.DeclareLost(100, 2.5, 0.0, &forgiven).empty());
  EXPECT_TRUE(forgiven.empty());
  EXPECT_FALSE(b.Finished(100));
  b.Report(mon, 3.0);
  EXPECT_TRUE(b.DeclareLost(100, 3.2, 0.0, &forgiven).empty());
  ASSERT_EQ(forgiven.size(), 1u);
  EXPECT_NE(forgiven[0].find("monitor has received 8 of 10 POSE from estimator"), std::string::npos);
  EXPECT_TRUE(b.Finished(100));
  // The next message is waited for as usual.
  est.utime = mon.utime = 200;
  est.published["POSE"] = 11;
  b.Report(est, 4.0);
  b.Report(mon, 4.0);
  EXPECT_FALSE(b.Finished(200));
}

}  // namespace
}  // namespace rover::simtime

namespace rover::simtime {
namespace {

// With a clock owner, the other members seal their batches by the clock's cut themselves:
// a message on its way to them does not hold the clock, one on its way to the owner does.
TEST(Barrier, WithAClockOwnerOnlyTheOwnersReceiptsHoldTheClock) {
  Barrier b({"sim", "estimator", "executor"}, 3.0, "sim");
  auto est = Report("estimator", 100);
  est.published["POSE"] = 3;
  est.published["MOBILITY_COMMAND"] = 0;
  auto exe = Report("executor", 100, {"POSE"});
  exe.received["POSE"][PublisherIdOf("estimator")] = 2;  // one POSE still on its way
  exe.published["MOBILITY_COMMAND"] = 4;
  auto sim = Report("sim", 100, {"MOBILITY_COMMAND"});
  sim.received["MOBILITY_COMMAND"][PublisherIdOf("executor")] = 3;  // one command on its way
  b.Report(est, 0.0);
  b.Report(exe, 0.0);
  b.Report(sim, 0.0);
  EXPECT_FALSE(b.Finished(100));
  EXPECT_NE(b.Holding(100).find("sim has received 3 of 4 MOBILITY_COMMAND from executor"), std::string::npos);
  EXPECT_EQ(b.Holding(100).find("executor has received"), std::string::npos);
  sim.received["MOBILITY_COMMAND"][PublisherIdOf("executor")] = 4;
  b.Report(sim, 0.0);
  EXPECT_TRUE(b.Finished(100));
  // What the members published is still the cut the next clock message carries.
  EXPECT_FALSE(b.Published().After("POSE", PublisherIdOf("estimator"), 2));
  EXPECT_TRUE(b.Published().After("POSE", PublisherIdOf("estimator"), 3));
  // A member's first message on a channel it had not published on is after the cut; the
  // clock owner's own are its to add (it sends them before the clock).
  EXPECT_TRUE(b.Published().After("HAZARD_QUERY", PublisherIdOf("executor"), 0));
  EXPECT_FALSE(b.Published().After("IMU", PublisherIdOf("sim"), 0));
  // A member that has not finished the instant still holds it.
  exe.utime = 200;
  b.Report(exe, 0.0);
  EXPECT_FALSE(b.Finished(200));
}

}  // namespace
}  // namespace rover::simtime
