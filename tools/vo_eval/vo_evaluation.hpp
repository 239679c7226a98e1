// Runs the VO pair by pair over a stereo sequence and judges it (common/vo/README.md, "How it
// is judged"): accuracy against truth, convergence, stage times, and the honesty of the
// reported covariance (VO-13).
#pragma once

#include "vo/visual_odometry.hpp"
#include "vo_eval/kitti_sequence.hpp"
#include "vo_eval/rendered_drive.hpp"
#include "vo_eval/synthetic_terrain.hpp"
#include "vo_eval/trajectory_metrics.hpp"
#include "vo_eval/trajectory_plot.hpp"

#include <functional>
#include <iosfwd>
#include <string>
#include <vector>

namespace rover::vo_eval {

// A sequence to evaluate, from a KITTI directory or the synthetic terrain.
struct EvalInput {
  std::string name;
  int num_frames = 0;
  geometry::StereoRig rig;
  std::vector<double> times_s;
  PoseList truth;                 // empty: no accuracy section
  bool truth_is_exact = false;    // synthetic truth; KITTI's is itself uncertain by cm
  TopViewOptions view;
  // Loads (or renders) frame k. Not timed.
  std::function<void(int, cv::Mat*, cv::Mat*)> load;
};

// `max_frames` > 0 keeps only the first frames.
EvalInput KittiInput(const KittiSequence& sequence, int max_frames = 0);
// The sequence must outlive the input (the loader renders from it).
EvalInput SyntheticInput(const SyntheticTerrainSequence& sequence, int num_frames);
// A drive over a rendered world; the sequence must outlive the input.
EvalInput RenderedInput(const RenderedDriveSequence& sequence);

struct EvalOptions {
  vo::VoOptions vo;
  // With no wheel odometry the prior is the previous motion (constant velocity), with a
  // wide one-sigma: a car's or a rover's speed changes little between frames, but we must
  // not let a good prior hide a VO that needs it.
  double prior_sigma_m = 0.3;
  double prior_sigma_deg = 3.0;
  // The first pair has no previous motion: the prior is "no motion", wider still.
  double initial_prior_sigma_m = 1.0;
  double initial_prior_sigma_deg = 10.0;
  // Instead, an odometry-like prior (needs truth; the rendered drives use it, since the
  // rover has wheel odometry and an IMU): the true motion perturbed by seeded Gaussian
  // noise, odometry_noise_fraction of the step per axis and odometry_noise_deg per angle,
  // with the covariance above (prior_sigma_m, prior_sigma_deg).
  bool odometry_prior = false;
  double odometry_noise_fraction = 0.02;
  double odometry_noise_deg = 0.3;
  std::uint64_t odometry_seed = 1;
  // The truth's own one-sigma per pair and per axis, added to VO's covariance in the NEES:
  // two uncertain estimates of one motion differ by the sum of their covariances. Negative
  // means "by the kind of truth": 0 for exact (synthetic, rendered) truth, and
  // kRealTruthSigmaM / kRealTruthSigmaDeg for a real sequence's.
  double truth_sigma_m = -1.0;
  double truth_sigma_deg = -1.0;
};

// A real sequence's truth (KITTI's comes from an RTK GPS/INS, an OXTS RT3003): centimetres
// per pair, and 0.03 deg, the unit's roll and pitch one-sigma, taken for all three angles
// (its heading is worse, 0.1 deg; the smaller figure keeps the NEES on the strict side).
constexpr double kRealTruthSigmaM = 0.01;
constexpr double kRealTruthSigmaDeg = 0.03;

// The truth sigmas an evaluation of `input` uses: the options', or by the truth's kind.
void TruthSigmas(const EvalInput& input, const EvalOptions& options, double* sigma_m,
                 double* sigma_deg);

struct FrameRecord {
  int frame = 0;
  vo::VoResult result;
  double wall_ms = 0.0;            // around the VO call only
  // This thread's CPU time over the same call: on a shared machine the wall clock also
  // counts the time other processes held the core, the CPU time does not.
  double cpu_ms = 0.0;
  bool accepted = false;           // status kOk: the VO motion enters the trajectory
  Eigen::Isometry3d motion = Eigen::Isometry3d::Identity();  // used in the trajectory
  double nees = -1.0;              // accepted frames with truth and a valid covariance
};

struct StageStats {
  double whole = 0, detect = 0, stereo = 0, track = 0, ransac = 0, ml = 0, total = 0;
  double window = 0;  // sliding-window refinement (windowed mode)
  double cpu = 0;  // thread CPU time of the whole call
};

struct EvalReport {
  std::vector<FrameRecord> frames;
  PoseList estimate;               // KITTI-style, starting at truth[0] (or identity)
  int pairs = 0;                   // frames after the first
  int converged = 0;               // pairs with status kOk
  double convergence_rate = 0.0;
  bool has_truth = false;
  TrajectoryAccuracy accuracy;
  SegmentOptions segments;
  // Against the truth with its own uncertainty (EvalOptions::truth_sigma_*): the figure
  // to hold against 6. And against the truth taken as exact: for a real sequence an upper
  // bound, which also counts the truth's errors. Equal where the truth is exact.
  NeesSummary nees;
  NeesSummary nees_exact_truth;
  double truth_sigma_m = 0.0, truth_sigma_deg = 0.0;
  // Windowed mode: lengths (pairs seen) of the tracks VO-8 used, over accepted pairs
  // (mean of the per-pair means, and the longest), keyframes, refinements published.
  double track_length_mean = 0;
  int track_length_max = 0;
  int keyframes = 0, window_used = 0;
  StageStats median_ms;            // over every VO call
  StageStats mean_ms;
};

// `progress` (optional) gets one line per frame.
EvalReport RunEvaluation(const EvalInput& input, const EvalOptions& options,
                         std::ostream* progress = nullptr);

// Writes DIR/poses.txt, frames.csv, metrics.json and trajectory.png (DIR is created).
// Throws std::runtime_error naming the file that cannot be written.
void WriteEvaluation(const std::string& out_dir, const EvalInput& input,
                     const EvalReport& report, const EvalOptions& options);

// Median and mean of each stage over the records.
void StageStatistics(const std::vector<FrameRecord>& frames, StageStats* median, StageStats* mean);

double Median(std::vector<double> values);

// The `vo:` section of a VO config file. Throws config::ConfigError naming the file/key.
vo::VoOptions LoadVoConfig(const std::string& path);
// configs/vo.yaml of the source tree this program was built from, or "" if it is absent.
std::string DefaultVoConfigPath();
// A file of the source tree this program was built from (no check that it exists).
std::string SourcePath(const std::string& relative);

}  // namespace rover::vo_eval
