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
    // The traversability map: on where the config enables it (configs/rover.yaml does not
    // yet: see its comment) or the deployment says `--map on`; `--map off` for a deployment
    // without cameras, which never sees the ground (every step would be hazard_unknown).
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
    std::unique_ptr<MapWorker> map;
    if (map_check.enabled) {
      const auto map_options = traversability::LoadMapOptions(section["map"]["traversability"]);
      map_check.max_driven_step_m =
          map_check.DrivenStepLimit(map_options.max_step_m, map_options.crest_view_range_m > 0.0);
      if (const std::string note = hazards::MapTiltLimitProblem(map_options.max_tilt_deg, options.tilt);
          !note.empty()) {
        std::cerr << "hazard_monitor: warning: " << note << "\n";
      }
      // The HAZCAM pair's own stereo options (its disparities, ranges, rectified field) over the map's.
      const auto hazcam_options = traversability::LoadCameraOptions(section["map"]["hazcam"], map_options);
      map = std::make_unique<MapWorker>(map_options, hazcam_options);
    }
    std::cerr << "hazard_monitor: traversability map " << (map ? "on" : "off") << "\n";
    bus::MapRules rules;
    rules.footprint = hazards::GridFootprint(options.footprint);
    rules.blind_margin_m = map_check.blind_margin_m;
    rules.unknown = map_check.Unknown();
    rules.max_driven_step_m = map_check.max_driven_step_m;
    avoidance::Grid grid;  // the map as the checks see it: the worker's newest
    int64_t last_frame_id = -1;
    if (map) grid = map->Initial();
    auto publish_map = [&] {
      if (map) proc.bus().Publish(channels::kTraversabilityMap, bus::MapToMsg(grid, rules, proc.now(), last_frame_id));
    };
    // Takes a grid the worker finished; true when there was one.
    auto take_map = [&] {
      if (!map) return false;
      std::string notes;
      const bool fresh = map->Take(&grid, &last_frame_id, &notes);
      if (!notes.empty()) std::cerr << notes;
      return fresh;
    };
    hazards::HazardAssessor assessor(options);
    hazards::DrivenTrail trail(map ? grid.cell_m : 0.2);
    // The map holds pairs placed with the poses of their time. When the pose source
    // restarts (its POSE count goes back: a restarted estimator starts again from its
    // start pose) or a new site frame begins, those no longer agree with the new poses,
    // and ghost steps would appear where old and new pairs overlap: the map starts again.
    bool have_pose = false;
    std::uint32_t last_pose_count = 0;
    std::int32_t last_site = 0;
    const std::vector<hazards::KeepOutZone> config_zones = options.zones;
    // Virtual time: one pair at a time goes to the worker, and its map is taken when the
    // compute profile's map time has passed since the pair came (never earlier, whatever
    // this machine's speed), so a query is answered at the same rover time in every run.
    std::deque<std::pair<std::int64_t, MapWorker::Job>> waiting_jobs;  // due, pair
    std::optional<std::int64_t> in_work_due;
    std::int64_t mapper_free_utime = 0;  // when the last pair taken is due
    std::uint64_t frames_received = 0, frames_mapped = 0;
    std::string zone_error;  // non-empty: the last zone set was invalid -> UNKNOWN

    proc.bus().Subscribe<rover_msgs::pose_t>(channels::kPose, [&](const rover_msgs::pose_t& m) {
      proc.ObserveTime(m.utime);
      const auto T = bus::PoseFromMsg(m);
      const auto v = geometry::XyzRpyFromPose(T);
      hazards::PoseSnapshot p;
      p.utime = m.utime;
      p.x = v[0];
      p.y = v[1];
      p.roll = v[3];
      p.pitch = v[4];
      p.yaw = v[5];
      p.position_sigma_m = hazards::HorizontalSigma(bus::CovarianceFromArray(m.covariance));
      assessor.OnPose(p);
      const auto count = static_cast<std::uint32_t>(static_cast<std::uint64_t>(m.pub_seq) & 0xffffffffu);
      if (map && have_pose && (count < last_pose_count || m.site_index != last_site)) {
        std::cerr << "hazard_monitor: traversability map cleared: "
                  << (m.site_index != last_site ? "a new site frame began"
                                                : "the pose source restarted (its POSE count went back)")
                  << "\n";
        map->Clear();
        trail = hazards::DrivenTrail(grid.cell_m);
      }
      have_pose = true;
      last_pose_count = count;
      last_site = m.site_index;
      if (map) trail.Add({p.x, p.y, p.yaw}, options.footprint);
    });
    proc.bus().Subscribe<rover_msgs::imu_t>(channels::kImu, [&](const rover_msgs::imu_t& m) {
      proc.ObserveTime(m.utime);
      const auto rpy = geometry::RpyFromRotation(bus::QuaternionFromArray(m.orientation).toRotationMatrix());
      assessor.OnAttitude(m.utime, rpy[0], rpy[1]);
    }, 200);
    proc.bus().Subscribe<rover_msgs::keepout_zones_t>(
        channels::kKeepOutZones, [&](const rover_msgs::keepout_zones_t& m) {
          auto zones = config_zones;
          try {
            const auto from_msg = bus::ZonesFromMsg(m);
            zones.insert(zones.end(), from_msg.begin(), from_msg.end());
            zone_error = hazards::ZoneSetProblem(zones);
          } catch (const std::invalid_argument& e) {
            zone_error = e.what();  // a zone that cannot be built: undecidable, so UNKNOWN
          }
          if (!zone_error.empty()) {
            std::cerr << "hazard_monitor: KEEPOUT_ZONES: " << zone_error << "\n";
            return;
          }
          assessor.SetZones(zones);
        });
    // Both pairs take the same path: validated, then mapped in the order they came (the
    // HAZCAM pair of a capture comes before its NAVCAM pair), each holding back the queries
    // asked after it.
    auto on_frame = [&](const rover_msgs::stereo_frame_t& frame, bool hazcam) {
      proc.ObserveTime(frame.utime);
      const char* channel = hazcam ? channels::kHazcamFrame : channels::kStereoFrame;
      vo::StereoImages images;
      if (const std::string bad = bus::ToStereoImages(frame, imaging::ImageLimits{}, images); !bad.empty()) {
        std::cerr << "hazard_monitor: " << channel << " " << frame.frame_id << ": " << bad << " (not mapped)\n";
        return;
      }
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
      if (proc.virtual_time()) {
        ++frames_received;
        // One mapper: a pair starts when it has come and the one before it is done.
        const double compute_s = hazcam ? proc.compute().hazcam_map_s : proc.compute().map_s;
        mapper_free_utime = proc.DueAt(std::max({proc.now(), frame.utime, mapper_free_utime}), compute_s);
        waiting_jobs.emplace_back(mapper_free_utime, std::move(job));
      } else {
        map->Add(std::move(job));
      }
    };
    if (map) {
      proc.bus().Subscribe<rover_msgs::stereo_frame_t>(
          channels::kStereoFrame, [&](const rover_msgs::stereo_frame_t& frame) { on_frame(frame, false); }, 4);
      proc.bus().Subscribe<rover_msgs::stereo_frame_t>(
          channels::kHazcamFrame, [&](const rover_msgs::stereo_frame_t& frame) { on_frame(frame, true); }, 4);
    }
    // A query that comes while a pair is being mapped waits for that map (answered on a
    // later tick): the step is judged on a map holding every pair taken before it. Pairs
    // that come after the query do not hold it back.
    std::vector<std::pair<rover_msgs::hazard_query_t, std::uint64_t>> held;  // and the pairs it waits for
    auto answer = [&](const rover_msgs::hazard_query_t& q) {
      rover_msgs::hazard_reply_t r{};
      r.utime = proc.now();
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
      } else if (!zone_error.empty()) {
        r.verdict = rover_msgs::hazard_reply_t::VERDICT_UNKNOWN;
        r.detail = "invalid keep-out zones: " + zone_error;
      } else {
        // A non-finite or negative margin makes the check UNKNOWN (CheckSweptPath).
        // Pose age is judged at the time of asking: a query held while a pair was mapped
        // is not refused for the rover time that ran on meanwhile.
        const int64_t asked = q.utime > 0 ? std::min(proc.now(), q.utime) : proc.now();
        auto check = assessor.CheckStep(path, asked, q.margin_m);
        if (map && check.verdict != hazards::Verdict::kUnsafe) {
          // The map judges the same swept path; an unsafe cell outranks an undecided
          // keep-out check, and either stops the step.
          // Ground the rover has driven over is known: it carried the rover.
          avoidance::Grid judged = grid;
          if (judged.Problem().empty()) trail.MarkDriven(&judged);
          const auto on_map = hazards::CheckPathOnMap(judged, rules.footprint, path, map_check);
          if (on_map.verdict == hazards::Verdict::kUnsafe ||
              (on_map.verdict == hazards::Verdict::kUnknown && check.verdict == hazards::Verdict::kSafe)) {
            check = on_map;
          }
        }
        r.verdict = static_cast<std::int8_t>(check.verdict);
        r.zone_name = check.zone_name;
        r.min_clearance_m = std::isfinite(check.min_clearance_m) ? check.min_clearance_m : 1e9;
        r.detail = check.detail;
      }
      proc.bus().Publish(channels::kHazardReply, r);
    };
    auto answer_held = [&] {
      if (!proc.virtual_time() && take_map()) publish_map();
      std::erase_if(held, [&](const auto& h) {
        if (map && (proc.virtual_time() ? frames_mapped < h.second : !map->Mapped(h.second))) return false;
        answer(h.first);
        return true;
      });
    };
    proc.bus().Subscribe<rover_msgs::hazard_query_t>(
        channels::kHazardQuery, [&](const rover_msgs::hazard_query_t& q) {
          held.emplace_back(q, !map ? 0 : proc.virtual_time() ? frames_received : map->Added());
          answer_held();
        });
    // Virtual time: true while a pair due by now is still being mapped.
    proc.set_pending_work([&]() -> bool {
      if (!map || !proc.virtual_time()) return false;
      if (in_work_due) {
        if (proc.now() < *in_work_due) return false;
        if (map->Done() < map->Added()) return true;
        if (take_map()) publish_map();
        in_work_due.reset();
        ++frames_mapped;
        answer_held();
      }
      if (!waiting_jobs.empty()) {
        in_work_due = std::max(waiting_jobs.front().first, proc.now());
        map->Add(std::move(waiting_jobs.front().second));
        waiting_jobs.pop_front();
      }
      return false;
    });

    // The map changes only when a pair has been mapped (published then); between pairs it
    // is sent again this often. Once a second, 249 copies of the 60 kB map made up 15 of the
    // demo's 23 MB and woke every process of the set each time.
    constexpr double kMapRefreshS = 5.0;
    int ticks = 0;
    proc.Run(
        [&] {
          const auto st = assessor.Assess(proc.now());
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
          if (!zone_error.empty()) {
            m.state = rover_msgs::hazard_status_t::STATE_UNKNOWN;
            m.detail = "invalid keep-out zones: " + zone_error;
          }
          proc.bus().Publish(channels::kHazardStatus, m);
          answer_held();
          if (++ticks % static_cast<int>(std::max(1.0, kMapRefreshS * publish_hz)) == 0) publish_map();
        },
        static_cast<int>(1000.0 / publish_hz));
    return 0;
  });
}
