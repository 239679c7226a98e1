// ./rover navbench [--runs N] [--jobs J] [--densities K,...|none] [--worlds NAME,...|none]
//                  [--seed S] [--out DIR] [--quick] [--min-goal M] [--max-goal M] [--no-plot]
//                  [--prepare | --report] [--resume]
//
// The Monte Carlo navigation benchmark (README, "Navigation benchmark"): seeded Golombek
// rock fields and fixed worlds (a wall with a gap, a cul-de-sac), one goto with avoidance
// per run. It writes every run's world, sequence and scenario into DIR/runs/ID/, runs them
// all through the scenario campaign (scenario_campaign --each, J at once), judges each run
// against truth (navbench_metrics.hpp), and prints and writes the table (DIR/results.txt,
// DIR/results.json) and a picture per run (DIR/plots/ID.png).
#include "bus/process.hpp"
#include "config/yaml_config.hpp"
#include "launch/process_set.hpp"
#include "navbench/navbench_metrics.hpp"
#include "navbench/navbench_plot.hpp"
#include "navbench/navbench_run.hpp"

#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <sstream>

namespace fs = std::filesystem;
using rover::config::ConfigError;
namespace nb = rover::navbench;

namespace {

constexpr const char* kUsage =
    "usage: navbench [--runs N] [--jobs J] [--densities K,...|none] [--worlds NAME,...|none] [--seed S]\n"
    "                [--out DIR] [--quick] [--min-goal M] [--max-goal M] [--no-plot] [--prepare | --report]\n"
    "                [--resume] [--ways [--ways-height top|mean]] [--set KEY=VALUE]...\n\n"
    "The navigation benchmark: N runs (default 20) per Golombek rock field k (default\n"
    "0.05,0.10,0.15,0.20; rocks 0.1 to 1.5 m) and per fixed world (default gap_wall,cul_de_sac),\n"
    "each one `goto ... avoid on` with VO and the map on: 20 to 50 m (--min-goal, --max-goal) in\n"
    "a seeded direction on the rock fields. Runs go through the scenario campaign, J at once\n"
    "(--jobs, default 1), into DIR/runs/ID/ (default DIR out/navbench). Prints per world kind:\n"
    "success (completed, truly inside the goal disc, no collision, no wheel off the map) of\n"
    "the runs that stayed on their maps, collisions of the true footprint with keep-out zones\n"
    "and with rocks where they rise over the belly's clearance (a tall rock's rim grazed is\n"
    "listed apart), runs that left the map (a wheel of the true track off the\n"
    "world's map, no collision: counted apart from navigation), safe aborts by reason, the median path ratio, the drive rate (m/h of rover\n"
    "time), VO false updates, the rover-time breakdown and the pose's honesty (horizontal NEES\n"
    "against truth); writes DIR/results.txt,\n"
    "DIR/results.json and DIR/plots/ID.png. --seed S (default 1) draws every run.\n"
    "--quick: 1 run at k = 0.10, 8 to 10 m, no fixed world (a smoke run). --prepare writes the\n"
    "runs and runs none; --report tables runs already in DIR; --resume runs only those without\n"
    "a summary.json (an interrupted benchmark, or more --runs on the same seed).\n"
    "--ways drives nothing: for each run it writes, whether the stack's own global planner\n"
    "(its clearance and costs, with any --set) finds a way to the goal on a perfect map of the\n"
    "world (its exact surface, rated by the map's rules); the table after driving gives it too.\n"
    "--ways-height mean takes each cell at its surface's mean (what the map's cells measure)\n"
    "instead of its highest point (what the body meets; top, the default).\n"
    "--set KEY=VALUE (repeatable): a rover-config setting tried on every run, by its dotted key\n"
    "(hazards.map.traversability.unframed_unknown=true, executor.avoid_margin_m=0.2), written\n"
    "to each run's scenario overrides; a misspelt key ends every run at once with the\n"
    "process's \"unknown key\" error (runs/ID/runner.log).\n\n"
    "On a Slurm cluster (docs/SCENARIOS.md, \"Campaigns on a Slurm cluster\"): --slurm writes the\n"
    "runs and submits them as a job array, one task a run (scenario_campaign --each LIST\n"
    "--slurm); sbatch options pass through: --partition P, --time T, --cpus-per-task N,\n"
    "--account A, --sbatch-arg ARG. --merge DIR tables them as above once they ended and\n"
    "names the runs missing or failed (exit 3); --resume DIR submits only those again.\n";

std::vector<std::string> SplitCommas(const std::string& text) {
  std::vector<std::string> parts;
  std::stringstream ss(text);
  for (std::string part; std::getline(ss, part, ',');) {
    if (!part.empty()) parts.push_back(part);
  }
  return parts;
}

// Runs scenario_campaign with `args`, its output on this stdout; returns its exit status.
int RunCampaignTool(const std::vector<std::string>& args) {
  std::vector<std::string> argv = {rover::launch::BinDir() + "/scenario_campaign"};
  argv.insert(argv.end(), args.begin(), args.end());
  std::cout << std::flush;
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error("fork failed");
  if (pid == 0) {
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    execv(args[0], args.data());
    std::perror(argv[0].c_str());
    _exit(127);
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

// The scenario campaign over the listed scenarios: run here (`jobs` at once), or with
// `cluster` ("--slurm" or "--prepare") and sbatch options, as a Slurm job array.
int RunCampaign(const std::string& list, const std::string& out_dir, int jobs, const std::string& cluster = "",
                const std::vector<std::string>& sbatch_args = {}) {
  std::vector<std::string> args = {"--each", list, "--out", out_dir, "--no-plot", "--min-pass", "0"};
  if (cluster.empty()) {
    args.insert(args.end(), {"--jobs", std::to_string(jobs)});
  } else {
    args.push_back(cluster);
    args.insert(args.end(), sbatch_args.begin(), sbatch_args.end());
  }
  const int code = RunCampaignTool(args);
  if (code == 2 || code >= 127) throw std::runtime_error("scenario_campaign failed (exit " + std::to_string(code) + ")");
  return code;
}

// The command line, after --quick has filled in what was not given.
struct Args {
  nb::BenchOptions options;
  int jobs = 1;
  bool plot = true, prepare_only = false, report_only = false, resume = false, help = false;
  bool ways_only = false;  // --ways: the plan on each world's perfect map, no drive
  bool ways_at_mean = false;  // --ways-height mean: each cell at its surface's mean
  std::string command = "navbench";
  // Slurm: submit the runs as an array (scenario_campaign --slurm), or merge or resubmit one.
  bool slurm = false;
  std::string merge_dir, resume_dir;
  std::vector<std::string> sbatch_args;  // scenario_campaign's sbatch options, as given
  std::vector<std::string> plan_args;    // every other argument: what --merge plans again
};

// An sbatch option that scenario_campaign takes (and its value) at argv[i], into `out`.
bool SbatchOption(int argc, char** argv, int& i, std::vector<std::string>* out) {
  const std::string arg = argv[i];
  const bool with_value = arg == "--partition" || arg == "--time" || arg == "--cpus-per-task" ||
                          arg == "--account" || arg == "--sbatch-arg";
  if (!with_value && arg.rfind("--sbatch-arg=", 0) != 0) return false;
  out->push_back(arg);
  if (with_value) {
    if (i + 1 >= argc) throw ConfigError("navbench: " + arg + ": missing value");
    out->push_back(argv[++i]);
  }
  return true;
}

// The Slurm options must make sense together.
void CheckSlurmArgs(const Args& a) {
  if (!a.merge_dir.empty() || !a.resume_dir.empty()) {
    if (!a.plan_args.empty() || a.slurm) {
      throw ConfigError("navbench: --merge DIR and --resume DIR take no other option (DIR has them): " +
                        (a.slurm ? std::string("--slurm") : a.plan_args.front()));
    }
    if (!a.merge_dir.empty() && (!a.resume_dir.empty() || !a.sbatch_args.empty())) {
      throw ConfigError("navbench: --merge DIR takes no --resume or sbatch option");
    }
    return;
  }
  if (!a.sbatch_args.empty() && !a.slurm && !a.prepare_only) {
    throw ConfigError("navbench: " + a.sbatch_args.front() + ": an sbatch option needs --slurm, --prepare or --resume DIR");
  }
  if (a.slurm && (a.prepare_only || a.report_only || a.resume)) {
    throw ConfigError("navbench: --slurm excludes --prepare, --report and --resume (--merge DIR, --resume DIR follow it)");
  }
}

// --densities K,...|none.
std::vector<double> ParseDensities(const std::string& text) {
  std::vector<double> densities;
  for (const auto& part : text == "none" ? std::vector<std::string>{} : SplitCommas(text)) {
    char* end = nullptr;
    const double k = std::strtod(part.c_str(), &end);
    if (*end != '\0' || !(k > 0 && k <= 0.5)) {
      throw ConfigError("navbench: --densities \"" + text + "\": expected Golombek k values in (0, 0.5] separated by commas, or none");
    }
    densities.push_back(k);
  }
  return densities;
}

// --worlds NAME,...|none.
std::vector<std::string> ParseWorlds(const std::string& text) {
  std::vector<std::string> worlds;
  if (text == "none") return worlds;
  for (const auto& name : SplitCommas(text)) {
    bool known = false;
    for (const auto& w : nb::FixedWorlds()) known = known || w.name == name;
    if (!known) throw ConfigError("navbench: --worlds: unknown world '" + name + "' (expected gap_wall, cul_de_sac or none)");
    worlds.push_back(name);
  }
  return worlds;
}

// A Slurm option at argv[i] (and its value) into `a`; false when argv[i] is none.
bool SlurmOption(int argc, char** argv, int& i, Args& a) {
  const std::string arg = argv[i];
  if (SbatchOption(argc, argv, i, &a.sbatch_args)) return true;
  if (arg == "--slurm") {
    a.slurm = true;
  } else if (arg == "--merge") {
    if (i + 1 >= argc) throw ConfigError("navbench: --merge: missing DIR (expected --merge DIR)");
    a.merge_dir = argv[++i];
  } else if (arg == "--resume" && i + 1 < argc && argv[i + 1][0] != '-') {
    a.resume_dir = argv[++i];  // --resume DIR: a Slurm array's; plain --resume: local
  } else {
    return false;
  }
  return true;
}

Args ParseArgs(int argc, char** argv) {
  Args a;
  nb::BenchOptions& options = a.options;
  bool quick = false, runs_set = false, densities_set = false, worlds_set = false, goals_set = false;
  for (int i = 1; i < argc; ++i) a.command += std::string(" ") + argv[i];
  auto value = [&](int& i, const std::string& flag) -> std::string {
    if (i + 1 >= argc) throw ConfigError("navbench: " + flag + ": missing value");
    return argv[++i];
  };
  auto number = [&](int& i, const std::string& flag, double lo, double hi, bool whole) -> double {
    const std::string v = value(i, flag);
    char* end = nullptr;
    const double d = std::strtod(v.c_str(), &end);
    if (v.empty() || *end != '\0' || !std::isfinite(d) || d < lo || d > hi || (whole && d != std::floor(d))) {
      std::ostringstream os;
      os << "navbench: " << flag << " \"" << v << "\": expected " << (whole ? "a whole number" : "a number")
         << " in [" << lo << ", " << hi << "]";
      throw ConfigError(os.str());
    }
    return d;
  };
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const int first = i;
    if (SlurmOption(argc, argv, i, a)) continue;
    if (arg == "--help" || arg == "-h") {
      a.help = true;
    } else if (arg == "--runs") {
      options.runs = static_cast<int>(number(i, arg, 1, 1000, true));
      runs_set = true;
    } else if (arg == "--jobs") {
      a.jobs = static_cast<int>(number(i, arg, 1, 64, true));
    } else if (arg == "--seed") {
      options.seed = static_cast<std::uint64_t>(number(i, arg, 0, 1e15, true));
    } else if (arg == "--out") {
      options.out_dir = value(i, arg);
    } else if (arg == "--densities") {
      options.densities = ParseDensities(value(i, arg));
      densities_set = true;
    } else if (arg == "--worlds") {
      options.worlds = ParseWorlds(value(i, arg));
      worlds_set = true;
    } else if (arg == "--min-goal") {
      options.min_goal_m = number(i, arg, 1, 500, false);
      goals_set = true;
    } else if (arg == "--max-goal") {
      options.max_goal_m = number(i, arg, 1, 500, false);
      goals_set = true;
    } else if (arg == "--quick") {
      quick = true;
    } else if (arg == "--no-plot") {
      a.plot = false;
    } else if (arg == "--prepare") {
      a.prepare_only = true;
    } else if (arg == "--set") {
      const auto setting = nb::ParseSetting(value(i, arg));
      for (const auto& o : options.overrides)
        if (o.key == setting.key) throw ConfigError("navbench: --set " + setting.key + ": given twice (expected each key once)");
      options.overrides.push_back(setting);
    } else if (arg == "--report") {
      a.report_only = true;
    } else if (arg == "--ways") {
      a.ways_only = true;
    } else if (arg == "--ways-height") {
      const std::string h = value(i, arg);
      if (h != "top" && h != "mean") throw ConfigError("navbench: --ways-height: expected top or mean, got '" + h + "'");
      a.ways_at_mean = h == "mean";
    } else if (arg == "--resume") {
      a.resume = true;
    } else {
      throw ConfigError("navbench: argument " + arg + ": unexpected (see navbench --help)");
    }
    for (int j = first; j <= i; ++j) a.plan_args.push_back(argv[j]);
  }
  // --quick fills in what was not given: one short run on one field.
  if (quick) {
    if (!runs_set) options.runs = 1;
    if (!densities_set) options.densities = {0.10};
    if (!worlds_set) options.worlds.clear();
    if (!goals_set) options.min_goal_m = 8, options.max_goal_m = 10;
  }
  if (options.min_goal_m > options.max_goal_m) throw ConfigError("navbench: --min-goal is over --max-goal");
  if (a.prepare_only && a.report_only) throw ConfigError("navbench: --prepare and --report exclude each other");
  if (a.ways_only && (a.prepare_only || a.report_only || a.resume || a.slurm))
    throw ConfigError("navbench: --ways drives nothing: it excludes --prepare, --report, --resume and --slurm");
  if (a.ways_at_mean && !a.ways_only) throw ConfigError("navbench: --ways-height: only with --ways");
  if (options.densities.empty() && options.worlds.empty()) throw ConfigError("navbench: no density and no world to run");
  CheckSlurmArgs(a);
  return a;
}

// Writes every run and the list the campaign reads (DIR/runs.txt); returns the list, or ""
// when there is nothing to run. With `resume`, a run that already has its summary.json is
// left as it is and not run again (a run depends only on the seed, its kind and index).
std::string PrepareRuns(const std::vector<nb::RunPlan>& plans, const nb::BenchOptions& options, bool resume) {
  const std::string list = options.out_dir + "/runs.txt";
  std::ofstream out(list);
  int written = 0;
  for (const auto& p : plans) {
    if (resume && fs::exists(p.dir + "/summary.json")) continue;
    nb::WriteRun(p, options.overrides);
    out << p.scenario_path() << "\n";
    ++written;
  }
  out.close();
  if (!out) throw std::runtime_error(list + ": cannot write");
  std::cout << "navbench: " << written << " runs (" << options.runs << " per world kind, seed " << options.seed
            << (resume ? ", " + std::to_string(plans.size() - static_cast<std::size_t>(written)) + " done before" : "")
            << ") written to " << options.out_dir << "/runs/\n";
  return written > 0 ? list : "";
}

// Judges every run, draws it, and prints and writes the table.
void Report(const std::vector<nb::RunPlan>& plans, const Args& args) {
  const std::string& out_dir = args.options.out_dir;
  std::vector<nb::RunFigures> figures;
  for (const auto& p : plans) {
    nb::RunTrack track;
    figures.push_back(nb::ReadRun(p, &track));
    if (args.plot && figures.back().ran) {
      const std::string why = nb::PlotRun(p, figures.back(), track, out_dir + "/plots");
      if (!why.empty()) std::cerr << "navbench: " << p.id << ": no picture: " << why << "\n";
    }
  }
  std::vector<std::string> groups;  // in plan order
  for (const auto& p : plans) {
    if (groups.empty() || groups.back() != p.group) groups.push_back(p.group);
  }
  std::vector<nb::GroupFigures> rows;
  for (const auto& g : groups) rows.push_back(nb::Aggregate(g, figures));
  const std::string table = nb::TableText(rows);
  std::cout << "\n" << table;
  std::ofstream(out_dir + "/results.txt") << "# " << args.command << "\n" << table;
  std::ofstream(out_dir + "/results.json") << nb::ResultsJson(rows, figures, args.command);
  std::cout << "wrote " << out_dir << "/results.txt, results.json" << (args.plot ? " and plots/ID.png" : "") << "\n";
}

// --ways: each run's world written, and the plan on its perfect map; one line a run, then
// per world kind how many have a way.
void Ways(const std::vector<nb::RunPlan>& plans, const nb::BenchOptions& options, bool at_mean) {
  std::map<std::string, std::pair<int, int>> counts;  // group: (with a way, worlds)
  std::vector<std::string> groups;
  for (const auto& p : plans) {
    nb::WriteRun(p, options.overrides);
    const nb::PerfectWay way = nb::RunPerfectWay(p, at_mean);
    if (counts.find(p.group) == counts.end()) groups.push_back(p.group);
    auto& [with, worlds] = counts[p.group];
    ++worlds;
    with += way.reachable;
    std::ostringstream line;
    line << std::fixed << std::setprecision(2) << std::left << std::setw(16) << p.id << p.straight_m() << " m straight, ";
    if (way.reachable) {
      line << "a way of " << way.length_m << " m";
    } else {
      line << "no way: " << way.why;
    }
    std::cout << line.str() << "\n";
  }
  std::cout << "\nthe plan on a perfect map (seed " << options.seed << ", each cell at its "
            << (at_mean ? "surface's mean" : "highest point") << "):\n";
  for (const auto& g : groups)
    std::cout << std::left << std::setw(11) << g << counts[g].first << " of " << counts[g].second
              << " worlds with a way\n";
}

// The file in DIR with the arguments a Slurm benchmark was asked with (what --merge plans).
std::string PlanArgsPath(const std::string& out_dir) { return out_dir + "/slurm/navbench_args.txt"; }

// --merge DIR: the campaign's merge (its table, the tasks missing or failed), then this
// benchmark's table and plots from the runs that finished. Exit 3 when one did not.
int Merge(const std::string& dir) {
  std::ifstream in(PlanArgsPath(dir));
  if (!in) throw ConfigError("navbench: --merge " + dir + ": no Slurm benchmark here (expected " + PlanArgsPath(dir) + ", written by navbench --slurm)");
  std::vector<std::string> words = {"navbench"};
  for (std::string line; std::getline(in, line);) words.push_back(line);
  words.push_back("--report");
  std::vector<char*> argv;
  for (auto& w : words) argv.push_back(w.data());
  Args args = ParseArgs(static_cast<int>(argv.size()), argv.data());
  args.options.out_dir = dir;
  const int code = RunCampaignTool({"--merge", dir});
  if (code == 2 || code >= 127) throw std::runtime_error("scenario_campaign --merge failed (exit " + std::to_string(code) + ")");
  Report(nb::PlanRuns(args.options), args);
  if (code == 3) std::cout << "navbench: runs missing or failed (above); ./rover navbench --resume " << dir << " submits them again\n";
  return code == 3 ? 3 : 0;
}

}  // namespace

int main(int argc, char** argv) {
  return rover::bus::RunMain("navbench", [&]() -> int {
    const Args args = ParseArgs(argc, argv);
    if (args.help) {
      std::cout << kUsage;
      return 0;
    }
    if (!args.merge_dir.empty()) return Merge(args.merge_dir);
    if (!args.resume_dir.empty()) {
      std::vector<std::string> resume = {"--resume", args.resume_dir};
      resume.insert(resume.end(), args.sbatch_args.begin(), args.sbatch_args.end());
      return RunCampaignTool(resume);
    }
    const std::vector<nb::RunPlan> plans = nb::PlanRuns(args.options);
    fs::create_directories(args.options.out_dir);
    if (args.ways_only) {
      Ways(plans, args.options, args.ways_at_mean);
      return 0;
    }
    if (!args.report_only) {
      const std::string list = PrepareRuns(plans, args.options, args.resume);
      if ((args.prepare_only || args.slurm) && !list.empty()) {
        RunCampaign(list, args.options.out_dir, 1, args.slurm ? "--slurm" : "--prepare", args.sbatch_args);
        std::ofstream saved(PlanArgsPath(args.options.out_dir));
        for (const auto& w : args.plan_args) {
          if (w != "--prepare" && w != "--resume") saved << w << "\n";
        }
      }
      if (args.prepare_only || args.slurm) return 0;
      if (!list.empty()) RunCampaign(list, args.options.out_dir, args.jobs);
    }
    Report(plans, args);
    return 0;
  });
}
