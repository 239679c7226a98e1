// CameraModelFromParams: the inverse of CameraModel::Params() for every model type.
#include "geometry/cahv_camera.hpp"
#include "geometry/cahvore_camera.hpp"
#include "geometry/camera_model.hpp"
#include "geometry/pinhole_camera.hpp"

#include <stdexcept>

namespace rover::geometry {

namespace {

Eigen::Vector3d Vec3(const std::vector<double>& p, std::size_t at) {
  return Eigen::Vector3d(p[at], p[at + 1], p[at + 2]);
}

[[noreturn]] void WrongCount(const std::string& type, const std::string& expected,
                             std::size_t got) {
  throw std::invalid_argument("CameraModelFromParams: type \"" + type + "\" takes " + expected +
                              ", got " + std::to_string(got));
}

}  // namespace

std::unique_ptr<CameraModel> CameraModelFromParams(const std::string& type, int width,
                                                   int height,
                                                   const std::vector<double>& params) {
  const std::size_t n = params.size();
  if (type == "pinhole") {
    if (n != 11 && n != 15 && n != 16) {
      WrongCount(type, "11, 15 or 16 parameters (fx fy cx cy tx ty tz qw qx qy qz [k1 k2 p1 p2 [k3]])",
                 n);
    }
    const Eigen::Quaterniond q(params[7], params[8], params[9], params[10]);
    if (!(q.norm() > 1e-9)) {
      throw std::invalid_argument("CameraModelFromParams: pinhole quaternion is zero (expected a rotation)");
    }
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = q.normalized().toRotationMatrix();
    T.translation() = Vec3(params, 4);
    return std::make_unique<PinholeCamera>(width, height, params[0], params[1], params[2],
                                           params[3],
                                           std::vector<double>(params.begin() + 11, params.end()),
                                           T);
  }
  if (type == "cahv") {
    if (n != 12) WrongCount(type, "12 parameters (C A H V)", n);
    return std::make_unique<CahvCamera>(width, height, Vec3(params, 0), Vec3(params, 3),
                                        Vec3(params, 6), Vec3(params, 9));
  }
  if (type == "cahvor") {
    if (n != 18) WrongCount(type, "18 parameters (C A H V O R)", n);
    return std::make_unique<CahvorCamera>(width, height, Vec3(params, 0), Vec3(params, 3),
                                          Vec3(params, 6), Vec3(params, 9), Vec3(params, 12),
                                          Vec3(params, 15));
  }
  if (type == "cahvore") {
    if (n != 22) WrongCount(type, "22 parameters (C A H V O R E linearity)", n);
    return std::make_unique<CahvoreCamera>(width, height, Vec3(params, 0), Vec3(params, 3),
                                           Vec3(params, 6), Vec3(params, 9), Vec3(params, 12),
                                           Vec3(params, 15), Vec3(params, 18), params[21]);
  }
  throw std::invalid_argument("CameraModelFromParams: unknown type \"" + type +
                              "\" (expected pinhole, cahv, cahvor or cahvore)");
}

}  // namespace rover::geometry
