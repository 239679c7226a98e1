#include "simtime/cut.hpp"

#include "simtime/barrier.hpp"


namespace rover::simtime {

std::uint32_t ChannelIdOf(const std::string& channel) { return PublisherIdOf(channel); }

void Cut::Set(std::uint32_t channel_id, std::uint32_t publisher, std::int64_t count) {
  if (count <= 0) {
    counts_.erase({channel_id, publisher});
    return;
  }
  counts_[{channel_id, publisher}] = count;
}

bool Cut::After(std::uint32_t channel_id, std::uint32_t publisher, std::int64_t count) const {
  const auto it = counts_.find({channel_id, publisher});
  if (it == counts_.end()) return complete_.count(publisher) > 0;
  return count >= it->second;
}

bool Cut::Reached(const std::function<std::int64_t(std::uint32_t, std::uint32_t)>& received) const {
  for (const auto& [key, count] : counts_) {
    const std::int64_t got = received(key.first, key.second);
    if (got >= 0 && got < count) return false;
  }
  return true;
}

}  // namespace rover::simtime
