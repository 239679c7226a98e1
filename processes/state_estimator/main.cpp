// state_estimator: attitude from the IMU, position from wheel odometry along that attitude,
// VO updates replacing the wheel motion between two captures (common/estimation).
// Publishes POSE on a rover-time schedule driven by the input messages, so that a replay
// of the same messages gives the same poses.
#include "bus/channels.hpp"
#include "bus/convert.hpp"
#include "bus/process.hpp"
#include "estimation/pose_estimator.hpp"
#include "state_estimator/estimator_messages.hpp"
#include "terrain/world.hpp"

#include <rover_msgs/imu_t.hpp>
#include <rover_msgs/new_site_t.hpp>
#include <rover_msgs/pose_t.hpp>
#include <rover_msgs/vo_update_t.hpp>
#include <rover_msgs/wheel_odometry_t.hpp>

#include <cmath>
#include <deque>
#include <iostream>

using namespace rover;

namespace {

using state_estimator::FromMsg;

// The initial pose: --start, else the world's start on its ground (--world), else the origin.
geometry::Pose StartPose(const bus::Process& proc) {
  if (auto s = proc.option("--start")) {
    const auto v = bus::ParseNumberList(*s, 4, "state_estimator: argument --start");
    return geometry::PoseFromXyzRpy(v[0], v[1], v[2], 0, 0, v[3] * M_PI / 180.0);
  }
  if (auto w = proc.option("--world")) {
    // Without it a hand-launched simulation starts the estimate at z = 0 while the rover
    // stands on the world's ground: a height error that is only the start's.
    double origin_height_m = 0.0;
    proc.config()["mobility"]["geometry"].Get("origin_height_m", origin_height_m);
    const auto world_options = terrain::WorldOptions::LoadFile(*w);
    const terrain::World world(world_options);
    const auto& p = world_options.start;
    return geometry::PoseFromXyzRpy(p.x, p.y, world.StartHeight(p.x, p.y, origin_height_m), 0, 0,
                                    p.yaw_deg * M_PI / 180.0);
  }
  return geometry::Pose::Identity();
}

// The estimator on the bus. POSE goes out on a rover-time schedule set by the inputs' own
// stamps (every period from the first), and at once after each VO update or new site.
class EstimatorNode {
 public:
  EstimatorNode(bus::Process& proc, const estimation::EstimatorOptions& options, const geometry::Pose& start,
                double publish_hz)
      : proc_(proc), estimator_(options), start_(start), period_us_(static_cast<std::int64_t>(1e6 / publish_hz)) {}

  void Subscribe() {
    auto& bus = proc_.bus();
    bus.Subscribe<rover_msgs::imu_t>(channels::kImu, [this](const rover_msgs::imu_t& m) {
      EnsureStarted(m.utime);
      estimator_.OnImu(m.utime, bus::QuaternionFromArray(m.orientation),
                       Eigen::Vector3d(m.angular_rate[0], m.angular_rate[1], m.angular_rate[2]));
      AfterInput(m.utime);
    }, 1000);
    bus.Subscribe<rover_msgs::wheel_odometry_t>(channels::kWheelOdometry, [this](const rover_msgs::wheel_odometry_t& m) {
      EnsureStarted(m.utime);
      estimator_.OnWheelOdometry(FromMsg(m));
      AfterInput(m.utime);
    }, 1000);
    bus.Subscribe<rover_msgs::vo_update_t>(channels::kVoUpdate, [this](const rover_msgs::vo_update_t& m) {
      if (m.status != rover_msgs::vo_update_t::STATUS_OK || !started_) return;  // prior stands
      waiting_vo_.push_back(FromMsg(m));
      TryVo();
    }, 100);
    bus.Subscribe<rover_msgs::new_site_t>(channels::kNewSite, [this](const rover_msgs::new_site_t& m) {
      if (!started_) return;
      estimator_.NewSite(m.site_index);
      Publish();
    });
  }

  std::int64_t rejected_vo() const { return rejected_vo_; }
  bool waiting_vo() const { return !waiting_vo_.empty(); }

 private:
  // The estimate starts at the first input's instant.
  void EnsureStarted(std::int64_t utime) {
    if (started_) return;
    estimator_.Reset(start_, utime);
    started_ = true;
    next_publish_ = utime;
  }

  void Publish() {
    const auto est = estimator_.Estimate();
    rover_msgs::pose_t msg{};
    msg.utime = est.utime;
    bus::PoseToArrays(est.T_site_rover, msg.position, msg.orientation);
    bus::CovarianceToArray(est.covariance, msg.covariance);
    msg.source = static_cast<std::int8_t>(est.source);
    msg.site_index = est.site_index;
    msg.odometer_m = est.odometer_m;
    msg.last_vo_to_frame = est.last_vo_to_frame;
    proc_.bus().Publish(channels::kPose, msg);
  }

  // Applies the VO updates whose `to` instant the estimate has reached, in order.
  void TryVo() {
    while (!waiting_vo_.empty()) {
      const auto result = estimator_.ApplyVoUpdate(waiting_vo_.front());
      if (result.status == estimation::VoUpdateStatus::kToInFuture) return;  // retry later
      if (!result.applied()) {
        ++rejected_vo_;
        std::cerr << "state_estimator: VO update " << waiting_vo_.front().from_frame_id << "->"
                  << waiting_vo_.front().to_frame_id << " refused: " << result.reason << "\n";
      }
      waiting_vo_.pop_front();
      Publish();  // the executor waits for the pose that includes the update
    }
  }

  void AfterInput(std::int64_t utime) {
    proc_.ObserveTime(utime);
    TryVo();
    if (utime >= next_publish_) {
      Publish();
      next_publish_ = utime - (utime - next_publish_) % period_us_ + period_us_;
    }
  }

  bus::Process& proc_;
  estimation::PoseEstimator estimator_;
  const geometry::Pose start_;
  const std::int64_t period_us_;
  bool started_ = false;
  std::int64_t next_publish_ = 0;
  std::deque<estimation::VoUpdate> waiting_vo_;  // updates whose `to` is not yet reached
  std::int64_t rejected_vo_ = 0;
};

}  // namespace

int main(int argc, char** argv) {
  return bus::RunMain("state_estimator", [&]() -> int {
    bus::Process proc("state_estimator",
                      "Pose from IMU attitude and wheel odometry, corrected by VO updates.\n"
                      "Reads IMU, WHEEL_ODOMETRY, VO_UPDATE, NEW_SITE; writes POSE.\n"
                      "Config: the `estimator:` section (see configs/rover.yaml).",
                      argc, argv,
                      {{"--start", "X,Y,Z,YAW_DEG", "initial pose in the site frame (default 0,0,0,0)"},
                       {"--world", "WORLD.yaml", "simulation: start where rover_sim does, at the world's start pose "
                                                 "on its ground (--start, when given, wins)"}});
    const auto section = proc.config()["estimator"];
    const auto options = estimation::LoadEstimatorOptions(section, {"publish_hz"});
    double publish_hz = 10.0;
    section.Get("publish_hz", publish_hz, 8.0, 1000.0);
    EstimatorNode node(proc, options, StartPose(proc), publish_hz);
    node.Subscribe();
    // It acts on its inputs only: quiet (virtual time's idle strides) unless a VO update
    // waits for the inputs to reach it.
    proc.set_quiet_until([&node] { return node.waiting_vo() ? 0 : bus::Process::kQuietForGood; });
    proc.DeclarePublications({{channels::kPose}});
    proc.Run([&] {
      const auto rejected = node.rejected_vo();
      proc.SetHealth(0, rejected ? std::to_string(rejected) + " VO updates refused" : "");
    });
    return 0;
  });
}
