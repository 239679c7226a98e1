// ./rover plot LOG_OR_RUN_DIR [--out DIR]
//
// The pictures an operator looks at after a drive, from the run's LCM log: traverse.png,
// error.png, slip.png (plots.hpp) and vo_steps/ (vo_steps.hpp), drawn by gnuplot. The
// scenario runner runs it at the end of every scenario and demo.
// Exit status: 0 when every picture the log allows was written, 1 when one failed,
// 2 on a bad argument or an unreadable log.
#include "bus/process.hpp"
#include "config/yaml_config.hpp"
#include "plot/drive_log.hpp"
#include "plot/gnuplot.hpp"
#include "plot/plots.hpp"
#include "plot/vo_steps.hpp"

#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

namespace fs = std::filesystem;
using rover::config::ConfigError;

namespace {

constexpr const char* kUsage =
    "usage: rover_plot LOG_OR_RUN_DIR [--out DIR] [--world WORLD.yaml] [--vo-steps N] [--vo-config FILE]\n\n"
    "Draws a run's pictures from its LCM log (a scenario's DIR/log.lcm, or any log of the\n"
    "rover's channels) with gnuplot:\n"
    "  traverse.png  on-board path by mode (blind, VO-corrected; hazard-avoidance steps by\n"
    "                arc vote and those that steered straight at a clear goal), wheel-\n"
    "                odometry-only path, true path, keep-out zones, goto goal discs, the\n"
    "                world's rocks (simulation), step ends, each sequence's abort, 1 m grid\n"
    "  error.png     position error against distance travelled, with the 10 % line (needs truth)\n"
    "  slip.png      commanded against measured progress per step, slip and its limit\n"
    "  vo_steps/     for up to N steps VO measured (default 6), spread evenly over the\n"
    "                drive, the left image with the features tracked from the previous\n"
    "                frame: inliers and outliers\n"
    "Data files and gnuplot scripts go to DIR/plot/. DIR defaults to the log's folder.\n"
    "--vo-config: the VO options for vo_steps (default configs/vo.yaml).\n"
    "--world: the simulated world, for its rocks (default: rover_sim's --world in a run\n"
    "DIR's commands.txt, as the scenario runner writes it; with neither, one line says the\n"
    "rocks are not drawn).\n";

// The world rover_sim ran on, from a scenario's commands.txt; "" when there is none.
std::string WorldOfRun(const std::string& run_dir) {
  std::ifstream commands(run_dir + "/commands.txt");
  std::string line;
  while (std::getline(commands, line)) {
    std::istringstream words(line);
    std::string word;
    words >> word;
    if (word != "rover_sim") continue;
    while (words >> word) {
      if (word == "--world" && words >> word) return word;
    }
  }
  return "";
}

}  // namespace

int main(int argc, char** argv) {
  return rover::bus::RunMain("rover_plot", [&]() -> int {
    std::string input, out_dir, world, vo_config = "configs/vo.yaml";
    int vo_steps = 6;
    for (int i = 1; i < argc; ++i) {
      const std::string arg = argv[i];
      if (arg == "--help" || arg == "-h") {
        std::cout << kUsage;
        return 0;
      } else if (arg == "--out" && i + 1 < argc) {
        out_dir = argv[++i];
      } else if (arg == "--world" && i + 1 < argc) {
        world = argv[++i];
      } else if (arg == "--vo-config" && i + 1 < argc) {
        vo_config = argv[++i];
      } else if (arg == "--vo-steps" && i + 1 < argc) {
        const std::string v = argv[++i];
        try {
          std::size_t used = 0;
          vo_steps = std::stoi(v, &used);
          if (used != v.size() || vo_steps < 0 || vo_steps > 100) throw std::invalid_argument(v);
        } catch (const std::exception&) {
          throw ConfigError("rover_plot: argument --vo-steps: \"" + v + "\": expected a whole number 0..100");
        }
      } else if (input.empty() && arg.rfind("--", 0) != 0) {
        input = arg;
      } else {
        throw ConfigError("rover_plot: argument " + arg + ": unexpected (expected LOG_OR_RUN_DIR [--out DIR])");
      }
    }
    if (input.empty()) throw ConfigError("rover_plot: missing LOG_OR_RUN_DIR (see --help)");
    std::error_code ec;
    const std::string log_path = fs::is_directory(input, ec) ? input + "/log.lcm" : input;
    if (!fs::is_regular_file(log_path, ec)) {
      throw ConfigError("rover_plot: " + log_path + ": no such log (expected an LCM log or a run folder holding log.lcm)");
    }
    if (out_dir.empty()) out_dir = fs::path(log_path).parent_path().string();
    if (out_dir.empty()) out_dir = ".";

    rover::plot::PlotPlace place;
    place.out_dir = out_dir;
    place.data_dir = out_dir + "/plot";
    fs::create_directories(place.data_dir);
    place.terminal = rover::plot::PngTerminal();
    if (place.terminal.empty()) {
      std::cerr << "rover_plot: gnuplot cannot be run: install the Debian package gnuplot-nox "
                   "(./rover setup does)\n";
      return 1;
    }

    auto log = rover::plot::ReadDriveLog(log_path);
    if (world.empty()) world = WorldOfRun(fs::path(log_path).parent_path().string());
    if (world.empty()) {
      // A log recorded by hand (not a scenario's run folder) does not say which world it drove.
      std::cout << "plot: no world: the log's folder has no commands.txt naming rover_sim's --world and no "
                   "--world was given, so traverse.png draws no rocks (pass --world FILE to draw them)\n";
    } else {
      std::error_code exists_ec;
      if (fs::is_regular_file(world, exists_ec)) {
        log.rocks = rover::plot::ReadWorldRocks(world, 0.10);
      } else {
        std::cout << "plot: " << world << ": no such world file; traverse.png is drawn without rocks\n";
      }
    }
    const std::string run_name = fs::absolute(log_path).parent_path().filename().string();
    // Every sequence the log holds, by file name.
    std::string names;
    for (const auto& r : log.runs) names += (names.empty() ? "" : ", ") + fs::path(r.name).filename().string();
    if (names.empty() && !log.sequence_name.empty()) names = fs::path(log.sequence_name).filename().string();
    place.title = run_name + (names.empty() ? "" : " (" + names + ")");
    for (const auto& [channel, n] : log.undecodable) {
      std::cout << "plot: " << n << " " << channel << " messages did not decode and are left out\n";
    }

    bool failed = false;
    for (const auto& outcome : {rover::plot::WriteTraversePlot(log, place), rover::plot::WriteErrorPlot(log, place),
                                rover::plot::WriteSlipPlot(log, place)}) {
      failed = failed || outcome.failed;
      if (outcome.written) std::cout << "plot: wrote " << outcome.file << ": " << outcome.note << "\n";
      else std::cout << "plot: " << outcome.note << "\n";
    }
    const auto vo = rover::plot::WriteVoSteps(log, vo_config, vo_steps, place);
    failed = failed || vo.failed;
    std::cout << "plot: " << vo.note << "\n";
    return failed ? 1 : 0;
  });
}
