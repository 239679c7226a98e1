#include "geometry/camera_io.hpp"

#include "geometry/cahv_camera.hpp"
#include "geometry/cahvore_camera.hpp"
#include "geometry/pinhole_camera.hpp"
#include "geometry/pose.hpp"

#include <cmath>
#include <stdexcept>

namespace rover::geometry {

namespace {

int RequireSize(const config::ConfigNode& node, const std::string& key) {
  if (!node.Has(key)) node.Fail("missing key \"" + key + "\" (expected an integer >= 1, pixels)");
  int value = 0;
  node.Get(key, value, 1, 1 << 20);
  return value;
}

Eigen::Vector3d RequireVector3(const config::ConfigNode& node, const std::string& key) {
  const std::vector<double> v = node.RequireVector(key, 3);
  return Eigen::Vector3d(v[0], v[1], v[2]);
}

Eigen::Isometry3d LoadPose(const config::ConfigNode& node) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  std::vector<double> position = {0, 0, 0};
  node.Get("position", position, 3);
  T.translation() = Eigen::Vector3d(position[0], position[1], position[2]);
  if (node.Has("rpy_deg") && node.Has("quaternion_wxyz")) {
    node["quaternion_wxyz"].Fail("both rpy_deg and quaternion_wxyz given (expected at most one)");
  }
  if (node.Has("rpy_deg")) {
    const std::vector<double> rpy = node.RequireVector("rpy_deg", 3);
    const double k = M_PI / 180.0;
    T.linear() = RotationFromRpy(rpy[0] * k, rpy[1] * k, rpy[2] * k) * BodyFromOptical();
  } else if (node.Has("quaternion_wxyz")) {
    const std::vector<double> q = node.RequireVector("quaternion_wxyz", 4);
    const Eigen::Quaterniond quat(q[0], q[1], q[2], q[3]);
    if (!(quat.norm() > 1e-9)) {
      node["quaternion_wxyz"].Fail("zero quaternion (expected a rotation, w x y z)");
    }
    T.linear() = quat.normalized().toRotationMatrix();
  }
  return T;
}

}  // namespace

Eigen::Matrix3d BodyFromOptical() {
  Eigen::Matrix3d R;
  // Columns: optical x (right) = body y, optical y (down) = body z, optical z = body x.
  R << 0, 0, 1,  //
      1, 0, 0,   //
      0, 1, 0;
  return R;
}

std::unique_ptr<CameraModel> LoadCameraModel(const config::ConfigNode& node) {
  if (!node.IsMap()) node.Fail("expected a camera mapping (type, width, height, ...)");
  std::string type;
  if (!node.Has("type")) {
    node.Fail("missing key \"type\" (expected one of: pinhole, cahv, cahvor, cahvore)");
  }
  node.GetEnum("type", type, {"pinhole", "cahv", "cahvor", "cahvore"});
  const int width = RequireSize(node, "width");
  const int height = RequireSize(node, "height");
  try {
    if (type == "pinhole") {
      node.CheckKeys({"type", "width", "height", "fx", "fy", "cx", "cy", "distortion",
                      "position", "rpy_deg", "quaternion_wxyz"});
      const double fx = node.RequireDouble("fx", 1e-9);
      const double fy = node.RequireDouble("fy", 1e-9);
      const double cx = node.RequireDouble("cx");
      const double cy = node.RequireDouble("cy");
      std::vector<double> distortion;
      if (node.Has("distortion")) {
        distortion = node["distortion"].AsVector();
        if (distortion.size() != 4 && distortion.size() != 5) {
          node["distortion"].Fail("expected 4 or 5 numbers (k1 k2 p1 p2 [k3]), got " +
                                  std::to_string(distortion.size()));
        }
      }
      return std::make_unique<PinholeCamera>(width, height, fx, fy, cx, cy, distortion,
                                             LoadPose(node));
    }
    if (type == "cahv") {
      node.CheckKeys({"type", "width", "height", "C", "A", "H", "V"});
      return std::make_unique<CahvCamera>(width, height, RequireVector3(node, "C"),
                                          RequireVector3(node, "A"), RequireVector3(node, "H"),
                                          RequireVector3(node, "V"));
    }
    if (type == "cahvore") {
      node.CheckKeys({"type", "width", "height", "C", "A", "H", "V", "O", "R", "E", "linearity"});
      return std::make_unique<CahvoreCamera>(
          width, height, RequireVector3(node, "C"), RequireVector3(node, "A"),
          RequireVector3(node, "H"), RequireVector3(node, "V"), RequireVector3(node, "O"),
          RequireVector3(node, "R"), RequireVector3(node, "E"),
          node.RequireDouble("linearity", -1.0, 1.0));
    }
    node.CheckKeys({"type", "width", "height", "C", "A", "H", "V", "O", "R"});
    return std::make_unique<CahvorCamera>(
        width, height, RequireVector3(node, "C"), RequireVector3(node, "A"),
        RequireVector3(node, "H"), RequireVector3(node, "V"), RequireVector3(node, "O"),
        RequireVector3(node, "R"));
  } catch (const std::invalid_argument& e) {
    // A model the constructor rejects (zero A, coplanar axes...) is a config mistake too.
    node.Fail(std::string(e.what()));
  }
}

StereoRig LoadStereoRig(const config::ConfigNode& node) {
  node.CheckKeys({"left", "right"});
  if (!node.Has("left")) node.Fail("missing key \"left\" (expected a camera mapping)");
  if (!node.Has("right")) node.Fail("missing key \"right\" (expected a camera mapping)");
  StereoRig rig;
  rig.left = LoadCameraModel(node["left"]);
  rig.right = LoadCameraModel(node["right"]);
  return rig;
}

StereoRig LoadStereoRigFile(const std::string& path) {
  return LoadStereoRig(config::ConfigNode::LoadFile(path));
}

}  // namespace rover::geometry
