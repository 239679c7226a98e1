// The recorder's queue: a flood on one channel fills that channel's share only.
#include "recorder/event_queue.hpp"

#include <gtest/gtest.h>

#include <thread>

namespace rover::recorder {
namespace {

Event Message(const std::string& channel, std::size_t bytes) {
  return Event{0, channel, std::vector<std::uint8_t>(bytes, 0x5a)};
}

TEST(EventQueue, AFloodOnOneChannelCostsThatChannelOnly) {
  EventQueue q(/*max_bytes=*/1000, /*max_channel_bytes=*/300);
  int flood_kept = 0;
  for (int i = 0; i < 100; ++i) flood_kept += q.Push(Message("STEREO_FRAME", 100)) ? 1 : 0;
  EXPECT_EQ(flood_kept, 3);  // 300 bytes of 100-byte messages
  for (int i = 0; i < 5; ++i) EXPECT_TRUE(q.Push(Message("POSE", 50))) << i;
  EXPECT_EQ(q.dropped().at("STEREO_FRAME"), 97);
  EXPECT_EQ(q.dropped().count("POSE"), 0u);
  EXPECT_EQ(q.max_bytes(), 300u + 250u);
  // The writer takes one: the flood's share has room for one more, and no more.
  ASSERT_TRUE(q.Pop().has_value());
  EXPECT_TRUE(q.Push(Message("STEREO_FRAME", 100)));
  EXPECT_FALSE(q.Push(Message("STEREO_FRAME", 100)));
}

TEST(EventQueue, TheWholeQueueIsBoundedWhateverTheChannels) {
  EventQueue q(/*max_bytes=*/1000, /*max_channel_bytes=*/300);
  int kept = 0;
  for (int c = 0; c < 10; ++c) {
    for (int i = 0; i < 10; ++i) kept += q.Push(Message("CH" + std::to_string(c), 100)) ? 1 : 0;
  }
  EXPECT_EQ(kept, 10);  // 1000 bytes in all
  EXPECT_LE(q.max_bytes(), 1000u);
}

TEST(EventQueue, EventsComeOutInOrderAndCloseEndsTheWriter) {
  EventQueue q(1000, 1000);
  q.Push(Message("A", 1));
  q.Push(Message("B", 2));
  std::thread closer([&] { q.Close(); });
  closer.join();
  auto a = q.Pop();
  auto b = q.Pop();
  ASSERT_TRUE(a && b);
  EXPECT_EQ(a->channel, "A");
  EXPECT_EQ(b->channel, "B");
  EXPECT_FALSE(q.Pop().has_value());
}


TEST(EventQueue, ABatchIsTakenAsItsEventsOneByOneWouldBe) {
  EventQueue q(/*max_bytes=*/1000, /*max_channel_bytes=*/300);
  std::vector<Event> batch;
  for (int i = 0; i < 4; ++i) batch.push_back(Message("STEREO_FRAME", 100));
  batch.push_back(Message("POSE", 50));
  EXPECT_EQ(q.PushAll(std::move(batch)), 1u);  // the fourth frame is over its channel's share
  EXPECT_EQ(q.dropped().at("STEREO_FRAME"), 1);
  EXPECT_EQ(q.max_bytes(), 350u);
  // A writer waiting on an empty queue is woken by the batch and takes it in order.
  EventQueue w(1000, 1000);
  std::vector<std::string> taken;
  std::thread writer([&] {
    while (auto e = w.Pop()) taken.push_back(e->channel);
  });
  std::vector<Event> two;
  two.push_back(Message("A", 1));
  two.push_back(Message("B", 1));
  EXPECT_EQ(w.PushAll(std::move(two)), 0u);
  w.Close();
  writer.join();
  EXPECT_EQ(taken, (std::vector<std::string>{"A", "B"}));
}

}  // namespace
}  // namespace rover::recorder
