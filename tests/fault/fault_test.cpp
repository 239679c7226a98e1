// The fault-injection suite: the full sim_vo deployment on a private bus, driving, while
//   - every channel gets hostile packets (tools/fault_inject: malformed, bad values, far
//     times, bad images), after which no process may have died or gone silent and a new
//     sequence must run to completion; or
//   - one process is killed with kill -9 mid-drive, after which no other process may die,
//     the rover must stop within a bound (2 s of wall time when the executor dies: the
//     mobility dead-man), and once the process is back a new sequence must complete.
// Each TEST is its own ctest entry (they run in parallel under ./rover test). Each prints
// "fault counts: ..." and writes it to test-out/fault_counts/ (packets sent, deaths,
// kills, safe stops). A death names the process, how it died and the packets sent last.
#include "bus/guard.hpp"
#include "fault/fault_rig.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

namespace rover::test {
namespace {

using S = rover_msgs::sequence_status_t;
// LCM's constants are declared in the class only: copies that tests may take by reference.
constexpr int kCompleted = S::STATE_COMPLETED;
constexpr int kAborted = S::STATE_ABORTED;

std::string Lines(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& i : items) out += "\n  " + i;
  return out;
}

std::string Describe(const std::optional<S>& s) {
  if (!s) return "no final status";
  return "state " + std::to_string(s->state) + (s->abort_reason.empty() ? "" : " (" + s->abort_reason + ")") +
         ": " + s->detail;
}

std::string TestName() { return ::testing::UnitTest::GetInstance()->current_test_info()->name(); }

// A new sequence runs to completion and the rover really moves: the wheels roll the
// commanded distance and the true position advances.
// The drive is forward: the mast cameras look ahead, and with the traversability map on
// the ground behind where the rover started was never seen, so a step back past it is
// refused (hazard_unknown), as it should be.
// How far the truth advances depends on where the drive under fault left the rover, which
// depends on the machine's speed: the cobbles and the drift sand north of the start take
// up to 85 % of a step (rover.yaml's rock_stall_slip). So truth is held to a tenth of what
// the wheels rolled, and the wheels to the drive's length.
void ExpectNewSequenceCompletes(FaultRig& rig, double metres) {
  std::ostringstream text;
  text << "drive " << metres << " m";
  const std::string drive = text.str();
  const double odometer = rig.odometer(), wheels = rig.wheels_rolled();
  const auto id = rig.Submit(DriveSequence(drive));
  const auto final = rig.WaitFinal(id, 120);
  ASSERT_TRUE(final.has_value()) << "the new sequence (" << drive << ") did not end within 120 s";
  EXPECT_EQ(final->state, kCompleted) << "the new sequence (" << drive << "): " << Describe(final);
  const double rolled = rig.wheels_rolled() - wheels, moved = rig.odometer() - odometer;
  std::ostringstream figures;
  figures << "new sequence (" << drive << "): the wheels rolled " << rolled << " m, the rover moved " << moved
          << " m in truth";
  rig.Note(figures.str());
  EXPECT_GT(rolled, 0.95 * metres) << "the wheels rolled " << rolled << " m for " << drive;
  EXPECT_GT(moved, 0.1 * rolled) << "the rover moved " << moved << " m in truth while its wheels rolled " << rolled
                                 << " m for " << drive;
}

// Sends one group of packets on every channel during a drive, then checks the stack.
void RunPacketGroup(const std::string& group) {
  FaultRig rig(TestName());
  ASSERT_TRUE(rig.StartAll());
  const auto drive = rig.Submit(DriveSequence("drive 2 m"));
  ASSERT_TRUE(rig.WaitSteps(drive, 1, 90)) << "the drive did not take its first step";

  fault::PacketOptions options;
  options.now_utime = rig.now_utime();
  options.max_payload_bytes = [](const std::string& channel) { return bus::MaxPayloadBytes(channel); };
  for (const auto& channel : fault::AllChannels()) {
    rig.Inject(fault::BuildPackets(group, channel.channel, options), 5);
  }
  rig.Note("sent " + std::to_string(rig.counts().packets) + " " + group + " packets");
  rig.Pump(1.0);
  if (!rig.Final(drive)) rig.Abort("fault test: the drive under fault ends here");
  EXPECT_TRUE(rig.WaitFinal(drive, 30).has_value()) << "the drive under fault did not end after an abort";

  EXPECT_TRUE(rig.deaths().empty()) << rig.deaths().size() << " processes died:" << Lines(rig.deaths());
  const std::size_t deaths_before = rig.deaths().size();
  rig.Pump(1.5);  // every live process heartbeats once a second
  EXPECT_TRUE(rig.Silent(2.5).empty()) << "silent for 2.5 s (dead or wedged):" << Lines(rig.Silent(2.5));
  ExpectNewSequenceCompletes(rig, 1.0);
  EXPECT_EQ(rig.deaths().size(), deaths_before) << "died later:" << Lines(rig.deaths());
  rig.Report();
}

TEST(FaultInjection, MalformedPacketsOnEveryChannelKillNoProcess) { RunPacketGroup("malformed"); }
TEST(FaultInjection, NanInfAndUnknownEnumsOnEveryChannelKillNoProcess) { RunPacketGroup("values"); }
TEST(FaultInjection, FarFutureAndFarPastTimesLeaveTheStackAbleToRunASequence) { RunPacketGroup("times"); }
TEST(FaultInjection, HostileImagesDuringADriveKillNoProcess) { RunPacketGroup("images"); }

// With keys (sim_vo_auth): commands that anyone on the LAN could send (unsigned, a made-up
// tag, the executor's own signed commands replayed, malformed, NaN, far times) on the five
// command channels during a drive are all refused, so the drive completes untouched.
TEST(FaultInjection, WithKeysSpoofedReplayedAndMalformedCommandsNeverTouchTheDrive) {
  FaultRig rig(TestName(), /*keyed=*/true);
  ASSERT_TRUE(rig.StartAll());
  // Short steps make the drive last (a longer one north meets the rock Adirondack).
  const auto drive = rig.Submit(DriveSequence("drive 2 m", 25));
  ASSERT_TRUE(rig.WaitSteps(drive, 2, 90)) << "the drive did not take two steps";
  const auto sim_dropped = rig.dropped("rover_sim"), executor_dropped = rig.dropped("sequence_executor");

  fault::PacketOptions options;
  options.now_utime = rig.now_utime();
  options.max_payload_bytes = [](const std::string& channel) { return bus::MaxPayloadBytes(channel); };
  const std::vector<std::string> commands = {"SEQUENCE_SUBMIT", "SEQUENCE_CONTROL", "MOBILITY_COMMAND",
                                             "KEEPOUT_ZONES", "NEW_SITE"};
  // The ones that would do harm first, while the drive surely runs: replays and spoofs.
  std::vector<fault::Packet> harmful = rig.CapturedCommands(), others;
  ASSERT_FALSE(harmful.empty()) << "no MOBILITY_COMMAND seen to replay";
  const std::size_t replays = harmful.size();
  for (const auto& channel : commands)
    for (auto& p : fault::BuildPackets("spoofed", channel, options)) harmful.push_back(std::move(p));
  for (const char* group : {"malformed", "values", "times"})
    for (const auto& channel : commands)
      for (auto& p : fault::BuildPackets(group, channel, options)) others.push_back(std::move(p));
  std::map<std::string, long> sent;
  for (const auto* list : {&harmful, &others})
    for (const auto& p : *list) ++sent[p.channel];
  rig.Inject(harmful, 5);
  EXPECT_FALSE(rig.Final(drive).has_value()) << "the drive ended before the spoofed commands were all sent: "
                                             << Describe(rig.Final(drive));
  rig.Inject(others, 5);
  rig.Note("sent " + std::to_string(rig.counts().packets) + " command packets, " + std::to_string(replays) +
           " of them replays");

  const auto final = rig.WaitFinal(drive, 90);
  EXPECT_TRUE(final && final->state == kCompleted)
      << "the drive under forged commands did not complete: " << Describe(final);
  rig.Pump(1.5);
  // Every command packet was refused: the drop counts grew by at least what was sent.
  EXPECT_GE(rig.dropped("rover_sim") - sim_dropped, sent["MOBILITY_COMMAND"]) << "rover_sim took a command";
  EXPECT_GE(rig.dropped("sequence_executor") - executor_dropped, sent["SEQUENCE_SUBMIT"] + sent["SEQUENCE_CONTROL"])
      << "sequence_executor took a submit or control";
  EXPECT_TRUE(rig.deaths().empty()) << rig.deaths().size() << " processes died:" << Lines(rig.deaths());
  EXPECT_TRUE(rig.Silent(2.5).empty()) << "silent for 2.5 s (dead or wedged):" << Lines(rig.Silent(2.5));
  ExpectNewSequenceCompletes(rig, 1.0);
  rig.Report();
}

// Kills `process` with kill -9 while the rover drives; checks the stop, the others, and
// that a new sequence completes once the process is back.
void RunKill(const std::string& process) {
  const bool executor = process == "sequence_executor";
  FaultRig rig(TestName());
  // At 50x a step lasts well under a second of wall time and ends by itself before any
  // dead-man could act; at 5x a 75 cm step lasts 3.75 s, so only the dead-man stops the
  // rover within 2 s of the executor's death.
  ASSERT_TRUE(rig.StartAll(executor ? 5 : 50));
  const auto drive = rig.Submit(DriveSequence("drive 2 m", executor ? 75 : 50));
  ASSERT_TRUE(rig.WaitMoving(90)) << "the rover was never seen moving";

  const auto killed_at = Clock::now();
  rig.Kill(process);
  // The executor's death is caught by the mobility dead-man; any other by the executor,
  // which hears its heartbeat stop (executor.heartbeat_timeout_s) and commands STOP.
  const double bound = executor ? 2.0 : rig.heartbeat_timeout_s() + 2.0;
  const auto latency = rig.StopLatency(killed_at, bound + 1.5);
  if (latency && *latency <= bound) ++rig.counts().safe_stops;
  if (latency) {
    rig.Note("the rover stopped " + std::to_string(*latency) + " s after the kill");
    EXPECT_LE(*latency, bound) << "the rover stopped " << *latency << " s after kill -9 " << process
                               << " (expected within " << bound << " s; " << rig.mobility_detail() << ")";
  } else {
    ADD_FAILURE() << "the rover still moved " << bound + 1.5 << " s after kill -9 " << process << " ("
                  << rig.mobility_detail() << ")";
  }
  EXPECT_TRUE(rig.deaths().empty()) << "another process died:" << Lines(rig.deaths());
  const std::size_t deaths_before = rig.deaths().size();
  if (!executor) {
    const auto final = rig.WaitFinal(drive, rig.heartbeat_timeout_s() + 10);
    EXPECT_TRUE(final && final->state == kAborted)
        << "the executor did not abort the drive after " << process << " died: " << Describe(final);
  }

  if (process == "rover_sim") {
    // The simulator owns the rover clock: the rover starts again, and so does everything.
    rig.StopAll();
    ASSERT_TRUE(rig.StartAll());
    ExpectNewSequenceCompletes(rig, 1.0);
  } else {
    ASSERT_TRUE(rig.Restart(process)) << process << " did not come back";
    ASSERT_TRUE(rig.WaitHazardSafe(30)) << "the hazard monitor could not decide a step within 30 s after " << process
                                        << " came back";
    if (executor) {
      const auto final = rig.WaitFinal(drive, 10);
      EXPECT_TRUE(final && final->state == kAborted && final->abort_reason == "interrupted")
          << "the restarted executor did not report the drive it was running as interrupted: "
          << Describe(final);
    }
    ExpectNewSequenceCompletes(rig, 1.0);
  }
  EXPECT_EQ(rig.deaths().size(), deaths_before) << "died later:" << Lines(rig.deaths());
  rig.Report();
}

// Freezes `process` with SIGSTOP for 5 s while the rover drives on a real clock at rate 1:
// a hung process must stop the rover within 2 s of wall time, as a dead one does (the
// executor hears its heartbeat stop; the executor's own hang, the mobility dead-man), and
// after SIGCONT the stack runs a new sequence.
void RunFreeze(const std::string& process) {
  FaultRig rig(TestName());
  ASSERT_TRUE(rig.StartAll(1));
  const auto drive = rig.Submit(DriveSequence("drive 2 m", 50));
  ASSERT_TRUE(rig.WaitMoving(120)) << "the rover was never seen moving";
  const auto frozen_at = Clock::now();
  rig.Freeze(process, true);
  const double bound = 2.0;
  const auto latency = rig.StopLatency(frozen_at, 5.0);
  rig.Freeze(process, false);
  if (latency) {
    rig.Note("the rover stopped " + std::to_string(*latency) + " s after SIGSTOP");
    EXPECT_LE(*latency, bound) << "the rover stopped " << *latency << " s after SIGSTOP " << process
                               << " (expected within " << bound << " s; " << rig.mobility_detail() << ")";
    if (*latency <= bound) ++rig.counts().safe_stops;
  } else {
    ADD_FAILURE() << "the rover still moved 5 s after SIGSTOP " << process << " (" << rig.mobility_detail() << ")";
  }
  const auto final = rig.WaitFinal(drive, 30);
  EXPECT_TRUE(final && final->state == kAborted)
      << "the drive did not end aborted after " << process << " hung: " << Describe(final);
  EXPECT_TRUE(rig.deaths().empty()) << "a process died:" << Lines(rig.deaths());
  ExpectNewSequenceCompletes(rig, 1.0);
  rig.Report();
}

// The time source itself falls silent on a real clock (rover_sim frozen for 3 s, longer than
// bus.time_source_silent_s): the executor aborts the drive `time_source_lost` (a STOP), each
// process says so in one line, and one more when the source speaks again; then a new
// sequence completes.
TEST(FaultFreeze, TimeSourceSilentAbortsTheDriveOnceAndWorkResumes) {
  FaultRig rig(TestName());
  ASSERT_TRUE(rig.StartAll(1));
  const auto drive = rig.Submit(DriveSequence("drive 2 m", 50));
  ASSERT_TRUE(rig.WaitMoving(120)) << "the rover was never seen moving";
  rig.Freeze("rover_sim", true);
  rig.Pump(3.0);
  rig.Freeze("rover_sim", false);
  const auto final = rig.WaitFinal(drive, 30);
  ASSERT_TRUE(final.has_value()) << "the drive did not end after the time source fell silent";
  EXPECT_EQ(final->state, kAborted) << Describe(final);
  EXPECT_EQ(final->abort_reason, "time_source_lost") << Describe(final);
  EXPECT_TRUE(rig.deaths().empty()) << "a process died:" << Lines(rig.deaths());
  ExpectNewSequenceCompletes(rig, 1.0);
  // One line for the silence and one for the return, in the executor's log.
  std::ifstream in(rig.out() + "/run1/sequence_executor.log");
  int silent = 0, back = 0;
  for (std::string line; std::getline(in, line);) {
    silent += line.find("the time source rover_sim fell silent") != std::string::npos &&
              line.find("sequence_executor:") == 0;
    back += line.find("the time source rover_sim speaks again") != std::string::npos;
  }
  EXPECT_EQ(silent, 1) << "lines saying the time source fell silent (see " << rig.out() << "/run1)";
  EXPECT_EQ(back, 1) << "lines saying the time source speaks again (see " << rig.out() << "/run1)";
  rig.Report();
}

TEST(FaultFreeze, SequenceExecutorHungStopsTheRoverWithinTwoSeconds) { RunFreeze("sequence_executor"); }
TEST(FaultFreeze, StateEstimatorHungStopsTheRoverWithinTwoSeconds) { RunFreeze("state_estimator"); }
TEST(FaultFreeze, HazardMonitorHungStopsTheRoverWithinTwoSeconds) { RunFreeze("hazard_monitor"); }
TEST(FaultFreeze, VisualOdometryHungStopsTheRoverWithinTwoSeconds) { RunFreeze("visual_odometry"); }
TEST(FaultFreeze, CameraCaptureHungStopsTheRoverWithinTwoSeconds) { RunFreeze("camera_capture"); }

// Virtual time (README, "Simulated time"): a process frozen with SIGSTOP holds the clock,
// so the rover stops at once (in rover time it does not move at all). Frozen for less
// than sim.barrier_timeout_s (10 s of wall time), it is waited for and the drive goes on
// after SIGCONT; frozen for longer, it is declared lost, the rover is halted, the clock
// runs on and the drive ends aborted. Either way no clock is wedged: once the process has
// caught up, a new sequence completes.
void RunFreezeVirtual(const std::string& process, double rate, double freeze_s) {
  FaultRig rig(TestName());
  rig.set_virtual(true);
  ASSERT_TRUE(rig.StartAll(rate));
  const auto drive = rig.Submit(DriveSequence("drive 2 m", 50));
  ASSERT_TRUE(rig.WaitMoving(120)) << "the rover was never seen moving";
  const auto frozen_at = Clock::now();
  rig.Freeze(process, true);
  const auto latency = rig.StopLatency(frozen_at, freeze_s);
  rig.Freeze(process, false);
  const double bound = 0.5;  // the clock stops at the next instant: wall time to notice it
  if (latency) {
    rig.Note("the rover stopped " + std::to_string(*latency) + " s after SIGSTOP");
    EXPECT_LE(*latency, bound) << "the rover stopped " << *latency << " s after SIGSTOP " << process;
    if (*latency <= bound) ++rig.counts().safe_stops;
  } else {
    ADD_FAILURE() << "the rover still moved " << freeze_s << " s after SIGSTOP " << process << " ("
                  << rig.mobility_detail() << ")";
  }
  const bool declared_lost = freeze_s > 10.0 && process != "rover_sim";  // rover_sim is the clock
  const auto final = rig.WaitFinal(drive, 120);
  if (declared_lost) {
    EXPECT_TRUE(final && final->state == kAborted)
        << "the drive did not end aborted after " << process << " was lost: " << Describe(final);
  } else {
    EXPECT_TRUE(final && final->state == kCompleted)
        << "the drive did not go on after " << process << " was frozen " << freeze_s << " s: " << Describe(final);
  }
  EXPECT_TRUE(rig.deaths().empty()) << "a process died:" << Lines(rig.deaths());
  EXPECT_TRUE(rig.WaitCaughtUp(process, 30)) << process << " did not catch up with rover time after SIGCONT";
  ExpectNewSequenceCompletes(rig, 1.0);
  rig.Report();
}

TEST(FaultFreezeVirtual, SequenceExecutorAt50x) { RunFreezeVirtual("sequence_executor", 50, 5); }
TEST(FaultFreezeVirtual, StateEstimatorAt50x) { RunFreezeVirtual("state_estimator", 50, 5); }
TEST(FaultFreezeVirtual, HazardMonitorAt50x) { RunFreezeVirtual("hazard_monitor", 50, 5); }
TEST(FaultFreezeVirtual, VisualOdometryAt50x) { RunFreezeVirtual("visual_odometry", 50, 5); }
TEST(FaultFreezeVirtual, CameraCaptureAt50x) { RunFreezeVirtual("camera_capture", 50, 5); }
TEST(FaultFreezeVirtual, RoverSimAt50x) { RunFreezeVirtual("rover_sim", 50, 5); }
TEST(FaultFreezeVirtual, CameraCaptureAtRate2) { RunFreezeVirtual("camera_capture", 2, 5); }
TEST(FaultFreezeVirtual, SequenceExecutorAtRate2) { RunFreezeVirtual("sequence_executor", 2, 5); }
TEST(FaultFreezeVirtual, StateEstimatorPastTheLimitIsDeclaredLost) { RunFreezeVirtual("state_estimator", 50, 12); }

// A ROVER_CLOCK message, `utime` and count as given, from rover_sim's publisher id.
fault::Packet ForgedClock(const std::string& label, std::int64_t utime, std::int64_t count) {
  rover_msgs::rover_clock_t m{};
  m.utime = utime;
  m.pub_seq = static_cast<std::int64_t>((static_cast<std::uint64_t>(bus::PublisherId("rover_sim")) << 32) |
                                        static_cast<std::uint64_t>(count));
  m.mode = rover_msgs::rover_clock_t::MODE_VIRTUAL;
  return {channels::kClock, label, bus::EncodeMessage(m), ""};
}

// Time cannot be forged: during a virtual-time drive, clock messages 600 s old, 600 s
// ahead (from rover_sim's own publisher id, with counts that follow its own) and the last
// real one replayed byte for byte leave every process's clock alone: the drive completes
// and so does the next sequence. With keys, every one of them is refused outright
// (unsigned, or a replayed counter).
void RunForgedClock(bool keyed) {
  FaultRig rig(TestName(), keyed);
  rig.set_virtual(true);
  ASSERT_TRUE(rig.StartAll());
  const auto drive = rig.Submit(DriveSequence("drive 2 m", 25));
  ASSERT_TRUE(rig.WaitSteps(drive, 2, 90)) << "the drive did not take two steps";
  const auto executor_dropped = rig.dropped("sequence_executor");
  const auto replay = rig.last_clock_bytes();
  ASSERT_FALSE(replay.empty()) << "no ROVER_CLOCK seen to replay";
  rover_msgs::rover_clock_t last;
  ASSERT_GE(last.decode(replay.data(), 0, static_cast<int>(replay.size())), 0);
  const auto count = static_cast<std::int64_t>(static_cast<std::uint64_t>(last.pub_seq) & 0xffffffffu);
  std::vector<fault::Packet> forged;
  // Five of each, sent one by one: each forged future clock stands alone (counts far
  // apart), as a replayed or mistaken one would. (Without keys, a forger who streams a
  // consistent clock of its own cannot be told from the time source: that is what keys
  // are for, and the keyed run below refuses every one.)
  for (int i = 0; i < 5; ++i) {
    forged.push_back(ForgedClock("ROVER_CLOCK 600 s old", last.utime - 600000000, count + 1 + i));
    forged.push_back(ForgedClock("ROVER_CLOCK 600 s ahead", last.utime + 600000000 + i * 100000000, count + 1000 * (i + 1)));
    forged.push_back({channels::kClock, "ROVER_CLOCK replayed", replay, ""});
  }
  rig.Inject(forged, 20);
  const auto final = rig.WaitFinal(drive, 120);
  EXPECT_TRUE(final && final->state == kCompleted) << "the drive under forged clocks did not complete: " << Describe(final);
  rig.Pump(1.0);
  // The 600 s ones were refused by every process (the replay of the current instant is
  // harmless without keys: the same instant again).
  EXPECT_GE(rig.dropped("sequence_executor") - executor_dropped, 10) << "the executor took a forged clock";
  EXPECT_TRUE(rig.deaths().empty()) << "a process died:" << Lines(rig.deaths());
  ExpectNewSequenceCompletes(rig, 1.0);
  rig.Report();
}

TEST(FaultForgedTime, OldFutureAndReplayedClocksLeaveTheDriveAlone) { RunForgedClock(false); }
TEST(FaultForgedTime, WithKeysOldFutureAndReplayedClocksAreRefused) { RunForgedClock(true); }

// With keys, a heartbeat is evidence of life: the executor frozen on a real clock while
// its last heartbeat is replayed four times a second must still trip the dead-man within
// 2 s (the replayed counter is refused), and the stack recovers after SIGCONT.
TEST(FaultForgedTime, WithKeysAReplayedHeartbeatDoesNotKeepTheDeadManQuiet) {
  FaultRig rig(TestName(), /*keyed=*/true);
  ASSERT_TRUE(rig.StartAll(1));
  rig.Submit(DriveSequence("drive 2 m", 50));
  ASSERT_TRUE(rig.WaitMoving(120)) << "the rover was never seen moving";
  const auto frozen_at = Clock::now();
  rig.Freeze("sequence_executor", true);
  rig.Pump(0.05);
  const auto heartbeat = rig.last_heartbeat_bytes("sequence_executor");
  ASSERT_FALSE(heartbeat.empty()) << "no heartbeat of the executor seen to replay";
  std::vector<fault::Packet> replays(20, fault::Packet{channels::kHeartbeat, "HEARTBEAT replayed", heartbeat, ""});
  rig.Inject(replays, 250);  // 5 s, four a second
  const auto latency = rig.StopLatency(frozen_at, 5.5);
  rig.Freeze("sequence_executor", false);
  ASSERT_TRUE(latency.has_value()) << "the rover still moved while a replayed heartbeat stood in for a frozen executor";
  rig.Note("the rover stopped " + std::to_string(*latency) + " s after SIGSTOP, heartbeats replayed");
  EXPECT_LE(*latency, 2.0) << "the replayed heartbeat kept the dead-man quiet for " << *latency << " s";
  EXPECT_TRUE(rig.deaths().empty()) << "a process died:" << Lines(rig.deaths());
  ExpectNewSequenceCompletes(rig, 1.0);
  rig.Report();
}

TEST(FaultKill, SequenceExecutorMidDriveStopsTheRoverWithinTwoSeconds) { RunKill("sequence_executor"); }
TEST(FaultKill, RoverSimMidDrive) { RunKill("rover_sim"); }
TEST(FaultKill, StateEstimatorMidDrive) { RunKill("state_estimator"); }
TEST(FaultKill, HazardMonitorMidDrive) { RunKill("hazard_monitor"); }
TEST(FaultKill, CameraCaptureMidDrive) { RunKill("camera_capture"); }
TEST(FaultKill, VisualOdometryMidDrive) { RunKill("visual_odometry"); }

// The tool by hand: sends what it lists, says how many, and refuses an unknown group.
TEST(FaultInjectTool, SendsTheGroupsItIsGivenAndCountsThem) {
  const std::string env = "ROVER_LCM_URL='" + PrivateUrl(37) + "' ";
  const auto listed = RunCommand(Bin("fault_inject") + " --list --group malformed --channel IMU,POSE");
  ASSERT_EQ(listed.exit_code, 0) << listed.output;
  long lines = 0;
  for (char c : listed.output) lines += c == '\n';
  const auto sent = RunCommand(env + Bin("fault_inject") +
                               " --group malformed --channel IMU,POSE --now-utime 1 --interval-ms 0 --quiet");
  ASSERT_EQ(sent.exit_code, 0) << sent.output;
  EXPECT_NE(sent.output.find("fault_inject: sent " + std::to_string(lines) + " packets"), std::string::npos)
      << sent.output << " (listed " << lines << ")";
  const auto bad = RunCommand(env + Bin("fault_inject") + " --group nonsense");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_EQ(bad.output,
            "fault_inject: group \"nonsense\" is unknown (expected all or malformed, values, times, images, spoofed)\n");
}

}  // namespace
}  // namespace rover::test
