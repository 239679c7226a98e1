// estimator_replay LOG.lcm [--config ROVER.yaml] [--set KEY=VALUE]... [--every S] [--csv FILE]
//
// Runs the pose estimator (common/estimation) again, offline, over a recorded run's inputs
// (IMU, WHEEL_ODOMETRY, VO_UPDATE, NEW_SITE, in the log's order) as the state_estimator
// process does: it starts at the run's first POSE, applies a VO update once its `to` is
// reached, and publishes a pose on the same rover-time schedule. Every pose is judged
// against SIM_TRUTH as the scenario summary judges POSE (tools/scenario/pose_truth.hpp).
// With the run's own configuration the replayed poses are the logged ones (the tool says
// by how much they differ); with `--set estimator.KEY=VALUE` it shows what a change to the
// estimator would have claimed on the same inputs, without driving again (the inputs are
// the run's: a drive the changed estimate would have steered differently is not redone).
// `--csv FILE` writes every replayed pose against truth. `--every S` prints a line every S
// seconds of rover time: distance, error and claimed sigma (horizontal, heading) and the
// NEES means so far.
#include "bus/channels.hpp"
#include "bus/convert.hpp"
#include "config/yaml_config.hpp"
#include "estimation/pose_estimator.hpp"
#include "scenario/pose_truth.hpp"
#include "scenario/vo_truth.hpp"
#include "state_estimator/estimator_messages.hpp"

#include <lcm/lcm-cpp.hpp>
#include <rover_msgs/imu_t.hpp>
#include <rover_msgs/new_site_t.hpp>
#include <rover_msgs/pose_t.hpp>
#include <rover_msgs/sim_truth_t.hpp>
#include <rover_msgs/vo_update_t.hpp>
#include <rover_msgs/wheel_odometry_t.hpp>
#include <yaml-cpp/yaml.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <deque>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

using namespace rover;

namespace {

const char* kUsage =
    "usage: estimator_replay LOG.lcm [--config ROVER.yaml] [--set estimator.KEY=VALUE]... [--every S] [--csv FILE]\n"
    "  --config: the rover config the run used (default: rover.yaml beside the log, else configs/rover.yaml)\n";

struct Args {
  std::string log, config;
  std::vector<std::pair<std::string, std::string>> sets;  // estimator keys
  double every_s = 0;
  std::string csv;  // every replayed pose against truth
};

Args ParseArgs(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string s = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw std::invalid_argument("estimator_replay: " + s + " expects a value");
      return argv[++i];
    };
    if (s == "--config") {
      a.config = value();
    } else if (s == "--set") {
      const std::string kv = value();
      const auto eq = kv.find('=');
      const std::string prefix = "estimator.";
      if (eq == std::string::npos || kv.rfind(prefix, 0) != 0 || eq == prefix.size()) {
        throw std::invalid_argument("estimator_replay: --set \"" + kv + "\": expected estimator.KEY=VALUE");
      }
      a.sets.emplace_back(kv.substr(prefix.size(), eq - prefix.size()), kv.substr(eq + 1));
    } else if (s == "--csv") {
      a.csv = value();
    } else if (s == "--every") {
      a.every_s = std::stod(value());
    } else if (s == "-h" || s == "--help") {
      std::cout << kUsage;
      std::exit(0);
    } else if (!s.empty() && s[0] == '-') {
      throw std::invalid_argument(std::string("estimator_replay: unknown option ") + s + "\n" + kUsage);
    } else if (a.log.empty()) {
      a.log = s;
    } else {
      throw std::invalid_argument("estimator_replay: one log only (got " + a.log + " and " + s + ")");
    }
  }
  if (a.log.empty()) throw std::invalid_argument(std::string("estimator_replay: missing LOG.lcm\n") + kUsage);
  if (a.config.empty()) {
    const auto beside = std::filesystem::path(a.log).parent_path() / "rover.yaml";
    a.config = std::filesystem::exists(beside) ? beside.string() : "configs/rover.yaml";
  }
  return a;
}

double HorizontalSigma(const double c[6][6]) {
  Eigen::Matrix2d P;
  P << c[0][0], c[0][1], c[1][0], c[1][1];
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(0.5 * (P + P.transpose()));
  return std::sqrt(std::max(0.0, es.eigenvalues().maxCoeff()));
}

// The state_estimator process's loop (processes/state_estimator/main.cpp) without the bus.
class Replay {
 public:
  Replay(const estimation::EstimatorOptions& options, double publish_hz)
      : estimator_(options), period_us_(static_cast<std::int64_t>(1e6 / publish_hz)) {}

  void Start(const rover_msgs::pose_t& first) { start_ = bus::PoseFromMsg(first); }
  bool can_start() const { return start_.has_value(); }

  void Imu(const rover_msgs::imu_t& m) {
    Begin(m.utime);
    estimator_.OnImu(m.utime, bus::QuaternionFromArray(m.orientation),
                     Eigen::Vector3d(m.angular_rate[0], m.angular_rate[1], m.angular_rate[2]));
    After(m.utime);
  }
  void Odometry(const rover_msgs::wheel_odometry_t& m) {
    Begin(m.utime);
    estimator_.OnWheelOdometry(state_estimator::FromMsg(m));
    After(m.utime);
  }
  void Vo(const rover_msgs::vo_update_t& m) {
    if (m.status != rover_msgs::vo_update_t::STATUS_OK || !started_) return;
    waiting_.push_back(state_estimator::FromMsg(m));
    TryVo();
  }
  void NewSite(const rover_msgs::new_site_t& m) {
    if (!started_) return;
    estimator_.NewSite(m.site_index);
    Publish();
  }

  const std::vector<rover_msgs::pose_t>& poses() const { return poses_; }
  int refused() const { return refused_; }
  const estimation::PoseEstimator& estimator() const { return estimator_; }

 private:
  void Begin(std::int64_t utime) {
    if (started_) return;
    estimator_.Reset(start_.value_or(geometry::Pose::Identity()), utime);
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
    poses_.push_back(msg);
  }
  void TryVo() {
    while (!waiting_.empty()) {
      const auto result = estimator_.ApplyVoUpdate(waiting_.front());
      if (result.status == estimation::VoUpdateStatus::kToInFuture) return;
      if (!result.applied()) ++refused_;
      waiting_.pop_front();
      Publish();
    }
  }
  void After(std::int64_t utime) {
    TryVo();
    if (utime >= next_publish_) {
      Publish();
      next_publish_ = utime - (utime - next_publish_) % period_us_ + period_us_;
    }
  }

  estimation::PoseEstimator estimator_;
  std::optional<geometry::Pose> start_;
  const std::int64_t period_us_;
  bool started_ = false;
  std::int64_t next_publish_ = 0;
  std::deque<estimation::VoUpdate> waiting_;
  std::vector<rover_msgs::pose_t> poses_;
  int refused_ = 0;
};

template <typename Msg>
std::optional<Msg> Decode(const lcm::LogEvent& ev) {
  Msg m;
  if (m.decode(ev.data, 0, ev.datalen) < 0) return std::nullopt;
  return m;
}

// One line every `every_s` of rover time, and the last pose.
void PrintTrace(const std::vector<rover_msgs::pose_t>& poses, const std::vector<rover_msgs::sim_truth_t>& truth,
                double every_s) {
  std::cout << "  rover_s   odometer_m  xy_err_m  xy_sigma_m  yaw_err_deg  yaw_sigma_deg  nees_xy_so_far  "
               "nees_yaw_so_far\n";
  std::vector<rover_msgs::pose_t> so_far;
  double next = 0;
  const std::int64_t t0 = poses.empty() ? 0 : poses.front().utime;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const auto& p = poses[i];
    so_far.push_back(p);
    const double t = static_cast<double>(p.utime - t0) * 1e-6;
    if (t < next && i + 1 != poses.size()) continue;
    next = t + every_s;
    const auto T = tools::TruthPoseAt(truth, p.utime);
    if (!T || p.site_index != 0) continue;
    const double e_xy = std::hypot(p.position[0] - T->translation().x(), p.position[1] - T->translation().y());
    const Eigen::Quaterniond q(p.orientation[0], p.orientation[1], p.orientation[2], p.orientation[3]);
    const double e_yaw = geometry::WrapAngle(geometry::RpyFromRotation(q.normalized().toRotationMatrix()).z() -
                                             geometry::RpyFromRotation(T->linear()).z());
    const auto h = tools::JudgePoses(so_far, truth);
    std::cout << std::fixed << std::setprecision(1) << std::setw(9) << t << std::setw(12) << p.odometer_m
              << std::setprecision(3) << std::setw(10) << e_xy << std::setw(12) << HorizontalSigma(p.covariance)
              << std::setw(13) << e_yaw * 180 / M_PI << std::setw(15) << std::sqrt(p.covariance[5][5]) * 180 / M_PI
              << std::setprecision(2) << std::setw(16) << (h ? h->horizontal_nees_mean : NAN) << std::setw(17)
              << (h ? h->heading_nees_mean : NAN) << "\n";
  }
}

// One line per pose of site 0 that truth covers: rover seconds, odometer, source, the
// horizontal error (site x, y), the heading error (rad), the covariance's x-y block and
// heading variance, and the true heading and position.
void WriteCsv(const std::string& path, const std::vector<rover_msgs::pose_t>& poses,
              const std::vector<rover_msgs::sim_truth_t>& truth) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("estimator_replay: --csv " + path + ": cannot write");
  out << "t_s,odometer_m,source,ex_m,ey_m,eyaw_rad,pxx,pxy,pyy,pyawyaw,true_yaw_rad,true_x_m,true_y_m\n"
      << std::setprecision(9);
  const std::int64_t t0 = poses.empty() ? 0 : poses.front().utime;
  for (const auto& p : poses) {
    const auto T = tools::TruthPoseAt(truth, p.utime);
    if (!T || p.site_index != 0) continue;
    const Eigen::Quaterniond q(p.orientation[0], p.orientation[1], p.orientation[2], p.orientation[3]);
    const double yaw_true = geometry::RpyFromRotation(T->linear()).z();
    const double e_yaw =
        geometry::WrapAngle(geometry::RpyFromRotation(q.normalized().toRotationMatrix()).z() - yaw_true);
    out << static_cast<double>(p.utime - t0) * 1e-6 << "," << p.odometer_m << "," << int(p.source) << ","
        << p.position[0] - T->translation().x() << "," << p.position[1] - T->translation().y() << "," << e_yaw << ","
        << p.covariance[0][0] << "," << p.covariance[0][1] << "," << p.covariance[1][1] << "," << p.covariance[5][5]
        << "," << yaw_true << "," << T->translation().x() << "," << T->translation().y() << "\n";
  }
}

int Run(const Args& args) {
  // The run's estimator section, with --set applied.
  YAML::Node root = YAML::LoadFile(args.config);
  YAML::Node section = root["estimator"];
  if (!section) section = YAML::Node(YAML::NodeType::Map);
  for (const auto& [key, value] : args.sets) section[key] = YAML::Load(value);
  const config::ConfigNode node(section, args.config, "estimator");
  const auto options = estimation::LoadEstimatorOptions(node, {"publish_hz"});
  double publish_hz = 10.0;
  node.Get("publish_hz", publish_hz, 8.0, 1000.0);

  lcm::LogFile log(args.log, "r");
  if (!log.good()) throw std::runtime_error(args.log + ": cannot read the LCM log");
  Replay replay(options, publish_hz);
  std::vector<rover_msgs::pose_t> logged;
  std::vector<rover_msgs::sim_truth_t> truth;
  // The inputs before the first logged POSE: the estimator starts at that pose, at the
  // first input, so they are held until it is known.
  std::vector<std::pair<std::string, std::vector<std::uint8_t>>> held;
  auto feed = [&](const std::string& channel, const void* data, int len) {
    lcm::LogEvent ev{};
    ev.channel = channel;
    ev.datalen = len;
    ev.data = const_cast<void*>(data);
    if (channel == channels::kImu) {
      if (auto m = Decode<rover_msgs::imu_t>(ev)) replay.Imu(*m);
    } else if (channel == channels::kWheelOdometry) {
      if (auto m = Decode<rover_msgs::wheel_odometry_t>(ev)) replay.Odometry(*m);
    } else if (channel == channels::kVoUpdate) {
      if (auto m = Decode<rover_msgs::vo_update_t>(ev)) replay.Vo(*m);
    } else if (channel == channels::kNewSite) {
      if (auto m = Decode<rover_msgs::new_site_t>(ev)) replay.NewSite(*m);
    }
  };
  for (const lcm::LogEvent* ev = log.readNextEvent(); ev != nullptr; ev = log.readNextEvent()) {
    if (ev->channel == channels::kSimTruth) {
      if (auto m = Decode<rover_msgs::sim_truth_t>(*ev)) truth.push_back(*m);
      continue;
    }
    if (ev->channel == channels::kPose) {
      auto m = Decode<rover_msgs::pose_t>(*ev);
      if (!m) continue;
      logged.push_back(*m);
      if (!replay.can_start()) {
        replay.Start(*m);
        for (auto& [channel, bytes] : held) feed(channel, bytes.data(), static_cast<int>(bytes.size()));
        held.clear();
      }
      continue;
    }
    if (!replay.can_start()) {
      const auto* p = static_cast<const std::uint8_t*>(ev->data);
      held.emplace_back(ev->channel, std::vector<std::uint8_t>(p, p + ev->datalen));
      continue;
    }
    feed(ev->channel, ev->data, ev->datalen);
  }
  std::sort(truth.begin(), truth.end(), [](const auto& a, const auto& b) { return a.utime < b.utime; });
  if (logged.empty() || truth.empty()) throw std::runtime_error(args.log + ": no POSE or no SIM_TRUTH in the log");

  const auto& poses = replay.poses();
  double max_dp = 0;
  const std::size_t n = std::min(poses.size(), logged.size());
  for (std::size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) max_dp = std::max(max_dp, std::abs(poses[i].position[k] - logged[i].position[k]));
  }
  std::cout << "estimator_replay: " << poses.size() << " poses replayed (" << logged.size() << " logged; "
            << replay.refused() << " VO updates refused); largest position difference from the log over the first "
            << n << ": " << max_dp << " m\n";
  if (args.every_s > 0) PrintTrace(poses, truth, args.every_s);
  if (!args.csv.empty()) WriteCsv(args.csv, poses, truth);
  auto report = [&](const char* what, const std::vector<rover_msgs::pose_t>& p) {
    const auto h = tools::JudgePoses(p, truth);
    if (!h || p.empty()) {
      std::cout << what << ": no pose to judge\n";
      return;
    }
    std::cout << std::setprecision(3) << what << ": " << h->poses << " poses, heading NEES mean "
              << h->heading_nees_mean << " (" << h->heading_beyond_pct << " % beyond 3 sigma), horizontal NEES mean "
              << h->horizontal_nees_mean << " (" << h->horizontal_beyond_pct << " % beyond); last pose: 3-sigma "
              << h->final_horizontal_3sigma_m << " m, error " << h->final_horizontal_error_m << " m, odometer "
              << p.back().odometer_m << " m\n";
  };
  report("logged  ", logged);
  report("replayed", poses);
  const double kDegPerHour = 180.0 / M_PI * 3600.0;
  std::cout << "replayed: gyro bias " << replay.estimator().gyro_bias_rad_per_s() * kDegPerHour << " deg/h, sigma "
            << replay.estimator().gyro_bias_sigma_rad_per_s() * kDegPerHour << " deg/h; VO yaw bias "
            << replay.estimator().vo_yaw_bias_rad_per_m() * 180.0 / M_PI << " deg/m, sigma "
            << replay.estimator().vo_yaw_bias_sigma_rad_per_m() * 180.0 / M_PI << " deg/m\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return Run(ParseArgs(argc, argv));
  } catch (const std::exception& e) {
    std::cerr << e.what() << "\n";
    return 2;
  }
}
