#include "terrain/world.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "terrain/albedo_noise.hpp"
#include "terrain/random.hpp"

namespace rover::terrain {

namespace {

constexpr double kDeg = M_PI / 180.0;

// Feature tags for SubSeed: changing one feature's draw never shifts another's.
enum SeedTag : std::uint64_t {
  kTagRoughness = 1,
  kTagRipples = 2,
  kTagRocks = 3,
  kTagAlbedo = 4,
  kTagRockAlbedo = 5,
};

// Albedo texture is flatter across scales than the relief (hurst 0.3), so centimetre
// texture survives: that is what the VO corner detector lives on.
constexpr double kAlbedoHurst = 0.3;
// Rock surfaces carry texture from 1 cm to 16 cm; the dust mottling common to all soils
// is one octave of 5 m.
constexpr double kRockTextureMinWavelength = 0.01;
constexpr double kRockTextureMaxWavelength = 0.16;
constexpr double kMottleWavelength = 5.0;

// Standard deviation of FractalNoise for these octaves, so `contrast` is a relative std.
double FractalStd(double min_wl, double max_wl, double hurst) {
  double sum_sq = 0.0;
  double amp = 1.0;
  const double step = std::pow(0.5, hurst);
  for (double lambda = max_wl; lambda >= min_wl * 0.999; lambda *= 0.5, amp *= step) {
    sum_sq += amp * amp;
  }
  return kValueNoiseStd * std::sqrt(std::max(sum_sq, 1e-12));
}

// Rounded max(d, 0) over a width b (quadratic blend), so ramps have no kink.
double SmoothPositive(double d, double b) {
  if (b <= 0.0) return std::max(d, 0.0);
  if (d >= 0.5 * b) return d;
  if (d <= -0.5 * b) return 0.0;
  const double t = d + 0.5 * b;
  return t * t / (2.0 * b);
}

double SlopeProfile(const SlopeOptions& s, double x, double y) {
  const double az = s.uphill_azimuth_deg * kDeg;
  const double along = (x - s.origin.x()) * std::cos(az) + (y - s.origin.y()) * std::sin(az);
  // clamp(along, from, to) with rounded corners.
  double v = s.from_m + SmoothPositive(along - s.from_m, s.blend_m);
  v = s.to_m - SmoothPositive(s.to_m - v, s.blend_m);
  return std::tan(s.angle_deg * kDeg) * v;
}

double CraterProfile(const CraterOptions& c, double x, double y) {
  const double r = std::hypot(x - c.center.x(), y - c.center.y());
  double e = 0.0;
  if (r < c.radius_m) {
    const double u = r / c.radius_m;
    e -= c.depth_m * (1.0 - u * u);
  }
  if (c.rim_height_m > 0.0 && c.rim_width_m > 0.0) {
    const double d = (r - c.radius_m) / c.rim_width_m;
    e += c.rim_height_m * std::exp(-d * d);
  }
  return e;
}

double DistanceToSegment(const Eigen::Vector2d& p, const Eigen::Vector2d& a,
                         const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0.0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (a + t * ab - p).norm();
}

// True if a disc of radius r at p touches the region.
bool DiscTouches(const Region& region, const Eigen::Vector2d& p, double r) {
  if (region.shape == Region::Shape::kCircle) {
    return (p - region.center).norm() < region.radius_m + r;
  }
  if (region.Contains(p)) return true;
  const auto& v = region.vertices;
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (DistanceToSegment(p, v[i], v[(i + 1) % v.size()]) < r) return true;
  }
  return false;
}

const SoilAlbedo& AlbedoOf(const AlbedoOptions& a, Soil s) {
  switch (s) {
    case Soil::kBedrock: return a.bedrock;
    case Soil::kPackedSoil: return a.packed_soil;
    case Soil::kSand: return a.sand;
  }
  return a.sand;
}

}  // namespace

const char* SoilName(Soil soil) {
  switch (soil) {
    case Soil::kBedrock: return "bedrock";
    case Soil::kPackedSoil: return "packed_soil";
    case Soil::kSand: return "sand";
  }
  return "unknown";
}

Soil SoilFromName(const std::string& name) {
  for (int i = 0; i < kNumSoils; ++i) {
    if (name == SoilName(static_cast<Soil>(i))) return static_cast<Soil>(i);
  }
  throw std::invalid_argument("unknown soil \"" + name +
                              "\" (expected bedrock, packed_soil or sand)");
}

bool Region::Contains(const Eigen::Vector2d& p) const {
  if (shape == Shape::kCircle) return (p - center).squaredNorm() <= radius_m * radius_m;
  bool inside = false;
  for (std::size_t i = 0, j = vertices.size() - 1; i < vertices.size(); j = i++) {
    const Eigen::Vector2d& a = vertices[i];
    const Eigen::Vector2d& b = vertices[j];
    if ((a.y() > p.y()) != (b.y() > p.y()) &&
        p.x() < (b.x() - a.x()) * (p.y() - a.y()) / (b.y() - a.y()) + a.x()) {
      inside = !inside;
    }
  }
  return inside;
}

Region Region::Circle(const Eigen::Vector2d& center, double radius_m) {
  Region r;
  r.shape = Shape::kCircle;
  r.center = center;
  r.radius_m = radius_m;
  return r;
}

Region Region::Polygon(std::vector<Eigen::Vector2d> vertices) {
  if (vertices.size() < 3) {
    throw std::invalid_argument("polygon needs at least 3 vertices, got " +
                                std::to_string(vertices.size()));
  }
  Region r;
  r.shape = Shape::kPolygon;
  r.vertices = std::move(vertices);
  return r;
}

double GolombekQ(double k) { return 1.79 + 0.152 / k; }

double GolombekCumulativeArea(double k, double diameter_m) {
  if (k <= 0.0) return 0.0;
  return k * std::exp(-GolombekQ(k) * diameter_m);
}

std::vector<Rock> SampleGolombekRocks(const RockFieldOptions& o, const Eigen::Vector2d& lo,
                                      const Eigen::Vector2d& hi, std::uint64_t seed) {
  std::vector<Rock> rocks;
  if (o.abundance_k <= 0.0) return rocks;
  if (!(o.min_diameter_m > 0.0) || !(o.max_diameter_m > o.min_diameter_m)) {
    throw std::invalid_argument("rock field: need 0 < min_diameter_m < max_diameter_m, got " +
                                std::to_string(o.min_diameter_m) + " and " +
                                std::to_string(o.max_diameter_m));
  }
  // Number density per m^2 per unit diameter: area density -dF/dD = k q exp(-qD), divided
  // by the area of one rock pi D^2 / 4. Tabulate its cumulative integral for inverse sampling.
  const double k = o.abundance_k, q = GolombekQ(k);
  constexpr int kBins = 4000;
  std::vector<double> d(kBins + 1), cum(kBins + 1, 0.0);
  const double log_lo = std::log(o.min_diameter_m), log_hi = std::log(o.max_diameter_m);
  auto density = [&](double D) { return k * q * std::exp(-q * D) / (M_PI * D * D / 4.0); };
  for (int i = 0; i <= kBins; ++i) {
    d[i] = std::exp(log_lo + (log_hi - log_lo) * i / kBins);
    if (i > 0) cum[i] = cum[i - 1] + 0.5 * (density(d[i]) + density(d[i - 1])) * (d[i] - d[i - 1]);
  }
  const double area = (hi.x() - lo.x()) * (hi.y() - lo.y());
  Random rng(seed);
  const std::uint64_t count = rng.Poisson(cum[kBins] * area);
  rocks.reserve(count);
  for (std::uint64_t n = 0; n < count; ++n) {
    const double u = rng.Uniform() * cum[kBins];
    const int i = static_cast<int>(std::upper_bound(cum.begin(), cum.end(), u) - cum.begin());
    const int b = std::clamp(i, 1, kBins);
    const double span = cum[b] - cum[b - 1];
    const double t = span > 0.0 ? (u - cum[b - 1]) / span : 0.0;
    Rock r;
    r.diameter_m = d[b - 1] + t * (d[b] - d[b - 1]);
    r.position = {rng.Uniform(lo.x(), hi.x()), rng.Uniform(lo.y(), hi.y())};
    r.height_m = r.diameter_m * o.height_ratio * (1.0 + o.height_spread * rng.Uniform(-1.0, 1.0));
    r.albedo = o.albedo_mean * (1.0 + o.albedo_spread * rng.Uniform(-1.0, 1.0));
    r.name = "rock_" + std::to_string(n);
    rocks.push_back(std::move(r));
  }
  return rocks;
}

World::World(WorldOptions options) : options_(std::move(options)) {
  const auto& o = options_;
  if (!(o.resolution_m > 0.0) || !(o.map_size_m.x() > 0.0) || !(o.map_size_m.y() > 0.0)) {
    throw std::invalid_argument("world \"" + o.name + "\": map size and resolution must be > 0");
  }
  res_ = o.resolution_m;
  nx_ = static_cast<int>(std::ceil(o.map_size_m.x() / res_ - 1e-9)) + 1;
  ny_ = static_cast<int>(std::ceil(o.map_size_m.y() / res_ - 1e-9)) + 1;
  if (static_cast<double>(nx_) * ny_ > kMaxWorldCells) {
    throw std::invalid_argument("world \"" + o.name + "\": map of " + std::to_string(nx_) + "x" +
                                std::to_string(ny_) +
                                " cells is too large (at most 16 million; coarsen resolution_m)");
  }
  x0_ = o.map_center.x() - 0.5 * (nx_ - 1) * res_;
  y0_ = o.map_center.y() - 0.5 * (ny_ - 1) * res_;
  for (int k = 0; k < kNumSoils; ++k) {
    const SoilAlbedo& s = AlbedoOf(o.albedo, static_cast<Soil>(k));
    soil_texture_norm_[k] = 1.0 / FractalStd(s.min_wavelength_m, s.max_wavelength_m, kAlbedoHurst);
  }
  rock_texture_norm_ = 1.0 / FractalStd(kRockTextureMinWavelength, kRockTextureMaxWavelength, kAlbedoHurst);
  albedo_seed_ = static_cast<std::uint32_t>(SubSeed(o.seed, kTagAlbedo));
  rock_albedo_seed_ = static_cast<std::uint32_t>(SubSeed(o.seed, kTagRockAlbedo));
  mottle_seed_ = static_cast<std::uint32_t>(SubSeed(o.seed, kTagAlbedo) ^ 0xABCDull);
  BuildSoil();
  BuildGround();
  BuildRocks();
  StampRocks();
  IndexRocks();
}

void World::BuildSoil() {
  soil_.assign(static_cast<std::size_t>(nx_) * ny_, static_cast<std::uint8_t>(options_.default_soil));
  for (const auto& patch : options_.soil_patches) {
    // Only visit the patch's bounding box.
    Eigen::Vector2d lo, hi;
    if (patch.region.shape == Region::Shape::kCircle) {
      lo = patch.region.center.array() - patch.region.radius_m;
      hi = patch.region.center.array() + patch.region.radius_m;
    } else {
      lo = hi = patch.region.vertices.front();
      for (const auto& v : patch.region.vertices) {
        lo = lo.cwiseMin(v);
        hi = hi.cwiseMax(v);
      }
    }
    const int i0 = std::max(0, static_cast<int>(std::floor((lo.x() - x0_) / res_)));
    const int i1 = std::min(nx_ - 1, static_cast<int>(std::ceil((hi.x() - x0_) / res_)));
    const int j0 = std::max(0, static_cast<int>(std::floor((lo.y() - y0_) / res_)));
    const int j1 = std::min(ny_ - 1, static_cast<int>(std::ceil((hi.y() - y0_) / res_)));
    for (int i = i0; i <= i1; ++i) {
      for (int j = j0; j <= j1; ++j) {
        if (patch.region.Contains({x0_ + i * res_, y0_ + j * res_})) {
          soil_[static_cast<std::size_t>(i) * ny_ + j] = static_cast<std::uint8_t>(patch.soil);
        }
      }
    }
  }
}

void World::BuildGround() {
  const auto& o = options_;
  const std::size_t n = static_cast<std::size_t>(nx_) * ny_;
  ground_.assign(n, 0.0f);

  // Ripple weight: the ripple soils' mask, box-blurred over ~half a wavelength so crests
  // fade out at a soil boundary instead of ending in a step.
  std::vector<float> ripple_weight;
  const bool ripples = o.ripples.amplitude_m > 0.0 && o.ripples.wavelength_m > 0.0;
  if (ripples) {
    ripple_weight.assign(n, 0.0f);
    for (std::size_t c = 0; c < n; ++c) {
      const Soil s = static_cast<Soil>(soil_[c]);
      ripple_weight[c] = std::find(o.ripples.soils.begin(), o.ripples.soils.end(), s) !=
                                 o.ripples.soils.end()
                             ? 1.0f
                             : 0.0f;
    }
    const int half = std::max(1, static_cast<int>(0.25 * o.ripples.wavelength_m / res_));
    // Separable running-sum box blur: first along j (east), then along i (north).
    std::vector<float> line;
    auto blur_line = [&](float* first, int len, int stride) {
      line.resize(len);
      for (int b = 0; b < len; ++b) line[b] = first[static_cast<std::size_t>(b) * stride];
      double sum = 0.0;
      int lo = 0, hi = -1;  // window [lo, hi]
      for (int b = 0; b < len; ++b) {
        while (hi < std::min(len - 1, b + half)) sum += line[++hi];
        while (lo < b - half) sum -= line[lo++];
        first[static_cast<std::size_t>(b) * stride] = static_cast<float>(sum / (hi - lo + 1));
      }
    };
    for (int i = 0; i < nx_; ++i) blur_line(&ripple_weight[static_cast<std::size_t>(i) * ny_], ny_, 1);
    for (int j = 0; j < ny_; ++j) blur_line(&ripple_weight[j], nx_, ny_);
  }

  const std::uint64_t rough_seed = SubSeed(o.seed, kTagRoughness);
  const std::uint64_t ripple_seed = SubSeed(o.seed, kTagRipples);
  const double rough_norm =
      o.roughness.amplitude_m > 0.0
          ? o.roughness.amplitude_m / FractalStd(o.roughness.min_wavelength_m,
                                                 o.roughness.max_wavelength_m, o.roughness.hurst)
          : 0.0;
  const double crest = o.ripples.crest_azimuth_deg * kDeg;
  // Ripple phase runs across the crests.
  const double across_x = -std::sin(crest), across_y = std::cos(crest);
  for (int i = 0; i < nx_; ++i) {
    const double x = x0_ + i * res_;
    for (int j = 0; j < ny_; ++j) {
      const double y = y0_ + j * res_;
      double e = o.base_elevation_m;
      for (const auto& s : o.slopes) e += SlopeProfile(s, x, y);
      for (const auto& c : o.craters) e += CraterProfile(c, x, y);
      if (rough_norm > 0.0) {
        e += rough_norm * FractalNoise(x, y, o.roughness.min_wavelength_m,
                                       o.roughness.max_wavelength_m, o.roughness.hurst,
                                       rough_seed);
      }
      const std::size_t c = static_cast<std::size_t>(i) * ny_ + j;
      if (ripples && ripple_weight[c] > 0.0f) {
        // A slow phase wander keeps the crests from being perfectly periodic.
        const double wander = 0.6 * ValueNoise(x / 6.0, y / 6.0, ripple_seed);
        const double phase = 2.0 * M_PI * (x * across_x + y * across_y) / o.ripples.wavelength_m;
        e += ripple_weight[c] * o.ripples.amplitude_m * std::sin(phase + 2.0 * M_PI * wander);
      }
      ground_[c] = static_cast<float>(e);
    }
  }
}

void World::BuildRocks() {
  const auto& o = options_;
  rocks_ = o.placed_rocks;
  for (auto& r : rocks_) r.placed = true;
  std::vector<Rock> random = SampleGolombekRocks(o.random_rocks, {x_min(), y_min()},
                                                 {x_max(), y_max()}, SubSeed(o.seed, kTagRocks));
  int index = 0;
  for (auto& r : random) {
    const Soil s = SoilAt(r.position.x(), r.position.y());
    if (std::find(o.random_rocks.soils.begin(), o.random_rocks.soils.end(), s) ==
        o.random_rocks.soils.end()) {
      continue;
    }
    bool excluded = false;
    for (const auto& region : o.random_rocks.exclude) {
      excluded = excluded || DiscTouches(region, r.position, 0.5 * r.diameter_m);
    }
    // Random rocks never overlap a placed rock: the placed ones are the scenario's props.
    for (const auto& p : o.placed_rocks) {
      excluded = excluded || (r.position - p.position).norm() < 0.5 * (r.diameter_m + p.diameter_m);
    }
    if (excluded) continue;
    r.name = "rock_" + std::to_string(index++);
    rocks_.push_back(std::move(r));
  }
}

double RockHeightAt(const Rock& rock, double distance_m) {
  const double R = 0.5 * rock.diameter_m;
  if (!(R > 0.0) || !(rock.height_m > 0.0)) return 0.0;
  const double u = (distance_m * distance_m) / (R * R);  // as StampRocks and ElevationDetailed
  return u < 1.0 ? rock.height_m * std::sqrt(1.0 - u) : 0.0;
}

void World::StampRocks() {
  // Rocks are half-ellipsoid bumps on the ground; where two overlap the higher one wins.
  std::vector<float> bump(ground_.size(), 0.0f);
  for (const auto& r : rocks_) {
    const double R = 0.5 * r.diameter_m;
    if (R <= 0.0 || r.height_m <= 0.0) continue;
    const int i0 = std::max(0, static_cast<int>(std::ceil((r.position.x() - R - x0_) / res_)));
    const int i1 = std::min(nx_ - 1, static_cast<int>(std::floor((r.position.x() + R - x0_) / res_)));
    const int j0 = std::max(0, static_cast<int>(std::ceil((r.position.y() - R - y0_) / res_)));
    const int j1 = std::min(ny_ - 1, static_cast<int>(std::floor((r.position.y() + R - y0_) / res_)));
    for (int i = i0; i <= i1; ++i) {
      const double dx = x0_ + i * res_ - r.position.x();
      for (int j = j0; j <= j1; ++j) {
        const double dy = y0_ + j * res_ - r.position.y();
        const double u = (dx * dx + dy * dy) / (R * R);
        if (u >= 1.0) continue;
        float& b = bump[static_cast<std::size_t>(i) * ny_ + j];
        b = std::max(b, static_cast<float>(r.height_m * std::sqrt(1.0 - u)));
      }
    }
  }
  surface_.resize(ground_.size());
  for (std::size_t c = 0; c < ground_.size(); ++c) surface_[c] = ground_[c] + bump[c];
}

namespace {

// Rock indices by the cells of a `cell`-sized grid over [x0, x0 + nx cell) x [y0, ...) that
// their discs touch, as a compressed list (start per cell, then the rocks, in rock order).
void BucketRocks(const std::vector<Rock>& rocks, double x0, double y0, double cell, int nx, int ny,
                 std::vector<int>& start, std::vector<int>& list) {
  std::vector<std::vector<int>> buckets(static_cast<std::size_t>(nx) * ny);
  for (int k = 0; k < static_cast<int>(rocks.size()); ++k) {
    const Rock& r = rocks[k];
    const double R = 0.5 * r.diameter_m;
    const int i0 = std::clamp(static_cast<int>(std::floor((r.position.x() - R - x0) / cell)), 0, nx - 1);
    const int i1 = std::clamp(static_cast<int>(std::floor((r.position.x() + R - x0) / cell)), 0, nx - 1);
    const int j0 = std::clamp(static_cast<int>(std::floor((r.position.y() - R - y0) / cell)), 0, ny - 1);
    const int j1 = std::clamp(static_cast<int>(std::floor((r.position.y() + R - y0) / cell)), 0, ny - 1);
    for (int i = i0; i <= i1; ++i) {
      for (int j = j0; j <= j1; ++j) buckets[static_cast<std::size_t>(i) * ny + j].push_back(k);
    }
  }
  start.assign(buckets.size() + 1, 0);
  list.clear();
  for (std::size_t b = 0; b < buckets.size(); ++b) {
    start[b] = static_cast<int>(list.size());
    list.insert(list.end(), buckets[b].begin(), buckets[b].end());
  }
  start.back() = static_cast<int>(list.size());
}

}  // namespace

void World::IndexRocks() {
  bx_ = std::max(1, static_cast<int>(std::ceil((x_max() - x0_) / bucket_size_)) + 1);
  by_ = std::max(1, static_cast<int>(std::ceil((y_max() - y0_) / bucket_size_)) + 1);
  BucketRocks(rocks_, x0_, y0_, bucket_size_, bx_, by_, bucket_start_, bucket_rocks_);
  fbx_ = std::max(1, static_cast<int>(std::ceil((x_max() - x0_) / kFineBucket)) + 1);
  fby_ = std::max(1, static_cast<int>(std::ceil((y_max() - y0_) / kFineBucket)) + 1);
  BucketRocks(rocks_, x0_, y0_, kFineBucket, fbx_, fby_, fine_start_, fine_rocks_);
}

bool World::Contains(double x, double y) const {
  return x >= x_min() && x <= x_max() && y >= y_min() && y <= y_max();
}

double World::Bilinear(const std::vector<float>& grid, double x, double y) const {
  const double u = std::clamp((x - x0_) / res_, 0.0, static_cast<double>(nx_ - 1));
  const double v = std::clamp((y - y0_) / res_, 0.0, static_cast<double>(ny_ - 1));
  const int i = std::min(static_cast<int>(u), nx_ - 2);
  const int j = std::min(static_cast<int>(v), ny_ - 2);
  const double tu = u - i, tv = v - j;
  const float* row0 = &grid[static_cast<std::size_t>(i) * ny_ + j];
  const float* row1 = row0 + ny_;
  return (1 - tu) * ((1 - tv) * row0[0] + tv * row0[1]) + tu * ((1 - tv) * row1[0] + tv * row1[1]);
}

double World::Elevation(double x, double y) const { return Bilinear(surface_, x, y); }

double World::GroundElevation(double x, double y) const { return Bilinear(ground_, x, y); }

double World::ElevationDetailed(double x, double y) const {
  double bump = 0.0;
  const double cx = std::clamp(x, x0_, x_max()), cy = std::clamp(y, y0_, y_max());
  const int bi = std::min(bx_ - 1, static_cast<int>((cx - x0_) / bucket_size_));
  const int bj = std::min(by_ - 1, static_cast<int>((cy - y0_) / bucket_size_));
  const std::size_t b = static_cast<std::size_t>(bi) * by_ + bj;
  for (int n = bucket_start_[b]; n < bucket_start_[b + 1]; ++n) {
    const Rock& r = rocks_[bucket_rocks_[n]];
    const double R = 0.5 * r.diameter_m;
    const double dx = cx - r.position.x(), dy = cy - r.position.y();
    const double u = (dx * dx + dy * dy) / (R * R);
    if (u < 1.0) bump = std::max(bump, r.height_m * std::sqrt(1.0 - u));
  }
  return GroundElevation(x, y) + bump;
}

Eigen::Vector2d World::Gradient(double x, double y) const {
  const double h = res_;
  return {(Elevation(x + h, y) - Elevation(x - h, y)) / (2 * h),
          (Elevation(x, y + h) - Elevation(x, y - h)) / (2 * h)};
}

Eigen::Vector3d World::NormalUp(double x, double y) const {
  const Eigen::Vector2d g = Gradient(x, y);
  // Up normal is (-gx, -gy, 1) in (north, east, up); site Z is down.
  return Eigen::Vector3d(-g.x(), -g.y(), -1.0).normalized();
}

Eigen::Vector3d World::SunDirection() const {
  const double az = options_.sun.azimuth_deg * kDeg, el = options_.sun.elevation_deg * kDeg;
  return {std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), -std::sin(el)};
}

double World::SlopeAngle(double x, double y) const {
  return std::acos(std::clamp(-NormalUp(x, y).z(), -1.0, 1.0));
}

Soil World::SoilAt(double x, double y) const {
  // Nearest node, clamped to the map (clamping first keeps the conversion in range).
  const int i = static_cast<int>(std::clamp((x - x0_) / res_, 0.0, nx_ - 1.0) + 0.5);
  const int j = static_cast<int>(std::clamp((y - y0_) / res_, 0.0, ny_ - 1.0) + 0.5);
  return static_cast<Soil>(soil_[static_cast<std::size_t>(i) * ny_ + j]);
}

void World::RocksNear(double x, double y, double radius_m, std::vector<int>& out) const {
  out.clear();
  const int i0 = std::clamp(static_cast<int>(std::floor((x - radius_m - x0_) / bucket_size_)), 0, bx_ - 1);
  const int i1 = std::clamp(static_cast<int>(std::floor((x + radius_m - x0_) / bucket_size_)), 0, bx_ - 1);
  const int j0 = std::clamp(static_cast<int>(std::floor((y - radius_m - y0_) / bucket_size_)), 0, by_ - 1);
  const int j1 = std::clamp(static_cast<int>(std::floor((y + radius_m - y0_) / bucket_size_)), 0, by_ - 1);
  for (int i = i0; i <= i1; ++i) {
    for (int j = j0; j <= j1; ++j) {
      const std::size_t b = static_cast<std::size_t>(i) * by_ + j;
      for (int n = bucket_start_[b]; n < bucket_start_[b + 1]; ++n) {
        const int k = bucket_rocks_[n];
        const Rock& r = rocks_[k];
        if ((r.position - Eigen::Vector2d(x, y)).norm() > radius_m + 0.5 * r.diameter_m) continue;
        if (std::find(out.begin(), out.end(), k) == out.end()) out.push_back(k);
      }
    }
  }
}

const Rock* World::FindRock(const std::string& name) const {
  for (const auto& r : rocks_) {
    if (r.placed && r.name == name) return &r;
  }
  return nullptr;
}

double World::Albedo(double x, double y, double footprint_m) const {
  double out = 0.0;
  AlbedoBatch(1, &x, &y, &footprint_m, &out);
  return out;
}

void World::AlbedoBatch(int n, const double* x, const double* y, const double* footprint_m,
                        double* out) const {
  const auto& a = options_.albedo;
  // Per point: what it is (a rock's surface or a soil), and so its mean, contrast and
  // texture octaves; then two vectorised noise passes (texture and mottling).
  struct Scratch {
    std::vector<float> x, y, inv_wl, texture, mottle_inv, mottle;
    std::vector<std::uint32_t> seed, mottle_seed;
    std::vector<int> octaves, mottle_octaves;
    std::vector<double> mean, gain;  // albedo = mean * (1 + gain * texture) * mottling
    std::vector<unsigned char> mottled;
  };
  thread_local Scratch s;
  const std::size_t m = static_cast<std::size_t>(std::max(n, 0));
  for (auto* v : {&s.x, &s.y, &s.inv_wl, &s.texture, &s.mottle_inv, &s.mottle}) v->resize(m);
  s.seed.resize(m);
  s.mottle_seed.resize(m);
  s.octaves.resize(m);
  s.mottle_octaves.resize(m);
  s.mean.resize(m);
  s.gain.resize(m);
  s.mottled.resize(m);
  const float rock_inv = static_cast<float>(1.0 / kRockTextureMaxWavelength);
  const double inv_res = 1.0 / res_;
  for (int p = 0; p < n; ++p) {
    const double px = x[p], py = y[p];
    s.x[p] = static_cast<float>(px);
    s.y[p] = static_cast<float>(py);
    s.mottle_inv[p] = static_cast<float>(1.0 / kMottleWavelength);
    s.mottle_seed[p] = mottle_seed_;
    // Octaves shorter than twice the footprint are left out (Albedo's contract).
    const double shortest = 2.0 * footprint_m[p];
    const Rock* rock = nullptr;
    if (px >= x0_ && py >= y0_ && px <= x_max() && py <= y_max()) {
      const int bi = std::min(fbx_ - 1, static_cast<int>((px - x0_) * (1.0 / kFineBucket)));
      const int bj = std::min(fby_ - 1, static_cast<int>((py - y0_) * (1.0 / kFineBucket)));
      const std::size_t b = static_cast<std::size_t>(bi) * fby_ + bj;
      for (int k = fine_start_[b]; k < fine_start_[b + 1] && !rock; ++k) {
        const Rock& r = rocks_[fine_rocks_[k]];
        const double R = 0.5 * r.diameter_m;
        const double dx = px - r.position.x(), dy = py - r.position.y();
        if (dx * dx + dy * dy < R * R) rock = &r;
      }
    }
    if (rock) {
      s.mean[p] = rock->albedo;
      s.gain[p] = a.rock_contrast * rock_texture_norm_;
      s.inv_wl[p] = rock_inv;
      s.seed[p] = rock_albedo_seed_;
      s.octaves[p] = OctaveCount(std::max(kRockTextureMinWavelength, shortest), kRockTextureMaxWavelength);
      s.mottle_octaves[p] = 0;
      s.mottled[p] = 0;
    } else {
      // SoilAt, inline: this loop runs for every pixel.
      const int i = static_cast<int>(std::clamp((px - x0_) * inv_res, 0.0, nx_ - 1.0) + 0.5);
      const int j = static_cast<int>(std::clamp((py - y0_) * inv_res, 0.0, ny_ - 1.0) + 0.5);
      const Soil soil = static_cast<Soil>(soil_[static_cast<std::size_t>(i) * ny_ + j]);
      const SoilAlbedo& sa = AlbedoOf(a, soil);
      s.mean[p] = sa.mean;
      s.gain[p] = sa.contrast * soil_texture_norm_[static_cast<int>(soil)];
      s.inv_wl[p] = static_cast<float>(1.0 / sa.max_wavelength_m);
      s.seed[p] = albedo_seed_;
      s.octaves[p] = sa.contrast > 0.0 ? OctaveCount(std::max(sa.min_wavelength_m, shortest), sa.max_wavelength_m) : 0;
      s.mottle_octaves[p] = 1;
      s.mottled[p] = 1;
    }
  }
  const float amp_step = static_cast<float>(std::pow(0.5, kAlbedoHurst));
  FractalNoiseBatch(n, s.x.data(), s.y.data(), s.inv_wl.data(), s.seed.data(), s.octaves.data(), amp_step,
                    s.texture.data());
  FractalNoiseBatch(n, s.x.data(), s.y.data(), s.mottle_inv.data(), s.mottle_seed.data(), s.mottle_octaves.data(),
                    1.0f, s.mottle.data());
  const double mottle_gain = a.large_scale_contrast / kValueNoise32Std;
  for (int p = 0; p < n; ++p) {
    const double mottling = s.mottled[p] ? 1.0 + mottle_gain * s.mottle[p] : 1.0;
    out[p] = std::clamp(s.mean[p] * (1.0 + s.gain[p] * s.texture[p]) * mottling, 0.02, 0.95);
  }
}

}  // namespace rover::terrain
