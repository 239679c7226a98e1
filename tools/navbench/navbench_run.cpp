#include "navbench/navbench_run.hpp"

#include "bus/channels.hpp"
#include "bus/keepout_convert.hpp"
#include "config/yaml_config.hpp"
#include "hazards/hazard_assessor.hpp"
#include "logcheck/log_reader.hpp"
#include "scenario/scenario.hpp"
#include "terrain/world.hpp"

#include <lcm/lcm-cpp.hpp>
#include <rover_msgs/keepout_zones_t.hpp>
#include <rover_msgs/sim_truth_t.hpp>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <random>
#include <sstream>
#include <stdexcept>

namespace fs = std::filesystem;

namespace rover::navbench {

namespace {

constexpr double kPi = 3.14159265358979323846;
// Room round the start and goal on a rock field's map: a detour may swing this far out.
constexpr double kMapMarginM = 12.0;
// No rock within this of the start or of the goal: a footprint's half-diagonal and a bit,
// so that every run can start, and every goal can be reached.
constexpr double kClearRadiusM = 1.6;

std::string Fixed(double v, int digits) {
  std::ostringstream os;
  os << std::fixed << std::setprecision(digits) << v;
  return os.str();
}

// The seed stream of one run: the benchmark's seed, its world kind and its index.
std::mt19937_64 RunRng(std::uint64_t seed, std::uint64_t kind, int index) {
  std::seed_seq seq{static_cast<std::uint32_t>(seed), static_cast<std::uint32_t>(seed >> 32),
                    static_cast<std::uint32_t>(kind), static_cast<std::uint32_t>(index)};
  return std::mt19937_64(seq);
}

std::string DensityLabel(double k) { return Fixed(k, 2); }

void WriteFile(const std::string& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
  if (!out) throw std::runtime_error(path + ": cannot write");
}

}  // namespace

const std::vector<FixedWorld>& FixedWorlds() {
  static const std::vector<FixedWorld> worlds = {
      // A wall of rocks over the step limit with one 3 m gap; the goal behind it.
      {"gap_wall", "configs/worlds/rock_gap_wall.yaml", 7.5, 0.0},
      // A U-shaped pocket of rocks over the limit opening toward the start; the goal behind
      // its closed end.
      {"cul_de_sac", "configs/worlds/rock_cul_de_sac.yaml", 10.0, 0.0},
  };
  return worlds;
}

double RunPlan::straight_m() const { return std::hypot(goal_x, goal_y); }

std::vector<RunPlan> PlanRuns(const BenchOptions& options) {
  std::vector<RunPlan> plans;
  const std::string root = fs::absolute(options.out_dir).lexically_normal().string();
  auto draw_seeds = [](std::mt19937_64& rng, RunPlan& p) {
    p.world_seed = 1 + rng() % 1000000;
    p.mobility_seed = 1 + rng() % 1000000;
    p.render_seed = 1 + rng() % 1000000;
  };
  for (const double k : options.densities) {
    for (int i = 1; i <= options.runs; ++i) {
      // The kind is k in thousandths: the same k draws the same runs in any set.
      std::mt19937_64 rng = RunRng(options.seed, static_cast<std::uint64_t>(std::lround(k * 1000)), i);
      std::uniform_real_distribution<double> unit(0.0, 1.0);
      RunPlan p;
      p.group = "k=" + DensityLabel(k);
      p.abundance_k = k;
      p.index = i;
      std::ostringstream id;
      id << "k" << DensityLabel(k) << "_r" << std::setw(2) << std::setfill('0') << i;
      p.id = id.str();
      p.dir = root + "/runs/" + p.id;
      draw_seeds(rng, p);
      const double length = options.min_goal_m + (options.max_goal_m - options.min_goal_m) * unit(rng);
      const double bearing = 2 * kPi * unit(rng);
      p.goal_x = length * std::cos(bearing);
      p.goal_y = length * std::sin(bearing);
      // The rover starts facing the goal within +-30 deg; the sun anywhere in azimuth.
      p.start_yaw_deg = bearing * 180 / kPi + 60 * (unit(rng) - 0.5);
      if (p.start_yaw_deg > 180) p.start_yaw_deg -= 360;
      p.sun_azimuth_deg = 360 * unit(rng);
      p.sun_elevation_deg = 35 + 30 * unit(rng);
      plans.push_back(p);
    }
  }
  for (const std::string& name : options.worlds) {
    const FixedWorld* world = nullptr;
    std::uint64_t kind = 100000;
    for (const auto& w : FixedWorlds()) {
      ++kind;
      if (w.name == name) {
        world = &w;
        break;
      }
    }
    if (world == nullptr) throw std::invalid_argument("navbench: unknown world '" + name + "'");
    for (int i = 1; i <= options.runs; ++i) {
      std::mt19937_64 rng = RunRng(options.seed, kind, i);
      std::uniform_real_distribution<double> unit(0.0, 1.0);
      RunPlan p;
      p.group = name;
      p.index = i;
      std::ostringstream id;
      id << name << "_r" << std::setw(2) << std::setfill('0') << i;
      p.id = id.str();
      p.dir = root + "/runs/" + p.id;
      p.world_file = world->world_file;
      draw_seeds(rng, p);
      p.goal_x = world->goal_x;
      p.goal_y = world->goal_y;
      p.start_yaw_deg = std::atan2(p.goal_y, p.goal_x) * 180 / kPi + 20 * (unit(rng) - 0.5);
      plans.push_back(p);
    }
  }
  return plans;
}

std::string RockFieldYaml(const RunPlan& p) {
  const double min_x = std::min(0.0, p.goal_x) - kMapMarginM, max_x = std::max(0.0, p.goal_x) + kMapMarginM;
  const double min_y = std::min(0.0, p.goal_y) - kMapMarginM, max_y = std::max(0.0, p.goal_y) + kMapMarginM;
  std::ostringstream os;
  os << "# navbench rock field " << p.id << " (tools/navbench): Golombek rocks at k = " << *p.abundance_k
     << ",\n# 0.1 to 1.5 m, none within " << kClearRadiusM << " m of the start (0, 0) or the goal ("
     << Fixed(p.goal_x, 2) << ", " << Fixed(p.goal_y, 2) << "). Keys: common/terrain/WORLD_FORMAT.md.\n"
     << "name: navbench_" << p.id << "\n"
     << "seed: " << p.world_seed << "\n"
     << "map: {center: [" << Fixed(0.5 * (min_x + max_x), 2) << ", " << Fixed(0.5 * (min_y + max_y), 2)
     << "], size_m: [" << Fixed(max_x - min_x, 2) << ", " << Fixed(max_y - min_y, 2) << "], resolution_m: 0.05}\n"
     << "roughness: {amplitude_m: 0.01, min_wavelength_m: 0.3, max_wavelength_m: 6.0}\n"
     << "soil:\n  default: packed_soil\n"
     << "rocks:\n  random:\n"
     << "    abundance_k: " << *p.abundance_k << "\n"
     << "    min_diameter_m: 0.1\n    max_diameter_m: 1.5\n"
     << "    exclude:\n"
     << "      - {circle: {center: [0, 0], radius_m: " << kClearRadiusM << "}}\n"
     << "      - {circle: {center: [" << Fixed(p.goal_x, 3) << ", " << Fixed(p.goal_y, 3)
     << "], radius_m: " << kClearRadiusM << "}}\n"
     << "albedo:\n  packed_soil: {mean: 0.28, contrast: 0.18}\n  rock_contrast: 0.2\n"
     << "sun: {azimuth_deg: " << Fixed(p.sun_azimuth_deg, 1) << ", elevation_deg: " << Fixed(p.sun_elevation_deg, 1)
     << "}\n"
     << "start: {x: 0, y: 0, yaw_deg: " << Fixed(p.start_yaw_deg, 2) << "}\n";
  return os.str();
}

std::string SequenceText(const RunPlan& p) {
  // Room for a path of three times the straight line, and rover time for it at a slow
  // 100 m/h (today's rate on rock fields is measured by navbench itself).
  const double straight = p.straight_m();
  const double goto_distance = std::ceil(3 * straight);
  const double time_s = std::ceil(goto_distance * 36.0 / 60.0) * 60.0;
  std::ostringstream os;
  os << "# navbench " << p.id << " (tools/navbench): " << Fixed(straight, 2) << " m to ("
     << Fixed(p.goal_x, 2) << ", " << Fixed(p.goal_y, 2) << ") with hazard avoidance.\n"
     << "vo on step 60 cm maxturn 18 deg failures 10 then continue\n"
     << "limit time " << time_s + 60 << " s distance " << goto_distance + 2 << " m\n"
     << "goto " << Fixed(p.goal_x, 3) << " m " << Fixed(p.goal_y, 3) << " m within " << p.goal_radius_m
     << " m time " << time_s << " s distance " << goto_distance << " m avoid on\n";
  return os.str();
}

tools::ConfigOverride ParseSetting(const std::string& text) {
  const std::size_t eq = text.find('=');
  const std::string key = text.substr(0, eq);
  auto bad = [&text](const std::string& why) {
    return config::ConfigError("navbench: --set \"" + text + "\": " + why);
  };
  if (eq == std::string::npos) throw bad("expected KEY=VALUE (a dotted rover-config key, e.g. executor.avoid_margin_m=0.2)");
  if (key.empty() || key.front() == '.' || key.back() == '.' || key.find("..") != std::string::npos)
    throw bad("expected a dotted key before '=' with no empty part");
  tools::ConfigOverride o;
  o.key = key;
  try {
    o.value = YAML::Load(text.substr(eq + 1));
  } catch (const YAML::Exception& e) {
    throw bad("the value is not YAML (" + e.msg + ")");
  }
  if (!o.value.IsDefined() || o.value.IsNull()) throw bad("expected a value after '='");
  return o;
}

void WriteRun(const RunPlan& p, const std::vector<tools::ConfigOverride>& overrides) {
  fs::create_directories(p.dir);
  std::string world = p.world_file.empty() ? p.dir + "/field.yaml" : fs::absolute(p.world_file).string();
  if (p.world_file.empty()) WriteFile(world, RockFieldYaml(p));
  WriteFile(p.dir + "/goto.seq", SequenceText(p));
  YAML::Emitter y;
  y << YAML::BeginMap;
  y << YAML::Key << "name" << YAML::Value << "navbench_" + p.id;
  y << YAML::Key << "description" << YAML::Value
    << "navbench: goto " + Fixed(p.straight_m(), 1) + " m with avoidance, VO and the map on";
  y << YAML::Key << "world" << YAML::Value << world;
  y << YAML::Key << "sequence" << YAML::Value << p.dir + "/goto.seq";
  // Named without the output folder, so that a run's log digest is the same wherever --out is.
  y << YAML::Key << "sequence_name" << YAML::Value << "navbench/" + p.id + "/goto.seq";
  y << YAML::Key << "deployment" << YAML::Value << "configs/deploy/sim_vo.yaml";
  y << YAML::Key << "start" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key << "x" << YAML::Value << 0
    << YAML::Key << "y" << YAML::Value << 0 << YAML::Key << "yaw_deg" << YAML::Value << p.start_yaw_deg
    << YAML::EndMap;
  // As fast as the barrier allows: virtual time makes the result independent of the rate.
  y << YAML::Key << "sim_rate" << YAML::Value << 10000;
  // Wall-clock limit: generous, so that only a hung run reaches it (the sequence's rover-time
  // limits end a wandering one).
  y << YAML::Key << "timeout_s" << YAML::Value << 7200;
  y << YAML::Key << "seeds" << YAML::Value << YAML::Flow << YAML::BeginMap;
  y << YAML::Key << "world" << YAML::Value << p.world_seed;
  y << YAML::Key << "mobility" << YAML::Value << p.mobility_seed << YAML::Key << "render" << YAML::Value
    << p.render_seed << YAML::EndMap;
  y << YAML::Key << "overrides" << YAML::Value << YAML::BeginMap;
  // The map on, unless a setting says otherwise.
  bool map_set = false;
  for (const auto& o : overrides) map_set = map_set || o.key == "hazards.map.enabled";
  if (!map_set) y << YAML::Key << "hazards.map.enabled" << YAML::Value << true;
  for (const auto& o : overrides) y << YAML::Key << o.key << YAML::Value << o.value;
  y << YAML::EndMap;
  y << YAML::Key << "expect" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key << "outcome"
    << YAML::Value << "completed" << YAML::EndMap;
  y << YAML::EndMap;
  WriteFile(p.scenario_path(), "# navbench run " + p.id + " (tools/navbench; ./rover navbench)\n" +
                                   std::string(y.c_str()) + "\n");
}

namespace {

// SIM_TRUTH as plane poses, and every keep-out zone ever in force (by name, the last
// definition), from a run's log.
void ReadLog(const std::string& log_path, std::vector<hazards::Pose2>* truth, std::vector<hazards::KeepOutZone>* zones) {
  rover::logcheck::LogReader log(log_path);
  if (!log.good()) throw std::runtime_error(log_path + ": cannot read the LCM log");
  std::vector<std::pair<std::int64_t, hazards::Pose2>> samples;
  std::map<std::string, hazards::KeepOutZone> by_name;
  for (const lcm::LogEvent* ev = log.readNextEvent(); ev != nullptr; ev = log.readNextEvent()) {
    if (ev->channel == channels::kSimTruth) {
      rover_msgs::sim_truth_t m;
      if (m.decode(ev->data, 0, ev->datalen) >= 0) samples.push_back({m.utime, {m.position[0], m.position[1], m.rpy[2]}});
    } else if (ev->channel == channels::kKeepOutZones) {
      rover_msgs::keepout_zones_t m;
      if (m.decode(ev->data, 0, ev->datalen) < 0) continue;
      try {
        for (auto& z : bus::ZonesFromMsg(m)) by_name[z.name] = z;
      } catch (const std::invalid_argument&) {
        // An invalid set was never in force (the hazard monitor refused it).
      }
    }
  }
  std::stable_sort(samples.begin(), samples.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  for (const auto& s : samples) truth->push_back(s.second);
  for (auto& [name, z] : by_name) zones->push_back(z);
}

// The plan on a perfect map of `world` for the run's goto, with `rover_config`'s settings.
PerfectWay PerfectWayIn(const terrain::World& world, const config::ConfigNode& rover_config,
                        const tools::ScenarioSpec& spec, const RunPlan& p, bool at_mean = false) {
  const PerfectWayOptions o = LoadPerfectWayOptions(rover_config);
  return PlanPerfectWay(PerfectMap(world, o.map, at_mean), o.planner, Eigen::Vector2d(spec.start_x, spec.start_y),
                        Eigen::Vector2d(p.goal_x, p.goal_y), p.goal_radius_m);
}

double Number(const YAML::Node& node, double fallback = 0) {
  return node && !node.IsNull() ? node.as<double>() : fallback;
}

}  // namespace

RunFigures ReadRun(const RunPlan& p, RunTrack* track) {
  RunFigures r;
  r.group = p.group;
  r.id = p.id;
  r.straight_m = p.straight_m();
  r.goal_x = p.goal_x;
  r.goal_y = p.goal_y;
  r.goal_radius_m = p.goal_radius_m;
  const std::string summary_path = p.dir + "/summary.json";
  if (!fs::exists(summary_path)) return r;
  r.ran = true;
  const YAML::Node s = YAML::LoadFile(summary_path);
  r.outcome = s["outcome"].as<std::string>();
  r.abort_reason = s["abort_reason"].IsNull() ? "" : s["abort_reason"].as<std::string>();
  if (const YAML::Node b = s["rover_time_breakdown"]; b && b.IsMap()) {
    r.rover_time_s = Number(b["span_s"]);
    r.driving_s = Number(b["driving_s"]);
    r.imaging_s = Number(b["imaging_s"]);
    r.vo_s = Number(b["vo_s"]);
    r.mapping_s = Number(b["mapping_s"]);
    r.planning_s = Number(b["planning_s"]);
    r.waiting_s = Number(b["waiting_s"]);
    r.steps = static_cast<int>(Number(b["steps"]));
    r.steps_thought_ahead = static_cast<int>(Number(b["steps_thought_ahead"]));
  }
  r.vo_accepted = static_cast<int>(Number(s["vo_updates_accepted"]));
  r.vo_false = static_cast<int>(Number(s["false_updates"]));
  if (const YAML::Node h = s["pose_honesty"]; h && h.IsMap()) {
    r.horizontal_poses = static_cast<int>(Number(h["horizontal_poses"]));
    r.horizontal_nees_mean = Number(h["horizontal_nees_mean"]);
    r.horizontal_beyond_pct = Number(h["horizontal_beyond_3_sigma_pct"]);
  }

  // The world and rover config the run used: the runner's copies when the scenario
  // overrode them (scenario_overrides.hpp), else the originals.
  const tools::ScenarioSpec spec = tools::LoadScenario(p.scenario_path());
  const std::string world_path = spec.world_overrides.empty() ? spec.world : p.dir + "/world.yaml";
  const std::string rover_path = spec.overrides.empty() ? spec.rover_config : p.dir + "/rover.yaml";
  const auto rover_config = config::ConfigNode::LoadFile(rover_path);
  const auto footprint = hazards::LoadHazardOptions(rover_config["hazards"], {"publish_hz"}).footprint;
  double max_height_m = 0.3, wheelbase_m = 1.1, track_m = 1.0;
  rover_config["mobility"]["rock_collision"].Get("max_height_m", max_height_m);
  rover_config["mobility"]["geometry"].Get("wheelbase_m", wheelbase_m);
  rover_config["mobility"]["geometry"].Get("track_m", track_m);
  const terrain::World world(terrain::WorldOptions::LoadFile(world_path));

  RunTrack t;
  const auto& o = world.options();
  t.map = {o.map_center.x() - 0.5 * o.map_size_m.x(), o.map_center.x() + 0.5 * o.map_size_m.x(),
           o.map_center.y() - 0.5 * o.map_size_m.y(), o.map_center.y() + 0.5 * o.map_size_m.y()};
  std::vector<const terrain::Rock*> tall;  // parallel to t.rocks_over_limit
  for (const auto& rock : world.rocks()) {
    const auto disc = hazards::KeepOutZone::Circle(rock.name.empty() ? "rock" : rock.name, rock.position.x(),
                                                   rock.position.y(), 0.5 * rock.diameter_m);
    (rock.height_m > max_height_m ? t.rocks_over_limit : t.small_rocks).push_back(disc);
    if (rock.height_m > max_height_m) tall.push_back(&rock);
  }
  ReadLog(p.dir + "/log.lcm", &t.truth, &t.zones);

  t.footprint = footprint;
  // Rocks as the simulator judges them (mobility.rock_collision): a contact when the surface
  // under the footprint rises over the belly's clearance; a corner over a rim is a graze.
  const CollisionReport rocks = JudgeRockCollisions(
      t.truth, footprint, t.rocks_over_limit,
      [&](std::size_t i, double gap_m) { return terrain::RockHeightAt(*tall[i], gap_m); }, max_height_m);
  const CollisionReport zones = JudgeCollisions(t.truth, footprint, t.zones);
  r.rock_contacts = rocks.contacts;
  r.rock_grazes = static_cast<int>(rocks.grazed.size());
  r.zone_contacts = zones.contacts;
  for (const auto* c : {&rocks, &zones}) {
    for (const std::size_t k : c->contact_samples) t.contact_poses.push_back(t.truth[k]);
  }
  r.off_map_samples = WheelsOffMap(t.truth, SixWheels(wheelbase_m, track_m), t.map).samples;
  r.driven_m = PathLength(t.truth);
  r.path_ratio = PathRatio(r.driven_m, Eigen::Vector2d(spec.start_x, spec.start_y), Eigen::Vector2d(p.goal_x, p.goal_y));
  // What the path ratio could at best be: the shortest way round every rock the map must
  // rate unsafe (taller than its step limit, hazards.map.traversability.max_step_m: the
  // stack refuses them, not only those over the collision height), the rover's centre half
  // its width off their discs.
  {
    double max_step_m = max_height_m;
    rover_config["hazards"]["map"]["traversability"].Get("max_step_m", max_step_m);
    std::vector<hazards::KeepOutZone> refused;
    for (const auto& rock : world.rocks())
      if (rock.height_m > max_step_m)
        refused.push_back(hazards::KeepOutZone::Circle("rock", rock.position.x(), rock.position.y(), 0.5 * rock.diameter_m));
    const ShortestPath best =
        ShortestSafePath(refused, 0.5 * footprint.width_m, Eigen::Vector2d(spec.start_x, spec.start_y),
                         Eigen::Vector2d(p.goal_x, p.goal_y), p.goal_radius_m, t.map);
    r.shortest_m = best.length_m;
    t.shortest = best.path;
  }
  {
    const PerfectWay way = PerfectWayIn(world, rover_config, spec, p);
    r.perfect_way = way.reachable;
    r.perfect_way_m = way.length_m;
  }
  if (!t.truth.empty()) {
    r.final_truth = Eigen::Vector2d(t.truth.back().x, t.truth.back().y);
    r.in_goal_disc = (*r.final_truth - Eigen::Vector2d(p.goal_x, p.goal_y)).norm() <= p.goal_radius_m;
  }
  if (track != nullptr) *track = std::move(t);
  return r;
}

PerfectWay RunPerfectWay(const RunPlan& p, bool at_mean) {
  const tools::ScenarioSpec spec = tools::LoadScenario(p.scenario_path());
  fs::create_directories(p.dir + "/perfect_way");
  const tools::RunConfigs files =
      tools::PrepareRunConfigs(spec.rover_config, spec.overrides, spec.world, spec.world_overrides, p.dir + "/perfect_way");
  const terrain::World world(terrain::WorldOptions::LoadFile(files.world));
  return PerfectWayIn(world, config::ConfigNode::LoadFile(files.rover_config), spec, p, at_mean);
}

}  // namespace rover::navbench
