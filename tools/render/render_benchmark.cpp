// Render time per stereo pair at 1024x1024 and 512x512 (targets 1.0 s and 0.25 s on one
// core), and the realism comparison of issue 4: Harris corner density and the spread of
// local contrast of rendered rocky and sand worlds against real NAVCAM images.
//
//   render_benchmark [--rig configs/cameras/navcam_pinhole.yaml] [--repeats 3]
#include "geometry/camera_io.hpp"
#include "geometry/pinhole_camera.hpp"
#include "geometry/pose.hpp"
#include "render/image_statistics.hpp"
#include "render/stereo_renderer.hpp"
#include "terrain/world.hpp"

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include <time.h>

namespace {

using namespace rover;

// NAVCAM-like: 1024x1024, 45 deg, 0.2 m baseline, 1.5 m mast, 35 deg down.
geometry::StereoRig DefaultRig() {
  const int size = 1024;
  const double f = 0.5 * size / std::tan(22.5 * M_PI / 180.0), c = 0.5 * (size - 1);
  geometry::StereoRig rig;
  for (int side = 0; side < 2; ++side) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = geometry::RotationFromRpy(0, -35 * M_PI / 180.0, 0) * geometry::BodyFromOptical();
    T.translation() = Eigen::Vector3d(0.45, side == 0 ? -0.1 : 0.1, -1.5);
    auto cam = std::make_shared<geometry::PinholeCamera>(size, size, f, f, c, c, std::vector<double>{}, T);
    (side == 0 ? rig.left : rig.right) = cam;
  }
  return rig;
}

terrain::WorldOptions RockyWorld() {
  terrain::WorldOptions wo;
  wo.name = "rocky (Gusev-like)";
  wo.seed = 3;
  wo.map_size_m = {60, 60};
  wo.resolution_m = 0.02;
  wo.default_soil = terrain::Soil::kPackedSoil;
  wo.roughness.amplitude_m = 0.05;
  wo.random_rocks.abundance_k = 0.12;
  wo.random_rocks.min_diameter_m = 0.04;
  wo.sun = {120, 35};
  return wo;
}

terrain::WorldOptions SandWorld() {
  terrain::WorldOptions wo;
  wo.name = "sand (Meridiani-like)";
  wo.seed = 4;
  wo.map_size_m = {60, 60};
  wo.resolution_m = 0.05;
  wo.default_soil = terrain::Soil::kSand;
  wo.roughness.amplitude_m = 0.03;
  wo.ripples.amplitude_m = 0.03;
  wo.ripples.wavelength_m = 3.0;
  wo.sun = {120, 35};
  return wo;
}

// CPU seconds of this thread: the machine is shared, so wall time overstates the cost.
double ThreadCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

void PrintRow(const std::string& name, const render::ImageStatistics& s) {
  std::printf("  %-44s %8d %12.0f %10.1f %10.1f\n", name.c_str(), s.corners, s.corners_per_mpix,
              s.local_std_mean, s.local_std_spread);
}

}  // namespace

int main(int argc, char** argv) {
  std::string rig_path;
  int repeats = 3;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--rig" && i + 1 < argc) {
      rig_path = argv[++i];
    } else if (a == "--repeats" && i + 1 < argc) {
      repeats = std::max(1, std::atoi(argv[++i]));
    } else {
      std::cerr << "render_benchmark: unknown argument '" << a << "' (expected --rig FILE, --repeats N)\n";
      return 2;
    }
  }
  geometry::StereoRig rig;
  try {
    rig = rig_path.empty() ? DefaultRig() : geometry::LoadStereoRigFile(rig_path);
  } catch (const std::exception& e) {
    std::cerr << e.what() << "\n";
    return 2;
  }
  std::printf("render_benchmark: rig %s, %dx%d\n", rig_path.empty() ? "(built-in NAVCAM-like)" : rig_path.c_str(),
              rig.left->width(), rig.left->height());

  const terrain::World rocky(RockyWorld());
  const terrain::World sand(SandWorld());
  const Eigen::Isometry3d T_rocky = geometry::PoseFromXyzRpy(0, 0, -rocky.Elevation(0, 0), 0, 0, 0.3);
  const Eigen::Isometry3d T_sand = geometry::PoseFromXyzRpy(0, 0, -sand.Elevation(0, 0), 0, 0, 0.3);

  std::printf("\nRender time per stereo pair (one thread; median of %d; CPU s is this thread's CPU time,\n"
              "the figure held to the target; first frame also adopts the world grid)\n", repeats);
  std::printf("  %-22s %6s %10s %10s %10s %10s %8s\n", "world", "size", "median CPU", "median s", "trace s",
              "first s", "target");
  render::StereoImages rocky_1024, sand_1024;
  for (const double scale : {1024.0 / rig.left->width(), 512.0 / rig.left->width()}) {
    for (int w = 0; w < 2; ++w) {
      const terrain::World& world = w == 0 ? rocky : sand;
      render::RenderOptions opt;
      opt.image_scale = scale;
      render::StereoRenderer renderer(opt);
      std::vector<double> times, cpu_times;
      double first = 0, trace = 0;
      render::StereoImages images;
      for (int r = 0; r <= repeats; ++r) {
        const auto t0 = std::chrono::steady_clock::now();
        const double c0 = ThreadCpuSeconds();
        images = renderer.RenderPair(world, rig, w == 0 ? T_rocky : T_sand, r);
        const double cpu = ThreadCpuSeconds() - c0;
        const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        if (r == 0) {
          first = s;
        } else {
          times.push_back(s);
          cpu_times.push_back(cpu);
          trace = renderer.last_timing().trace_seconds;
        }
      }
      std::sort(times.begin(), times.end());
      std::sort(cpu_times.begin(), cpu_times.end());
      const int size = images.left.cols;
      std::printf("  %-22s %6d %10.3f %10.3f %10.3f %10.3f %8s\n", world.options().name.c_str(), size,
                  cpu_times[cpu_times.size() / 2], times[times.size() / 2], trace, first,
                  size >= 1024 ? "<= 1.0" : "<= 0.25");
      if (size >= 1024) (w == 0 ? rocky_1024 : sand_1024) = images;
    }
  }

  std::printf("\nRealism (left images at 512 px working width; Harris corners above a fixed threshold,\n"
              "local std over 15x15 windows)\n");
  std::printf("  %-44s %8s %12s %10s %10s\n", "image", "corners", "per Mpix", "loc.std", "spread");
  PrintRow("rendered rocky (Gusev-like)", render::MeasureImage(rocky_1024.left));
  PrintRow("rendered sand (Meridiani-like)", render::MeasureImage(sand_1024.left));
  const std::filesystem::path dir = std::filesystem::path(ROVER_SHARED_DATA) / "mars" / "images";
  if (!std::filesystem::is_directory(dir)) {
    std::printf("  (real NAVCAM images not found in %s: comparison skipped)\n", dir.c_str());
    return 0;
  }
  std::vector<std::filesystem::path> files;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    const std::string n = e.path().filename().string();
    if ((n.rfind("2n", 0) == 0 || n.rfind("1N", 0) == 0) && e.path().extension() == ".png") files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  for (const auto& f : files) {
    const cv::Mat img = cv::imread(f.string(), cv::IMREAD_UNCHANGED);
    if (img.empty() || img.channels() != 1) continue;
    const std::string n = f.filename().string();
    const std::string label = (n.rfind("2n", 0) == 0 ? "Spirit/Gusev " : "Opportunity/Meridiani ") + n.substr(0, 13);
    PrintRow(label, render::MeasureImage(img));
  }
  return 0;
}
