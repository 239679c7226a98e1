// vo_replay LOG.lcm [--config FILE] [--out FILE.csv]
//
// Runs the VO library over a recorded run's stereo frames as the visual_odometry process
// does (the prior from the frames' on-board poses, the same configuration, a baseline
// frame starting the chain again) and judges every accepted update against the
// simulator's truth at the two capture times, as the scenario summary does. One CSV line
// per update, with what the published VO_UPDATE does not carry (keyframe, whether the
// window's refinement was published, the variance factors, track ages, the whole
// covariance), so that the updates beyond the 99.7 % NEES bound can be told apart by kind.
#include "bus/channels.hpp"
#include "bus/stereo_frame_convert.hpp"
#include "config/yaml_config.hpp"
#include "geometry/pose.hpp"
#include "imaging/image_check.hpp"
#include "scenario/vo_truth.hpp"
#include "vo/motion_prior.hpp"
#include "vo/visual_odometry.hpp"

#include <lcm/lcm-cpp.hpp>
#include <rover_msgs/sim_truth_t.hpp>
#include <rover_msgs/stereo_frame_t.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

using namespace rover;

namespace {

const char* kUsage = "usage: vo_replay LOG.lcm [--config VO.yaml] [--out FILE.csv]\n";

std::vector<rover_msgs::sim_truth_t> ReadTruth(const std::string& path) {
  lcm::LogFile log(path, "r");
  if (!log.good()) throw std::runtime_error(path + ": cannot read the LCM log");
  std::vector<rover_msgs::sim_truth_t> truth;
  for (const lcm::LogEvent* ev = log.readNextEvent(); ev != nullptr; ev = log.readNextEvent()) {
    if (ev->channel != rover::channels::kSimTruth) continue;
    rover_msgs::sim_truth_t m;
    if (m.decode(ev->data, 0, ev->datalen) >= 0) truth.push_back(m);
  }
  std::sort(truth.begin(), truth.end(), [](const auto& a, const auto& b) { return a.utime < b.utime; });
  return truth;
}

// The truth's speed (m/s) and pitch rate (deg/s) around `utime`, over +-0.1 s: whether
// the rover was still when the pair was taken.
double SpeedAt(const std::vector<rover_msgs::sim_truth_t>& truth, std::int64_t utime) {
  const auto a = tools::TruthPoseAt(truth, utime - 100000), b = tools::TruthPoseAt(truth, utime + 100000);
  return a && b ? (b->translation() - a->translation()).norm() / 0.2 : -1.0;
}
double PitchRateAt(const std::vector<rover_msgs::sim_truth_t>& truth, std::int64_t utime) {
  const auto a = tools::TruthPoseAt(truth, utime - 100000), b = tools::TruthPoseAt(truth, utime + 100000);
  return a && b ? Eigen::AngleAxisd(a->linear().transpose() * b->linear()).angle() * 180 / M_PI / 0.2 : -1.0;
}

}  // namespace

int main(int argc, char** argv) {
  std::string log_path, config_path = std::string(ROVER_SOURCE_DIR) + "/configs/vo.yaml", out_path;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h") {
      std::cout << kUsage
                << "Replays a recorded run's STEREO_FRAMEs through the VO library, as visual_odometry runs\n"
                   "it, and writes one CSV line per update with its error against SIM_TRUTH and its sigma.\n";
      return 0;
    }
    if ((a == "--config" || a == "--out") && i + 1 < argc) {
      (a == "--config" ? config_path : out_path) = argv[++i];
    } else if (!a.empty() && a[0] != '-' && log_path.empty()) {
      log_path = a;
    } else {
      std::cerr << "vo_replay: unexpected argument '" << a << "'\n" << kUsage;
      return 2;
    }
  }
  if (log_path.empty()) {
    std::cerr << kUsage;
    return 2;
  }
  try {
    const config::ConfigNode config = config::ConfigNode::LoadFile(config_path);
    vo::VisualOdometry odometry(vo::LoadVoOptions(config["vo"]));
    const vo::MotionPriorOptions prior = vo::LoadMotionPriorOptions(config["visual_odometry"]);
    const std::vector<rover_msgs::sim_truth_t> truth = ReadTruth(log_path);
    std::ofstream file;
    if (!out_path.empty()) {
      file.open(out_path);
      if (!file) throw std::runtime_error(out_path + ": cannot write");
    }
    std::ostream& out = out_path.empty() ? std::cout : file;
    out << "from,to,status,keyframe,window_used,window_frames,disparity_offset_px,inliers,tracked,s0sq,cluster,track_age,"
           "moved_m,turned_deg,speed_mps,pitch_rate_dps,nees,ex,ey,ez,eroll,epitch,eyaw,sx,sy,sz,sroll,spitch,syaw,"
           "window_vf,window_cvf";
    // The whole covariance (upper triangle, row by row), so that the NEES can be taken
    // apart by direction (the weak lateral-yaw and along-sight directions) offline.
    for (int a = 0; a < 6; ++a) {
      for (int b = a; b < 6; ++b) out << ",c" << a << b;
    }
    out << '\n';
    out << std::setprecision(6);

    lcm::LogFile log(log_path, "r");
    std::optional<rover_msgs::stereo_frame_t> previous;
    imaging::ImageLimits limits;
    int accepted = 0, beyond = 0;
    double nees_sum = 0;
    for (const lcm::LogEvent* ev = log.readNextEvent(); ev != nullptr; ev = log.readNextEvent()) {
      if (ev->channel != rover::channels::kStereoFrame) continue;
      rover_msgs::stereo_frame_t frame;
      if (frame.decode(ev->data, 0, ev->datalen) < 0) continue;
      if (frame.purpose == "science" || frame.purpose == "look") continue;  // not VO pairs
      if (frame.purpose == "vo_baseline") {
        odometry.Reset();
        previous.reset();
      }
      vo::StereoImages images;
      if (!bus::ToStereoImages(frame, limits, images).empty()) continue;
      const Eigen::Isometry3d T_site_curr = bus::PoseFromMsg(frame.pose_at_capture);
      Eigen::Isometry3d prior_T = Eigen::Isometry3d::Identity();
      Eigen::Matrix<double, 6, 6> prior_cov = Eigen::Matrix<double, 6, 6>::Identity();
      if (previous) {
        prior_T = bus::PoseFromMsg(previous->pose_at_capture).inverse() * T_site_curr;
        prior_cov = vo::MotionPriorCovariance(prior_T, prior);
      }
      const vo::VoResult r = odometry.Process(images, prior_T, prior_cov);
      if (r.status == vo::VoStatus::kOk && previous) {
        rover_msgs::vo_update_t u{};
        u.status = rover_msgs::vo_update_t::STATUS_OK;
        u.from_utime = previous->utime;
        u.to_utime = frame.utime;
        for (int i = 0; i < 3; ++i) u.delta_position[i] = r.T_prev_curr.translation()[i];
        const Eigen::Quaterniond q(r.T_prev_curr.linear());
        u.delta_orientation[0] = q.w();
        u.delta_orientation[1] = q.x();
        u.delta_orientation[2] = q.y();
        u.delta_orientation[3] = q.z();
        for (int a = 0; a < 6; ++a) {
          for (int b = 0; b < 6; ++b) u.covariance[a][b] = r.covariance(a, b);
        }
        const tools::VoCheck c = tools::CheckVoUpdate(u, truth);
        if (c.nees && c.true_delta) {
          ++accepted;
          nees_sum += *c.nees;
          beyond += c.false_update();
          const geometry::Vector6d e = c.delta - *c.true_delta;
          const geometry::Vector6d& t = *c.true_delta;
          const Eigen::Isometry3d T_true = geometry::PoseFromXyzRpy(t(0), t(1), t(2), t(3), t(4), t(5));
          out << previous->frame_id << ',' << frame.frame_id << ',' << int(r.status) << ',' << r.keyframe << ','
              << r.window_used << ',' << r.window_frames << ',' << r.disparity_offset_px << ',' << r.num_inliers << ',' << r.num_tracked << ','
              << r.variance_factor << ',' << r.cluster_factor << ',' << r.track_length_mean << ','
              << T_true.translation().norm() << ',' << Eigen::AngleAxisd(T_true.linear()).angle() * 180 / M_PI
              << ',' << SpeedAt(truth, frame.utime) << ',' << PitchRateAt(truth, frame.utime) << ',' << *c.nees;
          for (int i = 0; i < 6; ++i) out << ',' << (i >= 3 ? geometry::WrapAngle(e(i)) : e(i));
          for (int i = 0; i < 6; ++i) out << ',' << std::sqrt(c.covariance(i, i));
          out << ',' << r.window_variance_factor << ',' << r.window_covariance_variance_factor;
          for (int a = 0; a < 6; ++a) {
            for (int b = a; b < 6; ++b) out << ',' << c.covariance(a, b);
          }
          out << '\n';
        }
      }
      if (r.status != vo::VoStatus::kBadInput) {
        previous = frame;
        previous->left = {};
        previous->right = {};
      }
    }
    std::cerr << "vo_replay: " << accepted << " accepted updates with truth, " << beyond
              << " beyond the 99.7 % bound (" << std::fixed << std::setprecision(2)
              << (accepted ? 100.0 * beyond / accepted : 0.0) << " %), mean NEES "
              << (accepted ? nees_sum / accepted : 0.0) << "\n";
  } catch (const std::exception& e) {
    std::cerr << "vo_replay: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
