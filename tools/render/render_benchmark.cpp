// Render time per stereo pair at 1024x1024 and 512x512 (targets 1.0 s and 0.25 s on one
// core), and the realism comparison: Harris corner density and the spread of
// local contrast of a rendered rocky and a rendered sand world against real NAVCAM images
// (rocky Gusev, Spirit 2n*.png; smooth Meridiani, Opportunity 1N*.png), then a verdict per
// rendered world: which real images' range each figure falls in, or how far outside.
//
// The two worlds are catalogue worlds seen from their start pose, so that what is measured
// is what scenarios drive on (the demo drives flat_rock_course). The sand is meridiani_ripples:
// featureless_sand is blander than any real Meridiani image on purpose (VO must fail on it).
//
//   render_benchmark [--rig configs/cameras/navcam_pinhole.yaml] [--repeats 3]
//                    [--rocky configs/worlds/flat_rock_course.yaml]
//                    [--sand configs/worlds/meridiani_ripples.yaml] [--realism-only]
// --realism-only renders one 1024 pair per world and skips the timing (for tuning worlds).
#include "config/yaml_config.hpp"
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

// A catalogue world, as scenarios load it (a `render:` section is the renderer's, not
// the world's, and is left out: the benchmark uses default render options).
terrain::WorldOptions LoadWorld(const std::string& path) {
  const config::ConfigNode root = config::ConfigNode::LoadFile(path);
  if (!root.Has("render")) return terrain::WorldOptions::Load(root);
  YAML::Node copy = YAML::Clone(root.yaml());
  copy.remove("render");
  return terrain::WorldOptions::Load(config::ConfigNode(copy, path, ""));
}

// The world's start pose, with the attitude of a rover resting on the ground there.
Eigen::Isometry3d StartPose(const terrain::World& world) {
  const auto& s = world.options().start;
  const double yaw = s.yaw_deg * M_PI / 180.0;
  const Eigen::Vector3d n = geometry::RotationFromRpy(0, 0, yaw).transpose() * world.NormalUp(s.x, s.y);
  const double pitch = std::atan2(-n.x(), -n.z());
  const double roll = std::atan2(n.y(), std::hypot(n.x(), n.z()));
  return geometry::PoseFromXyzRpy(s.x, s.y, -world.Elevation(s.x, s.y), roll, pitch, yaw);
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

// The ground in each real image as a band of rows (fractions of the height, full width so
// the working scale stays that of the whole image), picked by eye: rendered images show
// only ground, so the real ones are measured without their sky and horizon (low, then
// sharp, contrast) and without the rover deck in view (solar cells: rows of artificial
// corners). Images not listed are measured whole.
struct GroundBand {
  const char* prefix;
  double top, bottom;
};
constexpr GroundBand kGroundBands[] = {
    {"1N491020376", 0.47, 1.00},  // bright outcrop with tracks; above it dunes, rim, sky
    {"1N546228391", 0.25, 0.75},  // ripple plains; above: far plains, sky; below: deck
    {"2n292280938", 0.00, 0.62},  // rocky plains; below: the deck
    {"2n292280989", 0.19, 0.81},  // rocky plains; above: hills, sky; below: the deck
    {"2n295663162", 0.12, 1.00},  // rocky slope with tracks; above: hill and sky
};

cv::Mat GroundOf(const cv::Mat& image, const std::string& file_name, bool* cropped) {
  for (const GroundBand& b : kGroundBands) {
    if (file_name.rfind(b.prefix, 0) == 0) {
      *cropped = true;
      const int top = static_cast<int>(std::lround(b.top * image.rows));
      const int bottom = static_cast<int>(std::lround(b.bottom * image.rows));
      return image.rowRange(top, bottom);
    }
  }
  *cropped = false;
  return image;
}

// The range of each figure over a group of real images.
struct Range {
  int images = 0;
  double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
  void Add(const render::ImageStatistics& s) {
    const double v[3] = {s.corners_per_mpix, s.local_std_mean, s.local_std_spread};
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min(lo[k], v[k]);
      hi[k] = std::max(hi[k], v[k]);
    }
    ++images;
  }
};

// "in Gusev [a, b]", or "1.4x above Gusev [a, b]" (ratio to the nearer end; a value of 0
// against a positive range prints as "0, below").
std::string Place(double v, const char* group, const Range& r, int k, const char* fmt) {
  char range[64], buf[160];
  char lo[24], hi[24];
  std::snprintf(lo, sizeof lo, fmt, r.lo[k]);
  std::snprintf(hi, sizeof hi, fmt, r.hi[k]);
  std::snprintf(range, sizeof range, "%s [%s, %s]", group, lo, hi);
  if (v >= r.lo[k] && v <= r.hi[k]) {
    std::snprintf(buf, sizeof buf, "in %s", range);
  } else if (v > r.hi[k]) {
    std::snprintf(buf, sizeof buf, "%.2fx above %s", r.hi[k] > 0 ? v / r.hi[k] : 0.0, range);
  } else if (v > 0) {
    std::snprintf(buf, sizeof buf, "%.2fx below %s", r.lo[k] / v, range);
  } else {
    std::snprintf(buf, sizeof buf, "0, below %s", range);
  }
  return buf;
}

void PrintVerdict(const std::string& name, const render::ImageStatistics& s, const char* target,
                  const Range& t, const char* other, const Range& o) {
  static const char* const kFigure[3] = {"corners/Mpix", "loc.std %", "spread %"};
  static const char* const kFormat[3] = {"%.0f", "%.1f", "%.1f"};
  const double v[3] = {s.corners_per_mpix, s.local_std_mean, s.local_std_spread};
  int inside = 0;
  std::printf("  rendered %s (should look like %s):\n", name.c_str(), target);
  for (int k = 0; k < 3; ++k) {
    char value[24];
    std::snprintf(value, sizeof value, kFormat[k], v[k]);
    const bool in_target = v[k] >= t.lo[k] && v[k] <= t.hi[k];
    inside += in_target;
    std::string line = Place(v[k], target, t, k, kFormat[k]);
    if (!in_target && v[k] >= o.lo[k] && v[k] <= o.hi[k]) line += std::string(" (in ") + other + " range)";
    std::printf("    %-13s %7s  %s\n", kFigure[k], value, line.c_str());
  }
  std::printf("    -> %d of 3 figures inside the %s range\n", inside, target);
}

}  // namespace

int main(int argc, char** argv) {
  std::string rig_path;
  std::string rocky_path = std::string(ROVER_SOURCE_DIR) + "/configs/worlds/flat_rock_course.yaml";
  std::string sand_path = std::string(ROVER_SOURCE_DIR) + "/configs/worlds/meridiani_ripples.yaml";
  int repeats = 3;
  bool realism_only = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--help" || a == "-h") {
      std::cout << "usage: render_benchmark [--rig FILE] [--repeats N] [--rocky WORLD.yaml] [--sand WORLD.yaml]\n"
                   "                        [--realism-only]\n\n"
                   "Render time per stereo pair at 1024 and 512 on one thread (median of N repeats after\n"
                   "a first frame, default 3), and corner density and contrast against real NAVCAM images\n"
                   "(--realism-only: those alone). Worlds default to flat_rock_course and meridiani_ripples.\n";
      return 0;
    } else if (a == "--rig" && i + 1 < argc) {
      rig_path = argv[++i];
    } else if (a == "--repeats" && i + 1 < argc) {
      repeats = std::max(1, std::atoi(argv[++i]));
    } else if (a == "--realism-only") {
      realism_only = true;
    } else if (a == "--rocky" && i + 1 < argc) {
      rocky_path = argv[++i];
    } else if (a == "--sand" && i + 1 < argc) {
      sand_path = argv[++i];
    } else {
      std::cerr << "render_benchmark: unknown argument '" << a
                << "' (expected --rig FILE, --repeats N, --rocky WORLD.yaml, --sand WORLD.yaml,\n"
                << "--realism-only)\n";
      return 2;
    }
  }
  geometry::StereoRig rig;
  terrain::WorldOptions rocky_options, sand_options;
  try {
    rig = rig_path.empty() ? DefaultRig() : geometry::LoadStereoRigFile(rig_path);
    rocky_options = LoadWorld(rocky_path);
    sand_options = LoadWorld(sand_path);
  } catch (const std::exception& e) {
    std::cerr << "render_benchmark: " << e.what() << "\n";
    return 2;
  }
  std::printf("render_benchmark: rig %s, %dx%d\n", rig_path.empty() ? "(built-in NAVCAM-like)" : rig_path.c_str(),
              rig.left->width(), rig.left->height());

  const terrain::World rocky(rocky_options);
  const terrain::World sand(sand_options);
  const Eigen::Isometry3d T_rocky = StartPose(rocky);
  const Eigen::Isometry3d T_sand = StartPose(sand);
  std::printf("worlds: rocky %s, sand %s (each from its start pose)\n", rocky_path.c_str(), sand_path.c_str());

  render::StereoImages rocky_1024, sand_1024;
  if (realism_only) {
    render::RenderOptions opt;
    opt.image_scale = 1024.0 / rig.left->width();
    render::StereoRenderer renderer(opt);
    rocky_1024 = renderer.RenderPair(rocky, rig, T_rocky, 1);
    sand_1024 = renderer.RenderPair(sand, rig, T_sand, 1);
  } else {
    std::printf("\nRender time per stereo pair (one thread; median of %d; CPU s is this thread's CPU time,\n"
                "the figure held to the target; first frame also adopts the world grid)\n", repeats);
    std::printf("  %-22s %6s %10s %10s %10s %10s %8s\n", "world", "size", "median CPU", "median s", "trace s",
                "first s", "target");
  }
  const std::vector<double> timed_scales =
      realism_only ? std::vector<double>{} : std::vector<double>{1024.0 / rig.left->width(), 512.0 / rig.left->width()};
  for (const double scale : timed_scales) {
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

  std::printf("\nRealism (left images at 512 px working width, each scaled so its median is 100 DN; Harris\n"
              "corners above a fixed threshold; local std over 15x15 windows in %% of the median, its mean\n"
              "and its spread over the image; real images: the ground rows only)\n");
  std::printf("  %-44s %8s %12s %10s %10s\n", "image", "corners", "per Mpix", "loc.std", "spread");
  const render::ImageStatistics rocky_stats = render::MeasureImage(rocky_1024.left);
  const render::ImageStatistics sand_stats = render::MeasureImage(sand_1024.left);
  PrintRow("rendered rocky " + rocky.options().name, rocky_stats);
  PrintRow("rendered sand " + sand.options().name, sand_stats);
  const std::filesystem::path dir = std::filesystem::path(ROVER_DATA_DIR) / "mars" / "images";
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
  Range gusev, meridiani;
  for (const auto& f : files) {
    const cv::Mat img = cv::imread(f.string(), cv::IMREAD_UNCHANGED);
    if (img.empty() || img.channels() != 1) continue;
    const std::string n = f.filename().string();
    const bool spirit = n.rfind("2n", 0) == 0;
    bool cropped = false;
    const render::ImageStatistics st = render::MeasureImage(GroundOf(img, n, &cropped));
    PrintRow((spirit ? "Spirit/Gusev " : "Opportunity/Meridiani ") + n.substr(0, 13) + (cropped ? " (ground)" : ""),
             st);
    (spirit ? gusev : meridiani).Add(st);
  }
  if (gusev.images == 0 || meridiani.images == 0) {
    std::printf("  (need both Gusev 2n* and Meridiani 1N* images for the verdict)\n");
    return 0;
  }
  std::printf("\nVerdict (each figure against the range of the real images of its kind; 'x' = how far\n"
              "outside, as a ratio to the nearer end)\n");
  PrintVerdict("rocky " + rocky.options().name, rocky_stats, "Gusev", gusev, "Meridiani", meridiani);
  PrintVerdict("sand " + sand.options().name, sand_stats, "Meridiani", meridiani, "Gusev", gusev);
  return 0;
}
