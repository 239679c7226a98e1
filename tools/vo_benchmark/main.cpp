// vo_benchmark: median milliseconds per stereo pair, split by VO stage, on one core
// (common/vo/README.md "How it is judged": 1024x1024, 512x512 and KITTI size). Images are
// decoded or rendered before timing; only the VO call is timed.
#include "vo_eval/vo_evaluation.hpp"

#include <opencv2/core.hpp>

#include <sched.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

namespace {

constexpr const char* kUsage =
    "usage: vo_benchmark [--kitti DIR] [--frames N] [--config FILE] [--working-scale S]\n"
    "  --kitti DIR        KITTI-layout sequence (default: the build's ROVER_DATA_DIR/kitti_06_0000_0050 if present)\n"
    "  --frames N         frames per input (default: all KITTI frames, 20 synthetic)\n"
    "  --config FILE      VO config (default: configs/vo.yaml)\n"
    "  --working-scale S  override vo.working_scale for every input\n";

[[noreturn]] void BadArgs(const std::string& message) {
  std::cerr << "vo_benchmark: " << message << "\n" << kUsage;
  std::exit(2);
}

// One core, one thread: the figures must not depend on how many cores are idle.
int PinToOneCore() {
  cv::setNumThreads(1);
  cpu_set_t current;
  CPU_ZERO(&current);
  if (sched_getaffinity(0, sizeof(current), &current) != 0) return -1;
  for (int cpu = 0; cpu < CPU_SETSIZE; ++cpu) {
    if (!CPU_ISSET(cpu, &current)) continue;
    cpu_set_t one;
    CPU_ZERO(&one);
    CPU_SET(cpu, &one);
    return sched_setaffinity(0, sizeof(one), &one) == 0 ? cpu : -1;
  }
  return -1;
}

// Loads every frame up front so that decoding and rendering stay out of the timing and
// out of the caches between calls.
rover::vo_eval::EvalInput Preloaded(const rover::vo_eval::EvalInput& input,
                                    std::vector<cv::Mat>* lefts, std::vector<cv::Mat>* rights) {
  lefts->resize(static_cast<std::size_t>(input.num_frames));
  rights->resize(static_cast<std::size_t>(input.num_frames));
  for (int k = 0; k < input.num_frames; ++k) input.load(k, &(*lefts)[k], &(*rights)[k]);
  rover::vo_eval::EvalInput out = input;
  out.load = [lefts, rights](int k, cv::Mat* l, cv::Mat* r) {
    *l = (*lefts)[static_cast<std::size_t>(k)];
    *r = (*rights)[static_cast<std::size_t>(k)];
  };
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace rover;
  std::string kitti_dir, config_path;
  int frames = 0;
  double working_scale = 0.0;
  for (int i = 1; i < argc; ++i) {
    const std::string s = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) BadArgs(s + ": expected a value");
      return argv[++i];
    };
    if (s == "--kitti") kitti_dir = value();
    else if (s == "--config") config_path = value();
    else if (s == "--frames") {
      const std::string v = value();
      frames = std::atoi(v.c_str());
      if (frames < 2) BadArgs("--frames: expected an integer >= 2, got \"" + v + "\"");
    } else if (s == "--working-scale") {
      const std::string v = value();
      working_scale = std::atof(v.c_str());
      if (!(working_scale > 0.0)) BadArgs("--working-scale: expected a number > 0, got \"" + v + "\"");
    } else if (s == "-h" || s == "--help") {
      std::cout << kUsage;
      return 0;
    } else {
      BadArgs("unknown argument " + s);
    }
  }
  const bool kitti_given = !kitti_dir.empty();
  if (!kitti_given) kitti_dir = std::string(ROVER_DATA_DIR) + "/kitti_06_0000_0050";

  try {
    if (config_path.empty()) config_path = vo_eval::DefaultVoConfigPath();
    if (config_path.empty()) {
      std::cerr << "vo_benchmark: configs/vo.yaml not found beside the source tree; give --config FILE\n";
      return 2;
    }
    vo_eval::EvalOptions options;
    options.vo = vo_eval::LoadVoConfig(config_path);
    if (working_scale > 0.0) options.vo.working_scale = working_scale;
    vo::ValidateVoOptions(options.vo);

    const int cpu = PinToOneCore();
    std::printf("vo_benchmark: config %s, working_scale %g, pinned to CPU %d, OpenCV threads %d\n",
                config_path.c_str(), options.vo.working_scale, cpu, cv::getNumThreads());

    // Both modes in the same run, so that their times are comparable on a busy machine:
    // the config's (windowed by default) and the MER frame-to-frame VO (window_size 0).
    vo_eval::EvalOptions frame_to_frame = options;
    frame_to_frame.vo.window_size = 0;
    struct Row {
      std::string name, mode;
      int width, height, frames, converged;
      vo_eval::StageStats median;
    };
    std::vector<Row> rows;
    auto run = [&](const std::string& name, const vo_eval::EvalInput& input) {
      std::vector<cv::Mat> lefts, rights;
      const vo_eval::EvalInput pre = Preloaded(input, &lefts, &rights);
      for (const vo_eval::EvalOptions* o : {&options, &frame_to_frame}) {
        const vo_eval::EvalReport report = vo_eval::RunEvaluation(pre, *o);
        const std::string mode = o->vo.window_size >= 2 ? "window " + std::to_string(o->vo.window_size) : "frame-to-frame";
        rows.push_back({name, mode, lefts[0].cols, lefts[0].rows, input.num_frames, report.converged,
                        report.median_ms});
        std::fprintf(stderr, "  %s (%s): %d frames done\n", name.c_str(), mode.c_str(), input.num_frames);
      }
    };

    std::error_code ec;
    vo_eval::KittiSequence kitti;
    if (std::filesystem::is_directory(kitti_dir, ec)) {
      kitti = vo_eval::OpenKittiSequence(kitti_dir);
      run("KITTI " + std::filesystem::path(kitti_dir).filename().string(), vo_eval::KittiInput(kitti, frames));
    } else if (kitti_given) {
      throw vo_eval::DatasetError(kitti_dir + ": expected a KITTI-layout dataset directory, not found");
    } else {
      std::printf("(no KITTI sequence at %s: skipped)\n", kitti_dir.c_str());
    }
    for (int size : {1024, 512}) {
      vo_eval::SyntheticTerrainOptions t;
      t.width = t.height = size;
      const vo_eval::SyntheticTerrainSequence terrain(t);
      run("synthetic terrain", vo_eval::SyntheticInput(terrain, frames > 0 ? frames : 20));
    }

    std::printf("\nmedian ms per stereo pair (one core; the VO call only)\n");
    std::printf("%-26s %-15s %10s %7s %9s %7s %7s %7s %7s %7s %7s %7s %7s %7s\n", "input", "mode", "size",
                "frames", "converged", "detect", "stereo", "track", "ransac", "ml", "window", "total", "wall",
                "cpu");
    for (const Row& r : rows) {
      char size[32];
      std::snprintf(size, sizeof(size), "%dx%d", r.width, r.height);
      std::printf("%-26s %-15s %10s %7d %5d/%-3d %7.2f %7.2f %7.2f %7.2f %7.2f %7.2f %7.2f %7.2f %7.2f\n",
                  r.name.c_str(), r.mode.c_str(), size, r.frames, r.converged, r.frames - 1, r.median.detect,
                  r.median.stereo, r.median.track, r.median.ransac, r.median.ml, r.median.window,
                  r.median.total, r.median.whole, r.median.cpu);
    }
    std::printf("(stage medians are taken separately, so they need not add up to the total; "
                "'wall' is timed around the call by the benchmark, 'cpu' is the thread's CPU time "
                "over the same call, which other processes on a busy machine do not inflate)\n");
    return 0;
  } catch (const vo_eval::DatasetError& e) {
    std::cerr << "vo_benchmark: " << e.what() << "\n";
    return 2;
  } catch (const config::ConfigError& e) {
    std::cerr << "vo_benchmark: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "vo_benchmark: " << e.what() << "\n";
    return 1;
  }
}
