// calib_import: writes a rig file (configs/cameras/*.yaml) from a stereo calibration made
// by OpenCV's stereoCalibrate or ROS's camera_calibration (tools/calib/calib_import.hpp).
#include "calib/arguments.hpp"
#include "calib/calib_import.hpp"
#include "config/number_list.hpp"
#include "config/yaml_config.hpp"

#include <filesystem>
#include <fstream>
#include <iostream>

using namespace rover;

namespace {

const char* kUsage =
    "usage: calib_import (--opencv FILE [--t-unit m|cm|mm] [--size WxH] | --ros-left FILE --ros-right FILE)\n"
    "                    --left-position X,Y,Z --left-rpy ROLL,PITCH,YAW --out RIG.yaml [--force]\n\n"
    "Writes the rig file camera_capture's capture.rig reads: both cameras as pinhole models with\n"
    "OpenCV distortion, in the rover frame (X forward, Y right, Z down), the left camera at its\n"
    "mount (metres; body roll, pitch, yaw in degrees, as rpy_deg in a rig file) and the right one\n"
    "where the calibration puts it.\n"
    "  --opencv FILE   cv::FileStorage YAML with K1|M1, D1, K2|M2, D2, R, T (X_right = R X_left + T)\n"
    "                  and image_width/image_height or imageSize (else --size)\n"
    "  --t-unit U      the unit of T (the calibration target's): m (default), cm or mm\n"
    "  --ros-left/--ros-right FILE   ROS camera_info YAML of each camera (camera_calibration)\n"
    "  --force         write a baseline outside 1 cm to 2 m or a focal length outside 50 to\n"
    "                  50,000 px (else one line naming the value and exit 2), and replace an\n"
    "                  existing --out (else it is kept, exit 2)\n"
    "Exit codes: 0 written; 2 a bad argument or file, an implausible calibration, or an\n"
    "existing --out (nothing written).\n";

using calib::BadArgument;

Eigen::Vector3d Triple(const std::string& option, const std::string& text) {
  std::vector<double> v;
  if (!config::ParseNumberList(text, &v) || v.size() != 3) {
    throw BadArgument("argument " + option + ": \"" + text + "\": expected 3 finite numbers separated by commas");
  }
  return {v[0], v[1], v[2]};
}

int Run(int argc, char** argv) {
  std::string opencv, ros_left, ros_right, out, unit = "m";
  bool have_position = false, have_rpy = false, force = false;
  int width = 0, height = 0;
  calib::Mount mount;
  calib::Arguments args(argc, argv);
  while (args.Next()) {
    const std::string& arg = args.option();
    if (args.IsHelp()) {
      std::cout << kUsage;
      return 0;
    } else if (arg == "--opencv") {
      opencv = args.Value();
    } else if (arg == "--ros-left") {
      ros_left = args.Value();
    } else if (arg == "--ros-right") {
      ros_right = args.Value();
    } else if (arg == "--out") {
      out = args.Value();
    } else if (arg == "--force") {
      force = true;
    } else if (arg == "--t-unit") {
      unit = args.Value();
      if (unit != "m" && unit != "cm" && unit != "mm") {
        throw BadArgument("argument --t-unit: \"" + unit + "\": expected m, cm or mm");
      }
    } else if (arg == "--size") {
      args.Size(1, "WIDTHxHEIGHT in pixels, e.g. 1024x1024", &width, &height);
    } else if (arg == "--left-position") {
      mount.position = Triple(arg, args.Value());
      have_position = true;
    } else if (arg == "--left-rpy") {
      mount.rpy_deg = Triple(arg, args.Value());
      have_rpy = true;
    } else {
      throw args.Unknown();
    }
  }
  if (opencv.empty() == (ros_left.empty() && ros_right.empty())) {
    throw BadArgument("expected either --opencv FILE or --ros-left FILE --ros-right FILE");
  }
  if (opencv.empty() && (ros_left.empty() || ros_right.empty())) {
    throw BadArgument("missing argument " + std::string(ros_left.empty() ? "--ros-left" : "--ros-right") + " FILE");
  }
  // Where the cameras sit on the rover is not in a calibration: it must be said, not assumed.
  if (!have_position) throw BadArgument("missing argument --left-position X,Y,Z (the left camera's centre, rover frame, m)");
  if (!have_rpy) throw BadArgument("missing argument --left-rpy ROLL,PITCH,YAW (the left camera's body angles, deg)");
  if (out.empty()) throw BadArgument("missing argument --out RIG.yaml");
  std::error_code ec;
  // A rig file already there is kept; a device or a pipe (/dev/null, /dev/stdout) is written.
  if (!force && std::filesystem::is_regular_file(out, ec)) {
    throw BadArgument("--out " + out + ": exists; kept (pass --force to replace it)");
  }
  const double scale = unit == "mm" ? 1e-3 : unit == "cm" ? 1e-2 : 1.0;
  const auto cal = opencv.empty() ? calib::LoadRosCameraInfoPair(ros_left, ros_right)
                                  : calib::LoadOpenCvStereo(opencv, scale, width, height);
  const std::string problem = calib::PlausibilityProblem(cal, opencv.empty() ? "" : unit);
  if (!problem.empty() && !force) {
    throw BadArgument((opencv.empty() ? ros_right : opencv) + ": " + problem + " (nothing written; --force writes it anyway)");
  }
  if (!problem.empty()) std::cerr << "calib_import: warning: " << problem << " (written anyway: --force)\n";
  std::ofstream file(out);
  file << calib::RigYaml(cal, mount);
  if (!file) throw BadArgument("cannot write " + out);
  std::cout << "calib_import: wrote " << out << " (baseline " << cal.T.norm() << " m)\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return Run(argc, argv);
  } catch (const BadArgument& e) {
    std::cerr << "calib_import: " << e.what() << "\n";
  } catch (const config::ConfigError& e) {
    std::cerr << e.what() << "\n";
  } catch (const std::exception& e) {
    std::cerr << "calib_import: " << e.what() << "\n";
  }
  return 2;
}
