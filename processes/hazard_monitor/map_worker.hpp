// The traversability map on its own thread: dense stereo on a pair takes long enough (a few
// hundred ms of wall time on a busy computer, tens of seconds of rover time at 50x) that the
// monitor's bus loop must not wait for it, or its status and replies would stall and
// the messages queued behind it would be judged against a stale rover clock. Pairs are
// mapped in the order they came; the bus loop takes each finished grid (Take) and holds
// back a hazard query until every pair added before it is mapped (Added, Mapped), so a
// step is always judged on a map that includes every pair taken before it was asked
// about; pairs added later, or a flood of them, do not hold it back (at most kMaxQueued
// wait; older ones are dropped). Pairs come from the mast's NAVCAMs (STEREO_FRAME) and the
// front HAZCAMs (HAZCAM_FRAME), each matched with its camera's options, into one map.
#pragma once

#include "avoidance/grid.hpp"
#include "bus/channels.hpp"
#include "traversability/as_grid.hpp"
#include "traversability/traversability_map.hpp"

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <mutex>
#include <string>
#include <thread>

namespace rover {

class MapWorker {
 public:
  struct Job {
    cv::Mat left, right;  // 8-bit grey
    geometry::StereoRig rig;
    geometry::Pose T_site_rover;
    geometry::Matrix6d covariance;
    int64_t frame_id = -1;
    // The HAZCAM pair of the capture frame_id: matched with the HAZCAM's options. The
    // camera_capture publishes it before the frame's NAVCAM pair, so the map a NAVCAM pair
    // gives holds both: only the NAVCAM pair advances the map's last frame id, which the
    // executor waits for before it votes on the map of a capture.
    bool hazcam = false;
    const char* Channel() const { return hazcam ? channels::kHazcamFrame : channels::kStereoFrame; }
  };

  MapWorker(const traversability::MapOptions& options, const traversability::MapOptions& hazcam_options)
      : map_(options), hazcam_options_(hazcam_options), initial_(traversability::AsGrid(map_)), grid_(initial_) {
    traversability::CheckMapOptions(hazcam_options_);
    thread_ = std::thread([this] { Loop(); });
  }
  ~MapWorker() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    cv_.notify_all();
    thread_.join();
  }
  MapWorker(const MapWorker&) = delete;
  MapWorker& operator=(const MapWorker&) = delete;

  // Queues a pair. When more than kMaxQueued wait (pairs come faster than they are
  // mapped: a flood, or a starved machine), the oldest waiting one is dropped, so the
  // queue, and the wait of a query held for it, stay bounded.
  // 4: two captures' worth, each a HAZCAM pair and its NAVCAM pair.
  static constexpr std::size_t kMaxQueued = 4;
  void Add(Job job) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      ++added_;
      if (jobs_.size() >= kMaxQueued) {
        notes_ += std::string("hazard_monitor: ") + jobs_.front().Channel() + " " + std::to_string(jobs_.front().frame_id) +
                  " dropped: pairs come faster than they are mapped\n";
        jobs_.pop_front();
        ++done_;
      }
      jobs_.push_back(std::move(job));
    }
    cv_.notify_all();
  }
  // How many pairs have been added: a query asked now waits for these (Mapped).
  std::uint64_t Added() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return added_;
  }
  // Pairs mapped, refused, dropped or cleared (Done() == Added(): the worker is idle).
  std::uint64_t Done() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return done_;
  }
  // Whether the first `added` pairs are mapped (or dropped) and the grid holding them
  // has been taken. Pairs added later do not hold the answer back.
  bool Mapped(std::uint64_t added) const {
    std::lock_guard<std::mutex> lock(mutex_);
    return done_ >= added && !fresh_;
  }
  // The newest grid when one was finished since the last call; `notes` gets one line per
  // mapped or refused pair.
  bool Take(avoidance::Grid* grid, int64_t* last_frame_id, std::string* notes) {
    std::lock_guard<std::mutex> lock(mutex_);
    *notes = std::move(notes_);
    notes_.clear();
    if (!fresh_) return false;
    fresh_ = false;
    *grid = grid_;
    *last_frame_id = last_frame_id_;
    return true;
  }
  // The grid before any pair (every cell unknown).
  avoidance::Grid Initial() const { return initial_; }
  // The NAVCAM map's options (fixed at construction, so safe to read beside the worker).
  const traversability::MapOptions& options() const { return map_.options(); }
  // Forgets every pair: queued ones, the one being mapped, and the map. For when the poses
  // the pairs were placed with can no longer be trusted against the new ones (the pose
  // source restarted, a new site frame). The next Take gives the empty grid.
  void Clear() {
    std::lock_guard<std::mutex> lock(mutex_);
    done_ += jobs_.size();
    jobs_.clear();
    ++generation_;
    grid_ = initial_;
    fresh_ = true;
  }

 private:
  void Loop() {
    for (;;) {
      Job job;
      std::uint64_t generation = 0;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        cv_.wait(lock, [this] { return stop_ || !jobs_.empty(); });
        if (stop_) return;
        job = std::move(jobs_.front());
        jobs_.pop_front();
        generation = generation_;
      }
      std::string note;
      bool ok = true;
      try {
        if (generation != mapped_generation_) {
          map_.Clear();
          mapped_generation_ = generation;
        }
        map_.Recentre(job.T_site_rover.translation().x(), job.T_site_rover.translation().y());
        map_.AddStereoPair(job.left, job.right, job.rig, job.T_site_rover, job.covariance,
                           job.hazcam ? &hazcam_options_ : nullptr);
        const auto& st = map_.last_update();
        note = std::string("hazard_monitor: mapped ") + (job.hazcam ? "HAZCAM " : "") + "frame " +
               std::to_string(job.frame_id) + ": " + std::to_string(st.points) +
               " points, " + std::to_string(static_cast<int>(1000 * (st.seconds_rectify + st.seconds_match +
                                                                      st.seconds_grid))) +
               " ms\n";
      } catch (const std::exception& e) {
        ok = false;
        note = std::string("hazard_monitor: ") + job.Channel() + " " + std::to_string(job.frame_id) + ": " + e.what() +
               " (not mapped)\n";
      }
      avoidance::Grid grid = ok ? traversability::AsGrid(map_) : avoidance::Grid{};
      std::lock_guard<std::mutex> lock(mutex_);
      ++done_;
      notes_ += note;
      if (generation != generation_) {
        notes_ += "hazard_monitor: frame " + std::to_string(job.frame_id) + " dropped: the map was cleared meanwhile\n";
      } else if (ok) {
        grid_ = std::move(grid);
        if (!job.hazcam) last_frame_id_ = std::max(last_frame_id_, job.frame_id);
        fresh_ = true;
      }
    }
  }

  traversability::TraversabilityMap map_;  // the worker thread's alone (after construction)
  const traversability::MapOptions hazcam_options_;
  std::uint64_t mapped_generation_ = 0;     // the worker thread's: the generation map_ holds
  const avoidance::Grid initial_;
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<Job> jobs_;
  bool fresh_ = false, stop_ = false;
  std::uint64_t generation_ = 0;  // Clear() counts up
  std::uint64_t added_ = 0, done_ = 0;  // pairs added; pairs mapped, dropped or cleared
  avoidance::Grid grid_;
  int64_t last_frame_id_ = -1;
  std::string notes_;
  std::thread thread_;
};

}  // namespace rover
