// Shared pieces of the renderer tests: a NAVCAM-like rectified pinhole rig and hand-made
// ground with markers whose 3-D position is known exactly.
#pragma once

#include "geometry/camera_io.hpp"
#include "geometry/pinhole_camera.hpp"
#include "geometry/pose.hpp"
#include "render/ground.hpp"

#include <cmath>
#include <memory>
#include <vector>

namespace rover::render::test {

// Two identical pinhole cameras 0.2 m apart on a 1.5 m mast, tilted `tilt_deg` down:
// a rectified pair (baseline along the camera x axis).
inline geometry::StereoRig NavcamRig(int size, double tilt_deg = 35.0) {
  const double f = 0.5 * size / std::tan(22.5 * M_PI / 180.0);
  const double c = 0.5 * (size - 1);
  geometry::StereoRig rig;
  for (int side = 0; side < 2; ++side) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = geometry::RotationFromRpy(0, -tilt_deg * M_PI / 180.0, 0) * geometry::BodyFromOptical();
    T.translation() = Eigen::Vector3d(0.45, side == 0 ? -0.1 : 0.1, -1.5);
    auto cam = std::make_shared<geometry::PinholeCamera>(size, size, f, f, c, c, std::vector<double>{}, T);
    (side == 0 ? rig.left : rig.right) = cam;
  }
  return rig;
}

// A dark Gaussian spot on the ground.
struct Marker {
  double x, y, sigma;
};

// A plane (elevation = base + gx x + gy y), optional smooth rocks (half-ellipsoids, or
// flat-topped: a level summit of radius flat_top inside an ellipsoidal shoulder), a
// uniform albedo, and markers.
class MarkedGround : public Ground {
 public:
  struct Bump {
    double x, y, radius, height;
    double flat_top = 0;
  };
  double base = 0, gx = 0, gy = 0, albedo = 0.5, marker_depth = 0.8;
  std::vector<Bump> bumps;
  std::vector<Marker> markers;

  double Elevation(double x, double y) const override {
    double e = base + gx * x + gy * y;
    for (const Bump& b : bumps) {
      const double r = std::hypot(x - b.x, y - b.y);
      if (r <= b.flat_top) {
        e += b.height;
      } else if (r < b.radius) {
        const double q = (r - b.flat_top) / (b.radius - b.flat_top);
        e += b.height * std::sqrt(1 - q * q);
      }
    }
    return e;
  }
  double Albedo(double x, double y) const override {
    double a = albedo;
    for (const Marker& m : markers) {
      const double r2 = ((x - m.x) * (x - m.x) + (y - m.y) * (y - m.y)) / (m.sigma * m.sigma);
      if (r2 < 40) a -= marker_depth * albedo * std::exp(-0.5 * r2);
    }
    return a;
  }
};

}  // namespace rover::render::test
