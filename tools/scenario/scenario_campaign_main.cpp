// ./rover campaign SCENARIO.yaml --variants N [--out DIR] [--seed S] [--min-pass PCT]
//
// Runs N seeded variants of one scenario (--jobs at once), each through scenario_runner
// on its own bus: new world, mobility-noise and render-noise seeds, the start pose moved by
// up to the scenario's `campaign:` jitter, and the world's first slope changed by up to
// +/- slope_jitter_deg. Prints a table with each variant's outcome and the pass rate (a
// variant passes when scenario_runner says it ended as expected), and writes
// DIR/campaign.json. Exit status 1 when the pass rate is below --min-pass or any variant
// slid blind (see BlindSlide), 2 on a bad argument.
//
// ./rover campaign --each LIST [--jobs J] [--out DIR] runs scenarios already written (one
// path a line in LIST, as `--prepare` or ./rover navbench writes them) once each, as they
// are, into the folder that holds each file; the same table, pass rate and campaign.json.
#include "bus/process.hpp"
#include "config/yaml_config.hpp"
#include "launch/process_set.hpp"
#include "report/json_writer.hpp"
#include "scenario/scenario.hpp"
#include "scenario/slurm_array.hpp"
#include "simtime/rate.hpp"

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <random>
#include <sstream>

namespace fs = std::filesystem;
using rover::config::ConfigError;
namespace slurm = rover::tools::slurm;

namespace {

struct Variant {
  int index = 0;
  std::uint64_t world_seed = 0, mobility_seed = 0, render_seed = 0;
  double x = 0, y = 0, yaw_deg = 0;
  std::optional<double> slope_deg;  // the world's first slope, when it has one
  std::string dir;
  // Results.
  int exit_code = -1;
  std::string outcome = "incomplete", abort_reason, detail;
  std::optional<double> clearance_m;
  double position_error_pct = 0;
  int vo_accepted = 0, false_updates = 0, steps = 0;
  std::string blind_slide;  // empty: none
  std::string log_digest;   // the run's log less its wall-time fields (README, "Simulated time")
  std::string missing;      // a merged Slurm task that did not finish: why (empty: it did)
  bool passed() const { return exit_code == 0 && blind_slide.empty(); }
};

// The world's first slope angle after the scenario's own world overrides, if it has one.
std::optional<double> FirstSlope(const rover::tools::ScenarioSpec& spec) {
  YAML::Node world = YAML::LoadFile(spec.world);
  rover::tools::ApplyOverrides(world, spec.world_overrides, spec.world);
  const YAML::Node slopes = world["slopes"];
  if (!slopes || !slopes.IsSequence() || slopes.size() == 0 || !slopes[0]["angle_deg"]) return std::nullopt;
  return slopes[0]["angle_deg"].as<double>();
}

// Variant k of the campaign: everything drawn from (campaign seed, k), so a campaign is
// reproducible and one variant can be run again alone from its scenario.yaml.
Variant MakeVariant(const rover::tools::ScenarioSpec& spec, std::optional<double> slope, std::uint64_t seed,
                    int k) {
  std::mt19937_64 rng(seed * 1000003ULL + static_cast<std::uint64_t>(k));
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  Variant v;
  v.index = k;
  v.world_seed = 1 + rng() % 1000000;
  v.mobility_seed = 1 + rng() % 1000000;
  v.render_seed = 1 + rng() % 1000000;
  v.x = spec.start_x + spec.campaign_start_jitter_m * unit(rng);
  v.y = spec.start_y + spec.campaign_start_jitter_m * unit(rng);
  v.yaw_deg = spec.start_yaw_deg + spec.campaign_yaw_jitter_deg * unit(rng);
  if (slope) v.slope_deg = *slope + spec.campaign_slope_jitter_deg * unit(rng);
  return v;
}

// A scenario run as written (--each): its seeds and start from the file, its folder the
// run's output folder.
Variant PreparedVariant(const std::string& path, int k) {
  const rover::tools::ScenarioSpec spec = rover::tools::LoadScenario(path);
  const YAML::Node root = YAML::LoadFile(path);
  Variant v;
  v.index = k;
  if (const YAML::Node seeds = root["seeds"]) {
    v.world_seed = seeds["world"].as<std::uint64_t>(0);
    v.mobility_seed = seeds["mobility"].as<std::uint64_t>(0);
    v.render_seed = seeds["render"].as<std::uint64_t>(0);
  }
  v.x = spec.start_x;
  v.y = spec.start_y;
  v.yaw_deg = spec.start_yaw_deg;
  v.dir = fs::path(path).parent_path().string();
  if (v.dir.empty()) v.dir = ".";
  return v;
}

// The scenario paths of an --each list: one a line; blank lines and # comments skipped.
std::vector<std::string> ReadScenarioList(const std::string& list_path) {
  std::ifstream in(list_path);
  if (!in) throw ConfigError("scenario_campaign: --each " + list_path + ": cannot read the list");
  std::vector<std::string> paths;
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    const auto first = line.find_first_not_of(" \t");
    if (first == std::string::npos || line[first] == '#') continue;
    line = line.substr(first, line.find_last_not_of(" \t\r") + 1 - first);
    if (!fs::exists(line)) {
      throw ConfigError(list_path + ":" + std::to_string(n) + ": " + line + ": no such scenario file");
    }
    paths.push_back(line);
  }
  if (paths.empty()) throw ConfigError("scenario_campaign: --each " + list_path + ": no scenario listed");
  return paths;
}

// The scenario file of a variant: the original with its seeds, start and slope replaced.
void WriteVariantScenario(const rover::tools::ScenarioSpec& spec, const Variant& v, const std::string& path) {
  YAML::Node root = YAML::LoadFile(spec.source);
  root["name"] = spec.name + "_v" + std::to_string(v.index);
  YAML::Node seeds(YAML::NodeType::Map);
  seeds["world"] = v.world_seed;
  seeds["mobility"] = v.mobility_seed;
  seeds["render"] = v.render_seed;
  root["seeds"] = seeds;
  YAML::Node start(YAML::NodeType::Map);
  start["x"] = v.x;
  start["y"] = v.y;
  start["yaw_deg"] = v.yaw_deg;
  root["start"] = start;
  if (v.slope_deg) {
    if (!root["world_overrides"] || !root["world_overrides"].IsMap()) {
      root["world_overrides"] = YAML::Node(YAML::NodeType::Map);
    }
    root["world_overrides"]["slopes.0.angle_deg"] = *v.slope_deg;
  }
  std::ofstream out(path);
  out << "# Variant " << v.index << " of " << spec.source << " (scenario_campaign)\n" << YAML::Dump(root) << "\n";
  if (!out) throw ConfigError(path + ": cannot write the variant scenario");
}

// Starts `argv` with stdout and stderr to `log_path`; returns its pid.
pid_t StartLogged(const std::vector<std::string>& argv, const std::string& log_path) {
  std::fflush(nullptr);
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error("fork failed");
  if (pid == 0) {
    const int fd = open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd >= 0) {
      dup2(fd, 1);
      dup2(fd, 2);
      close(fd);
    }
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    execv(args[0], args.data());
    _exit(127);
  }
  return pid;
}

// Waits for any child; returns its pid and exit status (128 + signal).
std::pair<pid_t, int> WaitAny() {
  int status = 0;
  pid_t pid = -1;
  while ((pid = waitpid(-1, &status, 0)) < 0 && errno == EINTR) {
  }
  if (pid < 0) throw std::runtime_error("waitpid failed");
  return {pid, WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status)};
}

// A blind slide: after `window` arc steps in a row whose true progress along the commanded
// direction, summed, is below `fraction` of the commanded, the rover drove on (another
// step), or its command ended completed. Empty when none, else where it happened.
std::string BlindSlide(const YAML::Node& summary, int window, double fraction) {
  const YAML::Node steps = summary["steps"];
  if (!steps || !steps.IsSequence()) return "";
  std::vector<std::pair<double, double>> arcs;  // commanded, true
  std::vector<std::size_t> index;
  for (std::size_t i = 0; i < steps.size(); ++i) {
    const double commanded = steps[i]["commanded"]["distance_m"].as<double>();
    if (std::abs(commanded) < 0.05) continue;
    arcs.emplace_back(commanded, steps[i]["true"]["distance_m"].as<double>());
    index.push_back(i);
  }
  const bool completed = summary["outcome"].as<std::string>() == "completed";
  for (std::size_t end = static_cast<std::size_t>(window); end <= arcs.size(); ++end) {
    double commanded = 0, moved = 0;
    for (std::size_t i = end - window; i < end; ++i) {
      commanded += std::abs(arcs[i].first);
      moved += std::copysign(1.0, arcs[i].first) * arcs[i].second;
    }
    const bool drove_on = index[end - 1] + 1 < steps.size();
    if (moved < fraction * commanded && (drove_on || completed)) {
      std::ostringstream os;
      os << std::fixed << std::setprecision(2) << "steps " << index[end - window] << "-" << index[end - 1]
         << ": " << moved << " m of " << commanded << " m, then " << (drove_on ? "drove on" : "completed");
      return os.str();
    }
  }
  return "";
}

void ReadResults(Variant& v, int window, double fraction) {
  const std::string path = v.dir + "/summary.json";
  if (!fs::exists(path)) {
    v.detail = "no summary.json (see " + v.dir + "/runner.log)";
    return;
  }
  const YAML::Node s = YAML::LoadFile(path);
  v.outcome = s["outcome"].as<std::string>();
  v.abort_reason = s["abort_reason"].IsNull() ? "" : s["abort_reason"].as<std::string>();
  v.detail = s["detail"].as<std::string>();
  if (s["min_keepout_clearance_m"] && !s["min_keepout_clearance_m"].IsNull()) {
    v.clearance_m = s["min_keepout_clearance_m"].as<double>();
  }
  v.position_error_pct = s["position_error_pct"].IsNull() ? 0.0 : s["position_error_pct"].as<double>();
  if (s["vo_updates_accepted"]) v.vo_accepted = s["vo_updates_accepted"].as<int>();
  if (s["false_updates"]) v.false_updates = s["false_updates"].as<int>();
  v.steps = static_cast<int>(s["steps"].size());
  if (s["log_digest"]) v.log_digest = s["log_digest"].as<std::string>();
  v.blind_slide = BlindSlide(s, window, fraction);
}

std::string Fixed(double v, int digits) {
  std::ostringstream os;
  os << std::fixed << std::setprecision(digits) << v;
  return os.str();
}

struct CampaignArgs {
  std::string scenario_path, out_dir, each_list;
  int variants = 0, window = 2, jobs = 1;
  std::uint64_t seed = 1;
  double min_pass_pct = 95.0, slide_pct = 10.0;
  bool plot = true, prepare_only = false;
  // Every run's --rate: max (no pacing: in virtual time a run's outcome and log are the
  // same at any rate), a number of rover seconds per wall second, or empty for each
  // scenario's own sim_rate.
  std::string rate = "max";
  // Slurm (slurm_array.hpp): submit as a job array; merge or resume one submitted before.
  bool slurm = false;
  std::string merge_dir, resume_dir;
  std::vector<std::string> sbatch_args;  // --partition P ... --sbatch-arg ARG, in order
  bool each() const { return !each_list.empty(); }
};

constexpr const char* kUsage =
    "usage: scenario_campaign SCENARIO.yaml --variants N [--out DIR] [--seed S] [--jobs N]\n"
    "       scenario_campaign --each LIST [--out DIR] [--jobs N]\n"
    "                         [--min-pass PCT] [--slide-window N] [--slide-progress PCT] [--no-plot]\n"
    "                         [--rate R|max|scenario]\n"
    "       scenario_campaign SCENARIO.yaml --variants N | --each LIST  --slurm [SBATCH OPTIONS]\n"
    "       scenario_campaign --merge DIR\n"
    "       scenario_campaign --resume DIR [SBATCH OPTIONS]\n\n"
    "Runs N seeded variants of a scenario (seeds, start pose, slope; the scenario's\n"
    "`campaign:` section sets the jitter), prints a table and the pass rate, and\n"
    "writes DIR/campaign.json (default DIR: out/campaign/NAME). Exit 1 when the\n"
    "pass rate is below --min-pass (default 95 %) or a variant slid blind: drove on\n"
    "after --slide-window (2) arc steps with true progress below --slide-progress\n"
    "(10 %) of the commanded. --no-plot skips each variant's pictures (about 4 s each).\n"
    "--jobs N runs N variants at once, each on its own private bus; in virtual time\n"
    "each variant's result and log digest are the same as with --jobs 1.\n"
    "--rate R|max|scenario: every run's pace (default max: as fast as the CPU goes; in\n"
    "virtual time the result and log digest are the same at any rate; scenario: each\n"
    "scenario's own sim_rate, as ./rover scenario runs it). A day_pause_night variant\n"
    "(a 12 h night parked) took 16 min of wall time at its 50x, at max about a minute.\n"
    "--each LIST runs the scenario files listed in LIST (one path a line) once each,\n"
    "as written, into the folder that holds each (./rover navbench uses it); DIR\n"
    "(default: LIST's folder) gets campaign.json.\n\n"
    "On a Slurm cluster (docs/SCENARIOS.md, \"Campaigns on a Slurm cluster\"):\n"
    "--prepare writes DIR/vK/scenario.yaml for every variant and DIR/slurm/ (array.sbatch,\n"
    "tasks.txt, plan.yaml) and runs nothing; --slurm does the same and submits the array\n"
    "with sbatch, one task a variant (./rover scenario on its node, on a private bus).\n"
    "SBATCH OPTIONS go to sbatch: --partition P, --time T, --cpus-per-task N, --account A,\n"
    "and --sbatch-arg ARG (any sbatch option, repeatable: --sbatch-arg=--qos=long).\n"
    "--merge DIR tables the tasks that finished as a local run does (campaign.json), and\n"
    "names every task missing or failed and why (exit 3 when there is one).\n"
    "--resume DIR submits again only the tasks missing or failed (not those still queued).\n";

// --rate's value as scenario_runner takes it (rover_sim's, simtime/rate.hpp); "scenario"
// (each scenario's own sim_rate) as empty.
std::string ParseRate(const std::string& v) {
  if (v == "scenario") return "";
  double rate = 0;
  if (!rover::simtime::ParseRate(v, &rate)) {
    throw ConfigError("scenario_campaign: argument --rate \"" + v + "\": expected scenario, " +
                      rover::simtime::kRateExpected + " (rover seconds per wall second)");
  }
  return v;
}

// A Slurm option at argv[i] (and its value): appended to a.sbatch_args or set in `a`.
// False when argv[i] is none.
bool ParseSlurmArg(int argc, char** argv, int& i, CampaignArgs& a) {
  const std::string arg = argv[i];
  auto value = [&]() -> std::string {
    if (i + 1 >= argc) throw ConfigError("scenario_campaign: " + arg + ": missing value");
    return argv[++i];
  };
  static const std::map<std::string, std::string> named = {
      {"--partition", "--partition="}, {"--time", "--time="}, {"--cpus-per-task", "--cpus-per-task="},
      {"--account", "--account="}};
  if (const auto it = named.find(arg); it != named.end()) {
    a.sbatch_args.push_back(it->second + value());
  } else if (arg == "--sbatch-arg") {
    a.sbatch_args.push_back(value());
  } else if (arg.rfind("--sbatch-arg=", 0) == 0) {
    a.sbatch_args.push_back(arg.substr(13));
  } else if (arg == "--slurm") {
    a.slurm = true;
  } else if (arg == "--merge") {
    a.merge_dir = value();
  } else if (arg == "--resume") {
    a.resume_dir = value();
  } else {
    return false;
  }
  return true;
}

// What the command line asks for must make sense together.
void CheckArgs(const CampaignArgs& a) {
  const bool cluster_dir = !a.merge_dir.empty() || !a.resume_dir.empty();
  if (cluster_dir) {
    if (!a.merge_dir.empty() && !a.resume_dir.empty()) throw ConfigError("scenario_campaign: --merge and --resume exclude each other");
    if (a.each() || !a.scenario_path.empty() || a.variants != 0 || a.slurm || a.prepare_only) {
      throw ConfigError("scenario_campaign: --merge DIR and --resume DIR take no SCENARIO.yaml, --each, --variants, "
                        "--slurm or --prepare (DIR/slurm/plan.yaml has them)");
    }
    if (!a.merge_dir.empty() && !a.sbatch_args.empty()) throw ConfigError("scenario_campaign: --merge DIR takes no sbatch option");
    return;
  }
  if (!a.sbatch_args.empty() && !a.slurm && !a.prepare_only) {
    throw ConfigError("scenario_campaign: " + a.sbatch_args.front() + ": an sbatch option needs --slurm, --prepare or --resume DIR");
  }
  if (a.slurm && a.prepare_only) throw ConfigError("scenario_campaign: --slurm and --prepare exclude each other (--slurm prepares too)");
  if (!a.each() && a.scenario_path.empty()) throw ConfigError("scenario_campaign: missing SCENARIO.yaml");
  if (!a.each() && a.variants == 0) throw ConfigError("scenario_campaign: missing --variants N");
  if (a.each() && (!a.scenario_path.empty() || a.variants != 0)) {
    throw ConfigError("scenario_campaign: --each LIST takes no SCENARIO.yaml or --variants");
  }
}

// The command line; nothing after --help (printed).
std::optional<CampaignArgs> ParseArgs(int argc, char** argv) {
  CampaignArgs a;
  auto number = [&](int& i, const std::string& flag) -> double {
    if (i + 1 >= argc) throw ConfigError("scenario_campaign: " + flag + ": missing value");
    const std::string v = argv[++i];
    char* end = nullptr;
    const double d = std::strtod(v.c_str(), &end);
    if (v.empty() || *end != '\0' || !std::isfinite(d)) {
      throw ConfigError("scenario_campaign: argument " + flag + " \"" + v + "\": expected a number");
    }
    return d;
  };
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      std::cout << kUsage;
      return std::nullopt;
    } else if (arg == "--variants") {
      const double n = number(i, arg);
      if (n < 1 || n > 10000 || n != std::floor(n)) {
        throw ConfigError("scenario_campaign: --variants " + Fixed(n, 2) + ": expected a whole number in [1, 10000]");
      }
      a.variants = static_cast<int>(n);
    } else if (arg == "--out" && i + 1 < argc) {
      a.out_dir = argv[++i];
    } else if (arg == "--seed") {
      const double s = number(i, arg);
      if (s < 0 || s != std::floor(s)) throw ConfigError("scenario_campaign: --seed: expected a whole number >= 0");
      a.seed = static_cast<std::uint64_t>(s);
    } else if (arg == "--min-pass") {
      a.min_pass_pct = number(i, arg);
      if (a.min_pass_pct < 0 || a.min_pass_pct > 100) throw ConfigError("scenario_campaign: --min-pass: expected 0 to 100");
    } else if (arg == "--slide-window") {
      const double n = number(i, arg);
      if (n < 1 || n > 100 || n != std::floor(n)) throw ConfigError("scenario_campaign: --slide-window: expected 1 to 100");
      a.window = static_cast<int>(n);
    } else if (arg == "--each" && i + 1 < argc) {
      a.each_list = argv[++i];
    } else if (arg == "--no-plot") {
      a.plot = false;
    } else if (arg == "--rate") {
      if (i + 1 >= argc) throw ConfigError("scenario_campaign: --rate: missing value (expected max, scenario or a number)");
      a.rate = ParseRate(argv[++i]);
    } else if (arg == "--prepare") {
      a.prepare_only = true;
    } else if (arg == "--jobs") {
      const double n = number(i, arg);
      if (n < 1 || n > 64 || n != std::floor(n)) throw ConfigError("scenario_campaign: --jobs: expected a whole number in [1, 64]");
      a.jobs = static_cast<int>(n);
    } else if (arg == "--slide-progress") {
      a.slide_pct = number(i, arg);
    } else if (ParseSlurmArg(argc, argv, i, a)) {
    } else if (a.scenario_path.empty() && arg.rfind("--", 0) != 0) {
      a.scenario_path = arg;
    } else {
      throw ConfigError("scenario_campaign: argument " + arg +
                        ": unexpected (expected SCENARIO.yaml --variants N [--out DIR])");
    }
  }
  CheckArgs(a);
  return a;
}

void PrintHeader(const CampaignArgs& a, const rover::tools::ScenarioSpec& spec, std::optional<double> slope,
                 bool columns = true) {
  if (a.each()) {
    std::cout << "campaign " << a.each_list << ": " << a.variants << " scenarios as written\n";
  } else {
    std::cout << "campaign " << spec.name << ": " << a.variants << " variants (seed " << a.seed << "), start +/- "
              << spec.campaign_start_jitter_m << " m, +/- " << spec.campaign_yaw_jitter_deg << " deg"
              << (slope ? ", slope " + Fixed(*slope, 1) + " +/- " + Fixed(spec.campaign_slope_jitter_deg, 1) + " deg"
                        : std::string(", no slope"))
              << "; expected " << spec.expect_outcome
              << (spec.expect_abort_reason.empty() ? "" : " (" + spec.expect_abort_reason + ")") << "\n";
  }
  if (!columns) return;
  std::cout << std::left << std::setw(4) << "var" << std::setw(22) << " seeds w/m/r" << std::setw(24)
            << " start x, y, yaw" << std::setw(7) << " slope" << std::setw(11) << " outcome" << std::setw(20)
            << " reason" << std::setw(10) << " clear m" << std::setw(8) << " err %" << std::setw(10)
            << " VO ok/fls" << std::setw(14) << " log digest" << " result\n" << std::flush;
}

void PrintRow(int k, const Variant& v) {
  std::ostringstream seeds, start;
  seeds << v.world_seed << "/" << v.mobility_seed << "/" << v.render_seed;
  start << Fixed(v.x, 2) << ", " << Fixed(v.y, 2) << ", " << Fixed(v.yaw_deg, 1);
  std::cout << std::left << std::setw(4) << k << " " << std::setw(21) << seeds.str() << " " << std::setw(23)
            << start.str() << " " << std::setw(6) << (v.slope_deg ? Fixed(*v.slope_deg, 1) : "-") << " "
            << std::setw(10) << v.outcome << " " << std::setw(19) << (v.abort_reason.empty() ? "-" : v.abort_reason)
            << " " << std::setw(9) << (v.clearance_m ? Fixed(*v.clearance_m, 3) : "-") << " " << std::setw(7)
            << Fixed(v.position_error_pct, 2) << " " << std::setw(9)
            << (std::to_string(v.vo_accepted) + "/" + std::to_string(v.false_updates)) << " "
            << std::setw(13) << (v.log_digest.empty() ? "-" : v.log_digest.substr(0, 12)) << " "
            << (!v.missing.empty() ? std::string("MISSING (below)")
                : v.passed()       ? "pass"
                : v.exit_code == 0 ? "FAIL (blind slide: " + v.blind_slide + ")"
                                                      : "FAIL (see " + v.dir + "/runner.log)")
            << "\n" << std::flush;
}

// --prepare: every variant's scenario.yaml, none run.
void PrepareVariants(const CampaignArgs& a, const rover::tools::ScenarioSpec& spec, std::optional<double> slope) {
  for (int k = 1; k <= a.variants; ++k) {
    Variant v = MakeVariant(spec, slope, a.seed, k);
    v.dir = a.out_dir + "/v" + std::to_string(k);
    fs::create_directories(v.dir);
    WriteVariantScenario(spec, v, v.dir + "/scenario.yaml");
  }
  std::cout << "wrote " << a.variants << " variant scenarios: " << a.out_dir << "/v1/scenario.yaml ... v"
            << a.variants << "/scenario.yaml\n";
}

// Variant k's scenario: the listed file as written (--each), or drawn and written to DIR/vK.
Variant NextVariant(const CampaignArgs& a, const rover::tools::ScenarioSpec& spec, std::optional<double> slope,
                    const std::vector<std::string>& listed, int k, std::string* variant_yaml) {
  if (a.each()) {
    *variant_yaml = listed[static_cast<std::size_t>(k - 1)];
    return PreparedVariant(*variant_yaml, k);
  }
  Variant v = MakeVariant(spec, slope, a.seed, k);
  v.dir = a.out_dir + "/v" + std::to_string(k);
  fs::create_directories(v.dir);
  *variant_yaml = v.dir + "/scenario.yaml";
  WriteVariantScenario(spec, v, *variant_yaml);
  return v;
}

// Up to `jobs` variants run at once (each scenario_runner opens its own private bus); rows
// are printed in variant order as soon as each one and those before it are done.
std::vector<Variant> RunVariants(const CampaignArgs& a, const rover::tools::ScenarioSpec& spec,
                                 std::optional<double> slope, const std::vector<std::string>& listed) {
  const std::string runner = rover::launch::BinDir() + "/scenario_runner";
  std::vector<Variant> results(static_cast<std::size_t>(a.variants));
  std::map<pid_t, int> running;  // pid -> variant index (0-based)
  int next = 0, printed = 0;
  std::vector<bool> done(static_cast<std::size_t>(a.variants), false);
  while (printed < a.variants) {
    while (next < a.variants && static_cast<int>(running.size()) < a.jobs) {
      std::string variant_yaml;
      const Variant v = NextVariant(a, spec, slope, listed, next + 1, &variant_yaml);
      std::vector<std::string> runner_args = {runner, variant_yaml, "--out", v.dir, "--quiet"};
      if (!a.plot) runner_args.push_back("--no-plot");
      if (!a.rate.empty()) runner_args.insert(runner_args.end(), {"--rate", a.rate});
      results[static_cast<std::size_t>(next)] = v;
      running[StartLogged(runner_args, v.dir + "/runner.log")] = next;
      ++next;
    }
    const auto [pid, code] = WaitAny();
    const auto it = running.find(pid);
    if (it == running.end()) continue;
    Variant& v = results[static_cast<std::size_t>(it->second)];
    v.exit_code = code;
    ReadResults(v, a.window, a.slide_pct / 100.0);
    done[static_cast<std::size_t>(it->second)] = true;
    running.erase(it);
    while (printed < a.variants && done[static_cast<std::size_t>(printed)]) {
      PrintRow(printed + 1, results[static_cast<std::size_t>(printed)]);
      ++printed;
    }
  }
  return results;
}

struct Totals {
  int passed = 0, slides = 0, accepted = 0, false_updates = 0;
  double pass_pct = 0;
};

Totals Count(const std::vector<Variant>& results) {
  Totals t;
  for (const auto& v : results) {
    t.passed += v.passed();
    t.slides += !v.blind_slide.empty();
    t.accepted += v.vo_accepted;
    t.false_updates += v.false_updates;
  }
  t.pass_pct = 100.0 * t.passed / static_cast<double>(results.size());
  return t;
}

void WriteCampaignJson(const CampaignArgs& a, const rover::tools::ScenarioSpec& spec,
                       const std::vector<Variant>& results, const Totals& t) {
  rover::tools::JsonWriter j;
  j.BeginObject();
  j.Field("scenario", a.each() ? a.each_list : spec.source).Field("seed", static_cast<long long>(a.seed)).Field("variants", a.variants);
  j.Field("passed", t.passed).Field("pass_rate_pct", t.pass_pct).Field("min_pass_pct", a.min_pass_pct);
  j.Field("blind_slides", t.slides).Field("vo_updates_accepted", t.accepted).Field("false_updates", t.false_updates);
  j.Key("runs").BeginArray();
  for (const auto& v : results) {
    j.BeginObject();
    j.Field("variant", v.index).Field("dir", v.dir);
    j.Field("world_seed", static_cast<long long>(v.world_seed));
    j.Field("mobility_seed", static_cast<long long>(v.mobility_seed));
    j.Field("render_seed", static_cast<long long>(v.render_seed));
    j.Field("start_x", v.x).Field("start_y", v.y).Field("start_yaw_deg", v.yaw_deg);
    j.Key("slope_deg");
    if (v.slope_deg) {
      j.Value(*v.slope_deg);
    } else {
      j.Null();
    }
    j.Field("outcome", v.outcome).Field("abort_reason", v.abort_reason).Field("detail", v.detail);
    j.Key("min_keepout_clearance_m");
    if (v.clearance_m) {
      j.Value(*v.clearance_m);
    } else {
      j.Null();
    }
    j.Field("position_error_pct", v.position_error_pct).Field("steps", v.steps);
    j.Field("vo_updates_accepted", v.vo_accepted).Field("false_updates", v.false_updates);
    j.Field("log_digest", v.log_digest);
    j.Field("blind_slide", v.blind_slide).Field("runner_exit", v.exit_code).Field("passed", v.passed());
    j.EndObject();
  }
  j.EndArray();
  j.Key("tasks_missing").BeginArray();  // Slurm tasks a merge found unfinished (slurm_array.hpp)
  for (const auto& v : results) {
    if (!v.missing.empty()) j.BeginObject().Field("variant", v.index).Field("why", v.missing).EndObject();
  }
  j.EndArray();
  j.EndObject();
  std::ofstream(a.out_dir + "/campaign.json") << j.str();
  std::cout << "wrote " << a.out_dir << "/campaign.json\n";
}

// The pass-rate line and campaign.json; the exit status of a run (0: passed).
int Conclude(const CampaignArgs& a, const rover::tools::ScenarioSpec& spec, const std::vector<Variant>& results) {
  const Totals t = Count(results);
  std::cout << "pass rate: " << t.passed << "/" << a.variants << " (" << Fixed(t.pass_pct, 1) << " %, threshold "
            << Fixed(a.min_pass_pct, 1) << " %); blind slides: " << t.slides << "; false VO updates: "
            << t.false_updates << " of " << t.accepted << " accepted"
            << (t.accepted > 0 ? " (" + Fixed(100.0 * t.false_updates / t.accepted, 2) + " %)" : std::string())
            << "\n";
  WriteCampaignJson(a, spec, results, t);
  return t.pass_pct + 1e-9 >= a.min_pass_pct && t.slides == 0 ? 0 : 1;
}

std::string Absolute(const std::string& path) { return fs::absolute(path).lexically_normal().string(); }

// The Slurm array of a campaign: one task a variant (or a listed scenario).
slurm::ArrayPlan PlanFor(const CampaignArgs& a, const rover::tools::ScenarioSpec& spec,
                         const std::vector<std::string>& listed) {
  slurm::ArrayPlan plan;
  plan.out_dir = Absolute(a.out_dir);
  plan.source_dir = ROVER_SOURCE_DIR;
  plan.build_dir = fs::path(rover::launch::BinDir()).parent_path().string();
  plan.job_name = "rover-" + (a.each() ? fs::path(plan.out_dir).filename().string() : spec.name);
  plan.plot = a.plot;
  plan.rate = a.rate;
  for (int k = 1; k <= a.variants; ++k) {
    plan.scenarios.push_back(a.each() ? Absolute(listed[static_cast<std::size_t>(k - 1)])
                                      : plan.out_dir + "/v" + std::to_string(k) + "/scenario.yaml");
  }
  plan.sbatch_args = a.sbatch_args;
  if (a.each()) {
    plan.settings["each"] = Absolute(a.each_list);
  } else {
    plan.settings["scenario"] = Absolute(spec.source);
    plan.settings["variants"] = std::to_string(a.variants);
    plan.settings["seed"] = std::to_string(a.seed);
  }
  plan.settings["min_pass"] = Fixed(a.min_pass_pct, 6);
  plan.settings["slide_window"] = std::to_string(a.window);
  plan.settings["slide_progress"] = Fixed(a.slide_pct, 6);
  return plan;
}

// The campaign's settings from its Slurm plan, as its command line gave them.
CampaignArgs ArgsFromPlan(const slurm::ArrayPlan& plan) {
  CampaignArgs a;
  auto get = [&](const std::string& key) -> std::string {
    const auto it = plan.settings.find(key);
    if (it == plan.settings.end()) throw ConfigError(plan.slurm_dir() + "/plan.yaml: settings." + key + ": missing");
    return it->second;
  };
  a.out_dir = plan.out_dir;
  a.plot = plan.plot;
  a.rate = plan.rate;
  if (plan.settings.count("each")) {
    a.each_list = get("each");
    a.variants = static_cast<int>(plan.scenarios.size());
    a.scenario_path = plan.scenarios.front();
  } else {
    a.scenario_path = get("scenario");
    a.variants = std::stoi(get("variants"));
    a.seed = std::stoull(get("seed"));
  }
  a.min_pass_pct = std::stod(get("min_pass"));
  a.window = std::stoi(get("slide_window"));
  a.slide_pct = std::stod(get("slide_progress"));
  return a;
}

// --prepare and --slurm: the variants' scenario files and DIR/slurm/; --slurm submits it.
int PrepareArray(const CampaignArgs& a, const rover::tools::ScenarioSpec& spec, std::optional<double> slope,
                 const std::vector<std::string>& listed) {
  if (!a.each()) PrepareVariants(a, spec, slope);
  const slurm::ArrayPlan plan = PlanFor(a, spec, listed);
  slurm::WritePlan(plan);
  const std::string script = plan.slurm_dir() + "/array.sbatch";
  if (!a.slurm) {
    std::cout << "wrote " << script << " (" << a.variants << " tasks); sbatch " << script
              << " runs them (--slurm submits it too, so that --merge sees the queue)\n";
    return 0;
  }
  std::vector<int> all;
  for (int k = 1; k <= a.variants; ++k) all.push_back(k);
  const std::string job = slurm::Submit(plan, all);
  std::cout << "submitted Slurm job " << job << ": " << a.variants << " array tasks (" << script
            << "); follow them with squeue -j " << job << ", then merge: ./rover campaign --merge " << plan.out_dir
            << "\n";
  return 0;
}

// The variant of task k, as the local run draws it (its results not read yet).
Variant TaskVariant(const CampaignArgs& a, const slurm::ArrayPlan& plan, const rover::tools::ScenarioSpec& spec,
                    std::optional<double> slope, int k) {
  if (a.each()) return PreparedVariant(plan.scenarios[static_cast<std::size_t>(k - 1)], k);
  Variant v = MakeVariant(spec, slope, a.seed, k);
  v.dir = a.out_dir + "/v" + std::to_string(k);
  return v;
}

// --merge DIR: the table and campaign.json of the tasks that finished, as a local run
// writes them; every task that did not, named with why. Exit 3 when there is one.
int MergeArray(const std::string& dir) {
  const slurm::ArrayPlan plan = slurm::ReadPlan(dir);
  fs::current_path(plan.source_dir);  // scenario files name their worlds from the root
  CampaignArgs a = ArgsFromPlan(plan);
  const auto spec = rover::tools::LoadScenario(a.scenario_path);
  const std::optional<double> slope = a.each() ? std::nullopt : FirstSlope(spec);
  PrintHeader(a, spec, slope);
  const std::vector<slurm::TaskStatus> statuses = slurm::ReadStatuses(plan);
  std::vector<Variant> results;
  int missing = 0, queued = 0;
  for (int k = 1; k <= a.variants; ++k) {
    Variant v = TaskVariant(a, plan, spec, slope, k);
    const slurm::TaskStatus& st = statuses[static_cast<std::size_t>(k - 1)];
    if (st.done()) {
      v.exit_code = st.exit_code;
      ReadResults(v, a.window, a.slide_pct / 100.0);
    } else {
      v.missing = v.detail = st.why;
      missing += st.resubmit();
      queued += !st.resubmit();
    }
    PrintRow(k, v);
    results.push_back(v);
  }
  const int code = Conclude(a, spec, results);
  if (missing + queued == 0) return code;
  std::cout << "merged " << a.variants - missing - queued << " of " << a.variants << " tasks; ";
  if (queued > 0) std::cout << queued << " still in Slurm's queue (merge again when they end)" << (missing ? "; " : "");
  if (missing > 0) std::cout << missing << " missing or failed: ./rover campaign --resume " << plan.out_dir << " submits them again";
  std::cout << "\n";
  for (const auto& st : statuses) {
    if (!st.done()) std::cout << "  task " << st.task << ": " << st.why << "\n";
  }
  return 3;
}

// --resume DIR: the tasks missing or failed, submitted again (those queued are left).
int ResumeArray(const std::string& dir, const std::vector<std::string>& sbatch_args) {
  slurm::ArrayPlan plan = slurm::ReadPlan(dir);
  std::vector<int> tasks;
  int queued = 0;
  for (const auto& st : slurm::ReadStatuses(plan)) {
    if (st.resubmit()) {
      tasks.push_back(st.task);
      std::cout << "task " << st.task << ": " << st.why << "\n";
    }
    queued += st.state == slurm::TaskStatus::State::kQueued;
  }
  if (tasks.empty()) {
    std::cout << "nothing to submit again: every task finished" << (queued ? " or is still in Slurm's queue" : "") << "\n";
    return 0;
  }
  plan.sbatch_args.insert(plan.sbatch_args.end(), sbatch_args.begin(), sbatch_args.end());
  for (int k : tasks) slurm::ClearTask(plan, k);
  const std::string job = slurm::Submit(plan, tasks);
  if (!sbatch_args.empty()) slurm::WritePlan(plan);  // the next --resume passes them too
  std::cout << "submitted Slurm job " << job << ": tasks " << slurm::ArraySpec(tasks) << " again"
            << (queued ? " (" + std::to_string(queued) + " still queued, left as they are)" : "")
            << "; then merge: ./rover campaign --merge " << plan.out_dir << "\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return rover::bus::RunMain("scenario_campaign", [&]() -> int {
    auto parsed = ParseArgs(argc, argv);
    if (!parsed) return 0;
    CampaignArgs& a = *parsed;
    if (!a.merge_dir.empty()) return MergeArray(a.merge_dir);
    if (!a.resume_dir.empty()) return ResumeArray(a.resume_dir, a.sbatch_args);
    const std::vector<std::string> listed = a.each() ? ReadScenarioList(a.each_list) : std::vector<std::string>{};
    if (a.each()) {
      a.variants = static_cast<int>(listed.size());
      a.scenario_path = listed.front();
    }
    const auto spec = rover::tools::LoadScenario(a.scenario_path);
    if (a.out_dir.empty()) {
      a.out_dir = a.each() ? fs::path(a.each_list).parent_path().string() : "out/campaign/" + spec.name;
      if (a.out_dir.empty()) a.out_dir = ".";
    }
    fs::create_directories(a.out_dir);
    const std::optional<double> slope = a.each() ? std::nullopt : FirstSlope(spec);
    PrintHeader(a, spec, slope, !a.prepare_only && !a.slurm);
    if (a.prepare_only || a.slurm) return PrepareArray(a, spec, slope, listed);
    const std::vector<Variant> results = RunVariants(a, spec, slope, listed);
    return Conclude(a, spec, results);
  });
}
