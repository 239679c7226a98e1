// The simulator's world as the renderer's ground: the world's own height grid (ground and
// rocks) is traced directly, and its albedo texture is sampled at every hit.
#pragma once

#include "render/ground.hpp"
#include "terrain/world.hpp"

namespace rover::render {

class WorldGround : public Ground {
 public:
  explicit WorldGround(const terrain::World& world) : world_(world) {}
  double Elevation(double x, double y) const override { return world_.Elevation(x, y); }
  double Albedo(double x, double y) const override { return world_.Albedo(x, y); }
  // World::Albedo drops texture octaves shorter than twice the footprint: above the
  // pixel's Nyquist limit, and the costliest octaves of the noise.
  double AlbedoOver(double x, double y, double footprint_m) const override {
    return world_.Albedo(x, y, footprint_m);
  }
  void AlbedoOverBatch(int n, const double* x, const double* y, const double* footprint_m,
                       double* out) const override {
    world_.AlbedoBatch(n, x, y, footprint_m, out);
  }
  bool NativeGrid(GridView* view) const override {
    view->x0 = world_.x_min();
    view->y0 = world_.y_min();
    view->h = world_.resolution();
    view->nx = world_.nx();
    view->ny = world_.ny();
    view->data = world_.elevation_grid().data();
    return true;
  }

 private:
  const terrain::World& world_;
};

inline Sun SunOf(const terrain::World& world) {
  return Sun{world.sun().azimuth_deg, world.sun().elevation_deg};
}

}  // namespace rover::render
