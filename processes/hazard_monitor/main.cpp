// hazard_monitor: keep-out zones against the footprint plus the position uncertainty, and
// tilt limits (common/hazards); with `hazards.map.enabled` or `--map on`, the traversability
// map (common/traversability) built from every STEREO_FRAME (the mast's NAVCAMs) and HAZCAM_FRAME
// (the front HAZCAMs, with `hazards.map.hazcam`'s stereo options) at the pose the frame carries, which
// every step's swept footprint must also pass (common/hazards/map_check.hpp), published on
// TRAVERSABILITY_MAP after each pair and every kMapRefreshS (for a console that joins late,
// or a message lost). Publishes HAZARD_STATUS at a steady rate and answers the
// executor's HAZARD_QUERY ("would this step's swept footprint enter a zone?"), with the
// query's own margin (the drift VO measured, the uncertainty the step adds) on top of the
// footprint grown by k sigma.
// A check that cannot decide (no pose, stale pose, invalid zones) says UNKNOWN, which
// the executor treats as unsafe.
#include "bus/channels.hpp"
#include "bus/convert.hpp"
#include "bus/keepout_convert.hpp"
#include "bus/process.hpp"
#include "bus/stereo_frame_convert.hpp"
#include "bus/traversability_convert.hpp"
#include "hazards/hazard_assessor.hpp"
#include "hazards/map_check.hpp"
#include "map_worker.hpp"
#include "traversability/traversability_map.hpp"

#include <rover_msgs/hazard_query_t.hpp>
#include <rover_msgs/hazard_reply_t.hpp>
#include <rover_msgs/hazard_status_t.hpp>
#include <rover_msgs/imu_t.hpp>
#include <rover_msgs/keepout_zones_t.hpp>
#include <rover_msgs/pose_t.hpp>

#include <algorithm>
#include <cmath>
#include <deque>
#include <optional>
#include <iostream>
#include <memory>
#include <stdexcept>

using namespace rover;

namespace {

// The map's checks: hazards.map, with `--map on|off` over its `enabled`. On where the
// config enables it or the deployment says `--map on`; `--map off` for a deployment without
// cameras, which never sees the ground (every step would be hazard_unknown).
hazards::MapCheckOptions LoadMapCheck(const bus::Process& proc, const config::ConfigNode& section) {
  hazards::MapCheckOptions map_check;
  map_check.enabled = false;
  if (section.Has("map")) map_check = hazards::LoadMapCheckOptions(section["map"], {"traversability", "hazcam"});
  if (const auto arg = proc.option("--map")) {
    if (*arg != "on" && *arg != "off") {
      throw config::ConfigError("hazard_monitor: argument --map: \"" + *arg + "\": expected on or off");
    }
    if (*arg == "on" && !section.Has("map")) {
      throw config::ConfigError("hazard_monitor: argument --map on: " + proc.config_path() +
                                " has no hazards.map section (expected the map's limits there)");
    }
    map_check.enabled = *arg == "on";
  }
  return map_check;
}

// The map's worker (none with the map off), and the driven-step limit it sets for the vote.
std::unique_ptr<MapWorker> MakeMapWorker(const config::ConfigNode& section, const hazards::HazardOptions& options,
                                         hazards::MapCheckOptions* map_check) {
  if (!map_check->enabled) return nullptr;
  const auto map_options = traversability::LoadMapOptions(section["map"]["traversability"]);
  map_check->max_driven_step_m =
      map_check->DrivenStepLimit(map_options.max_step_m, map_options.crest_view_range_m > 0.0);
  if (const std::string note = hazards::MapTiltLimitProblem(map_options.max_tilt_deg, options.tilt); !note.empty()) {
    std::cerr << "hazard_monitor: warning: " << note << "\n";
  }
  // The HAZCAM pair's own stereo options (its disparities, ranges, rectified field) over the map's.
  const auto hazcam_options = traversability::LoadCameraOptions(section["map"]["hazcam"], map_options);
  return std::make_unique<MapWorker>(map_options, hazcam_options);
}

hazards::PoseSnapshot SnapshotFromMsg(const rover_msgs::pose_t& m) {
  const auto v = geometry::XyzRpyFromPose(bus::PoseFromMsg(m));
  hazards::PoseSnapshot p;
  p.utime = m.utime;
  p.x = v[0];
  p.y = v[1];
  p.roll = v[3];
  p.pitch = v[4];
  p.yaw = v[5];
  p.position_sigma_m = hazards::HorizontalSigma(bus::CovarianceFromArray(m.covariance));
  return p;
}

// A pair for the map, its images checked and made 8-bit; nothing (with `bad` set) for a
// frame that does not decode.
std::optional<MapWorker::Job> JobFromFrame(const rover_msgs::stereo_frame_t& frame, bool hazcam, std::string* bad) {
  vo::StereoImages images;
  *bad = bus::ToStereoImages(frame, imaging::ImageLimits{}, images);
  if (!bad->empty()) return std::nullopt;
  if (images.left.depth() != CV_8U) {
    images.left.convertTo(images.left, CV_8U, 1.0 / 256.0);
    images.right.convertTo(images.right, CV_8U, 1.0 / 256.0);
  }
  MapWorker::Job job;
  job.left = images.left;
  job.right = images.right;
  job.rig = images.rig;
  job.T_site_rover = bus::PoseFromMsg(frame.pose_at_capture);
  job.covariance = bus::CovarianceFromArray(frame.pose_at_capture.covariance);
  job.frame_id = frame.frame_id;
  job.hazcam = hazcam;
  return job;
}

rover_msgs::hazard_status_t ToMsg(const hazards::HazardStatus& st) {
  rover_msgs::hazard_status_t m{};
  m.utime = st.utime;
  m.state = static_cast<std::int8_t>(st.state);
  m.keepout_violated = st.keepout_violated;
  m.zone_name = st.zone_name;
  m.min_clearance_m = std::isfinite(st.min_clearance_m) ? st.min_clearance_m : 1e9;
  m.tilt_violated = st.tilt_violated;
  m.roll_rad = st.roll_rad;
  m.pitch_rad = st.pitch_rad;
  m.roll_limit_rad = st.roll_limit_rad;
  m.pitch_limit_rad = st.pitch_limit_rad;
  m.detail = st.detail;
  return m;
}

// The hazard monitor on the bus: the pose, attitude and zones into the assessor, the
// stereo pairs into the map, the executor's queries answered on both, and the status out.
class HazardNode {
 public:
  HazardNode(bus::Process& proc, const hazards::HazardOptions& options, hazards::MapCheckOptions map_check,
             std::unique_ptr<MapWorker> map)
      : proc_(proc), options_(options), map_check_(map_check), map_(std::move(map)), assessor_(options),
        grid_(map_ ? map_->Initial() : avoidance::Grid{}), trail_(map_ ? grid_.cell_m : 0.2),
        config_zones_(options.zones) {
    rules_.footprint = hazards::GridFootprint(options.footprint);
    rules_.blind_margin_m = map_check_.blind_margin_m;
    rules_.unknown = map_check_.Unknown();
    rules_.max_driven_step_m = map_check_.max_driven_step_m;
    rules_.caution_goodness = map_ ? map_->options().CautionGoodness() : 0.0;
  }

  void Subscribe() {
    auto& bus = proc_.bus();
    bus.Subscribe<rover_msgs::pose_t>(channels::kPose, [this](const rover_msgs::pose_t& m) { OnPose(m); });
    bus.Subscribe<rover_msgs::imu_t>(channels::kImu, [this](const rover_msgs::imu_t& m) {
      proc_.ObserveTime(m.utime);
      const auto rpy = geometry::RpyFromRotation(bus::QuaternionFromArray(m.orientation).toRotationMatrix());
      assessor_.OnAttitude(m.utime, rpy[0], rpy[1]);
    }, 200);
    bus.Subscribe<rover_msgs::keepout_zones_t>(channels::kKeepOutZones,
                                               [this](const rover_msgs::keepout_zones_t& m) { OnZones(m); });
    if (map_) {
      bus.Subscribe<rover_msgs::stereo_frame_t>(
          channels::kStereoFrame, [this](const rover_msgs::stereo_frame_t& frame) { OnFrame(frame, false); }, 4);
      bus.Subscribe<rover_msgs::stereo_frame_t>(
          channels::kHazcamFrame, [this](const rover_msgs::stereo_frame_t& frame) { OnFrame(frame, true); }, 4);
    }
    bus.Subscribe<rover_msgs::hazard_query_t>(channels::kHazardQuery, [this](const rover_msgs::hazard_query_t& q) {
      held_.emplace_back(q, !map_ ? 0 : proc_.virtual_time() ? frames_received_ : map_->Added());
      AnswerHeld();
    });
    proc_.set_pending_work([this] { return PendingWork(); });
    // Quiet (virtual time's idle strides) with no query held and no pair to map, or until
    // the pair in work is due.
    proc_.set_quiet_until([this]() -> std::int64_t {
      if (!held_.empty() || !waiting_jobs_.empty()) return 0;
      return in_work_due_ ? *in_work_due_ : bus::Process::kQuietForGood;
    });
  }

  // The steady status, the queries a finished map releases, and now and then the map again.
  void Tick(double publish_hz) {
    FollowClockRate();
    auto m = ToMsg(assessor_.Assess(proc_.now()));
    if (!zone_error_.empty()) {
      m.state = rover_msgs::hazard_status_t::STATE_UNKNOWN;
      m.detail = "invalid keep-out zones: " + zone_error_;
    }
    proc_.bus().Publish(channels::kHazardStatus, m);
    AnswerHeld();
    // The map changes only when a pair has been mapped (published then); between pairs it
    // is sent again this often. Once a second, 249 copies of the 60 kB map made up 15 of
    // the demo's 23 MB and woke every process of the set each time.
    constexpr double kMapRefreshS = 5.0;
    if (++ticks_ % static_cast<int>(std::max(1.0, kMapRefreshS * publish_hz)) == 0) PublishMap();
  }

 private:
  void PublishMap() {
    if (map_) proc_.bus().Publish(channels::kTraversabilityMap, bus::MapToMsg(grid_, rules_, proc_.now(), last_frame_id_));
  }

  // Takes a grid the worker finished; true when there was one.
  bool TakeMap() {
    if (!map_) return false;
    std::string notes;
    const bool fresh = map_->Take(&grid_, &last_frame_id_, &notes);
    if (!notes.empty()) std::cerr << notes;
    return fresh;
  }

  // The map holds pairs placed with the poses of their time. When the pose source restarts
  // (its POSE count goes back: a restarted estimator starts again from its start pose) or a
  // new site frame begins, those no longer agree with the new poses, and ghost steps would
  // appear where old and new pairs overlap: the map starts again.
  void OnPose(const rover_msgs::pose_t& m) {
    proc_.ObserveTime(m.utime);
    const hazards::PoseSnapshot p = SnapshotFromMsg(m);
    assessor_.OnPose(p);
    const auto count = static_cast<std::uint32_t>(static_cast<std::uint64_t>(m.pub_seq) & 0xffffffffu);
    if (map_ && have_pose_ && (count < last_pose_count_ || m.site_index != last_site_)) {
      std::cerr << "hazard_monitor: traversability map cleared: "
                << (m.site_index != last_site_ ? "a new site frame began"
                                               : "the pose source restarted (its POSE count went back)")
                << "\n";
      map_->Clear();
      trail_ = hazards::DrivenTrail(grid_.cell_m);
    }
    have_pose_ = true;
    last_pose_count_ = count;
    last_site_ = m.site_index;
    if (map_) trail_.Add({p.x, p.y, p.yaw}, options_.footprint);
  }

  void OnZones(const rover_msgs::keepout_zones_t& m) {
    auto zones = config_zones_;
    try {
      const auto from_msg = bus::ZonesFromMsg(m);
      zones.insert(zones.end(), from_msg.begin(), from_msg.end());
      zone_error_ = hazards::ZoneSetProblem(zones);
    } catch (const std::invalid_argument& e) {
      zone_error_ = e.what();  // a zone that cannot be built: undecidable, so UNKNOWN
    }
    if (!zone_error_.empty()) {
      std::cerr << "hazard_monitor: KEEPOUT_ZONES: " << zone_error_ << "\n";
      return;
    }
    assessor_.SetZones(zones);
  }

  // Both pairs take the same path: validated, then mapped in the order they came (the
  // HAZCAM pair of a capture comes before its NAVCAM pair), each holding back the queries
  // asked after it. Virtual time: one pair at a time goes to the worker, and its map is
  // taken when the compute profile's map time has passed since the pair came (never
  // earlier, whatever this machine's speed), so a query is answered at the same rover time
  // in every run.
  void OnFrame(const rover_msgs::stereo_frame_t& frame, bool hazcam) {
    proc_.ObserveTime(frame.utime);
    std::string bad;
    auto job = JobFromFrame(frame, hazcam, &bad);
    if (!job) {
      std::cerr << "hazard_monitor: " << (hazcam ? channels::kHazcamFrame : channels::kStereoFrame) << " "
                << frame.frame_id << ": " << bad << " (not mapped)\n";
      return;
    }
    if (!proc_.virtual_time()) {
      map_->Add(std::move(*job));
      return;
    }
    ++frames_received_;
    // One mapper: a pair starts when it has come and the one before it is done.
    const double compute_s = hazcam ? proc_.compute().hazcam_map_s : proc_.compute().map_s;
    mapper_free_utime_ = proc_.DueAt(std::max({proc_.now(), frame.utime, mapper_free_utime_}), compute_s);
    waiting_jobs_.emplace_back(mapper_free_utime_, std::move(*job));
  }

  // Virtual time: true while a pair due by now is still being mapped.
  bool PendingWork() {
    if (!map_ || !proc_.virtual_time()) return false;
    if (in_work_due_) {
      if (proc_.now() < *in_work_due_) return false;
      if (map_->Done() < map_->Added()) return true;
      if (TakeMap()) PublishMap();
      in_work_due_.reset();
      ++frames_mapped_;
      AnswerHeld();
    }
    if (!waiting_jobs_.empty()) {
      in_work_due_ = std::max(waiting_jobs_.front().first, proc_.now());
      map_->Add(std::move(waiting_jobs_.front().second));
      waiting_jobs_.pop_front();
    }
    return false;
  }

  // A query that comes while a pair is being mapped waits for that map (answered on a
  // later tick): the step is judged on a map holding every pair taken before it. Pairs
  // that come after the query do not hold it back. A step chosen while driving
  // (hazard_query_t.map_frame_id > 0) is judged at once on the map in hand when that holds
  // the pair it was chosen on: the executor chose it there because all its ground was
  // known safe on that map, and this check holds it to the same map.
  void AnswerHeld() {
    if (!proc_.virtual_time() && TakeMap()) PublishMap();
    std::erase_if(held_, [&](const auto& h) {
      const bool on_map_in_hand = h.first.map_frame_id > 0 && last_frame_id_ >= h.first.map_frame_id;
      if (map_ && !on_map_in_hand &&
          (proc_.virtual_time() ? frames_mapped_ < h.second : !map_->Mapped(h.second)))
        return false;
      proc_.bus().Publish(channels::kHazardReply, Answer(h.first));
      return true;
    });
  }

  rover_msgs::hazard_reply_t Answer(const rover_msgs::hazard_query_t& q) {
    rover_msgs::hazard_reply_t r{};
    r.utime = proc_.now();
    r.query_id = q.query_id;
    std::vector<hazards::Pose2> path;
    bool finite = q.num_poses > 0;
    for (int i = 0; i < q.num_poses; ++i) {
      finite = finite && std::isfinite(q.x[i]) && std::isfinite(q.y[i]) && std::isfinite(q.yaw[i]);
      path.push_back({q.x[i], q.y[i], q.yaw[i]});
    }
    if (!finite) {
      r.verdict = rover_msgs::hazard_reply_t::VERDICT_UNKNOWN;
      r.detail = "query " + std::to_string(q.query_id) + ": empty or non-finite path";
      return r;
    }
    if (!zone_error_.empty()) {
      r.verdict = rover_msgs::hazard_reply_t::VERDICT_UNKNOWN;
      r.detail = "invalid keep-out zones: " + zone_error_;
      return r;
    }
    const auto check = CheckPath(path, q);
    r.verdict = static_cast<std::int8_t>(check.verdict);
    r.zone_name = check.zone_name;
    r.min_clearance_m = std::isfinite(check.min_clearance_m) ? check.min_clearance_m : 1e9;
    r.detail = check.detail;
    return r;
  }

  // Pose age is judged on the clock every guard reads (bus::Process::guard_seconds): rover
  // seconds in virtual time, wall seconds on a real clock, whose rover time runs at the
  // rate the time source's ROVER_CLOCK carries (1 on a rover). At 50x on a real clock, 2 s
  // of rover time was 40 ms of wall time: a busy machine's scheduling delay stopped drives.
  void FollowClockRate() {
    const double rate = proc_.bus().clock().rate();
    assessor_.set_clock_rate(proc_.virtual_time() || !std::isfinite(rate) || rate <= 0.0 ? 1.0 : rate);
  }

  // The swept path against the zones, tilt and pose age, then against the map.
  hazards::SweptCheck CheckPath(const std::vector<hazards::Pose2>& path, const rover_msgs::hazard_query_t& q) {
    // A non-finite or negative margin makes the check UNKNOWN (CheckSweptPath). Pose age
    // is judged at the time of asking: a query held while a pair was mapped is not refused
    // for the rover time that ran on meanwhile.
    const int64_t asked = q.utime > 0 ? std::min(proc_.now(), q.utime) : proc_.now();
    FollowClockRate();
    auto check = assessor_.CheckStep(path, asked, q.margin_m);
    if (!map_ || check.verdict == hazards::Verdict::kUnsafe) return check;
    // The map judges the same swept path; an unsafe cell outranks an undecided keep-out
    // check, and either stops the step. Ground the rover has driven over is known: it
    // carried the rover.
    avoidance::Grid judged = grid_;
    if (judged.Problem().empty()) trail_.MarkDriven(&judged);
    const auto on_map = hazards::CheckPathOnMap(judged, rules_.footprint, path, map_check_);
    if (on_map.verdict == hazards::Verdict::kUnsafe ||
        (on_map.verdict == hazards::Verdict::kUnknown && check.verdict == hazards::Verdict::kSafe)) {
      check = on_map;
    }
    return check;
  }

  bus::Process& proc_;
  const hazards::HazardOptions options_;
  const hazards::MapCheckOptions map_check_;
  std::unique_ptr<MapWorker> map_;
  hazards::HazardAssessor assessor_;
  bus::MapRules rules_;
  avoidance::Grid grid_;  // the map as the checks see it: the worker's newest
  int64_t last_frame_id_ = -1;
  hazards::DrivenTrail trail_;
  bool have_pose_ = false;
  std::uint32_t last_pose_count_ = 0;
  std::int32_t last_site_ = 0;
  const std::vector<hazards::KeepOutZone> config_zones_;
  std::deque<std::pair<std::int64_t, MapWorker::Job>> waiting_jobs_;  // due, pair
  std::optional<std::int64_t> in_work_due_;
  std::int64_t mapper_free_utime_ = 0;  // when the last pair taken is due
  std::uint64_t frames_received_ = 0, frames_mapped_ = 0;
  std::string zone_error_;  // non-empty: the last zone set was invalid -> UNKNOWN
  std::vector<std::pair<rover_msgs::hazard_query_t, std::uint64_t>> held_;  // and the pairs it waits for
  int ticks_ = 0;
};

}  // namespace

int main(int argc, char** argv) {
  return bus::RunMain("hazard_monitor", [&]() -> int {
    bus::Process proc("hazard_monitor",
                      "Keep-out, tilt and traversability-map checks. Reads POSE, IMU, KEEPOUT_ZONES,\n"
                      "HAZARD_QUERY, STEREO_FRAME and HAZCAM_FRAME (unless the map is off); writes HAZARD_STATUS\n"
                      "(steady rate), HAZARD_REPLY and TRAVERSABILITY_MAP.\n"
                      "Config: the `hazards:` section (see configs/rover.yaml).",
                      argc, argv,
                      {{"--map", "on|off",
                        "traversability map from STEREO_FRAME (default: hazards.map.enabled); "
                        "off: no cameras, zones and tilt only"}});
    const auto section = proc.config()["hazards"];
    const auto options = hazards::LoadHazardOptions(section, {"publish_hz"});
    double publish_hz = 10.0;
    section.Get("publish_hz", publish_hz, 1.0, 100.0);
    auto map_check = LoadMapCheck(proc, section);
    auto map = MakeMapWorker(section, options, &map_check);
    std::cerr << "hazard_monitor: traversability map " << (map ? "on" : "off") << "\n";
    HazardNode node(proc, options, map_check, std::move(map));
    node.Subscribe();
    proc.DeclarePublications({{channels::kHazardStatus}, {channels::kHazardReply},
                              {channels::kTraversabilityMap, "the map is on (hazards.map.enabled, --map)"}});
    proc.Run([&] { node.Tick(publish_hz); }, static_cast<int>(1000.0 / publish_hz));
    return 0;
  });
}
