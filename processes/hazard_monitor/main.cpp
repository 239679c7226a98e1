// hazard_monitor: keep-out zones against the footprint plus the position uncertainty, and
// tilt limits (common/hazards). Publishes HAZARD_STATUS at a steady rate and answers the
// executor's HAZARD_QUERY ("would this step's swept footprint enter a zone?"), with the
// query's own margin (the drift VO measured, the uncertainty the step adds) on top of the
// footprint grown by k sigma.
// A check that cannot decide (no pose, stale pose, invalid zones) says UNKNOWN, which
// the executor treats as unsafe.
#include "bus/channels.hpp"
#include "bus/convert.hpp"
#include "bus/keepout_convert.hpp"
#include "bus/process.hpp"
#include "hazards/hazard_assessor.hpp"

#include <rover_msgs/hazard_query_t.hpp>
#include <rover_msgs/hazard_reply_t.hpp>
#include <rover_msgs/hazard_status_t.hpp>
#include <rover_msgs/imu_t.hpp>
#include <rover_msgs/keepout_zones_t.hpp>
#include <rover_msgs/pose_t.hpp>

#include <cmath>
#include <iostream>
#include <stdexcept>

using namespace rover;

int main(int argc, char** argv) {
  return bus::RunMain("hazard_monitor", [&]() -> int {
    bus::Process proc("hazard_monitor",
                      "Keep-out and tilt checks. Reads POSE, IMU, KEEPOUT_ZONES, HAZARD_QUERY;\n"
                      "writes HAZARD_STATUS (steady rate) and HAZARD_REPLY.\n"
                      "Config: the `hazards:` section (see configs/rover.yaml).",
                      argc, argv);
    const auto section = proc.config()["hazards"];
    const auto options = hazards::LoadHazardOptions(section, {"publish_hz"});
    double publish_hz = 10.0;
    section.Get("publish_hz", publish_hz, 1.0, 100.0);
    hazards::HazardAssessor assessor(options);
    const std::vector<hazards::KeepOutZone> config_zones = options.zones;
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
    proc.bus().Subscribe<rover_msgs::hazard_query_t>(
        channels::kHazardQuery, [&](const rover_msgs::hazard_query_t& q) {
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
            const auto check = assessor.CheckStep(path, proc.now(), q.margin_m);
            r.verdict = static_cast<std::int8_t>(check.verdict);
            r.zone_name = check.zone_name;
            r.min_clearance_m = std::isfinite(check.min_clearance_m) ? check.min_clearance_m : 1e9;
            r.detail = check.detail;
          }
          proc.bus().Publish(channels::kHazardReply, r);
        });

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
        },
        static_cast<int>(1000.0 / publish_hz));
    return 0;
  });
}
