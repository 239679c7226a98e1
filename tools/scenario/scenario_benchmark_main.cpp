// ./rover bench scenario: how fast the whole process set simulates a drive.
// Runs configs/scenarios/bench_20m.yaml and the demo (or the scenarios given) several times
// through scenario_runner, once per rate of --rates (default: 50 and max, in one run), and
// prints
// per rate the rover time covered, the wall time, their ratio, and the log digest (virtual
// time: every rate must give the same one). Targets: at least 20x faster than real time at
// MER speed (~4 cm/s); the unlimited rate at most half of 50x's wall time.
#include "bus/process.hpp"
#include "launch/process_set.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

int main(int argc, char** argv) {
  return rover::bus::RunMain("scenario_benchmark", [&]() -> int {
    std::vector<std::string> scenarios;
    int runs = 3;
    std::vector<std::string> rates = {"50", "max"};
    for (int i = 1; i < argc; ++i) {
      const std::string arg = argv[i];
      if (arg == "--runs" && i + 1 < argc) {
        runs = std::max(1, std::atoi(argv[++i]));
      } else if (arg == "--rates" && i + 1 < argc) {
        rates.clear();
        std::stringstream ss(argv[++i]);
        for (std::string r; std::getline(ss, r, ',');)
          if (!r.empty()) rates.push_back(r);
      } else if (arg == "--help") {
        std::cout << "usage: scenario_benchmark [SCENARIO.yaml...] [--runs N] [--rates R1,R2,...]\n"
                     "  (default: configs/scenarios/bench_20m.yaml and demo.yaml, --runs 3 --rates 50,max;\n"
                     "  a rate is rover seconds per wall second, or max)\n";
        return 0;
      } else {
        scenarios.push_back(arg);
      }
    }
    if (scenarios.empty()) scenarios = {"configs/scenarios/bench_20m.yaml", "configs/scenarios/demo.yaml"};
    const std::string runner = rover::launch::BinDir() + "/scenario_runner";
    auto median = [](std::vector<double> v) {
      std::sort(v.begin(), v.end());
      return v[v.size() / 2];
    };
    for (const auto& scenario : scenarios) {
      std::printf("scenario %s, %d runs per rate (medians)\n", scenario.c_str(), runs);
      std::printf("  %-6s %10s %10s %10s %12s  %s\n", "rate", "distance m", "rover s", "wall s", "x real time",
                  "log digest");
      std::vector<double> walls;
      for (const auto& rate : rates) {
        std::vector<double> wall, rover, ratio, distance;
        std::string digest;
        for (int r = 0; r < runs; ++r) {
          const std::string stem = std::filesystem::path(scenario).stem().string();
        const std::string out = "out/bench_scenario_" + stem + "_" + rate + "_" + std::to_string(r);
          const std::string cmd = runner + " " + scenario + " --quiet --no-plot --rate " + rate + " --out " + out + " > /dev/null";
          if (std::system(cmd.c_str()) != 0) throw std::runtime_error("scenario run failed: " + cmd);
          const auto s = YAML::LoadFile(out + "/summary.json");
          if (s["outcome"].as<std::string>() != "completed") {
            throw std::runtime_error(out + "/summary.json: outcome " + s["outcome"].as<std::string>() +
                                     " (expected completed)");
          }
          wall.push_back(s["wall_time_s"].as<double>());
          rover.push_back(s["rover_time_s"].as<double>());
          distance.push_back(s["distance_travelled_m"].as<double>());
          ratio.push_back(rover.back() / wall.back());
          const std::string d = s["log_digest"] ? s["log_digest"].as<std::string>() : "-";
          digest = digest.empty() || digest == d ? d : "differs between runs";
        }
        walls.push_back(median(wall));
        std::printf("  %-6s %10.2f %10.1f %10.1f %12.1f  %s\n", rate.c_str(), median(distance), median(rover),
                    median(wall), median(ratio),
                    (digest.size() == 64 ? digest.substr(0, 16) : digest).c_str());  // a hex digest, shortened
      }
      if (walls.size() >= 2) {
        std::printf("  wall time %s / %s: %.2f   (target <= 0.5 for max / 50)\n", rates.back().c_str(),
                    rates.front().c_str(), walls.back() / walls.front());
      }
    }
    return 0;
  });
}
