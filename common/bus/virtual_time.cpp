#include "bus/virtual_time.hpp"

#include <stdexcept>

namespace rover::bus {

std::string SyncUrl(const std::string& bus_url) {
  const std::string scheme = "udpm://";
  if (bus_url.rfind(scheme, 0) != 0) return bus_url;
  const std::size_t end = bus_url.find('?', scheme.size());
  const std::string address = bus_url.substr(scheme.size(), end == std::string::npos ? std::string::npos : end - scheme.size());
  const std::size_t colon = address.rfind(':');
  int port = 7667;  // LCM's default
  std::string host = address;
  if (colon != std::string::npos) {
    host = address.substr(0, colon);
    try {
      port = std::stoi(address.substr(colon + 1));
    } catch (const std::exception&) {
      throw std::invalid_argument("LCM URL " + bus_url + ": the port is not a number");
    }
  }
  return scheme + host + ":" + std::to_string(port + 1) + (end == std::string::npos ? "" : bus_url.substr(end));
}

rover_msgs::sim_sync_t ToMsg(const simtime::SyncReport& r, std::int64_t seq) {
  rover_msgs::sim_sync_t m{};
  m.utime = r.utime;
  m.process = r.process;
  m.seq = seq;
  m.busy = r.busy ? 1 : 0;
  m.quiet_until = r.quiet_until;
  m.subscribes_all = r.subscribes_all ? 1 : 0;
  m.subscribed.assign(r.subscribed.begin(), r.subscribed.end());
  m.num_subscribed = static_cast<std::int32_t>(m.subscribed.size());
  for (const auto& [channel, count] : r.published) {
    m.published_channel.push_back(channel);
    m.published_count.push_back(count);
  }
  m.num_published = static_cast<std::int32_t>(m.published_channel.size());
  for (const auto& [channel, by_publisher] : r.received) {
    for (const auto& [publisher, count] : by_publisher) {
      m.received_channel.push_back(channel);
      m.received_publisher.push_back(publisher);
      m.received_count.push_back(count);
    }
  }
  m.num_received = static_cast<std::int32_t>(m.received_channel.size());
  return m;
}

simtime::SyncReport FromMsg(const rover_msgs::sim_sync_t& m) {
  simtime::SyncReport r;
  r.utime = m.utime;
  r.process = m.process;
  r.busy = m.busy != 0;
  r.quiet_until = m.quiet_until;
  r.subscribes_all = m.subscribes_all != 0;
  r.subscribed.insert(m.subscribed.begin(), m.subscribed.end());
  for (std::size_t i = 0; i < m.published_channel.size() && i < m.published_count.size(); ++i)
    r.published[m.published_channel[i]] = m.published_count[i];
  for (std::size_t i = 0; i < m.received_channel.size(); ++i) {
    if (i >= m.received_publisher.size() || i >= m.received_count.size()) break;
    r.received[m.received_channel[i]][static_cast<std::uint32_t>(m.received_publisher[i])] = m.received_count[i];
  }
  return r;
}

void SyncSender::Send(const simtime::SyncReport& report) {
  if (!lcm_) {
    lcm_ = std::make_unique<lcm::LCM>(url_);
    if (!lcm_->good()) throw std::runtime_error("cannot open the sync bus at " + url_);
  }
  const auto msg = ToMsg(report, seq_++);
  if (lcm_->publish(kSimSyncChannel, &msg) != 0) throw std::runtime_error("LCM publish failed on " + url_);
}

void SetCut(const simtime::Cut& cut, rover_msgs::rover_clock_t* m) {
  m->n_cut = static_cast<std::int32_t>(cut.counts().size());
  m->cut_channel.clear();
  m->cut_publisher.clear();
  m->cut_count.clear();
  for (const auto& [key, count] : cut.counts()) {
    m->cut_channel.push_back(static_cast<std::int32_t>(key.first));
    m->cut_publisher.push_back(static_cast<std::int32_t>(key.second));
    m->cut_count.push_back(count);
  }
  m->cut_complete.assign(cut.complete().begin(), cut.complete().end());
  m->n_complete = static_cast<std::int32_t>(m->cut_complete.size());
}

simtime::Cut CutOf(const rover_msgs::rover_clock_t& m) {
  simtime::Cut cut;
  for (std::size_t i = 0; i < static_cast<std::size_t>(m.n_cut) && i < m.cut_count.size(); ++i) {
    cut.Set(static_cast<std::uint32_t>(m.cut_channel[i]), static_cast<std::uint32_t>(m.cut_publisher[i]),
            m.cut_count[i]);
  }
  for (std::size_t i = 0; i < static_cast<std::size_t>(m.n_complete) && i < m.cut_complete.size(); ++i) {
    cut.SetComplete(static_cast<std::uint32_t>(m.cut_complete[i]));
  }
  return cut;
}

}  // namespace rover::bus
