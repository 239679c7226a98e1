// Internal to the renderer: the ground sampled into nested height grids, and exact
// ray intersection with them.
//
// Level L covers horizontal distances (R_{L-1}, R_L] from a centre (the stereo rig),
// R_L = near_range * 2^L, with cells that double too, so a cell spans about the same
// number of pixels at every distance. Each level is a bilinear height field; a ray is
// split where it crosses the circles R_L and each piece is traced in its own level.
// Tracing is coarse to fine over a max-mip (each coarse cell holds the highest node
// under it: a bilinear patch never rises above its corners, so the bound is exact),
// then the hit inside the final cell is the smallest root of a quadratic, so the hit
// lies on the bilinear surface to rounding error, far below 1 mm.
#pragma once

#include "render/ground.hpp"

#include <Eigen/Core>

#include <array>

#include <vector>

namespace rover::render::internal {

// An axis-aligned rectangle in the site XY plane.
struct Box2 {
  double x_min = 0, x_max = -1, y_min = 0, y_max = -1;
  bool empty() const { return x_max < x_min || y_max < y_min; }
  void Add(double x, double y);
  void Add(const Box2& b);
};

class HeightGrid {
 public:
  // Samples `ground` at nodes x0 + i h, y0 + j h covering `box`.
  void Build(const Ground& ground, const Box2& box, double cell_m);
  // Takes a ground's own grid as it is (no resampling).
  void Adopt(const Ground::GridView& view);

  // First hit of o + t d (site frame, Z down, |d| = 1) for t in [t0, t1]; returns t or
  // a negative value for none.
  // `start_mip`: the max-mip level the walk starts on; low when o + t0 d is known to be
  // near the surface (the walk climbs by itself where the ray is high).
  double Intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t0,
                   double t1, int start_mip = 6) const;

  // Intersect for a ray known to start close to the surface (from ConeFreeRange): walks
  // the finest cells one by one (a plain grid DDA, cheaper per step than the max-mip walk)
  // for up to `max_cells`, then hands what is left to Intersect. Same result.
  double IntersectNear(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t0, double t1,
                       int max_cells = 24) const;

  // A bundle of rays from one origin o whose unit directions all lie within `half_angle`
  // (rad) of the unit axis c: the largest r found such that no ray of the bundle meets
  // the surface at a distance below r (every ray may start its own trace there). Found by
  // marching the cone's bounding boxes through the max-mip, so it never overshoots: a
  // cone section is passed only when the highest node under its box is below its lowest
  // point. Stops refining at steps of `resolution_m`. Returns 0 when nothing can be said.
  // `known_free`: a range already known to be free for this bundle (say, from a wider
  // cone that holds it), where the march may begin.
  double ConeFreeRange(const Eigen::Vector3d& o, const Eigen::Vector3d& c, double half_angle,
                       double max_range, double resolution_m, double known_free = 0) const;
  // The highest node over the cells that meet `box`; -infinity when it misses the grid.
  double MaxOver(const Box2& box) const;

  // Elevation (up) and smooth up-normal at a point: the normal interpolates node
  // gradients so that shading shows no cell pattern.
  double ElevationAt(double x, double y) const;
  Eigen::Vector3d NormalUpAt(double x, double y) const;  // in site axes, Z down
  // The same, and InterpolateNodes(*field, x, y) into *field_value with the same weights
  // (one lookup for a hit's normal and its sun horizon).
  Eigen::Vector3d NormalUpAt(double x, double y, const std::vector<float>& field, double* field_value) const;

  // The sun's horizon on this grid: for each node, the lowest elevation at which a point
  // there still sees the sun over the grid's surface (the highest of e(q) - tan(el) |q - p|
  // over the surface toward the sun), or kNoHorizon where nothing can shade it. A hit
  // is in the terrain's shadow when its elevation is below the bilinear horizon there.
  // One O(nodes) sweep from the sun side: each node takes the better of its upstream
  // neighbour line's surface and horizon (linear along that grid line, exact for the
  // surface), lowered by the drop over one step. `toward_sun_xy` is the horizontal unit
  // vector toward the sun; its reach is the whole grid (no shadow_reach_m limit).
  static constexpr float kNoHorizon = -1e30f;
  std::vector<float> SunHorizon(double toward_sun_x, double toward_sun_y, double tan_elevation) const;
  // Bilinear value of a node field (same layout as the grid: row j of nx nodes) at (x, y).
  double InterpolateNodes(const std::vector<float>& field, double x, double y) const;

  double cell() const { return h_; }
  double max_elevation() const { return global_max_; }
  bool Contains(double x, double y) const;
  const Box2& box() const { return box_; }
  std::size_t nodes() const { return z_.size(); }

 private:
  void BuildMips();
  // Narrows [t0, t1] of o + t d to the grid's rectangle (rdx, rdy: 1/d.x, 1/d.y or 0);
  // false when the ray misses it.
  bool ClipToBox(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double rdx, double rdy, double* t0,
                 double* t1) const;
  void BuildGradients();
  // The cell of (x, y) (clamped into the grid): node index k of its low corner and the
  // bilinear fractions a (along x) and b (along y).
  void Locate(double x, double y, std::size_t* k, double* a, double* b) const;
  Eigen::Vector3d NormalAtNode(std::size_t k, double a, double b) const;
  float Z(int i, int j) const { return z_[static_cast<std::size_t>(j) * nx_ + i]; }
  double HitInCell(int i, int j, double gu, double gv, double du, double dv, double oe,
                   double de, double t, double t_exit) const;

  double x0_ = 0, y0_ = 0, h_ = 1, inv_h_ = 1;
  int nx_ = 0, ny_ = 0;
  Box2 box_;
  std::vector<float> z_;  // elevation up, row-major (j rows of i)
  std::vector<std::array<float, 2>> grad_;  // d(elevation)/dx, /dy per node, same layout
  // mips_[m] has cells of 2^m base cells; size cx_[m] x cy_[m].
  std::vector<std::vector<float>> mips_;
  std::vector<int> cx_, cy_;
  double global_max_ = 0;
};

class HeightLevels {
 public:
  // Builds the levels around `centre` (site XY). `boxes[L]` is the region level L must
  // cover (already limited to its radius); cell sizes are cells[L].
  void Build(const Ground& ground, const Eigen::Vector2d& centre, double near_range_m,
             const std::vector<Box2>& boxes, const std::vector<double>& cells);

  // First hit along o + t d, t in [t0, t1]. Returns t, or a negative value.
  // `level_out` gets the level of the hit.
  double Intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t0,
                   double t1, int* level_out = nullptr) const;

  // One level: the ground's own grid.
  void Adopt(const Ground::GridView& view);

  const HeightGrid& level(int L) const { return grids_[L]; }
  int levels() const { return static_cast<int>(grids_.size()); }
  int LevelAt(double x, double y) const;
  double max_elevation() const { return global_max_; }
  std::size_t nodes() const;

 private:
  Eigen::Vector2d centre_{0, 0};
  double near_range_ = 4;
  std::vector<HeightGrid> grids_;
  double global_max_ = 0;
};

}  // namespace rover::render::internal
