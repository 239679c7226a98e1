// The cut a virtual clock message carries (README, "Simulated time").
//
// When the clock moves from instant t to t+1 it says, per channel and publisher, how many
// messages had been published by then: everything the members reported at the end of t,
// and the time source's own messages for t+1 sent just before the clock. A receiver hands
// its callbacks, in the batch of t+1, exactly the messages below the cut:
//   - a message at or above it was published during t+1 by a process that heard the clock
//     first, and overtook the clock on its way here (two CPUs deliver in either order): it
//     waits for the next batch, where it arrives when it does not overtake;
//   - a message below it that has not come yet (the time source's, delivered late by the
//     kernel) is waited for before the batch is handed over.
// The cut names every channel a member of the barrier had published on (its publisher is
// *complete*): a member's first message on a new channel is after the cut too. Without
// that, the first MOBILITY_COMMAND of a run went into whichever batch was open when it
// arrived, and two runs of one campaign variant differed by an instant (SIMTIME_LOG.md).
// A publisher that is not a member (a tool on the bus) is not constrained.
// So which batch a message is handed over in depends on when it was published, never on
// when it arrived. No LCM here: the clock message is converted in common/bus.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <set>
#include <string>
#include <utility>

namespace rover::simtime {

// The id a cut names a channel by: FNV-1a of its name, as publishers are named.
std::uint32_t ChannelIdOf(const std::string& channel);

class Cut {
 public:
  // Sets the count published on `channel_id` by `publisher` (0 leaves it unconstrained).
  void Set(std::uint32_t channel_id, std::uint32_t publisher, std::int64_t count);
  void Set(const std::string& channel, std::uint32_t publisher, std::int64_t count) {
    Set(ChannelIdOf(channel), publisher, count);
  }
  // Says that the cut names every channel `publisher` had published on: on any other, it
  // had published nothing.
  void SetComplete(std::uint32_t publisher) { complete_.insert(publisher); }
  // Whether the message (channel, publisher, count) was published after the cut: its
  // count is at or above the cut's for its channel and publisher, or the cut is complete
  // for the publisher and does not name the channel.
  bool After(std::uint32_t channel_id, std::uint32_t publisher, std::int64_t count) const;
  bool After(const std::string& channel, std::uint32_t publisher, std::int64_t count) const {
    return After(ChannelIdOf(channel), publisher, count);
  }
  // Whether everything below the cut on the channels `wanted` takes has been received:
  // `received(channel_id, publisher)` gives how many came (the highest count seen + 1), or
  // -1 for a channel this receiver does not take.
  bool Reached(const std::function<std::int64_t(std::uint32_t, std::uint32_t)>& received) const;

  bool empty() const { return counts_.empty() && complete_.empty(); }
  // (channel id, publisher) -> count, in a fixed order (the clock message lists them so).
  const std::map<std::pair<std::uint32_t, std::uint32_t>, std::int64_t>& counts() const { return counts_; }
  const std::set<std::uint32_t>& complete() const { return complete_; }

 private:
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::int64_t> counts_;
  std::set<std::uint32_t> complete_;
};

}  // namespace rover::simtime
