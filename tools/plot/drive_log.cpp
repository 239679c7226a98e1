#include "plot/drive_log.hpp"

#include "bus/channels.hpp"
#include "bus/convert.hpp"
#include "bus/keepout_convert.hpp"
#include "estimation/pose_estimator.hpp"
#include "sequence/parser.hpp"
#include "terrain/world.hpp"

#include <lcm/lcm-cpp.hpp>
#include <rover_msgs/imu_t.hpp>
#include <rover_msgs/keepout_zones_t.hpp>
#include <rover_msgs/new_site_t.hpp>
#include <rover_msgs/pose_t.hpp>
#include <rover_msgs/sequence_submit_t.hpp>
#include <rover_msgs/sim_truth_t.hpp>
#include <rover_msgs/wheel_odometry_t.hpp>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <optional>
#include <stdexcept>
#include <variant>

namespace rover::plot {
namespace {

// Decodes one event into `msg`; false (and counted) when it does not decode.
template <typename Msg>
bool Decode(const lcm::LogEvent& ev, Msg& msg, DriveLog& out) {
  if (msg.decode(ev.data, 0, ev.datalen) >= 0) return true;
  ++out.undecodable[ev.channel];
  return false;
}

double SigmaXy(const rover_msgs::pose_t& m) {
  Eigen::Matrix2d c;
  c << m.covariance[0][0], m.covariance[0][1], m.covariance[1][0], m.covariance[1][1];
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(c, Eigen::EigenvaluesOnly);
  return std::sqrt(std::max(0.0, es.eigenvalues().maxCoeff()));
}

// The slip limit in force at each command of a submitted sequence (settings apply from
// their line to the rest of the sequence).
std::map<int, double> SlipLimits(const rover_msgs::sequence_submit_t& submit) {
  std::map<int, double> limits;
  const auto parsed = sequence::ParseSequence(submit.text, submit.name);
  if (!parsed.ok()) return limits;
  std::optional<double> in_force;
  for (std::size_t i = 0; i < parsed.sequence.commands.size(); ++i) {
    if (const auto* s = std::get_if<sequence::SlipSetting>(&parsed.sequence.commands[i].action)) {
      in_force = s->enabled ? std::optional<double>(s->limit_pct) : std::nullopt;
    }
    if (in_force) limits[static_cast<int>(i)] = *in_force;
  }
  return limits;
}

// Every goto's goal disc in a submitted sequence.
std::vector<GoalDisc> Goals(const rover_msgs::sequence_submit_t& submit) {
  std::vector<GoalDisc> goals;
  const auto parsed = sequence::ParseSequence(submit.text, submit.name);
  if (!parsed.ok()) return goals;
  for (std::size_t i = 0; i < parsed.sequence.commands.size(); ++i) {
    if (const auto* g = std::get_if<sequence::Goto>(&parsed.sequence.commands[i].action)) {
      goals.push_back({submit.submission_id, static_cast<int>(i), g->target, g->tolerance_m});
    }
  }
  return goals;
}

bool IsFinal(const rover_msgs::sequence_status_t& s) {
  return s.state == rover_msgs::sequence_status_t::STATE_COMPLETED ||
         s.state == rover_msgs::sequence_status_t::STATE_ABORTED ||
         s.state == rover_msgs::sequence_status_t::STATE_REJECTED;
}

// The wheel-odometry-only path: the estimator's library with IMU and odometry only,
// started at the first on-board pose (see drive_log.hpp).
class WheelOnlyPath {
 public:
  // The first pose already holds the odometry before it: the latest odometry message
  // seen is the reference the increments after it are measured from.
  void Start(const rover_msgs::pose_t& first) {
    const std::int64_t utime = reference_ ? std::min(first.utime, reference_->utime) : first.utime;
    estimator_.Reset(bus::PoseFromMsg(first), utime);
    started_ = true;
    Record(utime);
    if (reference_) OnOdometry(*reference_);
  }
  void OnImu(const rover_msgs::imu_t& m) {
    if (!started_) return;
    estimator_.OnImu(m.utime, bus::QuaternionFromArray(m.orientation),
                     Eigen::Vector3d(m.angular_rate[0], m.angular_rate[1], m.angular_rate[2]));
  }
  void OnOdometry(const rover_msgs::wheel_odometry_t& m) {
    if (!started_) {
      reference_ = m;
      return;
    }
    estimation::WheelOdometrySample s;
    s.utime = m.utime;
    s.distance_m = m.distance_m;
    s.curvature_per_m = m.curvature_per_m;
    s.turning_in_place = m.turning_in_place != 0;
    if (estimator_.OnWheelOdometry(s) == estimation::InputResult::kAccepted) Record(m.utime);
  }
  void OnNewSite(int site_index) {
    if (started_) estimator_.NewSite(site_index);
  }
  std::vector<PathPoint> path;

 private:
  void Record(std::int64_t utime) { path.push_back({utime, estimator_.pose().translation()}); }
  estimation::PoseEstimator estimator_;
  bool started_ = false;
  std::optional<rover_msgs::wheel_odometry_t> reference_;
};

}  // namespace

DriveLog ReadDriveLog(const std::string& log_path) {
  lcm::LogFile log(log_path, "r");
  if (!log.good()) throw std::runtime_error(log_path + ": cannot read the LCM log");
  DriveLog out;
  out.path = log_path;
  WheelOnlyPath wheel;
  std::map<std::string, ZoneRecord> zones;
  for (const lcm::LogEvent* ev = log.readNextEvent(); ev != nullptr; ev = log.readNextEvent()) {
    const std::string& ch = ev->channel;
    if (ch == channels::kPose) {
      rover_msgs::pose_t m{};
      if (!Decode(*ev, m, out)) continue;
      if (out.estimate.empty()) wheel.Start(m);
      EstimatePoint e;
      e.utime = m.utime;
      e.p = Eigen::Vector3d(m.position[0], m.position[1], m.position[2]);
      e.sigma_xy_m = SigmaXy(m);
      e.source = m.source;
      out.estimate.push_back(e);
    } else if (ch == channels::kImu) {
      rover_msgs::imu_t m{};
      if (Decode(*ev, m, out)) wheel.OnImu(m);
    } else if (ch == channels::kWheelOdometry) {
      rover_msgs::wheel_odometry_t m{};
      if (Decode(*ev, m, out)) wheel.OnOdometry(m);
    } else if (ch == channels::kNewSite) {
      rover_msgs::new_site_t m{};
      if (Decode(*ev, m, out)) wheel.OnNewSite(m.site_index);
    } else if (ch == channels::kSimTruth) {
      rover_msgs::sim_truth_t m{};
      if (!Decode(*ev, m, out)) continue;
      TruthPoint t;
      t.utime = m.utime;
      t.p = Eigen::Vector3d(m.position[0], m.position[1], m.position[2]);
      t.yaw = m.rpy[2];
      t.odometer_m = m.odometer_m;
      out.truth.push_back(t);
    } else if (ch == channels::kKeepOutZones) {
      rover_msgs::keepout_zones_t m{};
      if (!Decode(*ev, m, out)) continue;
      try {
        for (auto& z : bus::ZonesFromMsg(m)) {
          auto [it, added] = zones.try_emplace(z.name, ZoneRecord{z, m.utime});
          if (!added) it->second.zone = z;
        }
      } catch (const std::invalid_argument&) {
        // An invalid set was never in force (the hazard monitor refused it).
      }
    } else if (ch == channels::kStepReport) {
      rover_msgs::step_report_t m{};
      if (Decode(*ev, m, out)) out.steps.push_back(m);
    } else if (ch == channels::kVoUpdate) {
      rover_msgs::vo_update_t m{};
      if (Decode(*ev, m, out)) out.vo_updates.push_back(m);
    } else if (ch == channels::kSequenceSubmit) {
      rover_msgs::sequence_submit_t m{};
      if (!Decode(*ev, m, out)) continue;
      if (out.sequence_name.empty()) out.sequence_name = m.name;
      out.slip_limit_pct = SlipLimits(m);
      out.runs.push_back({m.submission_id, m.name, std::nullopt});
      for (const auto& g : Goals(m)) out.goals.push_back(g);
    } else if (ch == channels::kSequenceStatus) {
      rover_msgs::sequence_status_t m{};
      if (!Decode(*ev, m, out)) continue;
      if (IsFinal(m) && !out.final_status) out.final_status = m;
      if (IsFinal(m)) {
        auto run = std::find_if(out.runs.begin(), out.runs.end(),
                                [&](const SequenceRun& r) { return r.submission_id == m.submission_id; });
        if (run == out.runs.end()) {  // submitted before the recording began
          out.runs.push_back({m.submission_id, m.sequence_name, std::nullopt});
          run = std::prev(out.runs.end());
        }
        if (!run->final_status) run->final_status = m;
      }
    }
  }
  std::sort(out.truth.begin(), out.truth.end(),
            [](const TruthPoint& a, const TruthPoint& b) { return a.utime < b.utime; });
  out.wheel_only = std::move(wheel.path);
  for (auto& [name, z] : zones) out.zones.push_back(std::move(z));
  return out;
}

std::vector<RockMark> ReadWorldRocks(const std::string& world_path, double min_height_m) {
  const terrain::World world(terrain::WorldOptions::LoadFile(world_path));
  std::vector<RockMark> rocks;
  for (const auto& r : world.rocks()) {
    if (r.height_m < min_height_m) continue;
    rocks.push_back({r.placed ? r.name : "", r.position, r.diameter_m, r.height_m});
  }
  return rocks;
}

std::map<std::int64_t, rover_msgs::stereo_frame_t> ReadStereoFrames(const std::string& log_path,
                                                                    const std::set<std::int64_t>& ids) {
  std::map<std::int64_t, rover_msgs::stereo_frame_t> frames;
  if (ids.empty()) return frames;
  lcm::LogFile log(log_path, "r");
  if (!log.good()) throw std::runtime_error(log_path + ": cannot read the LCM log");
  for (const lcm::LogEvent* ev = log.readNextEvent(); ev != nullptr; ev = log.readNextEvent()) {
    if (ev->channel != channels::kStereoFrame) continue;
    rover_msgs::stereo_frame_t m{};
    if (m.decode(ev->data, 0, ev->datalen) < 0 || !ids.count(m.frame_id)) continue;
    frames[m.frame_id] = std::move(m);
    if (frames.size() == ids.size()) break;
  }
  return frames;
}

}  // namespace rover::plot
