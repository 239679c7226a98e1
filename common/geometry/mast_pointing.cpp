#include "geometry/mast_pointing.hpp"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace rover::geometry {

Eigen::Isometry3d MastPointingMotion(const StereoRig& rig, double pan_rad, double tilt_rad) {
  if (!rig.left || !rig.right) {
    throw std::invalid_argument("PointedRig: the stereo rig needs both a left and a right model");
  }
  if (!std::isfinite(pan_rad) || !std::isfinite(tilt_rad)) {
    std::ostringstream err;
    err << "PointedRig: pan " << pan_rad << " rad, tilt " << tilt_rad << " rad (expected finite angles)";
    throw std::invalid_argument(err.str());
  }
  const Eigen::Vector3d cl = rig.left->Center(), cr = rig.right->Center();
  const Eigen::Vector3d m = 0.5 * (cl + cr);
  Eigen::Vector3d bar = cr - cl;
  bar.z() = 0.0;  // the tilt axis is horizontal even on a rig mounted with some roll
  if (!(bar.norm() > 1e-9)) {
    throw std::invalid_argument(
        "PointedRig: the camera centres are one above the other (expected a horizontal baseline to tilt about)");
  }
  bar.normalize();
  const Eigen::Matrix3d R = Eigen::AngleAxisd(pan_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix() *
                            Eigen::AngleAxisd(-tilt_rad, bar).toRotationMatrix();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R;
  T.translation() = m - R * m;  // m stays where it is
  return T;
}

StereoRig PointedRig(const StereoRig& rig, double pan_rad, double tilt_rad) {
  if (pan_rad == 0.0 && tilt_rad == 0.0) return rig;
  const Eigen::Isometry3d T = MastPointingMotion(rig, pan_rad, tilt_rad);
  StereoRig pointed = rig;
  pointed.left = rig.left->Moved(T);
  pointed.right = rig.right->Moved(T);
  return pointed;
}

}  // namespace rover::geometry
