// ./rover map-cells LOG --at X,Y [--radius R] [--ground-radius M] [--band M]: every map the
// hazard monitor published in a run's log, and what each said about the cells round (X, Y).
#include "map_cells/map_cells.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <stdexcept>
#include <string>

namespace {

const char* kUsage =
    "usage: map_cells LOG --at X,Y [--radius R] [--ground-radius M] [--band M]\n"
    "Prints every TRAVERSABILITY_MAP in LOG and its cells within R m (0.3) of site point (X, Y):\n"
    "state, step, the cell's top and sigma, and the top's rise over the ground round it (a\n"
    "plane fitted within M m, 1.0, leaving out cells --band m over it, 0.083), as the vote's\n"
    "executor.avoid_top_rise_m reads it.\n";

double Number(const std::string& flag, const std::string& text, double lo, double hi) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || !std::isfinite(v) || v < lo || v > hi)
    throw std::invalid_argument(flag + ": '" + text + "' is not a number in [" + std::to_string(lo) + ", " +
                                std::to_string(hi) + "]");
  return v;
}

}  // namespace

int main(int argc, char** argv) {
  using rover::map_cells::Query;
  Query q;
  std::string log;
  bool have_at = false;
  try {
    for (int a = 1; a < argc; ++a) {
      const std::string arg = argv[a];
      if (arg == "-h" || arg == "--help") {
        std::cout << kUsage;
        return 0;
      }
      auto value = [&]() -> std::string {
        if (a + 1 >= argc) throw std::invalid_argument(arg + ": missing its value");
        return argv[++a];
      };
      if (arg == "--at") {
        const std::string v = value();
        const auto comma = v.find(',');
        if (comma == std::string::npos) throw std::invalid_argument("--at: '" + v + "' is not X,Y (metres)");
        q.x = Number("--at", v.substr(0, comma), -1e6, 1e6);
        q.y = Number("--at", v.substr(comma + 1), -1e6, 1e6);
        have_at = true;
      } else if (arg == "--radius") {
        q.radius_m = Number(arg, value(), 0.0, 10.0);
      } else if (arg == "--ground-radius") {
        q.ground_radius_m = Number(arg, value(), 0.2, 5.0);
      } else if (arg == "--band") {
        q.band_m = Number(arg, value(), 0.0, 1.0);
      } else if (!arg.empty() && arg[0] == '-') {
        throw std::invalid_argument("unknown option '" + arg + "' (expected --at, --radius, --ground-radius, --band)");
      } else if (log.empty()) {
        log = arg;
      } else {
        throw std::invalid_argument("one log only ('" + log + "' and '" + arg + "')");
      }
    }
    if (log.empty()) throw std::invalid_argument("missing the log (map_cells LOG --at X,Y)");
    if (!have_at) throw std::invalid_argument("missing --at X,Y (the site point whose cells to print)");
  } catch (const std::invalid_argument& e) {
    std::cerr << "map_cells: " << e.what() << "\n";
    return 2;
  }
  try {
    rover::map_cells::Print(rover::map_cells::ReadHistory(log, q), q, std::cout);
  } catch (const std::exception& e) {
    std::cerr << "map_cells: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
