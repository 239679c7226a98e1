// ./rover bench scenario: how fast, and at what CPU cost, the whole process set simulates a
// drive. Runs configs/scenarios/bench_20m.yaml and the demo (or the scenarios given) several
// times through scenario_runner, once per rate of --rates (default: 50 and max, in one run),
// and prints per rate the rover time covered, the wall time, their ratio, the CPU time of the
// whole set (user + sys of scenario_runner and every process it started: the children's
// rusage, which counts every descendant that was waited for) per rover-hour, and the log
// digest (virtual time: every rate must give the same one).
// --against DIR runs the same in another checkout of the project, built (its
// build/bin/scenario_runner and the processes beside it, its own scenarios and configs),
// in the same sitting, run for run in turn, so that a change's CPU figure and the code
// before it are measured under one load.
// Targets: at least 20x faster than real time at MER speed (~4 cm/s); the unlimited rate at
// most half of 50x's wall time.
#include "bus/process.hpp"
#include "launch/process_set.hpp"

#include <sys/resource.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

struct Options {
  std::vector<std::string> scenarios;
  int runs = 3;
  std::vector<std::string> rates = {"50", "max"};
  std::string against;  // another built checkout's root, or empty
};

// One run's figures.
struct Run {
  double wall_s = 0, rover_s = 0, distance_m = 0, cpu_s = 0;
  std::string digest;
};

// The figures of one build at one rate: medians over the runs.
struct RateFigures {
  double wall_s = 0, rover_s = 0, distance_m = 0, cpu_s = 0, cpu_per_rover_hour = 0, times_real = 0;
  std::string digest;
};

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// User + sys of every child waited for so far (scenario_runner's shell, scenario_runner, and
// through them every process of the set and the recorder).
double ChildrenCpuSeconds() {
  rusage ru{};
  getrusage(RUSAGE_CHILDREN, &ru);
  return rover::launch::CpuSeconds(ru);
}

// Runs `scenario` (a path relative to `root`, the checkout whose configs it names) with
// `bin`'s programs, into `out` (absolute).
Run RunOnce(const std::string& root, const std::string& bin, const std::string& scenario, const std::string& rate,
            const std::string& out) {
  const std::string cmd = "cd '" + root + "' && '" + bin + "/scenario_runner' '" + scenario +
                          "' --quiet --no-plot --rate " + rate + " --out '" + out + "' > /dev/null";
  const double cpu_before = ChildrenCpuSeconds();
  if (std::system(cmd.c_str()) != 0) throw std::runtime_error("scenario run failed: " + cmd);
  Run run;
  run.cpu_s = ChildrenCpuSeconds() - cpu_before;
  const auto s = YAML::LoadFile(out + "/summary.json");
  if (s["outcome"].as<std::string>() != "completed") {
    throw std::runtime_error(out + "/summary.json: outcome " + s["outcome"].as<std::string>() +
                             " (expected completed)");
  }
  run.wall_s = s["wall_time_s"].as<double>();
  run.rover_s = s["rover_time_s"].as<double>();
  run.distance_m = s["distance_travelled_m"].as<double>();
  run.digest = s["log_digest"] ? s["log_digest"].as<std::string>() : "-";
  return run;
}

// One build's side of a comparison: which checkout, which programs, which scenario file.
struct Build {
  std::string label, root, bin, scenario;
};

// The medians of one build's runs.
RateFigures Medians(const std::vector<Run>& runs) {
  std::vector<double> wall, rover, distance, cpu, cpu_per_hour, times_real;
  RateFigures f;
  for (const Run& run : runs) {
    wall.push_back(run.wall_s);
    rover.push_back(run.rover_s);
    distance.push_back(run.distance_m);
    cpu.push_back(run.cpu_s);
    cpu_per_hour.push_back(run.cpu_s / (run.rover_s / 3600.0));
    times_real.push_back(run.rover_s / run.wall_s);
    f.digest = f.digest.empty() || f.digest == run.digest ? run.digest : "differs between runs";
  }
  f.wall_s = Median(wall);
  f.rover_s = Median(rover);
  f.distance_m = Median(distance);
  f.cpu_s = Median(cpu);
  f.cpu_per_rover_hour = Median(cpu_per_hour);
  f.times_real = Median(times_real);
  return f;
}

// Each build's figures at `rate`. The builds take turns, run by run (this, against, this,
// ...), so that a load that comes and goes during the sitting (a shared machine) weighs on
// both alike rather than on whichever ran while it lasted.
std::vector<RateFigures> BenchRate(const Options& options, const std::vector<Build>& builds, const std::string& rate) {
  std::vector<std::vector<Run>> runs(builds.size());
  for (int r = 0; r < options.runs; ++r) {
    for (std::size_t b = 0; b < builds.size(); ++b) {
      const Build& build = builds[b];
      const std::string stem = std::filesystem::path(build.scenario).stem().string();
      const std::string out = std::filesystem::absolute("out/bench_scenario_" + stem + "_" + build.label + "_" + rate +
                                                        "_" + std::to_string(r)).string();
      runs[b].push_back(RunOnce(build.root, build.bin, build.scenario, rate, out));
    }
  }
  std::vector<RateFigures> figures;
  for (const auto& one : runs) figures.push_back(Medians(one));
  return figures;
}

void PrintRow(const std::string& label, const std::string& rate, const RateFigures& f) {
  std::printf("  %-7s %-6s %10.2f %9.1f %8.1f %10.1f %8.1f %12.1f  %s\n", label.c_str(), rate.c_str(), f.distance_m,
              f.rover_s, f.wall_s, f.times_real, f.cpu_s, f.cpu_per_rover_hour,
              (f.digest.size() == 64 ? f.digest.substr(0, 16) : f.digest).c_str());  // a hex digest, shortened
}

void BenchScenario(const Options& options, const std::string& scenario) {
  std::printf("scenario %s, %d runs per rate (medians)\n", scenario.c_str(), options.runs);
  std::printf("  %-7s %-6s %10s %9s %8s %10s %8s %12s  %s\n", "build", "rate", "distance m", "rover s", "wall s",
              "x realtime", "CPU s", "CPU s/rov-h", "log digest");
  std::vector<Build> builds = {{"this", std::filesystem::current_path().string(), rover::launch::BinDir(), scenario}};
  if (!options.against.empty()) {
    // The other checkout's own copy of the scenario: the same path inside it.
    const std::string there = std::filesystem::path(scenario).lexically_proximate(std::filesystem::current_path()).string();
    builds.push_back({"against", options.against, options.against + "/build/bin", there});
  }
  std::vector<double> walls;
  for (const auto& rate : options.rates) {
    const std::vector<RateFigures> figures = BenchRate(options, builds, rate);
    for (std::size_t b = 0; b < builds.size(); ++b) PrintRow(builds[b].label, rate, figures[b]);
    walls.push_back(figures[0].wall_s);
    if (figures.size() < 2) continue;
    std::printf("  %-7s %-6s CPU per rover-hour: against / this = %.2f\n", "", rate.c_str(),
                figures[1].cpu_per_rover_hour / figures[0].cpu_per_rover_hour);
  }
  if (walls.size() >= 2) {
    std::printf("  wall time %s / %s: %.2f   (target <= 0.5 for max / 50)\n", options.rates.back().c_str(),
                options.rates.front().c_str(), walls.back() / walls.front());
  }
}

Options ParseArguments(int argc, char** argv) {
  Options o;
  auto value = [&](int& i, const std::string& flag) -> std::string {
    if (i + 1 >= argc) throw std::runtime_error("scenario_benchmark: " + flag + " needs a value");
    return argv[++i];
  };
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--runs") {
      const std::string v = value(i, arg);
      o.runs = std::atoi(v.c_str());
      if (o.runs < 1) throw std::runtime_error("scenario_benchmark: --runs " + v + ": expected a whole number >= 1");
    } else if (arg == "--rates") {
      o.rates.clear();
      std::stringstream ss(value(i, arg));
      for (std::string r; std::getline(ss, r, ',');)
        if (!r.empty()) o.rates.push_back(r);
      if (o.rates.empty()) throw std::runtime_error("scenario_benchmark: --rates: expected R1,R2,... (a number or max)");
    } else if (arg == "--against") {
      o.against = std::filesystem::absolute(value(i, arg)).lexically_normal().string();
      if (!std::filesystem::is_regular_file(o.against + "/build/bin/scenario_runner")) {
        throw std::runtime_error("scenario_benchmark: --against " + o.against +
                                 ": expected another checkout of the project, built (build/bin/scenario_runner)");
      }
    } else if (!arg.empty() && arg[0] == '-') {
      throw std::runtime_error("scenario_benchmark: unknown option " + arg + " (see --help)");
    } else {
      o.scenarios.push_back(arg);
    }
  }
  if (o.scenarios.empty()) o.scenarios = {"configs/scenarios/bench_20m.yaml", "configs/scenarios/demo.yaml"};
  return o;
}

}  // namespace

int main(int argc, char** argv) {
  return rover::bus::RunMain("scenario_benchmark", [&]() -> int {
    for (int i = 1; i < argc; ++i) {
      if (std::string(argv[i]) == "--help") {
        std::cout << "usage: scenario_benchmark [SCENARIO.yaml...] [--runs N] [--rates R1,R2,...] [--against CHECKOUT]\n"
                     "  (default: configs/scenarios/bench_20m.yaml and demo.yaml, --runs 3 --rates 50,max;\n"
                     "  a rate is rover seconds per wall second, or max). CPU s is user + sys of the whole\n"
                     "  process set; --against runs the same in another built checkout (git worktree add\n"
                     "  DIR COMMIT, then ./rover build there: the code before a change) and prints the\n"
                     "  ratio of CPU per rover-hour (the long drive: configs/scenarios/bench_long_field.yaml)\n";
        return 0;
      }
    }
    const Options options = ParseArguments(argc, argv);
    for (const auto& scenario : options.scenarios) BenchScenario(options, scenario);
    return 0;
  });
}
