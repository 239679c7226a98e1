#include "bus/bus.hpp"
#include "bus/lcm_url_check.hpp"
#include "bus/channels.hpp"
#include "bus/process.hpp"
#include "bus/virtual_time.hpp"

#include <gtest/gtest.h>
#include <rover_msgs/heartbeat_t.hpp>
#include <rover_msgs/pose_t.hpp>
#include <rover_msgs/rover_clock_t.hpp>

#include <rover_msgs/sequence_control_t.hpp>
#include <rover_msgs/step_report_t.hpp>
#include <rover_msgs/traversability_map_t.hpp>
#include <rover_msgs/wheel_odometry_t.hpp>
#include <rover_msgs/imu_t.hpp>
#include <rover_msgs/rover_clock_t.hpp>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cmath>
#include <stdexcept>
#include <vector>

using rover::bus::Bus;

// memq:// is LCM's in-process provider: the typed wrapper is tested with no network.
TEST(Bus, LambdaSubscribeReceivesTypedMessages) {
  Bus bus("memq://");
  std::vector<std::int64_t> seen;
  bus.Subscribe<rover_msgs::heartbeat_t>(
      rover::channels::kHeartbeat,
      [&](const rover_msgs::heartbeat_t& hb) { seen.push_back(hb.seq); });
  for (int i = 0; i < 3; ++i) {
    rover_msgs::heartbeat_t hb{};
    hb.process = "x";
    hb.seq = 10 + i;
    bus.Publish(rover::channels::kHeartbeat, hb);
  }
  while (bus.Handle(0)) {
  }
  EXPECT_EQ(seen, (std::vector<std::int64_t>{10, 11, 12}));
}

TEST(Bus, CorruptMessageIsDroppedAndCounted) {
  Bus bus("memq://");
  int received = 0;
  bus.Subscribe<rover_msgs::pose_t>(rover::channels::kPose,
                                    [&](const rover_msgs::pose_t&) { ++received; });
  const char junk[] = "not a pose";
  bus.lcm().publish(rover::channels::kPose, junk, sizeof(junk));
  while (bus.Handle(0)) {
  }
  EXPECT_EQ(received, 0);
  EXPECT_EQ(bus.corrupt_count(), 1);
}

TEST(Bus, CallbackErrorIsReportedAndCountedAndTheLoopGoesOn) {
  Bus bus("memq://");
  int calls = 0;
  bus.Subscribe<rover_msgs::heartbeat_t>(rover::channels::kHeartbeat,
                                         [&](const rover_msgs::heartbeat_t&) {
                                           ++calls;
                                           throw std::runtime_error("boom");
                                         });
  rover_msgs::heartbeat_t hb{};
  hb.process = "x";
  bus.Publish(rover::channels::kHeartbeat, hb);
  bus.Publish(rover::channels::kHeartbeat, hb);
  EXPECT_NO_THROW(while (bus.Handle(0)) {});
  EXPECT_EQ(calls, 2);
  EXPECT_EQ(bus.dropped(), 2);
  EXPECT_NE(bus.last_drop().find("handler failed: boom"), std::string::npos) << bus.last_drop();
}

namespace {

// The bytes of `msg` with the big-endian int32 at `offset` replaced by `value`.
template <class Msg>
std::vector<std::uint8_t> EncodedWithInt32(const Msg& msg, std::size_t offset, std::int32_t value) {
  std::vector<std::uint8_t> bytes(msg.getEncodedSize());
  msg.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  for (int i = 0; i < 4; ++i) bytes.at(offset + i) = static_cast<std::uint8_t>(value >> (24 - 8 * i));
  return bytes;
}

// Publishes raw bytes on `channel` and handles them; returns how many callbacks ran.
template <class Msg>
int Deliver(Bus& bus, const std::string& channel, const std::vector<std::uint8_t>& bytes) {
  int received = 0;
  bus.Subscribe<Msg>(channel, [&](const Msg&) { ++received; });
  bus.lcm().publish(channel, bytes.data(), static_cast<unsigned>(bytes.size()));
  while (bus.Handle(0)) {
  }
  return received;
}

}  // namespace

// heartbeat_t: fingerprint 8, utime 8, then the process name's int32 length.
TEST(Bus, StringLengthsOfZeroNegativeOrHugeAreDroppedNotThrown) {
  rover_msgs::heartbeat_t hb{};
  hb.process = "sequence_executor";
  for (std::int32_t len : {0, -1, -2147483647 - 1, 2147483647}) {
    Bus bus("memq://");
    EXPECT_EQ(Deliver<rover_msgs::heartbeat_t>(bus, rover::channels::kHeartbeat, EncodedWithInt32(hb, 16, len)), 0)
        << len;
    EXPECT_EQ(bus.dropped(), 1) << len;
    EXPECT_NE(bus.last_drop().find("does not decode"), std::string::npos) << bus.last_drop();
  }
}

// wheel_odometry_t: fingerprint 8, utime 8, pub_seq 8, then num_wheels. A count of 2^31-1
// doubles would be a 16 GiB allocation: the cap refuses it before it is attempted.
TEST(Bus, ArrayCountsThatLieCannotAllocate) {
  rover_msgs::wheel_odometry_t odo{};
  odo.num_wheels = 6;
  odo.wheel_distance_m.assign(6, 0.0);
  for (std::int32_t count : {-1, 100000000, 2147483647}) {
    Bus bus("memq://");
    EXPECT_EQ(Deliver<rover_msgs::wheel_odometry_t>(bus, rover::channels::kWheelOdometry,
                                                    EncodedWithInt32(odo, 24, count)), 0)
        << count;
    EXPECT_EQ(bus.dropped(), 1) << count;
  }
}

TEST(Bus, OversizedPayloadIsDroppedBeforeDecoding) {
  Bus bus("memq://");
  std::vector<std::uint8_t> big(rover::bus::MaxPayloadBytes(rover::channels::kImu) + 1, 0);
  EXPECT_EQ(Deliver<rover_msgs::imu_t>(bus, rover::channels::kImu, big), 0);
  EXPECT_NE(bus.last_drop().find("over the channel's limit"), std::string::npos) << bus.last_drop();
}

TEST(Bus, NonFiniteAndUnknownValuesAreDropped) {
  Bus bus("memq://");
  int received = 0;
  bus.Subscribe<rover_msgs::pose_t>(rover::channels::kPose, [&](const rover_msgs::pose_t&) { ++received; });
  rover_msgs::pose_t pose{};
  pose.orientation[0] = 1;
  bus.Publish(rover::channels::kPose, pose);  // valid
  pose.position[1] = std::nan("");
  bus.Publish(rover::channels::kPose, pose);
  pose.position[1] = 0;
  pose.source = 7;
  bus.Publish(rover::channels::kPose, pose);
  while (bus.Handle(0)) {
  }
  EXPECT_EQ(received, 1);
  EXPECT_EQ(bus.dropped(), 2);
  EXPECT_NE(bus.last_drop().find("source 7 is unknown"), std::string::npos) << bus.last_drop();
}

// A step report's choice is one of its three values: 0 (the command's own step, also what a
// publisher that does not say leaves), the arc vote, or steered at the goal.
TEST(Bus, StepReportChoiceIsKnownOrDropped) {
  Bus bus("memq://");
  std::vector<int> choices;
  bus.Subscribe<rover_msgs::step_report_t>(rover::channels::kStepReport,
                                           [&](const rover_msgs::step_report_t& m) { choices.push_back(m.choice); });
  rover_msgs::step_report_t step{};
  step.vo_status = -1;
  for (int c : {0, 1, 2, 3, -1}) {
    step.choice = static_cast<std::int8_t>(c);
    bus.Publish(rover::channels::kStepReport, step);
  }
  while (bus.Handle(0)) {
  }
  EXPECT_EQ(choices, (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(bus.dropped(), 2);
  EXPECT_NE(bus.last_drop().find("choice -1 is unknown (expected 0 to 2)"), std::string::npos) << bus.last_drop();
}

// A map's caution level is a goodness: 0 (not given) to 1, and nothing else reaches the vote.
TEST(Bus, MapCautionLevelOutsideZeroToOneIsDropped) {
  Bus bus("memq://");
  std::vector<double> levels;
  bus.Subscribe<rover_msgs::traversability_map_t>(
      rover::channels::kTraversabilityMap,
      [&](const rover_msgs::traversability_map_t& m) { levels.push_back(m.caution_goodness); });
  rover_msgs::traversability_map_t map{};
  map.cell_m = 0.1;
  for (double level : {0.0, 0.4, 1.0, 1.5, -0.1, std::nan("")}) {
    map.caution_goodness = level;
    bus.Publish(rover::channels::kTraversabilityMap, map);
  }
  while (bus.Handle(0)) {
  }
  EXPECT_EQ(levels, (std::vector<double>{0.0, 0.4, 1.0}));
  EXPECT_EQ(bus.dropped(), 3);
  EXPECT_NE(bus.last_drop().find("caution_goodness is not finite"), std::string::npos) << bus.last_drop();
}

// A tick after a stall must see what arrived during it: HandleReceived handles the
// messages already received first (the executor's heartbeat watch once judged live peers
// lost from heartbeats still waiting in the socket on a starved machine).
TEST(Process, HandleReceivedLetsATickSeeEveryMessageReceivedBeforeIt) {
  const char* argv[] = {"test_process", "--lcm-url", "memq://"};
  rover::bus::Process proc("test_process", "test", 3, const_cast<char**>(argv));
  int peer_beats = 0;
  proc.bus().Subscribe<rover_msgs::heartbeat_t>(rover::channels::kHeartbeat,
                                                [&](const rover_msgs::heartbeat_t& hb) {
                                                  if (hb.process == "peer") ++peer_beats;
                                                });
  // memq is per bus instance: the peer's heartbeats are published on the process's bus.
  for (int i = 0; i < 5; ++i) {
    rover_msgs::heartbeat_t hb{};
    hb.process = "peer";
    hb.seq = i;
    proc.bus().Publish(rover::channels::kHeartbeat, hb);
  }
  int seen_at_first_tick = -1;
  proc.Run(
      [&] {
        EXPECT_EQ(peer_beats, 0);  // Run ticks before it handles what is waiting ...
        EXPECT_GE(proc.HandleReceived(50), 5);  // ... which HandleReceived handles first
        seen_at_first_tick = peer_beats;
        proc.Stop();
      },
      25);
  EXPECT_EQ(seen_at_first_tick, 5);
}

// A real-time process drops a virtual clock (another mode's); one that only watches (the
// web console started by hand on a simulation) observes it instead, and so takes messages
// stamped with rover time.
TEST(Process, AClockObserverFollowsAVirtualClockThatOthersDrop) {
  constexpr std::int64_t kBase = 10'000'000'000;  // rover time far from the wall clock
  for (const bool observer : {false, true}) {
    const char* argv[] = {"test_process", "--lcm-url", "memq://"};
    rover::bus::Process proc("test_process", "test", 3, const_cast<char**>(argv));
    ASSERT_FALSE(proc.virtual_time());
    proc.set_clock_observer(observer);
    proc.bus().set_publisher("rover_sim");  // memq: the time source publishes on this bus
    rover_msgs::rover_clock_t clock{};
    clock.utime = kBase;
    clock.rate = 50;
    clock.mode = rover_msgs::rover_clock_t::MODE_VIRTUAL;
    proc.bus().Publish(rover::channels::kClock, clock);
    proc.bus().set_publisher("test_process");
    while (proc.bus().Handle(0)) {
    }
    EXPECT_EQ(proc.bus().dropped(), observer ? 0 : 1) << "observer " << observer;
    EXPECT_EQ(proc.now(), observer ? kBase : 0) << "observer " << observer;
  }
}

TEST(Bus, PublishStampsPublisherAndCountPerChannel) {
  Bus bus("memq://");
  bus.set_publisher("state_estimator");
  std::vector<std::int64_t> seqs;
  bus.Subscribe<rover_msgs::pose_t>(rover::channels::kPose,
                                    [&](const rover_msgs::pose_t& m) { seqs.push_back(m.pub_seq); });
  rover_msgs::pose_t pose{};
  pose.orientation[0] = 1;
  for (int i = 0; i < 3; ++i) bus.Publish(rover::channels::kPose, pose);
  while (bus.Handle(0)) {
  }
  const std::int64_t id = static_cast<std::int64_t>(rover::bus::PublisherId("state_estimator")) << 32;
  EXPECT_EQ(seqs, (std::vector<std::int64_t>{id, id + 1, id + 2}));
  EXPECT_NE(rover::bus::PublisherId("state_estimator"), rover::bus::PublisherId("rover_sim"));
}

TEST(Bus, FarFutureOrFarPastTimesAreDroppedAndNeverMoveTheClock) {
  Bus bus("memq://");
  const auto wall = rover::bus::RoverClock::WallClock::now();
  constexpr std::int64_t kBase = 10'000'000'000'000;  // 115 days of rover time
  bus.clock().ObserveClock(kBase, 50.0, wall);
  std::vector<std::int64_t> seen;
  bus.Subscribe<rover_msgs::pose_t>(rover::channels::kPose, [&](const rover_msgs::pose_t& m) {
    seen.push_back(m.utime);
    bus.clock().Observe(m.utime, rover::bus::RoverClock::WallClock::now());
  });
  rover_msgs::pose_t pose{};
  pose.orientation[0] = 1;
  for (std::int64_t t : {kBase + 10'000, kBase + 1'000'000'000'000, std::int64_t{1}, kBase + 20'000}) {
    pose.utime = t;
    bus.Publish(rover::channels::kPose, pose);
  }
  while (bus.Handle(0)) {
  }
  EXPECT_EQ(seen, (std::vector<std::int64_t>{kBase + 10'000, kBase + 20'000}));
  EXPECT_EQ(bus.dropped(), 2);
  EXPECT_EQ(bus.clock().now(), kBase + 20'000);
}

TEST(RoverClock, APoisonedFirstAnchorIsForgottenWhenEverythingElseIsOlder) {
  rover::bus::TimeWindow w;
  w.resync_count = 5;
  w.resync_wall_s = 1.0;
  rover::bus::RoverClock clock(w);
  auto wall = rover::bus::RoverClock::WallClock::now();
  clock.ObserveClock(1'000'000'000'000'000, 1.0, wall);  // heard first, and a lie
  int rejected = 0;
  for (int i = 0; i < 20; ++i) {
    wall += std::chrono::milliseconds(100);
    if (!clock.Judge(1'000'000 + i * 100'000, wall).empty()) ++rejected;
  }
  EXPECT_GE(rejected, 5);
  EXPECT_LT(rejected, 20);
  EXPECT_FALSE(clock.anchored() && clock.now() > 1'000'000'000'000);
}

// Real time at 50x: a process starved for 10 s took one clock message late, and the
// messages between were lost (its socket overflowed). The next one, on time, is then 500 s
// ahead of the extrapolated clock and refused; the one after it confirms it (the source's
// next count, consistent with it), so the clock catches up instead of staying wedged behind
// for good. A forged future clock standing alone is still never taken.
TEST(RoverClock, ARealClockTakenLateCatchesUpAtTheSourcesNextMessage) {
  using namespace std::chrono_literals;
  rover::bus::RoverClock clock;
  const auto sent0 = rover::bus::RoverClock::WallClock::now();
  constexpr double kRate = 50;
  constexpr std::int64_t kBase = 1'000'000'000;
  // Rover time of a message the source sent `s` wall seconds after the first.
  auto utime_at = [&](double s) { return kBase + static_cast<std::int64_t>(s * kRate * 1e6); };
  ASSERT_EQ(clock.AcceptClock(kBase, 0, kRate, false, sent0 + 10s), "");
  const auto taken = [&](double s) { return sent0 + std::chrono::duration_cast<std::chrono::nanoseconds>(
                                                        std::chrono::duration<double>(s)); };
  const std::string refused = clock.AcceptClock(utime_at(10.0), 100, kRate, false, taken(10.0));
  EXPECT_NE(refused.find("ahead of the rover clock"), std::string::npos) << refused;
  EXPECT_NE(refused.find("unless the next clock message confirms it"), std::string::npos) << refused;
  EXPECT_EQ(clock.AcceptClock(utime_at(10.1), 101, kRate, false, taken(10.1)), "");
  EXPECT_EQ(clock.clock_utime(), utime_at(10.1));
  EXPECT_EQ(clock.Judge(utime_at(10.15), taken(10.15)), "") << "a message of the present is taken again";
  EXPECT_EQ(clock.AcceptClock(utime_at(10.2), 102, kRate, false, taken(10.2)), "");

  // Forged: 600 s ahead, counts far from the source's, one at a time.
  for (std::int64_t forged_count : {1000, 2000, 3000}) {
    EXPECT_NE(clock.AcceptClock(utime_at(10.2) + 600'000'000, forged_count, kRate, false, taken(10.25)), "");
  }
  EXPECT_EQ(clock.AcceptClock(utime_at(10.3), 103, kRate, false, taken(10.3)), "");
  EXPECT_EQ(clock.clock_utime(), utime_at(10.3));
  // A forgery with the source's next count is not confirmed by the source's message after
  // it, which it does not fit (that one is taken on its own, within the window).
  EXPECT_NE(clock.AcceptClock(utime_at(10.4) + 600'000'000, 103, kRate, false, taken(10.35)), "");
  EXPECT_EQ(clock.AcceptClock(utime_at(10.4), 104, kRate, false, taken(10.4)), "");
  EXPECT_EQ(clock.clock_utime(), utime_at(10.4));
}

TEST(Bus, CommandsNeedAValidTagWhenAKeyIsRequired) {
  // A stand-in MAC (the real one is HMAC-SHA256 in common/auth): the sum of the bytes.
  auto mac = [](const std::vector<std::uint8_t>& bytes) {
    std::uint32_t sum = 0;
    for (auto b : bytes) sum = sum * 31 + b;
    return std::vector<std::uint8_t>{std::uint8_t(sum), std::uint8_t(sum >> 8), std::uint8_t(sum >> 16),
                                     std::uint8_t(sum >> 24)};
  };
  std::int64_t last = 0;
  Bus::Auth auth;
  auth.required = true;
  std::int64_t counter = 0;
  auth.next = [&](std::string* sender, std::int64_t* c) { *sender = "tester"; *c = ++counter; };
  auth.tag = mac;
  auth.verify = [&](const std::string&, std::int64_t c, const std::vector<std::uint8_t>& bytes,
                    const std::vector<std::uint8_t>& tag) -> std::string {
    if (tag != mac(bytes)) return "wrong tag";
    if (c <= last) return "replayed counter";
    last = c;
    return "";
  };
  Bus bus("memq://");
  bus.set_auth(auth);
  std::vector<std::string> reasons;
  bus.Subscribe<rover_msgs::sequence_control_t>(
      rover::channels::kSequenceControl,
      [&](const rover_msgs::sequence_control_t& m) { reasons.push_back(m.reason); });
  rover_msgs::sequence_control_t ctl{};
  ctl.reason = "signed";
  bus.Publish(rover::channels::kSequenceControl, ctl);  // signed by the Bus
  ctl.reason = "unsigned";
  std::vector<std::uint8_t> bytes(ctl.getEncodedSize());
  ctl.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  bus.lcm().publish(rover::channels::kSequenceControl, bytes.data(), static_cast<unsigned>(bytes.size()));
  ctl.reason = "forged";
  ctl.auth.sender = "tester";
  ctl.auth.counter = 99;
  ctl.auth.tag = {1, 2, 3, 4};
  ctl.auth.tag_size = 4;
  bytes.resize(ctl.getEncodedSize());
  ctl.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  bus.lcm().publish(rover::channels::kSequenceControl, bytes.data(), static_cast<unsigned>(bytes.size()));
  while (bus.Handle(0)) {
  }
  EXPECT_EQ(reasons, (std::vector<std::string>{"signed"}));
  EXPECT_EQ(bus.dropped(), 2);
  EXPECT_NE(bus.last_drop().find("wrong tag"), std::string::npos) << bus.last_drop();
}

TEST(ParseNumberList, AcceptsAndRejects) {
  EXPECT_EQ(rover::bus::ParseNumberList("1,2.5,-3", 3, "--start"),
            (std::vector<double>{1, 2.5, -3}));
  EXPECT_THROW(rover::bus::ParseNumberList("1,2", 3, "--start"), rover::config::ConfigError);
  EXPECT_THROW(rover::bus::ParseNumberList("1,nan,2", 3, "--start"), rover::config::ConfigError);
  try {
    rover::bus::ParseNumberList("1,x,2", 3, "--start");
  } catch (const rover::config::ConfigError& e) {
    EXPECT_STREQ(e.what(), "--start: \"1,x,2\": expected 3 finite numbers separated by commas");
  }
}

// Virtual time's deferred delivery: whatever order an instant's messages arrive in, the
// callbacks see them sorted by channel, publisher and count once the batch is sealed.
TEST(Bus, DeferredDeliveryIsInTheSameOrderWhateverTheArrivalOrder) {
  auto run = [](const std::vector<std::string>& publishers) {
    Bus bus("memq://");
    bus.set_deferred(true, {rover::channels::kClock});
    std::vector<std::int64_t> seen;
    bus.Subscribe<rover_msgs::pose_t>(rover::channels::kPose,
                                      [&](const rover_msgs::pose_t& m) { seen.push_back(m.pub_seq >> 32); });  // the publisher
    rover_msgs::pose_t pose{};
    pose.orientation[0] = 1;
    for (const auto& name : publishers) {
      bus.set_publisher(name);
      bus.Publish(rover::channels::kPose, pose);
    }
    while (bus.Handle(0)) {
    }
    EXPECT_TRUE(seen.empty()) << "delivered before the batch was sealed";
    bus.SealBatch(100000);
    EXPECT_EQ(bus.DispatchBatch(), static_cast<int>(publishers.size()));
    return seen;
  };
  const auto a = run({"state_estimator", "rover_sim", "visual_odometry"});
  const auto b = run({"visual_odometry", "state_estimator", "rover_sim"});
  EXPECT_EQ(a.size(), 3u);
  EXPECT_EQ(a, b);
}

// A flood on one channel in virtual time is bounded per channel: the flood loses its own
// excess (dropped, counted, said), and the other channel's messages all arrive.
TEST(Bus, DeferredFloodOnOneChannelIsBoundedAndStarvesNoOther) {
  Bus bus("memq://");
  bus.set_deferred(true, {rover::channels::kClock});
  int beats = 0, poses = 0;
  bus.Subscribe<rover_msgs::heartbeat_t>(rover::channels::kHeartbeat,
                                         [&](const rover_msgs::heartbeat_t&) { ++beats; }, 30);
  bus.Subscribe<rover_msgs::pose_t>(rover::channels::kPose, [&](const rover_msgs::pose_t&) { ++poses; }, 30);
  rover_msgs::heartbeat_t hb{};
  hb.process = "flood";
  rover_msgs::pose_t pose{};
  pose.orientation[0] = 1;
  bus.set_publisher("flood");
  for (int i = 0; i < 2000; ++i) {
    hb.seq = i;
    bus.Publish(rover::channels::kHeartbeat, hb);
    if (i % 100 == 0) bus.Publish(rover::channels::kPose, pose);
    while (bus.Handle(0)) {
    }
  }
  EXPECT_LE(bus.held(), 256u + 20u);
  bus.SealBatch(100000);
  bus.DispatchBatch();
  EXPECT_EQ(poses, 20);
  EXPECT_EQ(beats, 256);  // max(8 x the queue capacity, 256)
  EXPECT_EQ(bus.dropped(), 2000 - 256);
  EXPECT_NE(bus.last_drop().find("HEARTBEAT: more than 256 messages"), std::string::npos) << bus.last_drop();
  // The next instant has its own allowance.
  hb.seq = 5000;
  bus.Publish(rover::channels::kHeartbeat, hb);
  while (bus.Handle(0)) {
  }
  bus.SealBatch(200000);
  bus.DispatchBatch();
  EXPECT_EQ(beats, 257);
}

// Virtual time: which batch a message is handed over in depends on when it was published,
// never on when it came. A POSE published after the cut (it overtook the clock) waits for
// the next batch; the batch waits for an IMU message below the cut that has not come.
TEST(Bus, TheClocksCutDecidesTheBatchNotTheArrival) {
  Bus bus("memq://");
  bus.set_deferred(true, {rover::channels::kClock});
  std::vector<std::string> delivered;
  bus.Subscribe<rover_msgs::imu_t>(rover::channels::kImu, [&](const rover_msgs::imu_t& m) {
    delivered.push_back("IMU " + std::to_string(m.pub_seq & 0xffffffff));
  });
  bus.Subscribe<rover_msgs::pose_t>(rover::channels::kPose, [&](const rover_msgs::pose_t& m) {
    delivered.push_back("POSE " + std::to_string(m.pub_seq & 0xffffffff));
  });
  auto send = [&](const std::string& publisher, const std::string& channel) {
    bus.set_publisher(publisher);
    if (channel == rover::channels::kImu) {
      rover_msgs::imu_t m{};
      m.orientation[0] = 1;
      bus.Publish(channel, m);
    } else {
      rover_msgs::pose_t m{};
      m.orientation[0] = 1;
      bus.Publish(channel, m);
    }
    while (bus.Handle(0)) {
    }
  };
  const auto sim = rover::bus::PublisherId("rover_sim");
  const auto est = rover::bus::PublisherId("state_estimator");
  send("rover_sim", rover::channels::kImu);         // IMU 0
  send("state_estimator", rover::channels::kPose);  // POSE 0
  send("state_estimator", rover::channels::kPose);  // POSE 1: published after the cut
  rover::simtime::Cut cut;
  cut.Set(rover::channels::kImu, sim, 2);  // IMU 1 was sent before the clock, not yet here
  cut.Set(rover::channels::kPose, est, 1);
  bus.ClockMoved(100, cut);
  EXPECT_TRUE(bus.seal_pending());
  EXPECT_FALSE(bus.SealWhenReady(false)) << "IMU 1 is below the cut and has not come";
  send("rover_sim", rover::channels::kImu);  // IMU 1
  EXPECT_TRUE(bus.SealWhenReady(false));
  EXPECT_FALSE(bus.seal_pending());
  bus.DispatchBatch();
  EXPECT_EQ(delivered, (std::vector<std::string>{"IMU 0", "IMU 1", "POSE 0"}));
  delivered.clear();
  rover::simtime::Cut next;
  next.Set(rover::channels::kImu, sim, 2);
  next.Set(rover::channels::kPose, est, 2);
  bus.ClockMoved(200, next);
  EXPECT_TRUE(bus.SealWhenReady(false));
  bus.DispatchBatch();
  EXPECT_EQ(delivered, (std::vector<std::string>{"POSE 1"})) << "the overtaking POSE, one batch later";
  // A message below the cut that never comes (lost on the way): forced, and named.
  delivered.clear();
  rover::simtime::Cut lost;
  lost.Set(rover::channels::kImu, sim, 5);
  bus.ClockMoved(300, lost);
  EXPECT_FALSE(bus.SealWhenReady(false));
  std::string missing;
  EXPECT_TRUE(bus.SealWhenReady(true, &missing));
  EXPECT_EQ(missing, "3 on IMU from publisher id " + std::to_string(sim));
}

// A member's first message on a channel, sent after the clock moved on and arriving before
// the batch is sealed, waits for the next batch, as its later ones do: the clock message
// says the cut is complete for its publisher. (Without it, a run's first MOBILITY_COMMAND
// was handed over in either of two instants, by arrival.)
TEST(Bus, AMembersFirstMessageOnAChannelWaitsForTheNextBatchWhenItOvertakesTheClock) {
  Bus bus("memq://");
  bus.set_deferred(true, {rover::channels::kClock});
  std::vector<std::string> delivered;
  bus.Subscribe<rover_msgs::pose_t>(rover::channels::kPose, [&](const rover_msgs::pose_t& m) {
    delivered.push_back("POSE " + std::to_string(m.pub_seq & 0xffffffff));
  });
  bus.set_publisher("state_estimator");
  rover_msgs::pose_t pose{};
  pose.orientation[0] = 1;
  bus.Publish(rover::channels::kPose, pose);  // POSE 0, published after the clock below
  while (bus.Handle(0)) {
  }
  rover::simtime::Cut cut;  // the estimator had published nothing when the clock moved on
  cut.SetComplete(rover::bus::PublisherId("state_estimator"));
  rover_msgs::rover_clock_t clock{};
  rover::bus::SetCut(cut, &clock);  // as rover_sim sends it, and a receiver reads it
  bus.ClockMoved(100, rover::bus::CutOf(clock));
  EXPECT_TRUE(bus.SealWhenReady(false));
  bus.DispatchBatch();
  EXPECT_TRUE(delivered.empty()) << "POSE 0 was published after this instant's cut";
  rover::simtime::Cut next;
  next.Set(rover::channels::kPose, rover::bus::PublisherId("state_estimator"), 1);
  next.SetComplete(rover::bus::PublisherId("state_estimator"));
  bus.ClockMoved(200, next);
  EXPECT_TRUE(bus.SealWhenReady(false));
  bus.DispatchBatch();
  EXPECT_EQ(delivered, (std::vector<std::string>{"POSE 0"}));
}

// A port another program holds without sharing it (CI met an outgoing socket on a test
// bus's port) is told apart from one LCM programs share: LCM binds with SO_REUSEADDR.
TEST(Bus, AHeldUdpPortIsToldApartFromAFreeOrSharedOne) {
  auto open_on = [](int port, bool share) {
    const int fd = socket(AF_INET, SOCK_DGRAM, 0);
    const int one = 1;
    if (share) setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(static_cast<std::uint16_t>(port));
    a.sin_addr.s_addr = htonl(INADDR_ANY);
    EXPECT_EQ(bind(fd, reinterpret_cast<const sockaddr*>(&a), sizeof a), 0) << "port " << port;
    return fd;
  };
  const int held = open_on(0, false);  // the kernel picks a free port, as for an outgoing socket
  sockaddr_in got{};
  socklen_t len = sizeof got;
  ASSERT_EQ(getsockname(held, reinterpret_cast<sockaddr*>(&got), &len), 0);
  const int port = ntohs(got.sin_port);
  EXPECT_FALSE(rover::bus::UdpPortReceivable(port));
  close(held);
  EXPECT_TRUE(rover::bus::UdpPortReceivable(port));
  const int shared = open_on(port, true);
  EXPECT_TRUE(rover::bus::UdpPortReceivable(port));
  close(shared);
}

// A udpm URL without recv_buf_size is said at start by a process that takes stereo pairs
// (or every channel), naming the URL and what to add; one that names it, another
// provider, or a process without image channels says nothing.
TEST(LcmUrl, NoReceiveBufferIsSaidByAProcessThatTakesImages) {
  const std::set<std::string> images = {"STEREO_FRAME", "POSE"};
  const std::set<std::string> hazcam = {"HAZCAM_FRAME"};
  const std::set<std::string> no_images = {"POSE", "IMU"};
  const std::string bare = "udpm://239.255.76.67:7667?ttl=1";
  const std::string w = rover::bus::SmallReceiveBufferWarning("visual_odometry", bare, images);
  EXPECT_EQ(w.rfind("visual_odometry: warning: the bus URL " + bare + " names no recv_buf_size", 0), 0u) << w;
  EXPECT_NE(w.find("expected &recv_buf_size=8388608"), std::string::npos) << w;
  EXPECT_EQ(w.find('\n'), std::string::npos) << "one line";
  EXPECT_FALSE(rover::bus::SmallReceiveBufferWarning("hazard_monitor", "udpm://239.255.76.67:7667", hazcam).empty());
  EXPECT_FALSE(rover::bus::SmallReceiveBufferWarning("rover_recorder", bare, {}, true).empty());
  EXPECT_TRUE(rover::bus::SmallReceiveBufferWarning("state_estimator", bare, no_images).empty());
  EXPECT_TRUE(rover::bus::SmallReceiveBufferWarning("visual_odometry", rover::bus::kDefaultLcmUrl, images).empty());
  EXPECT_TRUE(rover::bus::SmallReceiveBufferWarning("visual_odometry", "udpm://239.255.76.67:7667?recv_buf_size=4194304&ttl=1", images).empty());
  EXPECT_TRUE(rover::bus::SmallReceiveBufferWarning("visual_odometry", "memq://", images).empty());
}
