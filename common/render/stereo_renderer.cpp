#include "render/stereo_renderer.hpp"

#include "render/height_levels.hpp"
#include "render/world_ground.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <exception>
#include <thread>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace rover::render {

using internal::Box2;
using internal::HeightLevels;

struct StereoRenderer::RayTable {
  int width = 0, height = 0;
  Eigen::Vector3d origin;                // rover frame, when all rays share it
  double pixel_angle = 0;                // smallest angle between neighbouring rays, rad
  std::vector<Eigen::Vector3f> dirs;     // rover frame, unit
  std::vector<Eigen::Vector3f> origins;  // per pixel, only for non-central models
  // Square tiles of `tile` x `tile` pixels (central models only): the axis and half-angle
  // of a cone holding every ray of the tile, for ConeFreeRange. About 6 mrad across, so a
  // cone is a few centimetres wide where it meets the ground.
  int tile = 8;
  int tiles_x = 0, tiles_y = 0;
  std::vector<Eigen::Vector3d> tile_axis;
  std::vector<double> tile_half_angle;
  // The same for blocks of 2 x 2 tiles: a block's free range is where its four tiles'
  // own cone marches begin.
  int blocks_x = 0;
  std::vector<Eigen::Vector3d> block_axis;
  std::vector<double> block_half_angle;
};

namespace {

// The axis (mean direction) and half-angle of the cone holding the rays of the pixel
// rectangle [u0, u1) x [v0, v1) of a table's directions.
void BoundingCone(const std::vector<Eigen::Vector3f>& dirs, int width, int u0, int u1, int v0, int v1,
                  Eigen::Vector3d* axis, double* half_angle) {
  Eigen::Vector3d a = Eigen::Vector3d::Zero();
  for (int v = v0; v < v1; ++v) {
    for (int u = u0; u < u1; ++u) a += dirs[static_cast<std::size_t>(v) * width + u].cast<double>();
  }
  a.normalize();
  double half = 0;
  for (int v = v0; v < v1; ++v) {
    for (int u = u0; u < u1; ++u) {
      const Eigen::Vector3d d = dirs[static_cast<std::size_t>(v) * width + u].cast<double>();
      half = std::max(half, std::atan2(a.cross(d).norm(), a.dot(d)));
    }
  }
  *axis = a;
  // A margin for the rotation into the site frame.
  *half_angle = half + 1e-6;
}

}  // namespace

struct StereoRenderer::GridCache {
  Ground::GridView view;
  std::array<float, 8> probe{};
  HeightLevels levels;
  // The terrain's shadow for one sun, swept once and kept while grid and sun stay.
  double sun_azimuth_deg = 0, sun_elevation_deg = 0;
  bool has_horizon = false;
  std::vector<float> horizon;
};

namespace {

constexpr double kDeg = M_PI / 180.0;

double Seconds(std::chrono::steady_clock::time_point a, std::chrono::steady_clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

std::uint64_t SplitMix(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

// 65536 fixed standard-normal draws, indexed by a per-pixel hash: as random as needed for
// read noise, identical on every run and machine, and cheaper than a transcendental per
// pixel.
const std::vector<float>& NormalTable() {
  static const std::vector<float> table = [] {
    std::vector<float> t(1 << 16);
    std::uint64_t s = 0x5EEDull;
    for (std::size_t i = 0; i < t.size(); i += 2) {
      s = SplitMix(s);
      const double u1 = ((s >> 11) + 0.5) * 0x1.0p-53;
      s = SplitMix(s);
      const double u2 = ((s >> 11) + 0.5) * 0x1.0p-53;
      const double r = std::sqrt(-2.0 * std::log(u1));
      t[i] = static_cast<float>(r * std::cos(2 * M_PI * u2));
      t[i + 1] = static_cast<float>(r * std::sin(2 * M_PI * u2));
    }
    return t;
  }();
  return table;
}

// The rover's body, wheels and mast, in the rover frame, as shadow casters.
struct RoverSolids {
  std::vector<std::array<double, 6>> boxes;
  bool has_mast = false;
  double mx = 0, my = 0, mr = 0, mz_top = 0, mz_bottom = 0;

  // A sphere around every solid and the sun direction's reciprocals, set by Prepare for
  // one frame: most ground points' sun rays miss the sphere, and the slab tests of those
  // that do not need no division.
  Eigen::Vector3d bound_centre = Eigen::Vector3d::Zero();
  double bound_radius = -1;
  Eigen::Vector3d inv_s = Eigen::Vector3d::Zero();
  std::vector<std::array<double, 4>> box_spheres;

  void Prepare(const Eigen::Vector3d& s) {
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
    Eigen::Vector3d hi = -lo;
    for (const auto& b : boxes) {
      lo = lo.cwiseMin(Eigen::Vector3d(b[0], b[2], b[4]));
      hi = hi.cwiseMax(Eigen::Vector3d(b[1], b[3], b[5]));
    }
    if (has_mast) {
      lo = lo.cwiseMin(Eigen::Vector3d(mx - mr, my - mr, mz_top));
      hi = hi.cwiseMax(Eigen::Vector3d(mx + mr, my + mr, mz_bottom));
    }
    if (lo.x() <= hi.x()) {
      bound_centre = 0.5 * (lo + hi);
      bound_radius = 0.5 * (hi - lo).norm() + 1e-6;
    }
    for (int k = 0; k < 3; ++k) inv_s[k] = std::abs(s[k]) < 1e-15 ? 0.0 : 1.0 / s[k];
    box_spheres.clear();
    for (const auto& b : boxes) {
      const Eigen::Vector3d lo_b(b[0], b[2], b[4]), hi_b(b[1], b[3], b[5]);
      const Eigen::Vector3d c = 0.5 * (lo_b + hi_b);
      box_spheres.push_back({c.x(), c.y(), c.z(), 0.5 * (hi_b - lo_b).norm() + 1e-6});
    }
  }

  // Does the ray p + t s, t > 0, miss the bounding sphere centred at `centre`? The same
  // in any frame, so the site frame can ask before transforming the point.
  bool MissesBound(const Eigen::Vector3d& centre, const Eigen::Vector3d& p, const Eigen::Vector3d& s) const {
    if (bound_radius < 0) return true;
    return MissesSphere({centre.x(), centre.y(), centre.z(), bound_radius}, p, s);
  }
  // Sphere {x, y, z, radius}: most sun rays that enter the rover's bound still miss a
  // given box, and this is cheaper than its slab test.
  static bool MissesSphere(const std::array<double, 4>& c, const Eigen::Vector3d& p, const Eigen::Vector3d& s) {
    const Eigen::Vector3d v(c[0] - p.x(), c[1] - p.y(), c[2] - p.z());
    const double tc = v.dot(s);
    return tc < -c[3] || v.squaredNorm() - tc * tc > c[3] * c[3];
  }

  // Does the ray p + t s, t > 0 (rover frame), pass through a solid? s as in Prepare.
  bool Blocks(const Eigen::Vector3d& p, const Eigen::Vector3d& s) const {
    if (MissesBound(bound_centre, p, s)) return false;
    for (std::size_t bi = 0; bi < boxes.size(); ++bi) {
      const auto& b = boxes[bi];
      if (MissesSphere(box_spheres[bi], p, s)) continue;
      double t0 = 1e-6, t1 = std::numeric_limits<double>::infinity();
      bool miss = false;
      for (int k = 0; k < 3 && !miss; ++k) {
        const double lo = b[2 * k], hi = b[2 * k + 1];
        if (inv_s[k] == 0.0) {
          miss = p[k] < lo || p[k] > hi;
          continue;
        }
        double ta = (lo - p[k]) * inv_s[k], tb = (hi - p[k]) * inv_s[k];
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
        miss = t0 > t1;
      }
      if (!miss) return true;
    }
    if (has_mast) {
      const double px = p.x() - mx, py = p.y() - my;
      const double a = s.x() * s.x() + s.y() * s.y();
      if (a > 1e-15) {
        const double b = 2 * (px * s.x() + py * s.y());
        const double c = px * px + py * py - mr * mr;
        const double disc = b * b - 4 * a * c;
        if (disc >= 0) {
          const double sq = std::sqrt(disc);
          for (double t : {(-b - sq) / (2 * a), (-b + sq) / (2 * a)}) {
            const double z = p.z() + t * s.z();
            if (t > 0 && z >= mz_top && z <= mz_bottom) return true;
          }
        }
      }
    }
    return false;
  }
};

RoverSolids MakeRoverSolids(const RoverShadowOptions& options, const geometry::StereoRig& rig) {
  RoverSolids solids;
  if (!options.enabled) return solids;
  const RoverShadowOptions o = MastUnderRig(options, rig);
  solids.boxes = o.boxes;
  if (o.wheels) {
    // MER-like: 0.25 m wheels, 0.16 m wide, at x = -0.6, 0, 0.6 and y = +-0.6.
    for (double x : {-0.6, 0.0, 0.6}) {
      for (double y : {-0.6, 0.6}) solids.boxes.push_back({x - 0.125, x + 0.125, y - 0.08, y + 0.08, -0.25, 0.0});
    }
  }
  solids.has_mast = true;
  solids.mr = o.mast_radius_m;
  solids.mx = o.mast_x_m;
  solids.my = o.mast_y_m;
  solids.mz_top = o.mast_z_top_m;
  solids.mz_bottom = o.mast_z_bottom_m;
  return solids;
}

std::string ModelKey(const geometry::CameraModel& m) {
  std::ostringstream os;
  os.precision(17);
  os << m.type() << ' ' << m.width() << ' ' << m.height();
  for (double p : m.Params()) os << ' ' << p;
  return os.str();
}

void Require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("render options: " + what);
}

}  // namespace

StereoRenderer::StereoRenderer(RenderOptions options) : options_(std::move(options)) {
  const RenderOptions& o = options_;
  Require(o.image_scale > 0 && o.image_scale <= 4, "image_scale must be in (0, 4], got " + std::to_string(o.image_scale));
  Require(o.noise_sigma_dn >= 0, "noise_sigma_dn must be >= 0, got " + std::to_string(o.noise_sigma_dn));
  Require(o.max_range_m > 0, "max_range_m must be > 0, got " + std::to_string(o.max_range_m));
  Require(o.shadow_reach_m >= 0, "shadow_reach_m must be >= 0, got " + std::to_string(o.shadow_reach_m));
  Require(o.grid_near_range_m > 0, "grid_near_range_m must be > 0, got " + std::to_string(o.grid_near_range_m));
  Require(o.grid_cell_pixels > 0, "grid_cell_pixels must be > 0, got " + std::to_string(o.grid_cell_pixels));
  Require(o.ambient >= 0 && o.ambient <= 1, "ambient must be in [0, 1], got " + std::to_string(o.ambient));
  Require(o.exposure_dn > 0, "exposure_dn must be > 0, got " + std::to_string(o.exposure_dn));
  Require(o.rover_shadow.mast_radius_m >= 0, "rover_shadow.mast_radius_m must be >= 0");
  for (const auto& b : o.rover_shadow.boxes) {
    Require(b[0] <= b[1] && b[2] <= b[3] && b[4] <= b[5],
            "rover_shadow.boxes: each box is [x_min, x_max, y_min, y_max, z_min, z_max] with min <= max");
  }
}

const StereoRenderer::RayTable& StereoRenderer::RaysFor(const geometry::CameraModel& model) {
  const std::string key = ModelKey(model);
  auto it = ray_cache_.find(key);
  if (it != ray_cache_.end()) return *it->second;
  if (ray_cache_.size() >= 8) ray_cache_.clear();
  auto table = std::make_shared<RayTable>();
  table->width = model.width();
  table->height = model.height();
  table->origin = model.Center();
  const std::size_t n = static_cast<std::size_t>(table->width) * table->height;
  table->dirs.resize(n);
  bool central = true;
  std::vector<Eigen::Vector3f> origins(n);
  for (int v = 0; v < table->height; ++v) {
    for (int u = 0; u < table->width; ++u) {
      Eigen::Vector3d o, d;
      model.BackProject(Eigen::Vector2d(u, v), &o, &d);
      const std::size_t k = static_cast<std::size_t>(v) * table->width + u;
      table->dirs[k] = d.normalized().cast<float>();
      origins[k] = (o - table->origin).cast<float>();
      if ((o - table->origin).norm() > 1e-9) central = false;
    }
  }
  // The finest angular pixel over a coarse lattice of the image, so that the albedo
  // footprint is never overstated where the model's pixels are smallest.
  double angle = M_PI;
  for (int v = 0; v + 1 < table->height; v += std::max(1, table->height / 16)) {
    for (int u = 0; u + 1 < table->width; u += std::max(1, table->width / 16)) {
      const std::size_t k = static_cast<std::size_t>(v) * table->width + u;
      const Eigen::Vector3d d0 = table->dirs[k].cast<double>();
      for (const std::size_t kn : {k + 1, k + table->width}) {
        const Eigen::Vector3d d1 = table->dirs[kn].cast<double>();
        angle = std::min(angle, std::atan2(d0.cross(d1).norm(), d0.dot(d1)));
      }
    }
  }
  table->pixel_angle = angle;
  if (!central) {
    table->origins = std::move(origins);
  } else {
    const int T = table->tile = std::clamp(static_cast<int>(std::lround(0.006 / table->pixel_angle)), 2, 16);
    table->tiles_x = (table->width + T - 1) / T;
    table->tiles_y = (table->height + T - 1) / T;
    for (int ty = 0; ty < table->tiles_y; ++ty) {
      for (int tx = 0; tx < table->tiles_x; ++tx) {
        Eigen::Vector3d axis;
        double half = 0;
        BoundingCone(table->dirs, table->width, tx * T, std::min(table->width, (tx + 1) * T), ty * T,
                     std::min(table->height, (ty + 1) * T), &axis, &half);
        table->tile_axis.push_back(axis);
        table->tile_half_angle.push_back(half);
      }
    }
    table->blocks_x = (table->tiles_x + 1) / 2;
    for (int by = 0; by < (table->tiles_y + 1) / 2; ++by) {
      for (int bx = 0; bx < table->blocks_x; ++bx) {
        Eigen::Vector3d axis;
        double half = 0;
        BoundingCone(table->dirs, table->width, 2 * bx * T, std::min(table->width, (2 * bx + 2) * T), 2 * by * T,
                     std::min(table->height, (2 * by + 2) * T), &axis, &half);
        table->block_axis.push_back(axis);
        table->block_half_angle.push_back(half);
      }
    }
  }
  ray_cache_[key] = table;
  return *table;
}

StereoImages StereoRenderer::RenderPair(const terrain::World& world,
                                        const geometry::StereoRig& rig_in_rover_frame,
                                        const Eigen::Isometry3d& T_site_rover,
                                        std::int64_t frame_seed) {
  const WorldGround ground(world);
  return RenderPair(ground, SunOf(world), rig_in_rover_frame, T_site_rover, frame_seed);
}

StereoImages StereoRenderer::RenderPair(const Ground& ground, const Sun& world_sun,
                                        const geometry::StereoRig& rig_in_rover_frame,
                                        const Eigen::Isometry3d& T_site_rover,
                                        std::int64_t frame_seed) {
  if (!rig_in_rover_frame.left || !rig_in_rover_frame.right) {
    throw std::invalid_argument("RenderPair: the stereo rig needs both a left and a right model");
  }
  const RenderOptions& o = options_;
  const auto t_start = std::chrono::steady_clock::now();
  StereoImages out;
  if (o.image_scale == 1.0) {
    out.rig.left = rig_in_rover_frame.left->Clone();
    out.rig.right = rig_in_rover_frame.right->Clone();
  } else {
    out.rig.left = rig_in_rover_frame.left->Scaled(o.image_scale);
    out.rig.right = rig_in_rover_frame.right->Scaled(o.image_scale);
  }
  const Sun sun = o.sun_override ? Sun{o.sun_azimuth_deg, o.sun_elevation_deg} : world_sun;
  const double az = sun.azimuth_deg * kDeg, el = sun.elevation_deg * kDeg;
  const Eigen::Vector3d s_site(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), -std::sin(el));

  const Eigen::Matrix3d R = T_site_rover.linear();
  const Eigen::Vector3d tr = T_site_rover.translation();
  const RayTable* tables[2] = {&RaysFor(*out.rig.left), &RaysFor(*out.rig.right)};

  // ---- The height field this frame traces.
  const HeightLevels* levels = nullptr;
  const bool sun_up = el > 0;
  // The native grid's terrain shadow as a horizon field (SunHorizon); other grounds are
  // resampled per frame and trace a shadow ray per lit pixel instead.
  const std::vector<float>* horizon = nullptr;
  HeightLevels frame_levels;
  Ground::GridView view;
  if (ground.NativeGrid(&view)) {
    std::array<float, 8> probe{};
    const std::size_t total = static_cast<std::size_t>(view.nx) * view.ny;
    for (std::size_t k = 0; k < probe.size(); ++k) probe[k] = view.data[(total - 1) * k / (probe.size() - 1)];
    const bool same = grid_cache_ && grid_cache_->view.data == view.data && grid_cache_->view.nx == view.nx &&
                      grid_cache_->view.ny == view.ny && grid_cache_->view.x0 == view.x0 &&
                      grid_cache_->view.y0 == view.y0 && grid_cache_->view.h == view.h &&
                      grid_cache_->probe == probe;
    if (!same) {
      grid_cache_ = std::make_shared<GridCache>();
      grid_cache_->view = view;
      grid_cache_->probe = probe;
      grid_cache_->levels.Adopt(view);
    }
    levels = &grid_cache_->levels;
    if (sun_up && o.shadow_reach_m > 0 &&
        (!grid_cache_->has_horizon || grid_cache_->sun_azimuth_deg != sun.azimuth_deg ||
         grid_cache_->sun_elevation_deg != sun.elevation_deg)) {
      grid_cache_->horizon = levels->level(0).SunHorizon(std::cos(az), std::sin(az), std::tan(el));
      grid_cache_->sun_azimuth_deg = sun.azimuth_deg;
      grid_cache_->sun_elevation_deg = sun.elevation_deg;
      grid_cache_->has_horizon = true;
    }
    if (sun_up && o.shadow_reach_m > 0) horizon = &grid_cache_->horizon;
  } else {
    // Sample the ground into nested grids around the rig, over what the cameras can see
    // and what can shadow it.
    const Eigen::Vector3d rig_c = T_site_rover * (0.5 * (out.rig.left->Center() + out.rig.right->Center()));
    const Eigen::Vector2d centre = rig_c.head<2>();
    int n_levels = 1;
    while (o.grid_near_range_m * std::ldexp(1.0, n_levels - 1) < o.max_range_m) ++n_levels;
    Eigen::Vector3d o0, d0, o1, d1;
    const geometry::CameraModel& lm = *out.rig.left;
    const Eigen::Vector2d pc(0.5 * (lm.width() - 1), 0.5 * (lm.height() - 1));
    lm.BackProject(pc, &o0, &d0);
    lm.BackProject(pc + Eigen::Vector2d(1, 0), &o1, &d1);
    const double pixel_angle = std::acos(std::clamp(d0.normalized().dot(d1.normalized()), -1.0, 1.0));
    const Eigen::Vector2d sun_xy = s_site.head<2>();
    const double reach_xy = o.shadow_reach_m;
    std::vector<Box2> boxes(n_levels);
    std::vector<double> cells(n_levels);
    for (int L = 0; L < n_levels; ++L) {
      const double RL = o.grid_near_range_m * std::ldexp(1.0, L);
      cells[L] = std::max(1e-4, o.grid_cell_pixels * RL * pixel_angle);
      Box2 f;
      for (const RayTable* tab : tables) {
        const int steps = 16;
        for (int a = 0; a <= steps; ++a) {
          for (int b = 0; b <= steps; ++b) {
            const int u = (tab->width - 1) * a / steps, v = (tab->height - 1) * b / steps;
            const std::size_t k = static_cast<std::size_t>(v) * tab->width + u;
            Eigen::Vector3d org = tab->origin;
            if (!tab->origins.empty()) org += tab->origins[k].cast<double>();
            const Eigen::Vector3d os = T_site_rover * org;
            const Eigen::Vector3d ds = R * tab->dirs[k].cast<double>();
            double t_end = o.max_range_m;
            const double px = os.x() - centre.x(), py = os.y() - centre.y();
            const double qa = ds.x() * ds.x() + ds.y() * ds.y();
            if (qa > 1e-18) {
              const double qb = 2 * (px * ds.x() + py * ds.y()), qc = px * px + py * py - RL * RL;
              const double disc = qb * qb - 4 * qa * qc;
              if (disc > 0) t_end = std::min(t_end, (-qb + std::sqrt(disc)) / (2 * qa));
            }
            t_end = std::max(t_end, 0.0);
            f.Add(os.x(), os.y());
            f.Add(os.x() + t_end * ds.x(), os.y() + t_end * ds.y());
          }
        }
      }
      const double margin = 0.03 * RL + 2 * cells[L];
      f = Box2{f.x_min - margin, f.x_max + margin, f.y_min - margin, f.y_max + margin};
      Box2 swept = f;
      swept.Add(Box2{f.x_min + reach_xy * sun_xy.x(), f.x_max + reach_xy * sun_xy.x(),
                     f.y_min + reach_xy * sun_xy.y(), f.y_max + reach_xy * sun_xy.y()});
      const double lim = RL + margin;
      boxes[L] = Box2{std::max(swept.x_min, centre.x() - lim), std::min(swept.x_max, centre.x() + lim),
                      std::max(swept.y_min, centre.y() - lim), std::min(swept.y_max, centre.y() + lim)};
    }
    frame_levels.Build(ground, centre, o.grid_near_range_m, boxes, cells);
    levels = &frame_levels;
  }
  const auto t_grid = std::chrono::steady_clock::now();

  // ---- Trace both images.
  RoverSolids solids = MakeRoverSolids(o.rover_shadow, out.rig);
  const bool check_rover = !solids.boxes.empty() || solids.has_mast;
  const Eigen::Vector3d s_rover = R.transpose() * s_site;
  solids.Prepare(s_rover);
  const Eigen::Vector3d bound_centre_site = T_site_rover * solids.bound_centre;
  const double t_shadow = o.shadow_reach_m / std::max(std::cos(el), 1e-3);
  const std::vector<float>& normal = NormalTable();
  const std::uint64_t base_seed = SplitMix(o.noise_seed ^ SplitMix(static_cast<std::uint64_t>(frame_seed)));

  // Scene radiance first, in DN at exposure_dn; the exposure and the sensor come after,
  // once both images are known.
  cv::Mat radiance[2];
  cv::Mat depths[2];
  // Traces one camera. The two share nothing they write, so they may run at once
  // (options.threads = 2) and give the same images, bit for bit.
  auto trace = [&](int cam) {
    // One row's hits, so that the ground's albedo is asked for a row at a time.
    std::vector<double> hit_x, hit_y, hit_footprint, hit_albedo, hit_light;
    std::vector<int> hit_column;
    const RayTable& tab = *tables[cam];
    for (auto* a : {&hit_x, &hit_y, &hit_footprint, &hit_albedo, &hit_light}) a->resize(tab.width);
    hit_column.resize(tab.width);
    cv::Mat rad(tab.height, tab.width, CV_32FC1);
    cv::Mat depth(tab.height, tab.width, CV_32FC1);
    const Eigen::Vector3d origin_site = T_site_rover * tab.origin;
    // Where each tile's rays may start: no ray of the tile meets the ground before it.
    // Only on a single grid (the world's own), which is where the time goes.
    const bool tiled = !tab.tile_axis.empty() && levels->levels() == 1;
    std::vector<double> tile_start(static_cast<std::size_t>(std::max(tab.tiles_x, 1)), 0.0);
    std::vector<double> block_start(static_cast<std::size_t>(std::max(tab.blocks_x, 1)), 0.0);
    for (int v = 0; v < tab.height; ++v) {
      if (tiled && v % tab.tile == 0) {
        const internal::HeightGrid& g = levels->level(0);
        const int ty = v / tab.tile;
        // Refining to a quarter cell: a start that close costs the rays fewer steps than
        // the finer march costs the tile.
        const double resolution = 0.25 * g.cell();
        if (ty % 2 == 0) {
          for (int bx = 0; bx < tab.blocks_x; ++bx) {
            const std::size_t i = static_cast<std::size_t>(ty / 2) * tab.blocks_x + bx;
            block_start[bx] = g.ConeFreeRange(origin_site, R * tab.block_axis[i], tab.block_half_angle[i],
                                              o.max_range_m, resolution);
          }
        }
        for (int tx = 0; tx < tab.tiles_x; ++tx) {
          const std::size_t i = static_cast<std::size_t>(ty) * tab.tiles_x + tx;
          // Less a part in a million: the float directions are unit only to that.
          tile_start[tx] = (1 - 1e-6) * g.ConeFreeRange(origin_site, R * tab.tile_axis[i], tab.tile_half_angle[i],
                                                        o.max_range_m, resolution, block_start[tx / 2]);
        }
      }
      float* rrow = rad.ptr<float>(v);
      float* drow = depth.ptr<float>(v);
      int hits = 0;
      for (int u = 0; u < tab.width; ++u) {
        const std::size_t k = static_cast<std::size_t>(v) * tab.width + u;
        Eigen::Vector3d os = origin_site;
        if (!tab.origins.empty()) os += R * tab.origins[k].cast<double>();
        const Eigen::Vector3d ds = R * tab.dirs[k].cast<double>();
        int level = 0;
        // A tile's rays start close to the ground: from the finest mip.
        const double t = tiled ? levels->level(0).IntersectNear(os, ds, tile_start[u / tab.tile], o.max_range_m)
                               : levels->Intersect(os, ds, 0.0, o.max_range_m, &level);
        if (t < 0) {
          rrow[u] = static_cast<float>(ds.z() < 0 ? o.sky_dn : o.far_ground_dn);
          drow[u] = 0.0f;
          continue;
        }
        drow[u] = static_cast<float>(t);
        const Eigen::Vector3d p = os + t * ds;
        const internal::HeightGrid& g = levels->level(level);
        double horizon_here = 0;
        const Eigen::Vector3d n = horizon ? g.NormalUpAt(p.x(), p.y(), *horizon, &horizon_here) : g.NormalUpAt(p.x(), p.y());
        // The pixel sees t * pixel_angle of ground across the ray and that over
        // cos(incidence) along it: the footprint is the side of the square of the same
        // area, so texture the pixel can only alias is left out, and no more.
        const double across = t * tab.pixel_angle;
        hit_footprint[hits] = across / std::sqrt(std::max(std::abs(n.dot(ds)), 0.05));
        hit_x[hits] = p.x();
        hit_y[hits] = p.y();
        hit_column[hits] = u;
        double direct = 0;
        const double cos_i = n.dot(s_site);
        if (sun_up && cos_i > 0) {
          bool lit = true;
          if (check_rover && !solids.MissesBound(bound_centre_site, p, s_site)) {
            lit = !solids.Blocks(R.transpose() * (p - tr), s_rover);
          }
          if (lit && horizon) {
            // The same lift off the surface as the shadow ray below.
            lit = -p.z() + std::max(0.002, 0.05 * g.cell()) >= horizon_here;
          } else if (lit && t_shadow > 0) {
            // Start a little above the surface so the ray does not hit its own cell.
            const Eigen::Vector3d start(p.x(), p.y(), p.z() - std::max(0.002, 0.05 * g.cell()));
            lit = levels->Intersect(start, s_site, 0.0, t_shadow) < 0;
          }
          if (lit) direct = cos_i;
        }
        hit_light[hits++] = o.exposure_dn * (o.ambient + (1 - o.ambient) * direct);
      }
      ground.AlbedoOverBatch(hits, hit_x.data(), hit_y.data(), hit_footprint.data(), hit_albedo.data());
      for (int h = 0; h < hits; ++h) rrow[hit_column[h]] = static_cast<float>(hit_albedo[h] * hit_light[h]);
    }
    radiance[cam] = rad;
    depths[cam] = depth;
  };
  if (o.threads >= 2) {
    // A second thread, not OpenCV's pool: two equal halves, and no pool to size.
    std::exception_ptr right_failed;
    std::thread right([&] {
      try {
        trace(1);
      } catch (...) {
        right_failed = std::current_exception();
      }
    });
    try {
      trace(0);
    } catch (...) {
      right.join();
      throw;
    }
    right.join();
    if (right_failed) std::rethrow_exception(right_failed);
  } else {
    trace(0);
    trace(1);
  }
  out.depth_left = depths[0];
  out.depth_right = depths[1];

  // Automatic exposure, as the NAVCAMs had: one gain for both cameras (stereo matching
  // wants the pair alike), from the left image's mean, so that low sun is not simply
  // dark. It depends on the rendered radiance only, not on anything else from truth.
  double gain = 1.0;
  if (o.auto_exposure) {
    const double mean = cv::mean(radiance[0])[0];
    if (mean > 1e-9) gain = o.target_mean_dn / mean;
  }
  out.exposure_gain = gain;
  for (int cam = 0; cam < 2; ++cam) {
    const cv::Mat& rad = radiance[cam];
    cv::Mat img(rad.rows, rad.cols, CV_8UC1);
    const std::uint64_t cam_seed = SplitMix(base_seed + 0x1234567ull * (cam + 1));
    for (int v = 0; v < rad.rows; ++v) {
      const float* rrow = rad.ptr<float>(v);
      std::uint8_t* row = img.ptr<std::uint8_t>(v);
      for (int u = 0; u < rad.cols; ++u) {
        const std::size_t k = static_cast<std::size_t>(v) * rad.cols + u;
        double value = gain * rrow[u];
        if (o.noise_sigma_dn > 0) value += o.noise_sigma_dn * normal[SplitMix(cam_seed + k) & 0xFFFF];
        // Round half up and clamp: truncation is floor once clamped to [0, 255].
        row[u] = static_cast<std::uint8_t>(std::clamp(value + 0.5, 0.0, 255.0));
      }
    }
    (cam == 0 ? out.left : out.right) = img;
  }
  const auto t_end = std::chrono::steady_clock::now();
  timing_.grid_seconds = Seconds(t_start, t_grid);
  timing_.trace_seconds = Seconds(t_grid, t_end);
  timing_.grid_nodes = levels->nodes();
  return out;
}

cv::Mat DisparityFromDepth(const cv::Mat& depth_left, const geometry::StereoRig& rig) {
  if (depth_left.type() != CV_32FC1 || depth_left.cols != rig.left->width() ||
      depth_left.rows != rig.left->height()) {
    throw std::invalid_argument("DisparityFromDepth: depth must be CV_32FC1 of the left model's size");
  }
  cv::Mat disp(depth_left.size(), CV_32FC1, cv::Scalar(std::numeric_limits<float>::quiet_NaN()));
  for (int v = 0; v < depth_left.rows; ++v) {
    for (int u = 0; u < depth_left.cols; ++u) {
      const float r = depth_left.at<float>(v, u);
      if (!(r > 0)) continue;
      Eigen::Vector3d o, d;
      rig.left->BackProject(Eigen::Vector2d(u, v), &o, &d);
      Eigen::Vector2d pr;
      if (rig.right->Project(o + r * d.normalized(), &pr)) disp.at<float>(v, u) = static_cast<float>(u - pr.x());
    }
  }
  return disp;
}

cv::Mat ColourDisparity(const cv::Mat& disparity) {
  double lo = 0, hi = 1;
  cv::Mat valid = disparity == disparity;  // not NaN
  cv::minMaxLoc(disparity, &lo, &hi, nullptr, nullptr, valid);
  if (hi <= lo) hi = lo + 1;
  cv::Mat scaled;
  disparity.convertTo(scaled, CV_8UC1, 255.0 / (hi - lo), -255.0 * lo / (hi - lo));
  cv::Mat colour;
  cv::applyColorMap(scaled, colour, cv::COLORMAP_JET);
  colour.setTo(cv::Scalar(0, 0, 0), ~valid);
  return colour;
}

}  // namespace rover::render
