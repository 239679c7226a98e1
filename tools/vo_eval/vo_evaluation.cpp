#include "vo_eval/vo_evaluation.hpp"

#include "geometry/pose.hpp"
#include "report/json_writer.hpp"

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <ostream>
#include <sstream>
#include <stdexcept>

namespace rover::vo_eval {
namespace {

constexpr double kDeg = M_PI / 180.0;

Eigen::Matrix<double, 6, 6> PriorCovariance(double sigma_m, double sigma_deg) {
  Eigen::Matrix<double, 6, 1> d;
  const double r = sigma_deg * kDeg;
  d << sigma_m * sigma_m, sigma_m * sigma_m, sigma_m * sigma_m, r * r, r * r, r * r;
  return d.asDiagonal();
}

std::string CsvQuoted(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) {
    if (c == '"') out += '"';
    out += c == '\n' ? ' ' : c;
  }
  return out + "\"";
}

std::string JsonString(const std::string& s) { return tools::JsonWriter::Quote(s); }

std::string JsonNumber(double v) { return tools::JsonWriter::Number(v); }

double ThreadCpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return 1e3 * static_cast<double>(ts.tv_sec) + 1e-6 * static_cast<double>(ts.tv_nsec);
}

std::string StageJson(const StageStats& s) {
  std::ostringstream o;
  o << "{\"whole\": " << JsonNumber(s.whole) << ", \"whole_cpu\": " << JsonNumber(s.cpu) << ", \"detect\": " << JsonNumber(s.detect)
    << ", \"stereo\": " << JsonNumber(s.stereo) << ", \"track\": " << JsonNumber(s.track)
    << ", \"ransac\": " << JsonNumber(s.ransac) << ", \"ml\": " << JsonNumber(s.ml)
    << ", \"window\": " << JsonNumber(s.window) << ", \"total\": " << JsonNumber(s.total) << "}";
  return o.str();
}

}  // namespace

vo::VoOptions LoadVoConfig(const std::string& path) {
  const config::ConfigNode root = config::ConfigNode::LoadFile(path);
  if (!root.Has("vo")) root.Fail("expected a `vo:` section");
  return vo::LoadVoOptions(root["vo"]);
}

std::string DefaultVoConfigPath() {
  namespace fs = std::filesystem;
  std::vector<fs::path> candidates = {fs::path(ROVER_SOURCE_DIR) / "configs" / "vo.yaml"};
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) candidates.push_back(exe.parent_path().parent_path().parent_path() / "configs" / "vo.yaml");
  for (const fs::path& p : candidates) {
    if (fs::is_regular_file(p, ec)) return p.string();
  }
  return "";
}

std::string SourcePath(const std::string& relative) {
  return (std::filesystem::path(ROVER_SOURCE_DIR) / relative).string();
}

double Median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 == 1 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

void StageStatistics(const std::vector<FrameRecord>& frames, StageStats* median, StageStats* mean) {
  std::vector<double> v[9];
  for (const FrameRecord& f : frames) {
    const vo::StageTimes& t = f.result.times;
    const double x[9] = {f.wall_ms, t.detect_ms, t.stereo_ms, t.track_ms, t.ransac_ms, t.ml_ms, t.total_ms, f.cpu_ms,
                         t.window_ms};
    for (int i = 0; i < 9; ++i) v[i].push_back(x[i]);
  }
  double med[9], avg[9];
  for (int i = 0; i < 9; ++i) {
    med[i] = Median(v[i]);
    avg[i] = 0.0;
    for (double x : v[i]) avg[i] += x;
    if (!v[i].empty()) avg[i] /= static_cast<double>(v[i].size());
  }
  *median = {med[0], med[1], med[2], med[3], med[4], med[5], med[6], med[8], med[7]};
  *mean = {avg[0], avg[1], avg[2], avg[3], avg[4], avg[5], avg[6], avg[8], avg[7]};
}

EvalInput KittiInput(const KittiSequence& sequence, int max_frames) {
  EvalInput in;
  in.name = sequence.dir;
  in.num_frames = max_frames > 0 ? std::min(max_frames, sequence.size()) : sequence.size();
  in.rig = sequence.rig;
  in.times_s.assign(sequence.times_s.begin(), sequence.times_s.begin() + in.num_frames);
  if (sequence.has_truth()) {
    in.truth.assign(sequence.truth.begin(), sequence.truth.begin() + in.num_frames);
  }
  in.load = [&sequence](int k, cv::Mat* left, cv::Mat* right) {
    StereoFrameImages images = LoadStereoFrame(sequence, k);
    *left = images.left;
    *right = images.right;
  };
  return in;
}

EvalInput SyntheticInput(const SyntheticTerrainSequence& sequence, int num_frames) {
  if (num_frames < 2) {
    throw std::invalid_argument("SyntheticInput: need at least 2 frames, got " +
                                std::to_string(num_frames));
  }
  EvalInput in;
  const SyntheticTerrainOptions& o = sequence.options();
  in.name = "synthetic terrain " + std::to_string(o.width) + "x" + std::to_string(o.height) +
            " seed " + std::to_string(o.seed);
  in.num_frames = num_frames;
  in.rig = sequence.rig();
  for (int k = 0; k < num_frames; ++k) {
    in.times_s.push_back(0.1 * k);
    in.truth.push_back(sequence.TruthPose(k));
  }
  in.truth_is_exact = true;
  in.view.down = sequence.DownInWorld();
  in.view.forward = sequence.ForwardInWorld();
  in.load = [&sequence](int k, cv::Mat* left, cv::Mat* right) { sequence.Render(k, left, right); };
  return in;
}

EvalInput RenderedInput(const RenderedDriveSequence& sequence) {
  EvalInput in;
  const RenderedDriveOptions& o = sequence.options();
  in.name = "rendered world " + sequence.world_name() + " " + std::to_string(sequence.rig().left->width()) +
            "x" + std::to_string(sequence.rig().left->height()) + " seed " + std::to_string(o.seed);
  in.num_frames = sequence.size();
  in.rig = sequence.rig();
  for (int k = 0; k < in.num_frames; ++k) {
    in.times_s.push_back(10.0 * k);
    in.truth.push_back(sequence.SitePose(k));
  }
  in.truth_is_exact = true;
  in.view.down = Eigen::Vector3d(0, 0, 1);  // site frame: Z down
  in.view.forward = sequence.SitePose(0).linear().col(0);
  in.load = [&sequence](int k, cv::Mat* left, cv::Mat* right) { sequence.Render(k, left, right); };
  return in;
}

void TruthSigmas(const EvalInput& input, const EvalOptions& options, double* sigma_m,
                 double* sigma_deg) {
  *sigma_m = options.truth_sigma_m >= 0.0 ? options.truth_sigma_m
                                          : (input.truth_is_exact ? 0.0 : kRealTruthSigmaM);
  *sigma_deg = options.truth_sigma_deg >= 0.0 ? options.truth_sigma_deg
                                              : (input.truth_is_exact ? 0.0 : kRealTruthSigmaDeg);
}

EvalReport RunEvaluation(const EvalInput& input, const EvalOptions& options, std::ostream* progress) {
  if (input.num_frames < 2) {
    throw std::invalid_argument("RunEvaluation: " + input.name + ": need at least 2 frames, got " +
                                std::to_string(input.num_frames));
  }
  vo::VisualOdometry odometry(options.vo);
  EvalReport report;
  report.has_truth = static_cast<int>(input.truth.size()) == input.num_frames;

  if (options.odometry_prior && !report.has_truth) {
    throw std::invalid_argument("RunEvaluation: " + input.name + ": an odometry prior needs truth");
  }
  Eigen::Isometry3d velocity = Eigen::Isometry3d::Identity();  // last motion, prev->curr
  bool have_velocity = false;
  std::mt19937_64 odometry_rng(options.odometry_seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  std::vector<double> nees_values, nees_exact_values;
  std::vector<Eigen::Matrix<double, 6, 1>> normalised, normalised_exact;
  TruthSigmas(input, options, &report.truth_sigma_m, &report.truth_sigma_deg);
  Eigen::Matrix<double, 6, 6> truth_cov = Eigen::Matrix<double, 6, 6>::Zero();
  truth_cov.diagonal() << Eigen::Vector3d::Constant(report.truth_sigma_m * report.truth_sigma_m),
      Eigen::Vector3d::Constant(std::pow(report.truth_sigma_deg * kDeg, 2));

  for (int k = 0; k < input.num_frames; ++k) {
    vo::StereoImages images;
    input.load(k, &images.left, &images.right);
    images.rig = input.rig;
    images.frame_id = k;
    images.utime = static_cast<std::int64_t>(std::llround(input.times_s[static_cast<std::size_t>(k)] * 1e6));

    Eigen::Matrix<double, 6, 6> prior_cov =
        have_velocity ? PriorCovariance(options.prior_sigma_m, options.prior_sigma_deg)
                      : PriorCovariance(options.initial_prior_sigma_m, options.initial_prior_sigma_deg);
    if (options.odometry_prior && k > 0) {
      const Eigen::Isometry3d truth_motion =
          input.truth[static_cast<std::size_t>(k - 1)].inverse() * input.truth[static_cast<std::size_t>(k)];
      const double s = options.odometry_noise_fraction * truth_motion.translation().norm();
      const double r = options.odometry_noise_deg * kDeg;
      velocity = truth_motion * geometry::PoseFromXyzRpy(s * gauss(odometry_rng), s * gauss(odometry_rng),
                                                         s * gauss(odometry_rng), r * gauss(odometry_rng),
                                                         r * gauss(odometry_rng), r * gauss(odometry_rng));
      prior_cov = PriorCovariance(options.prior_sigma_m, options.prior_sigma_deg);
    }
    const double cpu0 = ThreadCpuMs();
    const auto t0 = std::chrono::steady_clock::now();
    vo::VoResult result = odometry.Process(images, velocity, prior_cov);
    const auto t1 = std::chrono::steady_clock::now();
    const double cpu1 = ThreadCpuMs();

    FrameRecord rec;
    rec.frame = k;
    rec.wall_ms = std::chrono::duration<double, std::milli>(t1 - t0).count();
    rec.cpu_ms = cpu1 - cpu0;
    rec.accepted = result.status == vo::VoStatus::kOk;
    // VO-10: a failed step keeps the prior (here the constant-velocity motion).
    rec.motion = rec.accepted ? result.T_prev_curr : velocity;
    if (k > 0) {
      ++report.pairs;
      if (rec.accepted) {
        ++report.converged;
        if (!options.odometry_prior) velocity = result.T_prev_curr;
        have_velocity = true;
        if (report.has_truth) {
          const Eigen::Isometry3d truth_motion =
              input.truth[static_cast<std::size_t>(k - 1)].inverse() * input.truth[static_cast<std::size_t>(k)];
          const Eigen::Matrix<double, 6, 1> e = MotionError(truth_motion, result.T_prev_curr);
          rec.nees = Nees(e, result.covariance);
          if (rec.nees >= 0.0) {
            const Eigen::Matrix<double, 6, 6> both = result.covariance + truth_cov;
            nees_exact_values.push_back(rec.nees);
            normalised_exact.push_back(e.cwiseQuotient(result.covariance.diagonal().cwiseSqrt()));
            nees_values.push_back(Nees(e, both));
            normalised.push_back(e.cwiseQuotient(both.diagonal().cwiseSqrt()));
          }
        }
      }
    } else {
      rec.motion = Eigen::Isometry3d::Identity();
    }
    rec.result = std::move(result);
    if (progress) {
      char line[256];
      std::snprintf(line, sizeof(line), "frame %4d  %-18s inliers %4d/%4d  %7.2f ms  %s\n", k,
                    vo::ToString(rec.result.status), rec.result.num_inliers, rec.result.num_tracked,
                    rec.wall_ms, rec.result.reason.c_str());
      *progress << line << std::flush;
    }
    report.frames.push_back(std::move(rec));
  }

  PoseList motions;
  for (const FrameRecord& f : report.frames) motions.push_back(f.motion);
  report.estimate =
      ComposeMotions(motions, report.has_truth ? input.truth.front() : Eigen::Isometry3d::Identity());
  report.convergence_rate =
      report.pairs > 0 ? static_cast<double>(report.converged) / report.pairs : 0.0;
  if (report.has_truth) {
    report.accuracy = EvaluateTrajectory(input.truth, report.estimate, report.segments);
    report.nees = SummariseNees(nees_values, normalised);
    report.nees_exact_truth = SummariseNees(nees_exact_values, normalised_exact);
  }
  StageStatistics(report.frames, &report.median_ms, &report.mean_ms);
  int with_tracks = 0;
  for (std::size_t i = 1; i < report.frames.size(); ++i) {
    const vo::VoResult& r = report.frames[i].result;
    if (r.status != vo::VoStatus::kOk) continue;
    report.keyframes += r.keyframe ? 1 : 0;
    report.window_used += r.window_used ? 1 : 0;
    if (r.track_length_max > 0) {
      report.track_length_mean += r.track_length_mean;
      ++with_tracks;
    }
    report.track_length_max = std::max(report.track_length_max, r.track_length_max);
  }
  if (with_tracks > 0) report.track_length_mean /= with_tracks;
  return report;
}

void WriteEvaluation(const std::string& out_dir, const EvalInput& input, const EvalReport& report,
                     const EvalOptions& options) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::create_directories(out_dir, ec);
  if (!fs::is_directory(out_dir)) {
    throw std::runtime_error(out_dir + ": cannot create the output directory" +
                             (ec ? ": " + ec.message() : std::string()));
  }
  const std::string poses_path = (fs::path(out_dir) / "poses.txt").string();
  WriteKittiPoses(poses_path, report.estimate);

  const std::string csv_path = (fs::path(out_dir) / "frames.csv").string();
  {
    std::ofstream csv(csv_path);
    if (!csv) throw std::runtime_error(csv_path + ": cannot write");
    csv << "frame,time_s,status,reason,accepted,num_detected,num_matched,num_tracked,num_inliers,"
           "iterations,detect_ms,stereo_ms,track_ms,ransac_ms,ml_ms,total_ms,wall_ms,cpu_ms,"
           "x_m,y_m,z_m,roll_deg,pitch_deg,yaw_deg,"
           "sigma_x_m,sigma_y_m,sigma_z_m,sigma_roll_deg,sigma_pitch_deg,sigma_yaw_deg,"
           "err_x_m,err_y_m,err_z_m,err_roll_deg,err_pitch_deg,err_yaw_deg,nees,variance_factor,cluster_factor,"
           "keyframe,window_used,window_frames,window_points,window_iterations,window_ms,"
           "track_length_mean,track_length_max,disparity_offset_px\n";
    for (const FrameRecord& f : report.frames) {
      const vo::VoResult& r = f.result;
      const geometry::Vector6d m = geometry::XyzRpyFromPose(f.motion);
      char buf[512];
      std::snprintf(buf, sizeof(buf),
                    "%d,%.6f,%s,%s,%d,%d,%d,%d,%d,%d,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,"
                    "%.6f,%.6f,%.6f,%.5f,%.5f,%.5f,",
                    f.frame, input.times_s[static_cast<std::size_t>(f.frame)], vo::ToString(r.status),
                    CsvQuoted(r.reason).c_str(), f.accepted ? 1 : 0, r.num_detected, r.num_matched,
                    r.num_tracked, r.num_inliers, r.iterations, r.times.detect_ms, r.times.stereo_ms,
                    r.times.track_ms, r.times.ransac_ms, r.times.ml_ms, r.times.total_ms, f.wall_ms, f.cpu_ms,
                    m(0), m(1), m(2), m(3) / kDeg, m(4) / kDeg, m(5) / kDeg);
      csv << buf;
      // The VO's own one-sigma (accepted frames), and the error against truth.
      for (int i = 0; i < 6; ++i) {
        const double unit = i < 3 ? 1.0 : 1.0 / kDeg;
        if (f.accepted) csv << JsonNumber(std::sqrt(std::max(0.0, r.covariance(i, i))) * unit);
        csv << ",";
      }
      const bool truth = f.frame > 0 && static_cast<int>(input.truth.size()) > f.frame;
      Eigen::Matrix<double, 6, 1> e = Eigen::Matrix<double, 6, 1>::Zero();
      if (truth) {
        const auto k = static_cast<std::size_t>(f.frame);
        e = MotionError(input.truth[k - 1].inverse() * input.truth[k], f.motion);
      }
      for (int i = 0; i < 6; ++i) {
        if (truth) csv << JsonNumber(e(i) * (i < 3 ? 1.0 : 1.0 / kDeg));
        csv << ",";
      }
      if (f.nees >= 0.0) csv << JsonNumber(f.nees);
      csv << ",";
      if (f.accepted) csv << JsonNumber(r.variance_factor);
      csv << ",";
      if (f.accepted) csv << JsonNumber(r.cluster_factor);
      csv << "," << (r.keyframe ? 1 : 0) << "," << (r.window_used ? 1 : 0) << "," << r.window_frames << ","
          << r.window_points << "," << r.window_iterations << "," << JsonNumber(r.times.window_ms) << ","
          << JsonNumber(r.track_length_mean) << "," << r.track_length_max << "," << JsonNumber(r.disparity_offset_px) << "\n";
    }
    if (!csv) throw std::runtime_error(csv_path + ": write failed");
  }

  const std::string json_path = (fs::path(out_dir) / "metrics.json").string();
  {
    std::map<std::string, int> status_counts;
    for (std::size_t i = 1; i < report.frames.size(); ++i) {
      ++status_counts[vo::ToString(report.frames[i].result.status)];
    }
    std::ostringstream j;
    j << "{\n";
    j << "  \"dataset\": " << JsonString(input.name) << ",\n";
    j << "  \"frames\": " << report.frames.size() << ",\n";
    j << "  \"working_scale\": " << JsonNumber(options.vo.working_scale) << ",\n";
    j << "  \"prior\": {\"kind\": " << (options.odometry_prior ? "\"odometry (truth with noise)\"" : "\"constant velocity\"") << ", \"sigma_m\": " << JsonNumber(options.prior_sigma_m)
      << ", \"sigma_deg\": " << JsonNumber(options.prior_sigma_deg) << "},\n";
    j << "  \"convergence\": {\"pairs\": " << report.pairs << ", \"converged\": " << report.converged
      << ", \"rate\": " << JsonNumber(report.convergence_rate) << ", \"status_counts\": {";
    bool first = true;
    for (const auto& [name, count] : status_counts) {
      j << (first ? "" : ", ") << JsonString(name) << ": " << count;
      first = false;
    }
    j << "}},\n";
    if (report.has_truth) {
      const TrajectoryAccuracy& a = report.accuracy;
      j << "  \"accuracy\": {\n";
      j << "    \"definition\": \"KITTI devkit segment errors, every frame a start\",\n";
      j << "    \"segment_lengths_m\": [";
      for (std::size_t i = 0; i < report.segments.lengths_m.size(); ++i) {
        j << (i ? ", " : "") << JsonNumber(report.segments.lengths_m[i]);
      }
      j << "],\n";
      j << "    \"segments\": " << a.num_segments << ",\n";
      j << "    \"trans_error_percent\": " << JsonNumber(a.num_segments ? a.trans_error_percent : NAN) << ",\n";
      j << "    \"rot_error_deg_per_m\": " << JsonNumber(a.num_segments ? a.rot_error_deg_per_m : NAN) << ",\n";
      j << "    \"per_length\": [";
      for (std::size_t i = 0; i < a.lengths_m.size(); ++i) {
        j << (i ? ", " : "") << "{\"length_m\": " << JsonNumber(a.lengths_m[i])
          << ", \"segments\": " << a.segments_per_length[i]
          << ", \"trans_error_percent\": " << JsonNumber(a.trans_error_percent_per_length[i])
          << ", \"rot_error_deg_per_m\": " << JsonNumber(a.rot_error_deg_per_m_per_length[i]) << "}";
      }
      j << "],\n";
      j << "    \"path_length_m\": " << JsonNumber(a.path_length_m) << ",\n";
      j << "    \"final_position_error_m\": " << JsonNumber(a.final_position_error_m) << ",\n";
      j << "    \"final_position_error_percent\": " << JsonNumber(a.final_position_error_percent) << "\n";
      j << "  },\n";
      const auto nees_json = [&j](const NeesSummary& n, const char* indent) {
        j << indent << "\"count\": " << n.count << ",\n";
        j << indent << "\"mean\": " << JsonNumber(n.count ? n.mean : NAN) << ",\n";
        j << indent << "\"median\": " << JsonNumber(n.count ? n.median : NAN) << ",\n";
        j << indent << "\"max\": " << JsonNumber(n.count ? n.max : NAN) << ",\n";
        j << indent << "\"false_positives\": " << n.false_positives << ",\n";
        j << indent << "\"within_1sigma\": {\"expected\": 0.683";
        const char* names[6] = {"x", "y", "z", "roll", "pitch", "yaw"};
        for (int i = 0; i < 6; ++i) j << ", \"" << names[i] << "\": " << JsonNumber(n.within_1sigma(i));
        j << "}";
      };
      j << "  \"nees\": {\n";
      j << "    \"truth\": "
        << JsonString(input.truth_is_exact ? "exact (synthetic)"
                                           : "real: uncertain itself, by truth_sigma per pair")
        << ",\n";
      j << "    \"definition\": \"e' inv(cov + truth_cov) e per accepted pair, e = xyz and rpy of "
           "T_prev_curr minus truth, truth_cov = diag(truth_sigma_m^2 x3, truth_sigma_deg^2 x3)\",\n";
      j << "    \"truth_sigma_m\": " << JsonNumber(report.truth_sigma_m) << ",\n";
      j << "    \"truth_sigma_deg\": " << JsonNumber(report.truth_sigma_deg) << ",\n";
      j << "    \"expected_mean\": 6,\n";
      j << "    \"false_positive_chi2\": " << JsonNumber(kChi2Dof6ThreeSigma) << ",\n";
      nees_json(report.nees, "    ");
      j << ",\n    \"against_exact_truth\": {\n";
      nees_json(report.nees_exact_truth, "      ");
      j << "\n    }\n  },\n";
    } else {
      j << "  \"accuracy\": null,\n  \"nees\": null,\n";
    }
    j << "  \"window\": {\"size\": " << options.vo.window_size << ", \"keyframes\": " << report.keyframes
      << ", \"refinements_published\": " << report.window_used
      << ", \"track_length_mean\": " << JsonNumber(report.track_length_mean)
      << ", \"track_length_max\": " << report.track_length_max
      << ", \"median_ms\": " << JsonNumber(report.median_ms.window) << "},\n";
    j << "  \"timing_ms\": {\n";
    j << "    \"measured\": \"around the VO call only (image decoding excluded); stages from VoResult.times (wall clock); whole_cpu is this thread's CPU time over the call, which a busy machine does not inflate\",\n";
    j << "    \"calls\": " << report.frames.size() << ",\n";
    j << "    \"median\": " << StageJson(report.median_ms) << ",\n";
    j << "    \"mean\": " << StageJson(report.mean_ms) << "\n";
    j << "  }\n}\n";
    std::ofstream out(json_path);
    if (!out) throw std::runtime_error(json_path + ": cannot write");
    out << j.str();
    if (!out) throw std::runtime_error(json_path + ": write failed");
  }

  const std::string png_path = (fs::path(out_dir) / "trajectory.png").string();
  TopViewOptions view = input.view;
  if (view.title.empty()) {
    char title[128];
    if (report.has_truth && report.accuracy.num_segments > 0) {
      std::snprintf(title, sizeof(title), "trans %.2f %%  rot %.4f deg/m  converged %d/%d",
                    report.accuracy.trans_error_percent, report.accuracy.rot_error_deg_per_m,
                    report.converged, report.pairs);
    } else {
      std::snprintf(title, sizeof(title), "converged %d/%d", report.converged, report.pairs);
    }
    view.title = title;
  }
  const cv::Mat plot = DrawTopView(report.has_truth ? input.truth : PoseList{}, report.estimate, view);
  if (!cv::imwrite(png_path, plot)) throw std::runtime_error(png_path + ": cannot write");
}

}  // namespace rover::vo_eval
