// ./rover hazard-eval WORLD.yaml: how well the rover's own traversability map finds the
// world's hazards (hazard_evaluation.hpp).
//   hazard_eval WORLD.yaml [--rig configs/cameras/navcam_pinhole.yaml] [--size 512]
//               [--rover-config configs/rover.yaml] [--map-options FILE.yaml]
//               [--poses "x,y,yaw_deg;x,y,yaw_deg;..."] [--steps 5] [--step-m 0.5]
//               [--min-detection 0.95] [--max-false-unsafe 0.05] [--verbose]
//               [--hazcam configs/cameras/hazcam_front.yaml] [--dump-cells R]
//               [--truth-height max|mean] [--top-rise M]
// --hazcam: the front HAZCAM pair as well, rendered at 256 px at each pose and mapped with the
// rover config's hazards.map.hazcam options before the main pair (as hazard_monitor gets it).
// --dump-cells R: every rated in-view cell within R m, the map's and the truth's ratings
// and tops (the map's: its points' mean height plus one standard deviation).
// --top-rise M: also the vote's view with executor.avoid_top_rise_m at M (a cell whose top
// stands M over the ground round it is unsafe to the vote): rocks and cells it finds, and the
// traversable cells it marks.
// --truth-height max|mean: a cell's true height is its highest point (max, the default:
// what the body meets) or its mean (what the map's cells measure).
// --poses items may add that pair's own pose error: x,y,yaw,ex,ey,ez,eroll,epitch,eyaw.
// --pose-error x,y,z,roll,pitch,yaw: the map gets each pair at the true pose moved by these
// (metres, degrees), as an estimate's error at capture.
// --attitude roll,pitch: the rover stands at this roll and pitch (deg) at every pose, not at
// the ground's normal (rover_sim settles the rover on its wheels: -0.70, 0.26 at
// flat_rock_course's start).
// --pose-sigma m,deg: the pose covariance handed to the map (0.02 m, 0.5 deg; the state
// estimator's at the start: 0, 0.2).
// --frame-seed S: the first pose's pair is rendered with noise seed S (then S + 1, ...; 1).
// --map-options: a YAML of traversability::MapOptions keys, bare, under `traversability:`,
// or a rover config's hazards.map.traversability (configs/rover.yaml: hazard_monitor's map).
// Default poses: the world's start and --steps - 1 more, --step-m apart along its heading.
// --min-detection / --max-false-unsafe check the 0-4 m row: exit 1 when one fails.
// Bad arguments or files: one line naming what was expected, exit 2.
#include "hazard_evaluation.hpp"

#include "config/yaml_config.hpp"
#include "config/number_list.hpp"
#include "geometry/camera_io.hpp"

#include <opencv2/core/utility.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace {

int Usage(const std::string& message) {
  std::cerr << "hazard-eval: " << message << "\n";
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace rover;
  std::string world_path, rig_path = "configs/cameras/navcam_pinhole.yaml";
  std::string rover_path = "configs/rover.yaml", map_path, poses_text, hazcam_path;
  double size = 512, steps = 5, step_m = 0.5, min_detection = -1, max_false_unsafe = -1, dump_m = 0, top_rise_m = 0,
         frame_seed = 1;
  bool verbose = false, truth_at_mean = false;
  std::array<double, 6> pose_error = {0, 0, 0, 0, 0, 0};
  std::optional<std::array<double, 2>> attitude, pose_sigma;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has = i + 1 < argc;
    if (a == "--help" || a == "-h") {
      std::cout << "usage: hazard-eval WORLD.yaml [--rig RIG.yaml] [--size N] [--rover-config FILE]\n"
                   "       [--map-options FILE] [--poses \"x,y,yaw;...\"] [--steps N] [--step-m M]\n"
                   "       [--min-detection F] [--max-false-unsafe F] [--verbose]\n"
                   "       [--hazcam HAZCAM_RIG.yaml] [--dump-cells R] [--frame-seed S]\n"
                   "       [--pose-error x,y,z,roll,pitch,yaw] [--attitude roll,pitch]\n"
                   "       [--pose-sigma m,deg] [--truth-height max|mean] [--top-rise M]\n";
      return 0;
    } else if (a == "--rig") {
      if (!has) return Usage("--rig: expected a stereo rig YAML file");
      rig_path = argv[++i];
    } else if (a == "--rover-config") {
      if (!has) return Usage("--rover-config: expected the rover YAML (configs/rover.yaml)");
      rover_path = argv[++i];
    } else if (a == "--map-options") {
      if (!has) return Usage("--map-options: expected a YAML file of traversability map options");
      map_path = argv[++i];
    } else if (a == "--poses") {
      if (!has) return Usage("--poses: expected \"x,y,yaw_deg;x,y,yaw_deg;...\"");
      poses_text = argv[++i];
    } else if (a == "--size") {
      if (!has || !config::ParseNumberInRange(argv[++i], 64, 2048, &size) || size != std::floor(size))
        return Usage("--size: expected an image width in pixels, an integer in [64, 2048]");
    } else if (a == "--steps") {
      if (!has || !config::ParseNumberInRange(argv[++i], 1, 50, &steps) || steps != std::floor(steps))
        return Usage("--steps: expected a number of poses, an integer in [1, 50]");
    } else if (a == "--step-m") {
      if (!has || !config::ParseNumberInRange(argv[++i], 0.01, 10, &step_m))
        return Usage("--step-m: expected metres between poses, in [0.01, 10]");
    } else if (a == "--min-detection") {
      if (!has || !config::ParseNumberInRange(argv[++i], 0, 1, &min_detection))
        return Usage("--min-detection: expected a fraction in [0, 1]");
    } else if (a == "--max-false-unsafe") {
      if (!has || !config::ParseNumberInRange(argv[++i], 0, 1, &max_false_unsafe))
        return Usage("--max-false-unsafe: expected a fraction in [0, 1]");
    } else if (a == "--hazcam") {
      if (!has) return Usage("--hazcam: expected the HAZCAM rig YAML file (configs/cameras/hazcam_front.yaml)");
      hazcam_path = argv[++i];
    } else if (a == "--pose-error") {
      std::vector<double> v;
      if (!has || !config::ParseNumberList(argv[++i], &v) || v.size() != 6)
        return Usage("--pose-error: expected \"x,y,z,roll,pitch,yaw\" (metres, degrees)");
      std::copy(v.begin(), v.end(), pose_error.begin());
    } else if (a == "--attitude") {
      std::vector<double> v;
      if (!has || !config::ParseNumberList(argv[++i], &v) || v.size() != 2 || std::abs(v[0]) > 45 || std::abs(v[1]) > 45)
        return Usage("--attitude: expected \"roll,pitch\" (degrees, each within 45)");
      attitude = {v[0], v[1]};
    } else if (a == "--pose-sigma") {
      std::vector<double> v;
      if (!has || !config::ParseNumberList(argv[++i], &v) || v.size() != 2 || !(v[0] >= 0 && v[0] <= 10) ||
          !(v[1] >= 0 && v[1] <= 45))
        return Usage("--pose-sigma: expected \"m,deg\" (position sigma in [0, 10] m, attitude sigma in [0, 45] deg)");
      pose_sigma = {v[0], v[1]};
    } else if (a == "--frame-seed") {
      if (!has || !config::ParseNumberInRange(argv[++i], 1, 1e9, &frame_seed) || frame_seed != std::floor(frame_seed))
        return Usage("--frame-seed: expected the first pair's noise seed, an integer in [1, 1e9]");
    } else if (a == "--truth-height") {
      const std::string v = has ? argv[++i] : "";
      if (v != "max" && v != "mean") return Usage("--truth-height: expected max or mean");
      truth_at_mean = v == "mean";
    } else if (a == "--top-rise") {
      if (!has || !config::ParseNumberInRange(argv[++i], 0.05, 1, &top_rise_m))
        return Usage("--top-rise: expected a height in metres, in [0.05, 1]");
    } else if (a == "--dump-cells") {
      if (!has || !config::ParseNumberInRange(argv[++i], 0.1, 10, &dump_m))
        return Usage("--dump-cells: expected a range in metres, in [0.1, 10]");
    } else if (a == "--verbose") {
      verbose = true;
    } else if (!a.empty() && a[0] == '-') {
      return Usage("unknown option '" + a + "' (see --help)");
    } else if (world_path.empty()) {
      world_path = a;
    } else {
      return Usage("unexpected argument '" + a + "' (expected one WORLD.yaml)");
    }
  }
  if (world_path.empty()) return Usage("expected a world file (WORLD.yaml) as the first argument");

  try {
    hazard_eval::EvalOptions options;
    options.image_size = static_cast<int>(size);
    const config::ConfigNode root = config::ConfigNode::LoadFile(world_path);
    terrain::WorldOptions world_options;
    if (root.Has("render")) {
      options.render = render::LoadRenderOptions(root["render"]);
      YAML::Node copy = YAML::Clone(root.yaml());
      copy.remove("render");
      world_options = terrain::WorldOptions::Load(config::ConfigNode(copy, world_path, ""));
    } else {
      world_options = terrain::WorldOptions::Load(root);
    }
    const config::ConfigNode rover = config::ConfigNode::LoadFile(rover_path);
    const config::ConfigNode rc = rover["mobility"]["rock_collision"];
    if (rc.IsNull() || !rc.Has("max_height_m"))
      rc.Fail("expected mobility.rock_collision.max_height_m (the rover's step limit)");
    options.rock_limit_m = rc.RequireDouble("max_height_m", 0.01, 5.0);
    // The map options: --map-options, else the rover config's own (what the hazard
    // monitor builds its map with).
    if (map_path.empty() && rover.Has("hazards") && rover["hazards"].Has("map") &&
        rover["hazards"]["map"].Has("traversability")) {
      options.map = traversability::LoadMapOptions(rover["hazards"]["map"]["traversability"]);
    } else if (!map_path.empty()) {
      const config::ConfigNode m = config::ConfigNode::LoadFile(map_path);
      // A bare options map, a `traversability:` section, or a rover config's
      // hazards.map.traversability.
      if (m.Has("hazards") && m["hazards"].Has("map") && m["hazards"]["map"].Has("traversability"))
        options.map = traversability::LoadMapOptions(m["hazards"]["map"]["traversability"]);
      else
        options.map = traversability::LoadMapOptions(m.Has("traversability") ? m["traversability"] : m);
    }
    if (!poses_text.empty()) {
      std::stringstream ss(poses_text);
      std::string item;
      while (std::getline(ss, item, ';')) {
        std::vector<double> v;
        if (!config::ParseNumberList(item, &v) || (v.size() != 3 && v.size() != 9))
          return Usage("--poses: '" + item + "': expected x,y,yaw_deg (metres, degrees), then optionally that pair's "
                       "pose error x,y,z,roll,pitch,yaw");
        hazard_eval::EvalPose ep{v[0], v[1], v[2]};
        if (v.size() == 9) std::copy(v.begin() + 3, v.end(), ep.error.begin());
        options.poses.push_back(ep);
      }
    } else {
      const auto& s = world_options.start;
      const double yaw = s.yaw_deg * M_PI / 180.0;
      for (int k = 0; k < static_cast<int>(steps); ++k)
        options.poses.push_back({s.x + k * step_m * std::cos(yaw), s.y + k * step_m * std::sin(yaw), s.yaw_deg});
    }
    if (!hazcam_path.empty()) {
      const config::ConfigNode m = rover["hazards"]["map"];
      if (m.IsNull() || !m.Has("hazcam")) m.Fail("expected hazards.map.hazcam (the HAZCAM pair's stereo options)");
      options.hazcam_map = traversability::LoadCameraOptions(m["hazcam"], options.map);
      options.hazcam_rig = geometry::LoadStereoRigFile(hazcam_path);
    }
    options.dump_range_m = dump_m;
    options.truth_at_cell_mean = truth_at_mean;
    options.top_rise_m = top_rise_m;
    options.first_frame_seed = static_cast<std::int64_t>(frame_seed);
    options.pose_error = pose_error;
    if (attitude) {
      options.fixed_attitude = true;
      options.roll_deg = (*attitude)[0];
      options.pitch_deg = (*attitude)[1];
    }
    if (pose_sigma) {
      options.pose_sigma_m = (*pose_sigma)[0];
      options.pose_sigma_deg = (*pose_sigma)[1];
    }
    const geometry::StereoRig rig = geometry::LoadStereoRigFile(rig_path);
    const terrain::World world(world_options);
    cv::setNumThreads(1);  // one core, as on the rover computer

    const hazard_eval::EvalResult r = hazard_eval::Evaluate(world, rig, options);
    std::printf("hazard-eval: world %s, %zu poses, %dx%d stereo pairs, map step limit %.2f m, "
                "rover step limit %.2f m\n",
                world_options.name.c_str(), options.poses.size(), options.image_size,
                options.image_size * rig.left->height() / rig.left->width(), options.map.max_step_m,
                options.rock_limit_m);
    std::printf("%s", hazard_eval::FormatTable(r, options.rock_limit_m, options.top_rise_m).c_str());
    std::printf("map update (AddStereoPair + rating): median %.0f ms over %zu pairs\n",
                1000 * r.median_update_seconds, r.update_seconds.size());
    for (const auto& s : r.sightings) {
      if (!verbose && s.detected) continue;
      std::printf("  %s %s from pose %d at %.1f m: %.2f m tall, map step %.2f m (%s)\n",
                  s.detected ? "found " : "MISSED", s.name.c_str(), s.pose, s.range_m, s.height_m,
                  s.step_m, s.state.c_str());
    }
    if (verbose) {
      for (const auto& f : r.false_unsafe)
        std::printf("  false unsafe from pose %d at %.1f m, cell (%.1f, %.1f): map step %.2f tilt %.1f "
                    "rough %.3f; truth step %.2f tilt %.1f rough %.3f (%s)\n",
                    f.pose, f.range_m, f.x, f.y, f.map.step_m, f.map.tilt_rad * 180 / M_PI,
                    f.map.roughness_m, f.truth.step_m, f.truth.tilt_rad * 180 / M_PI,
                    f.truth.roughness_m, traversability::CellStateName(f.truth.state));
    }
    for (const auto& d : r.dumped)
      std::printf("  cell from pose %d at %.1f m (%.1f, %.1f): map %s step %.2f tilt %.1f rough %.3f sigma %.3f top %.2f%s; "
                  "truth %s step %.2f tilt %.1f rough %.3f top %.2f\n",
                  d.pose, d.range_m, d.x, d.y, d.map.crest_unseen ? "unknown (crest unseen)" : traversability::CellStateName(d.map.state), d.map.step_m,
                  d.map.tilt_rad * 180 / M_PI, d.map.roughness_m, d.map.sigma_m, d.map.elevation_m,
                  d.map.height_sigma_m < 0 ? " (no points of its own)" : "",
                  traversability::CellStateName(d.truth.state), d.truth.step_m, d.truth.tilt_rad * 180 / M_PI,
                  d.truth.roughness_m, d.truth.elevation_m);
    const hazard_eval::BandCounts near = r.Within4m();
    int status = 0;
    if (min_detection >= 0) {
      const double f = near.rocks ? static_cast<double>(near.rocks_detected) / near.rocks : 0.0;
      const bool ok = near.rocks > 0 && f >= min_detection;
      std::printf("check: rocks over %.2f m detected within 4 m: %d of %d (%.1f %%), need >= %.1f %%: %s\n",
                  options.rock_limit_m, near.rocks_detected, near.rocks, 100 * f,
                  100 * min_detection, ok ? "PASS" : "FAIL");
      if (!ok) status = 1;
    }
    if (max_false_unsafe >= 0) {
      const double f = near.traversable_cells
                           ? static_cast<double>(near.false_unsafe_cells) / near.traversable_cells
                           : 1.0;
      const bool ok = near.traversable_cells > 0 && f < max_false_unsafe;
      std::printf("check: traversable cells marked unsafe within 4 m: %d of %d (%.1f %%), need < %.1f %%: %s\n",
                  near.false_unsafe_cells, near.traversable_cells, 100 * f, 100 * max_false_unsafe,
                  ok ? "PASS" : "FAIL");
      if (!ok) status = 1;
    }
    return status;
  } catch (const config::ConfigError& e) {
    return Usage(e.what());
  } catch (const std::invalid_argument& e) {
    return Usage(e.what());
  } catch (const std::exception& e) {
    return Usage(std::string("error: ") + e.what());
  }
}
