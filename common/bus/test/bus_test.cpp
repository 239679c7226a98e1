#include "bus/bus.hpp"
#include "bus/channels.hpp"
#include "bus/process.hpp"

#include <gtest/gtest.h>
#include <rover_msgs/heartbeat_t.hpp>
#include <rover_msgs/pose_t.hpp>

#include <stdexcept>

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

TEST(Bus, CallbackErrorIsRaisedInTheLoop) {
  Bus bus("memq://");
  bus.Subscribe<rover_msgs::heartbeat_t>(
      rover::channels::kHeartbeat,
      [](const rover_msgs::heartbeat_t&) { throw std::runtime_error("boom"); });
  rover_msgs::heartbeat_t hb{};
  bus.Publish(rover::channels::kHeartbeat, hb);
  EXPECT_THROW(bus.Handle(0), std::runtime_error);
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
