// ./rover bench scenario: how fast the whole process set simulates a 20 m drive.
// Runs configs/scenarios/bench_20m.yaml (or the scenario given) several times through
// scenario_runner and prints the rover time covered, the wall time, and their ratio.
// Target: at least 20x faster than real time at MER speed (~4 cm/s).
#include "bus/process.hpp"
#include "launch/process_set.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <vector>

int main(int argc, char** argv) {
  return rover::bus::RunMain("scenario_benchmark", [&]() -> int {
    std::string scenario = "configs/scenarios/bench_20m.yaml";
    int runs = 3;
    for (int i = 1; i < argc; ++i) {
      const std::string arg = argv[i];
      if (arg == "--runs" && i + 1 < argc) {
        runs = std::max(1, std::atoi(argv[++i]));
      } else if (arg == "--help") {
        std::cout << "usage: scenario_benchmark [SCENARIO.yaml] [--runs N]\n";
        return 0;
      } else {
        scenario = arg;
      }
    }
    const std::string runner = rover::launch::BinDir() + "/scenario_runner";
    std::vector<double> wall, rover, ratio, distance;
    for (int r = 0; r < runs; ++r) {
      const std::string out = "out/bench_scenario_" + std::to_string(r);
      const std::string cmd = runner + " " + scenario + " --quiet --out " + out + " > /dev/null";
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
    }
    auto median = [](std::vector<double> v) {
      std::sort(v.begin(), v.end());
      return v[v.size() / 2];
    };
    std::printf("scenario %s, %d runs (medians)\n", scenario.c_str(), runs);
    std::printf("  distance driven (truth)   %8.2f m\n", median(distance));
    std::printf("  rover time covered        %8.1f s\n", median(rover));
    std::printf("  wall time (whole run)     %8.1f s\n", median(wall));
    std::printf("  faster than real time     %8.1f x   (target >= 20 x)\n", median(ratio));
    return 0;
  });
}
