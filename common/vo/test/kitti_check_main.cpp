// Test-only driver: runs the VO over a KITTI-layout sequence with a constant-velocity
// prior and prints the KITTI-style average translational error and ms per frame.
// Usage: vo_kitti_check [DATASET_DIR] [vo.yaml] [--scale S]
// (The project's evaluator is tools/vo_eval; this exists to tune and check the library.)
#include "geometry/kitti_calib.hpp"
#include "vo/visual_odometry.hpp"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

using namespace rover;

static std::vector<Eigen::Isometry3d> ReadPoses(const std::string& path) {
  std::vector<Eigen::Isometry3d> poses;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream ss(line);
    Eigen::Matrix4d M = Eigen::Matrix4d::Identity();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) ss >> M(r, c);
    if (!ss) break;
    Eigen::Isometry3d T;
    T.matrix() = M;
    poses.push_back(T);
  }
  return poses;
}

int main(int argc, char** argv) {
  cv::setNumThreads(1);
  std::string dir = std::string(ROVER_DATA_DIR) + "/kitti_06_0000_0050";
  std::string yaml;
  double scale = -1;
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    if (a == "--help" || a == "-h") {
      std::cout << "usage: vo_kitti_check [DATASET_DIR] [vo.yaml] [--scale S]\n\n"
                   "Test-only driver: VO over a KITTI-layout sequence with a constant-velocity\n"
                   "prior; prints the average translational error and ms per frame. The project's\n"
                   "evaluator is vo_eval (./rover vo-eval).\n";
      return 0;
    }
    if (a == "--scale" && i + 1 < argc) scale = std::stod(argv[++i]);
    else if (a.size() > 5 && a.substr(a.size() - 5) == ".yaml") yaml = a;
    else dir = a;
  }
  vo::VoOptions opt;
  if (!yaml.empty()) opt = vo::LoadVoOptions(config::ConfigNode::LoadFile(yaml)["vo"]);
  if (scale > 0) opt.working_scale = scale;
  const auto gt = ReadPoses(dir + "/poses.txt");
  char name[64];
  std::snprintf(name, sizeof(name), "/image_0/%06d.png", 0);
  cv::Mat first = cv::imread(dir + name, cv::IMREAD_UNCHANGED);
  const int W = first.cols, H = first.rows;
  const geometry::StereoRig rig = geometry::LoadKittiCalib(dir + "/calib.txt", W, H);
  vo::VisualOdometry odo(opt);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  std::vector<Eigen::Isometry3d> est{pose};
  Eigen::Isometry3d velocity = Eigen::Isometry3d::Identity();
  Eigen::Matrix<double, 6, 6> cov = Eigen::Matrix<double, 6, 6>::Zero();
  cov.diagonal() << 0.5 * 0.5, 0.5 * 0.5, 0.5 * 0.5, 0.05 * 0.05, 0.05 * 0.05, 0.05 * 0.05;
  std::vector<double> ms, cpu_ms;
  double st[5] = {0, 0, 0, 0, 0};
  int ok = 0, n = 0;
  for (int i = 0;; ++i) {
    std::snprintf(name, sizeof(name), "%06d.png", i);
    vo::StereoImages im;
    im.left = cv::imread(dir + "/image_0/" + name, cv::IMREAD_UNCHANGED);
    im.right = cv::imread(dir + "/image_1/" + name, cv::IMREAD_UNCHANGED);
    if (im.left.empty()) break;
    im.rig = rig;
    im.frame_id = i;
    timespec c0, c1;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &c0);
    const vo::VoResult r = odo.Process(im, velocity, cov);
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &c1);
    if (i == 0) continue;
    cpu_ms.push_back((c1.tv_sec - c0.tv_sec) * 1e3 + (c1.tv_nsec - c0.tv_nsec) * 1e-6);
    ++n;
    ms.push_back(r.times.total_ms);
    st[0] += r.times.detect_ms; st[1] += r.times.stereo_ms; st[2] += r.times.track_ms;
    st[3] += r.times.ransac_ms; st[4] += r.times.ml_ms;
    if (r.status == vo::VoStatus::kOk) {
      ++ok;
      velocity = r.T_prev_curr;
    } else {
      std::printf("frame %d: %s %s\n", i, vo::ToString(r.status), r.reason.c_str());
    }
    pose = pose * velocity;
    est.push_back(pose);
    if (getenv("VO_VERBOSE")) {
      const Eigen::Isometry3d gd = gt[i - 1].inverse() * gt[i];
      const Eigen::Isometry3d e = gd.inverse() * velocity;
      std::printf("%2d det %3d mat %3d trk %3d inl %3d it %2d  %.1f ms  err %.4f m %.4f deg sig %.4f\n", i,
                  r.num_detected, r.num_matched, r.num_tracked, r.num_inliers, r.iterations,
                  r.times.total_ms, e.translation().norm(),
                  Eigen::AngleAxisd(e.linear()).angle() * 180 / M_PI,
                  std::sqrt(r.covariance.topLeftCorner<3, 3>().trace()));
    }
  }
  // KITTI-style segments of 10..50 m, every frame as a start.
  std::vector<double> dist{0};
  for (size_t i = 1; i < gt.size(); ++i)
    dist.push_back(dist.back() + (gt[i].translation() - gt[i - 1].translation()).norm());
  double terr = 0, rerr = 0;
  int segs = 0;
  for (double len : {10.0, 20.0, 30.0, 40.0, 50.0}) {
    for (size_t a = 0; a < est.size(); ++a) {
      size_t b = a;
      while (b < est.size() && dist[b] - dist[a] < len) ++b;
      if (b >= est.size()) break;
      const Eigen::Isometry3d dg = gt[a].inverse() * gt[b];
      const Eigen::Isometry3d de = est[a].inverse() * est[b];
      const Eigen::Isometry3d e = de.inverse() * dg;
      terr += e.translation().norm() / len;
      rerr += Eigen::AngleAxisd(e.linear()).angle() / len;
      ++segs;
    }
  }
  std::vector<double> sorted = ms;
  std::sort(sorted.begin(), sorted.end());
  std::sort(cpu_ms.begin(), cpu_ms.end());
  std::printf("median thread CPU time %.1f ms per frame (wall-clock figures below include waiting for a loaded machine)\n", cpu_ms[cpu_ms.size() / 2]);
  const double final_err = (est.back().translation() - gt[est.size() - 1].translation()).norm() / dist[est.size() - 1];
  std::printf("frames %d converged %d  avg trans err %.3f %%  rot %.4f deg/m  final %.3f %%  "
              "median %.1f ms  mean %.1f ms [detect %.1f stereo %.1f track %.1f ransac %.1f ml %.1f]\n",
              n, ok, 100 * terr / segs, rerr / segs * 180 / M_PI, 100 * final_err,
              sorted[sorted.size() / 2], [&] { double s = 0; for (double v : ms) s += v; return s / ms.size(); }(),
              st[0] / n, st[1] / n, st[2] / n, st[3] / n, st[4] / n);
  return 0;
}
