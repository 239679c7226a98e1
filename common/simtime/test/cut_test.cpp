// The cut a virtual clock message carries: which messages belong to the instant it starts.
#include "simtime/cut.hpp"

#include <gtest/gtest.h>

namespace rover::simtime {
namespace {

TEST(Cut, AMessageAtOrAboveTheCutWasPublishedAfterIt) {
  Cut cut;
  cut.Set("POSE", 7u, 3);  // counts 0, 1 and 2 were published before the clock moved on
  EXPECT_FALSE(cut.After("POSE", 7u, 0));
  EXPECT_FALSE(cut.After("POSE", 7u, 2));
  EXPECT_TRUE(cut.After("POSE", 7u, 3));
  EXPECT_TRUE(cut.After("POSE", 7u, 40));
  EXPECT_FALSE(cut.After("POSE", 8u, 40));      // another publisher: the cut says nothing
  EXPECT_FALSE(cut.After("HEARTBEAT", 7u, 40));  // another channel: nothing
  cut.Set("POSE", 7u, 0);                        // nothing published: no constraint
  EXPECT_TRUE(cut.empty());
  EXPECT_FALSE(cut.After("POSE", 7u, 0));
}

// A member's first message on a channel, published after the clock moved on, belongs to
// the next batch like any other: the first MOBILITY_COMMAND of a run went into whichever
// batch was open when it arrived before the cut was complete for its publisher.
TEST(Cut, AMembersFirstMessageOnAChannelTheCutDoesNotNameIsAfterIt) {
  Cut cut;
  cut.Set("HAZARD_QUERY", 7u, 1);
  EXPECT_FALSE(cut.After("MOBILITY_COMMAND", 7u, 0));  // not known complete: unconstrained
  cut.SetComplete(7u);
  EXPECT_FALSE(cut.empty());
  EXPECT_TRUE(cut.After("MOBILITY_COMMAND", 7u, 0));  // it had published nothing there
  EXPECT_FALSE(cut.After("HAZARD_QUERY", 7u, 0));     // below the count it reported
  EXPECT_TRUE(cut.After("HAZARD_QUERY", 7u, 1));
  EXPECT_FALSE(cut.After("MOBILITY_COMMAND", 8u, 0));  // not a member: unconstrained
}

TEST(Cut, IsReachedWhenEveryMessageBelowItOnAChannelTakenHasCome) {
  Cut cut;
  cut.Set("IMU", 1u, 10);
  cut.Set("SIM_TRUTH", 1u, 5);
  std::int64_t imu = 9, truth = 5;
  const auto received = [&](std::uint32_t channel, std::uint32_t) -> std::int64_t {
    if (channel == ChannelIdOf("IMU")) return imu;
    return truth;
  };
  EXPECT_FALSE(cut.Reached(received));  // the tenth IMU message is still on its way
  imu = 10;
  EXPECT_TRUE(cut.Reached(received));
  imu = 12;  // more than the cut (published after it, overtook the clock): reached too
  EXPECT_TRUE(cut.Reached(received));
  truth = 2;
  const auto not_taken = [&](std::uint32_t channel, std::uint32_t) -> std::int64_t {
    return channel == ChannelIdOf("IMU") ? imu : -1;  // this receiver does not take SIM_TRUTH
  };
  EXPECT_TRUE(cut.Reached(not_taken));
  EXPECT_FALSE(cut.Reached(received));
}

TEST(Cut, ChannelIdsAreFnv1aOfTheName) {
  EXPECT_EQ(ChannelIdOf(""), 2166136261u);
  EXPECT_EQ(ChannelIdOf("a"), 0xe40c292cu);  // the published FNV-1a 32-bit test vector
  EXPECT_NE(ChannelIdOf("POSE"), ChannelIdOf("IMU"));
}

}  // namespace
}  // namespace rover::simtime
