// The ground as the renderer sees it: a height field (rocks included) and an albedo.
//
// The renderer needs only these two functions of site (x, y), so that it can draw the
// simulator's world (WorldGround, world_ground.hpp) and, in tests, hand-made ground with
// markers whose 3-D position is known exactly.
#pragma once

namespace rover::render {

class Ground {
 public:
  virtual ~Ground() = default;
  // Metres UP at site (x north, y east). The site Z of the surface is -Elevation(x, y).
  virtual double Elevation(double x, double y) const = 0;
  // Lambertian albedo in [0, 1]; may carry detail down to millimetres.
  virtual double Albedo(double x, double y) const = 0;
  // The albedo as a pixel that sees a ground patch `footprint_m` across records it: a
  // ground may leave out texture finer than the patch (it would only alias). Default: the
  // point value.
  virtual double AlbedoOver(double x, double y, double /*footprint_m*/) const { return Albedo(x, y); }
  // AlbedoOver for n points at once (the renderer asks a row at a time, so a ground can
  // vectorise). Default: one point at a time.
  virtual void AlbedoOverBatch(int n, const double* x, const double* y, const double* footprint_m,
                               double* out) const {
    for (int p = 0; p < n; ++p) out[p] = AlbedoOver(x[p], y[p], footprint_m[p]);
  }

  // A ground that IS a bilinear height grid exposes it, and the renderer traces that grid
  // itself: every hit then lies exactly on Elevation()'s surface. Node (i, j) is at
  // (x0 + i h, y0 + j h) with elevation data[i * ny + j]. Outside it nothing is hit.
  struct GridView {
    double x0 = 0, y0 = 0, h = 1;
    int nx = 0, ny = 0;
    const float* data = nullptr;
  };
  virtual bool NativeGrid(GridView* /*view*/) const { return false; }
};

// Where the sun is. Azimuth from north toward east, elevation above the horizon.
struct Sun {
  double azimuth_deg = 135.0;
  double elevation_deg = 45.0;
};

}  // namespace rover::render
