// vo_eval: runs the VO over a KITTI-layout stereo sequence, over a synthetic textured
// terrain, or over a drive across a rendered catalogue world, the last two with exact
// motion (VO-13), and writes poses.txt, frames.csv, metrics.json and
// trajectory.png. Exit code 2 on a bad dataset, config or argument.
#include "vo_eval/vo_evaluation.hpp"

#include "config/yaml_config.hpp"

#include <opencv2/core.hpp>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <string>

namespace {

constexpr const char* kUsage =
    "usage: vo_eval DATASET_DIR --out DIR [options]\n"
    "       vo_eval --synthetic --out DIR [--frames N] [--size PIXELS] [options]\n"
    "       vo_eval --world WORLD.yaml --out DIR [--rig RIG.yaml] [--frames N] [--size PIXELS]\n"
    "               [--step-m X] [--turn-step-deg X] [options]\n"
    "options:\n"
    "  --config FILE          VO config with a `vo:` section (default: configs/vo.yaml)\n"
    "  --seed N               RANSAC seed, and the synthetic terrain's or the drive's seed (default 1)\n"
    "  --frames N             use only the first N frames (synthetic default 40: 11.7 m, so 10 m\n"
    "                         segments exist; world default 30)\n"
    "  --size PIXELS          synthetic image side (default 1024); world image width (default 512)\n"
    "  --rig FILE             world: the stereo rig (default configs/cameras/navcam_pinhole.yaml)\n"
    "  --step-m X             world: step along the heading per frame (default 0.4)\n"
    "  --turn-step-deg X      world: largest heading change per frame (default 4)\n"
    "  --working-scale S      override vo.working_scale (1, 0.5 or 0.25)\n"
    "  --window-size N        override vo.window_size (0: the frame-to-frame VO, no window)\n"
    "  --prior-sigma-m X      constant-velocity prior one-sigma, metres (default 0.3)\n"
    "  --prior-sigma-deg X    constant-velocity prior one-sigma, degrees (default 3)\n"
    "  --truth-sigma-m X      the truth's own one-sigma per pair and axis, metres, added to VO's\n"
    "                         covariance in the NEES (default: 0 for exact truth, 0.01 for a\n"
    "                         real sequence)\n"
    "  --truth-sigma-deg X    the same for angles, degrees (default 0, or 0.03 for real truth)\n"
    "  --quiet                no per-frame lines\n";

struct Args {
  std::string dataset, out, config, world, rig;
  bool synthetic = false, quiet = false;
  long seed = 1;
  bool seed_given = false;
  int frames = 0, size = 0;
  double step_m = 0.4, turn_step_deg = 4.0;
  int window_size = -1;
  double working_scale = 0.0, prior_sigma_m = -1.0, prior_sigma_deg = -1.0;
  double truth_sigma_m = -1.0, truth_sigma_deg = -1.0;  // negative: by the truth's kind
};

[[noreturn]] void BadArgs(const std::string& message) {
  std::cerr << "vo_eval: " << message << "\n" << kUsage;
  std::exit(2);
}

double NumberArg(const std::string& flag, const char* text) {
  char* end = nullptr;
  const double v = std::strtod(text, &end);
  if (end == text || *end != '\0') BadArgs(flag + ": expected a number, got \"" + text + "\"");
  return v;
}

double NonNegative(const std::string& flag, double v) {
  if (!(v >= 0.0) || !std::isfinite(v)) BadArgs(flag + ": expected a finite number >= 0");
  return v;
}

Args Parse(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string s = argv[i];
    auto value = [&]() -> const char* {
      if (i + 1 >= argc) BadArgs(s + ": expected a value");
      return argv[++i];
    };
    if (s == "--out") a.out = value();
    else if (s == "--config") a.config = value();
    else if (s == "--synthetic") a.synthetic = true;
    else if (s == "--world") a.world = value();
    else if (s == "--rig") a.rig = value();
    else if (s == "--step-m") a.step_m = NumberArg(s, value());
    else if (s == "--turn-step-deg") a.turn_step_deg = NumberArg(s, value());
    else if (s == "--quiet") a.quiet = true;
    else if (s == "--seed") { a.seed = static_cast<long>(NumberArg(s, value())); a.seed_given = true; }
    else if (s == "--frames") a.frames = static_cast<int>(NumberArg(s, value()));
    else if (s == "--size") a.size = static_cast<int>(NumberArg(s, value()));
    else if (s == "--working-scale") a.working_scale = NumberArg(s, value());
    else if (s == "--window-size") {
      const double v = NumberArg(s, value());
      if (v < 0 || v > 10 || v != static_cast<int>(v)) BadArgs("--window-size: expected an integer 0..10");
      a.window_size = static_cast<int>(v);
    }
    else if (s == "--prior-sigma-m") a.prior_sigma_m = NumberArg(s, value());
    else if (s == "--prior-sigma-deg") a.prior_sigma_deg = NumberArg(s, value());
    else if (s == "--truth-sigma-m") a.truth_sigma_m = NonNegative(s, NumberArg(s, value()));
    else if (s == "--truth-sigma-deg") a.truth_sigma_deg = NonNegative(s, NumberArg(s, value()));
    else if (s == "-h" || s == "--help") { std::cout << kUsage; std::exit(0); }
    else if (!s.empty() && s[0] == '-') BadArgs("unknown option " + s);
    else if (a.dataset.empty()) a.dataset = s;
    else BadArgs("unexpected argument " + s);
  }
  if (a.out.empty()) BadArgs("--out DIR is required");
  if (int(a.synthetic) + int(!a.world.empty()) + int(!a.dataset.empty()) != 1) {
    BadArgs("give one of DATASET_DIR, --synthetic or --world WORLD.yaml");
  }
  if (a.frames < 0 || ((a.synthetic || !a.world.empty()) && a.frames == 1)) {
    BadArgs("--frames: expected at least 2");
  }
  if (a.size == 0) a.size = a.world.empty() ? 1024 : 512;
  if (a.size < 64) BadArgs("--size: expected at least 64 pixels, got " + std::to_string(a.size));
  if (a.seed < 0) BadArgs("--seed: expected a non-negative integer");
  return a;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace rover;
  const Args args = Parse(argc, argv);
  // The time target is per frame on one core: no OpenCV worker threads.
  cv::setNumThreads(1);
  try {
    std::string config_path = args.config;
    if (config_path.empty()) {
      config_path = vo_eval::DefaultVoConfigPath();
      if (config_path.empty()) {
        std::cerr << "vo_eval: configs/vo.yaml not found beside the source tree; give --config FILE\n";
        return 2;
      }
    }
    vo_eval::EvalOptions options;
    options.vo = vo_eval::LoadVoConfig(config_path);
    if (args.seed_given) options.vo.ransac_seed = static_cast<std::uint64_t>(args.seed);
    if (args.working_scale > 0.0) options.vo.working_scale = args.working_scale;
    if (args.window_size >= 0) options.vo.window_size = args.window_size;
    if (args.prior_sigma_m > 0.0) options.prior_sigma_m = args.prior_sigma_m;
    if (args.prior_sigma_deg > 0.0) options.prior_sigma_deg = args.prior_sigma_deg;
    options.truth_sigma_m = args.truth_sigma_m;
    options.truth_sigma_deg = args.truth_sigma_deg;
    vo::ValidateVoOptions(options.vo);

    vo_eval::EvalInput input;
    vo_eval::KittiSequence kitti;
    std::unique_ptr<vo_eval::SyntheticTerrainSequence> terrain;
    std::unique_ptr<vo_eval::RenderedDriveSequence> drive;
    if (!args.world.empty()) {
      vo_eval::RenderedDriveOptions d;
      d.world_path = args.world;
      d.rig_path = args.rig.empty() ? vo_eval::SourcePath("configs/cameras/navcam_pinhole.yaml") : args.rig;
      d.size = args.size;
      d.frames = args.frames > 0 ? args.frames : 30;
      d.step_m = args.step_m;
      d.turn_step_deg = args.turn_step_deg;
      d.seed = static_cast<std::uint64_t>(args.seed);
      drive = std::make_unique<vo_eval::RenderedDriveSequence>(d);
      input = vo_eval::RenderedInput(*drive);
      // The rover has wheel odometry and an IMU: the prior is the true motion with
      // odometry-like noise, not constant velocity.
      options.odometry_prior = true;
      options.odometry_seed = d.seed;
    } else if (args.synthetic) {
      vo_eval::SyntheticTerrainOptions t;
      t.width = t.height = args.size;
      t.seed = static_cast<std::uint64_t>(args.seed);
      terrain = std::make_unique<vo_eval::SyntheticTerrainSequence>(t);
      input = vo_eval::SyntheticInput(*terrain, args.frames > 0 ? args.frames : 40);
    } else {
      kitti = vo_eval::OpenKittiSequence(args.dataset);
      input = vo_eval::KittiInput(kitti, args.frames);
    }
    std::cout << "vo_eval: " << input.name << ": " << input.num_frames << " frames, config "
              << config_path << "\n";
    const vo_eval::EvalReport report =
        vo_eval::RunEvaluation(input, options, args.quiet ? nullptr : &std::cout);
    vo_eval::WriteEvaluation(args.out, input, report, options);

    std::printf("converged %d/%d pairs (%.1f %%)\n", report.converged, report.pairs,
                100.0 * report.convergence_rate);
    if (report.has_truth) {
      const auto& a = report.accuracy;
      std::printf("translational error %.3f %%, rotational error %.4f deg/m over %d segments; "
                  "final position error %.3f m (%.2f %% of %.2f m)\n",
                  a.trans_error_percent, a.rot_error_deg_per_m, a.num_segments,
                  a.final_position_error_m, a.final_position_error_percent, a.path_length_m);
      std::printf("NEES mean %.2f (expect 6) over %d accepted pairs, %d beyond 3 sigma",
                  report.nees.mean, report.nees.count, report.nees.false_positives);
      if (report.truth_sigma_m > 0.0 || report.truth_sigma_deg > 0.0) {
        std::printf(", with the truth uncertain by %.3g m and %.3g deg a pair; taking the truth "
                    "as exact: mean %.2f, %d beyond\n",
                    report.truth_sigma_m, report.truth_sigma_deg, report.nees_exact_truth.mean,
                    report.nees_exact_truth.false_positives);
      } else {
        std::printf(" (exact truth)\n");
      }
    }
    std::printf("ms per frame: median %.2f (detect %.2f stereo %.2f track %.2f ransac %.2f ml %.2f), "
                "mean %.2f; CPU median %.2f\n",
                report.median_ms.whole, report.median_ms.detect, report.median_ms.stereo,
                report.median_ms.track, report.median_ms.ransac, report.median_ms.ml,
                report.mean_ms.whole, report.median_ms.cpu);
    if (options.vo.window_size >= 2) {
      std::printf("window %d: %d keyframes, %d refinements published; tracks used by VO-8: mean length %.2f "
                  "pairs, longest %d; window median %.2f ms\n",
                  options.vo.window_size, report.keyframes, report.window_used, report.track_length_mean,
                  report.track_length_max, report.median_ms.window);
    } else {
      std::printf("window off (frame-to-frame)\n");
    }
    std::printf("wrote %s/{poses.txt,frames.csv,metrics.json,trajectory.png}\n", args.out.c_str());
    return 0;
  } catch (const vo_eval::DatasetError& e) {
    std::cerr << "vo_eval: " << e.what() << "\n";
    return 2;
  } catch (const config::ConfigError& e) {
    std::cerr << "vo_eval: " << e.what() << "\n";
    return 2;
  } catch (const std::invalid_argument& e) {
    std::cerr << "vo_eval: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "vo_eval: " << e.what() << "\n";
    return 1;
  }
}
