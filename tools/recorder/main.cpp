// rover_recorder [--lcm-url URL] OUTPUT.lcm: records every channel to a standard LCM log.
//
// Why not lcm-logger: LCM 1.3.1 drops a message for a subscription whose queue already
// holds `queue capacity` undispatched messages (30 by default), and lcm-logger cannot set
// that capacity from its command line. At the default 50x sim rate the bus carries a few
// thousand messages a second, so a logger whose dispatch thread loses the CPU for ~10 ms on
// a busy 2-core machine loses messages, with the kernel's receive errors at 0.
// This recorder reads the bus's socket itself (bus/udpm_receiver.hpp: LCM's own receiver
// would wake two threads for each datagram), does nothing on that thread but copy each
// message into its own deep queue, writes from a second thread with
// lcm::LogFile (the standard format: lcm-logplayer and every LCM tool read it), and checks
// every message's publisher count as it goes, so it reports any loss it could not prevent.
//
// It publishes a heartbeat (process "rover_recorder") once a wall second, like the rover's
// processes: `dropped` counts messages it had to drop, the detail says what it wrote and lost.
//
// In virtual time ($ROVER_TIME=virtual: README, "Simulated time") it is a member of the
// simulated set: it sends a sync report after what it received, so the clock waits until
// every message of an instant has reached the log, and it writes each instant's messages in
// one canonical order (channel, publisher, count), stamped with the instant's rover time,
// and beats once a rover second. The same run then gives the same log, byte for byte,
// however busy the machine was.
// SIGINT or SIGTERM stops it: it dispatches what LCM already holds, writes everything queued,
// flushes, prints counts per channel and exits 0 (1 if the log could not be written).
#include "bus/bus.hpp"
#include "bus/channels.hpp"
#include "bus/lcm_url_check.hpp"
#include "bus/udpm_receiver.hpp"
#include "bus/virtual_time.hpp"
#include "simtime/cut.hpp"
#include "logcheck/log_check.hpp"
#include "recorder/event_queue.hpp"

#include <lcm/lcm-cpp.hpp>
#include <rover_msgs/heartbeat_t.hpp>
#include <rover_msgs/rover_clock_t.hpp>

#include <atomic>
#include <chrono>
#include <cerrno>
#include <cstring>
#include <condition_variable>
#include <csignal>
#include <cstdlib>
#include <deque>
#include <iostream>
#include <mutex>
#include <optional>
#include <sstream>
#include <string>
#include <poll.h>
#include <sys/stat.h>
#include <thread>
#include <tuple>
#include <vector>
#include <algorithm>
#include <map>
#include <memory>

namespace {

using rover::recorder::Event;
using rover::recorder::EventQueue;
using rover::recorder::kMaxChannelBytes;
using rover::recorder::kMaxQueuedBytes;

constexpr int kReportsPerSecond = 20;              // loss lines on stderr, then a count

std::atomic<bool> g_stop{false};
const std::uint32_t kClockSource = rover::bus::PublisherId("rover_sim");
void OnSignal(int) { g_stop = true; }

// The receive thread: copies each message into the queue and nothing else (in virtual
// time: into the instant's batch, written sorted when the clock moves on).
class Receiver {
 public:
  Receiver(lcm::LCM& lcm, EventQueue& queue, bool virtual_time, const std::string& url)
      : lcm_(lcm), queue_(queue), virtual_(virtual_time) {
    if (virtual_) sync_ = std::make_unique<rover::bus::SyncSender>(url);
  }
  void OnMessage(const std::string& channel, const std::uint8_t* p, std::size_t size, std::int64_t recv_utime) {
    Event e{recv_utime, channel, std::vector<std::uint8_t>(p, p + size)};
    if (!virtual_) {
      if (!queue_.Push(std::move(e))) ++dropped_;
      return;
    }
    // LCM's own probe, sent whenever a process opens the bus: when is up to the scheduler.
    if (channel == "LCM_SELF_TEST") return;
    // The instant's batch is bounded per channel as the queue is (a flood cannot make it
    // grow without end while the clock waits); a message dropped here is counted.
    std::size_t& held_bytes = held_bytes_[channel];
    if (held_bytes + e.data.size() > kMaxChannelBytes) {
      ++dropped_;
      return;
    }
    held_bytes += e.data.size();
    Held h{{channel, 0u, 0, arrivals_++}, std::move(e)};
    channel_ids_.emplace(rover::simtime::ChannelIdOf(channel), channel);
    if (const auto* type = rover::logcheck::FindChannel(channel)) {
      const auto read = rover::logcheck::ReadStamp(*type, h.event.data.data(), h.event.data.size());
      if (read.stamp) {
        auto& seen = received_[channel][read.stamp->publisher_id];
        seen = std::max(seen, read.stamp->count + 1);
        h.key = {channel, read.stamp->publisher_id, read.stamp->count, 0};
        if (channel == rover::channels::kClock && read.stamp->publisher_id == kClockSource &&
            read.stamp->utime > std::max(instant_, pending_ ? pending_->next : 0)) {
          // A new instant: what came before it is written once all of it has come.
          if (pending_) Flush(true);
          rover_msgs::rover_clock_t clock;
          rover::simtime::Cut cut;
          if (clock.decode(h.event.data.data(), 0, static_cast<int>(h.event.data.size())) >= 0) {
            cut = rover::bus::CutOf(clock);
          }
          pending_ = Pending{read.stamp->utime, std::move(cut), std::chrono::steady_clock::now(), std::move(h)};
          Flush(false);
          return;
        }
      }
    }
    // A heartbeat stamped after this instant overtook the clock message of its own (it
    // can on a multi-core computer): it waits for its instant (Bus::SealBatch says why).
    if (channel == rover::channels::kHeartbeat && instant_ > 0) {
      rover_msgs::heartbeat_t hb;
      if (hb.decode(h.event.data.data(), 0, static_cast<int>(h.event.data.size())) >= 0 && hb.utime > instant_) {
        later_.emplace_back(hb.utime, std::move(h));
        return;
      }
    }
    held_.push_back(std::move(h));
    if (pending_) Flush(false);
  }
  // Virtual time, on the receive thread after each burst: the sync report when an instant
  // has been written, and at least every 0.25 s of wall time (alive). What arrives
  // meanwhile is not reported: the barrier does not wait for it to be counted, as the
  // recorder writes each instant by its clock's cut (simtime/barrier.hpp).
  void AfterBurst() {
    if (!virtual_) return;
    const auto now = std::chrono::steady_clock::now();
    // A message below the cut that has not come a wall second after its clock was lost on
    // the way: the instant is written without it.
    if (pending_ && now - pending_->since > std::chrono::seconds(1)) Flush(true);
    if (!changed_ && now - last_sync_ < std::chrono::milliseconds(250)) return;
    rover::simtime::SyncReport r;
    r.process = "rover_recorder";
    r.utime = instant_ > 0 ? instant_ : -1;
    r.subscribes_all = true;
    r.received = received_;
    if (heartbeats_ > 0) r.published[rover::channels::kHeartbeat] = heartbeats_;
    // It writes what comes: nothing of its own to do (virtual time's idle strides).
    r.quiet_until = std::int64_t{1} << 62;
    sync_->Send(r);
    changed_ = false;
    last_sync_ = now;
  }
  // Virtual time, at the end: the last instant was not finished (the clock stopped in
  // it), so what came of it may be partial: it is left out, and the log ends with the last
  // whole instant, the same in every run.
  void Finish() {
    if (virtual_ && pending_) Flush(false);  // the instant the last clock ended, if whole
    if (virtual_) held_.clear();
  }
  bool virtual_time() const { return virtual_; }
  // Virtual time: a clock message has come whose cut names messages not yet here.
  bool awaiting_cut() const { return pending_.has_value(); }
  std::int64_t dropped() const { return dropped_; }

 private:
  struct Held {
    std::tuple<std::string, std::uint32_t, std::int64_t, std::uint64_t> key;  // channel, publisher, count, arrival
    Event event;
  };
  // A clock message moved the clock on to `next`: the instant before it is written once
  // every message below the clock's cut has come (simtime/cut.hpp).
  struct Pending {
    std::int64_t next;
    rover::simtime::Cut cut;
    std::chrono::steady_clock::time_point since;
    Held clock;
  };
  void Flush(bool force) {
    const auto received = [this](std::uint32_t channel_id, std::uint32_t publisher) -> std::int64_t {
      const auto name = channel_ids_.find(channel_id);
      if (name == channel_ids_.end()) return 0;  // it takes every channel
      const auto channel = received_.find(name->second);
      if (channel == received_.end()) return 0;
      const auto count = channel->second.find(publisher);
      return count == channel->second.end() ? 0 : count->second;
    };
    if (!pending_->cut.Reached(received)) {
      if (!force) return;
      std::cerr << "rover_recorder: rover time " << instant_
                << ": written without messages the clock says were sent (lost on the way)\n";
    }
    Pending p = std::move(*pending_);
    pending_.reset();
    FlushInstant(p.next, p.cut);
    held_bytes_[p.clock.event.channel] += p.clock.event.data.size();
    held_.push_back(std::move(p.clock));
  }
  // Writes the held batch below `cut`, sorted, stamped with its instant, and moves to
  // `next`; what the cut says was sent after it (it overtook the clock) waits for `next`.
  // The first clock message writes nothing: what came before it (processes starting, not
  // yet held by the barrier) waits for the first instant's batch, so that which of those
  // messages beat the first clock message decides neither the log's order nor the count in
  // the first heartbeat (a demo campaign's digest differed between two runs so).
  void FlushInstant(std::int64_t next, const rover::simtime::Cut& cut) {
    const bool first = instant_ == 0;
    std::vector<Held> after;
    std::vector<Held> batch;
    for (auto& h : held_) {
      const auto& [channel, publisher, count, arrival] = h.key;
      if (first || cut.After(channel, publisher, count)) {
        after.push_back(std::move(h));
      } else {
        batch.push_back(std::move(h));
      }
    }
    // Counted by the instants written, not as they arrive: a heartbeat that overtook the
    // clock message of its own instant arrives early, and a count of arrivals in the
    // heartbeat's detail would then differ from run to run.
    received_total_ += static_cast<std::int64_t>(batch.size());
    std::sort(batch.begin(), batch.end(), [](const Held& a, const Held& b) { return a.key < b.key; });
    std::vector<Event> events;
    events.reserve(batch.size());
    for (auto& h : batch) {
      h.event.timestamp = instant_ > 0 ? instant_ : next;
      events.push_back(std::move(h.event));
    }
    dropped_ += static_cast<std::int64_t>(queue_.PushAll(std::move(events)));
    held_ = std::move(after);
    held_bytes_.clear();
    for (const auto& h : held_) held_bytes_[h.event.channel] += h.event.data.size();
    instant_ = next;
    changed_ = true;  // an instant written: worth a sync report
    std::erase_if(later_, [&](auto& entry) {
      if (entry.first > instant_) return false;
      held_bytes_[entry.second.event.channel] += entry.second.event.data.size();
      held_.push_back(std::move(entry.second));
      return true;
    });
    if (instant_ >= next_heartbeat_) {  // once a rover second, from what it has received
      rover_msgs::heartbeat_t hb{};
      hb.utime = instant_;
      hb.process = "rover_recorder";
      hb.seq = heartbeats_++;
      hb.state = dropped_ > 0 ? rover_msgs::heartbeat_t::STATE_DEGRADED : rover_msgs::heartbeat_t::STATE_OK;
      hb.detail = "received " + std::to_string(received_total_) + " messages, " + std::to_string(dropped_) + " dropped";
      hb.dropped = dropped_;
      lcm_.publish(rover::channels::kHeartbeat, &hb);
      next_heartbeat_ = instant_ + 1000000;
    }
  }

  lcm::LCM& lcm_;
  EventQueue& queue_;
  bool virtual_;
  std::atomic<std::int64_t> dropped_{0};
  std::unique_ptr<rover::bus::SyncSender> sync_;
  std::vector<Held> held_;
  std::map<std::string, std::size_t> held_bytes_;
  std::vector<std::pair<std::int64_t, Held>> later_;
  std::optional<Pending> pending_;
  std::map<std::uint32_t, std::string> channel_ids_;  // cut channel id -> channel
  std::map<std::string, std::map<std::uint32_t, std::int64_t>> received_;
  std::int64_t instant_ = 0, next_heartbeat_ = 0, heartbeats_ = 0, received_total_ = 0;
  std::uint64_t arrivals_ = 0;
  bool changed_ = true;
  std::chrono::steady_clock::time_point last_sync_{};
};

// The writer thread: writes each event, follows the publishers' counts, reports losses.
class Writer {
 public:
  Writer(const std::string& path, EventQueue& queue)
      : path_(path), log_(path, "w"), queue_(queue),
        tracker_(rover::logcheck::TrackerOptions{.from_start = true, .detect_joined = true}) {
    if (!log_.good()) throw std::runtime_error(path + ": cannot open for writing");
  }

  void Run() {
    while (auto e = queue_.Pop()) {
      lcm::LogEvent ev{};
      ev.timestamp = e->timestamp;
      ev.channel = e->channel;
      ev.datalen = static_cast<std::int32_t>(e->data.size());
      ev.data = e->data.data();
      if (!write_failed_ && (log_.writeEvent(&ev) != 0 || std::ferror(log_.getFilePtr()))) {
        FailWrite(std::strerror(errno));
      }
      if (!write_failed_) {
        ++written_;
        bytes_ += static_cast<std::int64_t>(e->data.size());
        // An event on disk: magic, event number, timestamp, channel and data lengths, both.
        file_bytes_ += 4 + 8 + 8 + 4 + static_cast<std::int64_t>(ev.channel.size()) + 4 + ev.datalen;
      } else {
        ++not_written_;
      }
      Check(*e);
    }
    // The C library buffers: a full disk may show only now, or only in the file's size.
    if (!write_failed_ && std::fflush(log_.getFilePtr()) != 0) FailWrite(std::strerror(errno));
    struct stat st {};
    if (!write_failed_ && ::stat(path_.c_str(), &st) == 0 && st.st_size < file_bytes_) {
      FailWrite("the file holds " + std::to_string(st.st_size) + " of the " + std::to_string(file_bytes_) +
                " bytes written");
    }
  }

  // Why the log is not whole, or empty when it is (for the closing report's verdict).
  std::string WriteProblem() const {
    if (!write_failed_) return "";
    return "writing the log failed (" + write_error_ + ")" +
           (not_written_ > 0 ? ": " + std::to_string(not_written_) + " messages not written" : "") +
           "; the log's end is missing";
  }

  // For the heartbeat (read from another thread).
  std::int64_t written() const { return written_; }
  std::int64_t lost() const { return lost_; }
  std::int64_t rover_utime() const { return rover_utime_; }
  bool write_failed() const { return write_failed_; }
  std::int64_t bytes() const { return bytes_; }
  // Only after Run() has returned.
  rover::logcheck::LogReport Report() const {
    return rover::logcheck::Summarize(path_, tracker_, consistency_, WriteProblem());
  }

 private:
  void FailWrite(const std::string& why) {
    write_failed_ = true;
    write_error_ = why;
    std::cerr << "rover_recorder: " << path_ << ": write failed (" << why << "); "
              << "messages from now on are not recorded\n";
  }

  void Check(const Event& e) {
    std::optional<rover::logcheck::Restart> restart;
    const auto gap = tracker_.ObserveAt(e.timestamp, e.channel, e.data.data(), e.data.size(), &restart);
    consistency_.Observe(e.channel, e.data.data(), e.data.size());
    if (e.channel == rover::channels::kClock && e.data.size() >= 16) {
      std::int64_t utime = 0;
      for (int i = 8; i < 16; ++i) utime = (utime << 8) | e.data[i];
      rover_utime_ = utime;
    }
    if (gap) {
      lost_ += gap->lost;
      Tell("lost " + std::to_string(gap->lost) + " on " + gap->channel + " from " +
             tracker_.PublisherName(gap->publisher) + " (count " +
             std::to_string(gap->count_before) + " then " + std::to_string(gap->count_after) +
             ") between utime " + std::to_string(gap->utime_before) + " and " +
             std::to_string(gap->utime_after));
    }
    if (restart) {
      Tell("restart: " + restart->channel + " from " + tracker_.PublisherName(restart->publisher) +
             " at utime " + std::to_string(restart->utime) + " (count " +
             std::to_string(restart->count_before) + " before)");
    }
  }

  // One line per loss, at most kReportsPerSecond a second; the rest are counted.
  void Tell(const std::string& line) {
    const auto now = std::chrono::steady_clock::now();
    if (now - window_start_ >= std::chrono::seconds(1)) {
      if (suppressed_ > 0) {
        std::cerr << "rover_recorder: " << suppressed_ << " more loss reports in the last second\n";
      }
      window_start_ = now;
      in_window_ = 0;
      suppressed_ = 0;
    }
    if (in_window_++ < kReportsPerSecond) {
      std::cerr << "rover_recorder: " << line << "\n";
    } else {
      ++suppressed_;
    }
  }

  std::string path_;
  lcm::LogFile log_;
  EventQueue& queue_;
  rover::logcheck::LossTracker tracker_;
  rover::logcheck::ConsistencyCheck consistency_;
  std::atomic<std::int64_t> written_{0}, lost_{0}, rover_utime_{0}, bytes_{0};
  std::atomic<bool> write_failed_{false};
  std::string write_error_;             // writer thread only (read after it ends)
  std::int64_t file_bytes_ = 0;         // what the file must hold
  std::int64_t not_written_ = 0;
  std::chrono::steady_clock::time_point window_start_ = std::chrono::steady_clock::now();
  int in_window_ = 0;
  std::int64_t suppressed_ = 0;
};

void PublishHeartbeat(lcm::LCM& lcm, std::int64_t seq, const Writer& writer,
                      const Receiver& receiver) {
  rover_msgs::heartbeat_t hb{};
  hb.utime = writer.rover_utime();
  hb.process = "rover_recorder";
  hb.seq = seq;
  const bool lossy = writer.lost() > 0 || receiver.dropped() > 0 || writer.write_failed();
  hb.state = writer.write_failed() ? rover_msgs::heartbeat_t::STATE_FAULT
             : lossy              ? rover_msgs::heartbeat_t::STATE_DEGRADED
                                  : rover_msgs::heartbeat_t::STATE_OK;
  hb.detail = "wrote " + std::to_string(writer.written()) + " messages, " +
              std::to_string(writer.lost()) + " lost upstream, " +
              std::to_string(receiver.dropped()) + " dropped" +
              (writer.write_failed() ? ", write failed" : "");
  hb.dropped = receiver.dropped();
  lcm.publish(rover::channels::kHeartbeat, &hb);
}

struct Args {
  std::string url;
  std::string output;
};

// Returns nullopt after printing help; throws std::invalid_argument on a bad argument.
std::optional<Args> ParseArgs(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      std::cout << "usage: rover_recorder [--lcm-url URL] OUTPUT.lcm\n\n"
                   "Records every LCM channel to OUTPUT.lcm in the standard LCM log format\n"
                   "(lcm-logplayer reads it) without the losses of lcm-logger 1.3.1: a deep\n"
                   "subscription queue, a receive thread that only copies, a writer thread.\n"
                   "Reports every lost message it detects from the publishers' counts\n"
                   "(pub_seq, heartbeat seq) on stderr, and counts per channel at exit.\n"
                   "Stops on SIGINT or SIGTERM after writing everything received.\n\n"
                   "  --lcm-url URL   the bus (default $ROVER_LCM_URL, else "
                << rover::bus::kDefaultLcmUrl << ")\n";
      return std::nullopt;
    } else if (arg == "--lcm-url") {
      if (i + 1 >= argc) throw std::invalid_argument("argument --lcm-url: missing URL");
      a.url = argv[++i];
    } else if (arg.rfind("--lcm-url=", 0) == 0) {
      a.url = arg.substr(10);
    } else if (a.output.empty() && arg.rfind("-", 0) != 0) {
      a.output = arg;
    } else {
      throw std::invalid_argument("argument " + arg + ": unexpected (expected [--lcm-url URL] OUTPUT.lcm)");
    }
  }
  if (a.output.empty()) throw std::invalid_argument("missing OUTPUT.lcm (expected [--lcm-url URL] OUTPUT.lcm)");
  struct stat st {};
  if (::stat(a.output.c_str(), &st) == 0 && !S_ISREG(st.st_mode)) {
    throw std::invalid_argument(a.output + ": exists and is not a regular file (expected a path for the log)");
  }
  if (a.url.empty()) {
    const char* env = std::getenv("ROVER_LCM_URL");
    a.url = env != nullptr && *env != '\0' ? env : rover::bus::kDefaultLcmUrl;
  }
  return a;
}

}  // namespace

int main(int argc, char** argv) {
  std::optional<Args> args;
  try {
    args = ParseArgs(argc, argv);
  } catch (const std::invalid_argument& e) {
    std::cerr << "rover_recorder: " << e.what() << "\n";
    return 2;
  }
  if (!args) return 0;
  try {
    if (const std::string problem = rover::bus::LcmUrlProblem(args->url); !problem.empty()) {
      std::cerr << "rover_recorder: argument --lcm-url: " << args->url << ": " << problem << " (expected "
                << rover::bus::kLcmUrlExpected << ")\n";
      return 2;
    }
    // LCM publishes the heartbeats and sync reports; the bus is read by this process's own
    // receiver (bus/udpm_receiver.hpp), which LCM's receive thread would double.
    lcm::LCM lcm(args->url);
    if (!lcm.good()) throw std::runtime_error("cannot open the LCM bus at " + args->url);
    rover::bus::UdpmReceiver socket(args->url, "LCM bus");
    if (const std::string w = rover::bus::SmallReceiveBufferWarning("rover_recorder", args->url, {}, true); !w.empty()) {
      std::cerr << w << "\n";
    }
    EventQueue queue;
    Writer writer(args->output, queue);
    const char* time_env = std::getenv("ROVER_TIME");
    const bool virtual_time = time_env != nullptr && std::string(time_env) == "virtual";
    Receiver receiver(lcm, queue, virtual_time, args->url);
    std::signal(SIGINT, OnSignal);
    std::signal(SIGTERM, OnSignal);

    const auto start = std::chrono::steady_clock::now();
    std::atomic<bool> receiving{true};
    const rover::bus::UdpmReceiver::Handler take = [&receiver](const std::string& channel, const std::uint8_t* data,
                                                               std::size_t size, std::int64_t recv_utime) {
      receiver.OnMessage(channel, data, size, recv_utime);
    };
    // Waits up to `ms` for the bus and takes every message waiting (a bounded burst).
    const auto take_burst = [&](int ms) {
      pollfd p{socket.fd(), POLLIN, 0};
      if (::poll(&p, 1, ms) <= 0) return 0;
      return socket.Drain(take);
    };
    std::thread receive_thread([&] {
      while (receiving) {
        take_burst(receiver.virtual_time() ? 50 : 100);
        // After each burst: a flood cannot hold back the sync report.
        receiver.AfterBurst();
      }
      // Stopping: take what the socket already holds (bounded, as a live bus never goes
      // quiet), and in virtual time what the last clock's cut says was sent before it: the
      // barrier did not wait for this recorder to count it (simtime/barrier.hpp).
      const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(2);
      while (std::chrono::steady_clock::now() < until) {
        if (take_burst(receiver.awaiting_cut() ? 20 : 0) <= 0 && !receiver.awaiting_cut()) break;
      }
      receiver.Finish();
    });
    std::thread write_thread([&] { writer.Run(); });
    std::cerr << "rover_recorder: recording " << args->url << " to " << args->output << "\n";

    std::int64_t seq = 0;
    auto next_heartbeat = std::chrono::steady_clock::now();
    while (!g_stop) {
      if (!virtual_time && std::chrono::steady_clock::now() >= next_heartbeat) {
        PublishHeartbeat(lcm, seq++, writer, receiver);
        next_heartbeat += std::chrono::seconds(1);
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    receiving = false;
    receive_thread.join();
    queue.Close();
    write_thread.join();

    const double wall_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const auto report = writer.Report();
    std::ostringstream os;
    os << "rover_recorder: wrote " << writer.written() << " messages ("
       << writer.bytes() / 1048576.0 << " MB) to " << args->output << " in " << wall_s
       << " s; lost upstream " << report.lost << ", dropped here " << receiver.dropped()
       << "; deepest queue " << queue.max_events() << " messages, "
       << queue.max_bytes() / 1048576.0 << " MB (bound " << kMaxQueuedBytes / 1048576 << " MB, "
       << kMaxChannelBytes / 1048576 << " MB a channel)\n";
    for (const auto& [channel, n] : queue.dropped()) {
      os << "rover_recorder: dropped " << n << " on " << channel
         << " (its share of the queue was full: a flood, or a disk slower than the bus)\n";
    }
    os << rover::logcheck::FormatReport(report);
    std::cerr << os.str();
    return writer.write_failed() ? 1 : 0;
  } catch (const std::exception& e) {
    std::cerr << "rover_recorder: error: " << e.what() << "\n";
    return 1;
  }
}
