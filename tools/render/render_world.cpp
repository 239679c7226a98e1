// Renders a world from a pose so that a person can look at it:
//   render_world WORLD.yaml --pose x,y,yaw_deg [--rig configs/cameras/navcam_pinhole.yaml]
//                [--size 512] [--seed N] --out DIR
// writes DIR/left.png, DIR/right.png and DIR/disparity_truth.png (disparity from the true
// depth, colour-mapped). A `render:` section in the world file sets RenderOptions.
// Bad arguments: one line naming the argument and what was expected, exit 2.
#include "config/number_list.hpp"
#include "config/yaml_config.hpp"
#include "geometry/camera_io.hpp"
#include "geometry/pose.hpp"
#include "render/render_options.hpp"
#include "render/stereo_renderer.hpp"
#include "terrain/world.hpp"

#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

namespace {

int Usage(const std::string& message) {
  std::cerr << "render_world: " << message << "\n";
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace rover;
  std::string world_path, out_dir, rig_path = "configs/cameras/navcam_pinhole.yaml";
  std::vector<double> pose;
  int size = 512;
  long long seed = 0;
  bool have_pose = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has_value = i + 1 < argc;
    if (a == "--help" || a == "-h") {
      std::cout << "usage: render_world WORLD.yaml --pose x,y,yaw_deg [--rig RIG.yaml] [--size N] [--seed N] --out DIR\n";
      return 0;
    } else if (a == "--pose") {
      if (!has_value || !rover::config::ParseNumberList(argv[++i], &pose) || pose.size() != 3) {
        return Usage("--pose: expected x,y,yaw_deg (three numbers, metres and degrees)");
      }
      have_pose = true;
    } else if (a == "--rig") {
      if (!has_value) return Usage("--rig: expected a stereo rig YAML file");
      rig_path = argv[++i];
    } else if (a == "--out") {
      if (!has_value) return Usage("--out: expected an output directory");
      out_dir = argv[++i];
    } else if (a == "--size") {
      std::vector<double> v;
      if (!has_value || !rover::config::ParseNumberList(argv[++i], &v) || v.size() != 1 || v[0] < 16 || v[0] > 4096 ||
          v[0] != std::floor(v[0])) {
        return Usage("--size: expected an image width in pixels, an integer in [16, 4096]");
      }
      size = static_cast<int>(v[0]);
    } else if (a == "--seed") {
      std::vector<double> v;
      if (!has_value || !rover::config::ParseNumberList(argv[++i], &v) || v.size() != 1 || v[0] != std::floor(v[0])) {
        return Usage("--seed: expected an integer");
      }
      seed = static_cast<long long>(v[0]);
    } else if (!a.empty() && a[0] == '-') {
      return Usage("unknown option '" + a + "' (expected --pose, --rig, --size, --seed, --out)");
    } else if (world_path.empty()) {
      world_path = a;
    } else {
      return Usage("unexpected argument '" + a + "' (expected one WORLD.yaml)");
    }
  }
  if (world_path.empty()) return Usage("WORLD.yaml: expected a world file as the first argument");
  if (!have_pose) return Usage("--pose: expected x,y,yaw_deg");
  if (out_dir.empty()) return Usage("--out: expected an output directory");

  try {
    const config::ConfigNode root = config::ConfigNode::LoadFile(world_path);
    render::RenderOptions options;
    terrain::WorldOptions world_options;
    if (root.Has("render")) {
      options = render::LoadRenderOptions(root["render"]);
      // The world loader rejects keys it does not know: hand it the file without ours.
      YAML::Node copy = YAML::Clone(root.yaml());
      copy.remove("render");
      world_options = terrain::WorldOptions::Load(config::ConfigNode(copy, world_path, ""));
    } else {
      world_options = terrain::WorldOptions::Load(root);
    }
    const geometry::StereoRig rig = geometry::LoadStereoRigFile(rig_path);
    options.image_scale = static_cast<double>(size) / rig.left->width();
    const terrain::World world(world_options);
    const double x = pose[0], y = pose[1], yaw = pose[2] * M_PI / 180.0;
    // The rover's attitude on the ground under it: pitch and roll from the surface normal.
    const Eigen::Vector3d n = world.NormalUp(x, y);  // site axes, z < 0
    const Eigen::Matrix3d Rz = geometry::RotationFromRpy(0, 0, yaw);
    const Eigen::Vector3d n_yawed = Rz.transpose() * n;  // in the yawed (level) frame
    const double pitch = std::atan2(-n_yawed.x(), -n_yawed.z());
    const double roll = std::atan2(n_yawed.y(), std::hypot(n_yawed.x(), n_yawed.z()));
    const Eigen::Isometry3d T = geometry::PoseFromXyzRpy(x, y, -world.Elevation(x, y), roll, pitch, yaw);

    render::StereoRenderer renderer(options);
    const render::StereoImages images = renderer.RenderPair(world, rig, T, seed);
    const cv::Mat disparity = render::DisparityFromDepth(images.depth_left, images.rig);
    std::filesystem::create_directories(out_dir);
    const std::filesystem::path dir(out_dir);
    for (const auto& [name, img] : {std::pair<std::string, cv::Mat>{"left.png", images.left},
                                    {"right.png", images.right},
                                    {"disparity_truth.png", render::ColourDisparity(disparity)}}) {
      const std::string path = (dir / name).string();
      if (!cv::imwrite(path, img)) throw std::runtime_error(path + ": cannot write");
      std::printf("wrote %s (%dx%d)\n", path.c_str(), img.cols, img.rows);
    }
    std::printf("world %s, pose x=%.3f y=%.3f z=%.3f roll=%.2f pitch=%.2f yaw=%.2f deg, render %.3f s\n",
                world_options.name.c_str(), x, y, T.translation().z(), roll * 180 / M_PI, pitch * 180 / M_PI,
                pose[2], renderer.last_timing().grid_seconds + renderer.last_timing().trace_seconds);
  } catch (const config::ConfigError& e) {
    return Usage(e.what());
  } catch (const std::exception& e) {
    std::cerr << "render_world: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
