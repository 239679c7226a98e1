// Traversability map speed: median time of one map update (AddStereoPair:
// rectify, dense stereo, triangulate, bin, rate) on ONE core, at 512x512 and 1024x1024.
//   traversability_benchmark [--world configs/worlds/rock_field.yaml]
//                            [--rig configs/cameras/navcam_pinhole.yaml] [--pairs 20]
//                            [--sizes 512,1024] [--map-options FILE.yaml]
// --map-options: traversability::MapOptions keys, bare, under `traversability:`, or a rover
// config's hazards.map.traversability (default: the options' defaults).
// The pairs are rendered first (not timed) at poses 0.2 m apart along the world's start
// heading; then each is added to one map, re-centred on its pose. Prints the median wall
// and thread-CPU time per update (on a shared machine the CPU time is the one to trust) and
// the stages' wall times. Targets: <= 150 ms at 512x512, <= 600 ms at 1024x1024, judged on
// CPU time. Bad arguments: one line, exit 2.
#include "config/number_list.hpp"
#include "config/yaml_config.hpp"
#include "geometry/camera_io.hpp"
#include "geometry/pose.hpp"
#include "render/stereo_renderer.hpp"
#include "terrain/world.hpp"
#include "traversability/traversability_map.hpp"

#include <opencv2/core/utility.hpp>

#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

namespace {

int Usage(const std::string& message) {
  std::cerr << "traversability_benchmark: " << message << "\n";
  return 2;
}

// CPU time of this thread: the machine may be shared, and wall time then counts the others.
double ThreadCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace

int main(int argc, char** argv) {
  using namespace rover;
  std::string world_path = "configs/worlds/rock_field.yaml";
  std::string rig_path = "configs/cameras/navcam_pinhole.yaml";
  std::vector<int> sizes{512, 1024};
  int pairs = 20;
  std::string map_path;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has = i + 1 < argc;
    std::vector<int> v;
    if (a == "--help" || a == "-h") {
      std::cout << "usage: traversability_benchmark [--world WORLD.yaml] [--rig RIG.yaml] [--pairs N] [--sizes 512,1024]\n"
                   "       [--map-options FILE.yaml]\n";
      return 0;
    } else if (a == "--world") {
      if (!has) return Usage("--world: expected a world YAML file");
      world_path = argv[++i];
    } else if (a == "--rig") {
      if (!has) return Usage("--rig: expected a stereo rig YAML file");
      rig_path = argv[++i];
    } else if (a == "--pairs") {
      if (!has || !config::ParseIntList(argv[++i], 1, 1000, &v) || v.size() != 1)
        return Usage("--pairs: expected a number of stereo pairs in [1, 1000]");
      pairs = v[0];
    } else if (a == "--sizes") {
      if (!has || !config::ParseIntList(argv[++i], 64, 4096, &sizes))
        return Usage("--sizes: expected image widths in pixels, e.g. 512,1024 (each in [64, 4096])");
    } else if (a == "--map-options") {
      if (!has) return Usage("--map-options: expected a YAML file of traversability map options");
      map_path = argv[++i];
    } else {
      return Usage("unknown argument '" + a + "' (see --help)");
    }
  }
  try {
    const terrain::World world(terrain::WorldOptions::LoadFile(world_path));
    const geometry::StereoRig rig = geometry::LoadStereoRigFile(rig_path);
    traversability::MapOptions map_options;
    if (!map_path.empty()) {
      const config::ConfigNode m = config::ConfigNode::LoadFile(map_path);
      if (m.Has("hazards") && m["hazards"].Has("map") && m["hazards"]["map"].Has("traversability"))
        map_options = traversability::LoadMapOptions(m["hazards"]["map"]["traversability"]);
      else
        map_options = traversability::LoadMapOptions(m.Has("traversability") ? m["traversability"] : m);
    }
    cv::setNumThreads(1);  // one core
    const auto& start = world.options().start;
    const double yaw = start.yaw_deg * M_PI / 180.0;
    geometry::Matrix6d cov = geometry::Matrix6d::Zero();
    cov.diagonal() << 4e-4, 4e-4, 4e-4, 7.6e-5, 7.6e-5, 7.6e-5;  // 2 cm, 0.5 deg
    std::printf("traversability_benchmark: world %s, %d pairs per size, one core\n",
                world.options().name.c_str(), pairs);
    std::printf("%-10s %10s %10s %11s %9s %8s %8s\n", "size", "wall ms", "CPU ms", "rectify ms",
                "match ms", "grid ms", "points");
    for (int size : sizes) {
      render::RenderOptions ro;
      ro.image_scale = static_cast<double>(size) / rig.left->width();
      std::vector<render::StereoImages> images;
      std::vector<geometry::Pose> poses;
      {  // the renderer (and any threads it keeps) is gone before the timing starts
        render::StereoRenderer renderer(ro);
        for (int k = 0; k < pairs; ++k) {
          const double x = start.x + 0.2 * k * std::cos(yaw), y = start.y + 0.2 * k * std::sin(yaw);
          poses.push_back(geometry::PoseFromXyzRpy(x, y, -world.Elevation(x, y), 0, 0, yaw));
          images.push_back(renderer.RenderPair(world, rig, poses.back(), k + 1));
        }
      }
      traversability::TraversabilityMap map(map_options);
      std::vector<double> total, cpu, rect, match, grid, points;
      for (int k = 0; k < pairs; ++k) {
        map.Recentre(poses[k].translation().x(), poses[k].translation().y());
        const auto t0 = std::chrono::steady_clock::now();
        const double c0 = ThreadCpuSeconds();
        map.AddStereoPair(images[k].left, images[k].right, images[k].rig, poses[k], cov);
        map.cells();
        total.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
        cpu.push_back(ThreadCpuSeconds() - c0);
        rect.push_back(map.last_update().seconds_rectify);
        match.push_back(map.last_update().seconds_match);
        grid.push_back(map.last_update().seconds_grid);
        points.push_back(map.last_update().points);
      }
      const double target = size <= 512 ? 150.0 : size <= 1024 ? 600.0 : 0.0;
      char label[32];
      std::snprintf(label, sizeof label, "%dx%d", size, size * rig.left->height() / rig.left->width());
      std::string verdict;
      if (target > 0)
        verdict = std::string("   target <= ") + std::to_string(static_cast<int>(target)) + " ms: " +
                  (1000 * Median(cpu) <= target ? "met" : "MISSED") + " (CPU)";
      std::printf("%-10s %10.1f %10.1f %11.1f %9.1f %8.1f %8.0f%s\n", label, 1000 * Median(total),
                  1000 * Median(cpu), 1000 * Median(rect), 1000 * Median(match), 1000 * Median(grid),
                  Median(points), verdict.c_str());
    }
  } catch (const std::exception& e) {
    return Usage(e.what());
  }
  return 0;
}
