// The simulated Mars site: one terrain model shared by the rover simulator and the
// renderer, so that the rover drives on exactly the ground the cameras see.
//
// Coordinates are the site frame (pose.hpp): X north, Y east, Z down. Heights are given
// as *elevation* (metres, up), so a surface point is (x, y, -Elevation(x, y)).
//
// The world is built once, deterministically from WorldOptions::seed, into a height grid
// (ground + rocks) and a soil grid at `map.resolution_m`. Queries are bilinear on that
// grid and cheap (no allocation), so the simulator can call them at 100 Hz or more.
//
// Outside the map every query clamps the point to the nearest map edge (the terrain
// continues flat-extended); call Contains() to know whether a point is on the map. The
// simulator faults when the rover leaves it; the renderer may look past it.
//
// Every key of the world YAML is documented in common/terrain/WORLD_FORMAT.md.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

#include "config/yaml_config.hpp"

namespace rover::terrain {

// Soils, from firm to loose. The slip model (mobility) and the albedo texture depend on it.
enum class Soil : std::uint8_t {
  kBedrock = 0,     // outcrop: low slip, strong texture at cm to m scales
  kPackedSoil = 1,  // Gusev-like plains soil with pebbles: some slip, medium texture
  kSand = 2,        // loose fine sand (Meridiani): high slip on slopes, almost no texture
};
inline constexpr int kNumSoils = 3;
const char* SoilName(Soil soil);  // "bedrock", "packed_soil", "sand"
// Throws std::invalid_argument naming the word if it is not a soil name.
Soil SoilFromName(const std::string& name);

// A circle or a polygon in the site frame (x north, y east).
struct Region {
  enum class Shape { kCircle, kPolygon };
  Shape shape = Shape::kCircle;
  Eigen::Vector2d center = Eigen::Vector2d::Zero();  // circle
  double radius_m = 0.0;                             // circle
  std::vector<Eigen::Vector2d> vertices;             // polygon (>= 3, either winding)
  bool Contains(const Eigen::Vector2d& p) const;

  static Region Circle(const Eigen::Vector2d& center, double radius_m);
  static Region Polygon(std::vector<Eigen::Vector2d> vertices);
};

// A planar tilt of the whole map, optionally limited to a band along its uphill direction
// (a ramp): elevation += tan(angle) * clamp(s, from_m, to_m), s = (p - origin) . uphill,
// with the corners rounded over blend_m so the rover's pitch changes smoothly.
struct SlopeOptions {
  double angle_deg = 0.0;           // [0, 45]
  double uphill_azimuth_deg = 0.0;  // direction of steepest ascent, from north toward east
  Eigen::Vector2d origin = Eigen::Vector2d::Zero();
  double from_m = -1e9;  // the slope starts at s = from_m (flat below)
  double to_m = 1e9;     // and ends at s = to_m (flat above)
  double blend_m = 0.5;
};

// A bowl: parabolic floor depth_m below the surroundings at the centre, plus a Gaussian rim.
struct CraterOptions {
  Eigen::Vector2d center = Eigen::Vector2d::Zero();
  double radius_m = 5.0;
  double depth_m = 1.0;
  double rim_height_m = 0.2;
  double rim_width_m = 1.0;
};

// Gentle multi-scale roughness (fractal value noise).
struct RoughnessOptions {
  double amplitude_m = 0.0;  // RMS height of the roughness
  double min_wavelength_m = 0.2;
  double max_wavelength_m = 8.0;
  double hurst = 0.8;  // octave amplitude ~ wavelength^hurst
};

// Aeolian ripples: sinusoidal crests on chosen soils (sand by default).
struct RippleOptions {
  double amplitude_m = 0.0;
  double wavelength_m = 2.0;
  double crest_azimuth_deg = 0.0;  // direction the crests run along, from north toward east
  std::vector<Soil> soils{Soil::kSand};
};

struct SoilPatch {
  Soil soil = Soil::kSand;
  Region region;
};

struct Rock {
  std::string name;  // placed rocks carry their name; random rocks "rock_<index>"
  Eigen::Vector2d position = Eigen::Vector2d::Zero();
  double diameter_m = 0.0;
  double height_m = 0.0;  // above the ground around it (half-ellipsoid bump)
  bool keepout = false;   // operators should put a keep-out zone around it
  bool placed = false;    // true if listed in the world file, false if drawn at random
  double albedo = 0.3;    // mean albedo of this rock's surface
};

// How far `rock`'s half-ellipsoid rises above the ground around it at a horizontal distance
// `distance_m` from its centre: height_m * sqrt(1 - (2 d / diameter_m)^2), 0 at its rim and
// beyond. A body passing over the rock's edge meets this height, not the top's.
double RockHeightAt(const Rock& rock, double distance_m);

// Random rocks from the Golombek size-frequency model: the fraction of ground covered by
// rocks of diameter >= D is F(D) = k exp(-q D), q = 1.79 + 0.152 / k (Golombek & Rapp 1997).
struct RockFieldOptions {
  double abundance_k = 0.0;  // k, fraction of area covered by all rocks; 0 = no random rocks
  double min_diameter_m = 0.1;
  double max_diameter_m = 1.0;
  double height_ratio = 0.5;   // height = ratio * D
  double height_spread = 0.2;  // relative spread of the ratio, uniform +-
  double albedo_mean = 0.30;   // mean albedo of the rocks' surfaces
  double albedo_spread = 0.25;  // relative spread of a rock's albedo, uniform +-
  std::vector<Soil> soils{Soil::kBedrock, Soil::kPackedSoil, Soil::kSand};  // where they lie
  std::vector<Region> exclude;  // no random rocks whose disc touches these regions
};

struct SunOptions {
  double azimuth_deg = 90.0;    // direction toward the sun, from north toward east
  double elevation_deg = 45.0;  // above the horizon
};

// Albedo texture per soil: mean * (1 + contrast * fractal noise over [min, max] wavelength).
struct SoilAlbedo {
  double mean = 0.22;
  double contrast = 0.1;
  double min_wavelength_m = 0.01;
  double max_wavelength_m = 2.0;
};

struct AlbedoOptions {
  SoilAlbedo bedrock{0.26, 0.35, 0.01, 1.0};
  SoilAlbedo packed_soil{0.22, 0.12, 0.01, 2.0};
  SoilAlbedo sand{0.20, 0.02, 0.05, 4.0};
  double rock_contrast = 0.25;      // texture on rock surfaces (cm scale)
  double large_scale_contrast = 0.05;  // metre-scale dust mottling common to all soils
};

struct StartPose {
  double x = 0.0, y = 0.0, yaw_deg = 0.0;
};

struct WorldOptions {
  std::string name = "world";
  std::uint64_t seed = 1;
  // Map: a square-celled grid covering center +- size/2.
  Eigen::Vector2d map_center = Eigen::Vector2d::Zero();
  Eigen::Vector2d map_size_m{40.0, 40.0};
  double resolution_m = 0.05;
  double base_elevation_m = 0.0;
  std::vector<SlopeOptions> slopes;
  std::vector<CraterOptions> craters;
  RoughnessOptions roughness;
  RippleOptions ripples;
  Soil default_soil = Soil::kBedrock;
  std::vector<SoilPatch> soil_patches;  // later patches win
  std::vector<Rock> placed_rocks;
  RockFieldOptions random_rocks;
  SunOptions sun;
  AlbedoOptions albedo;
  StartPose start;  // suggested start pose for scenarios on this world

  // Reads a world YAML (format: WORLD_FORMAT.md). Throws config::ConfigError naming the
  // file and key on a bad or unknown key.
  static WorldOptions Load(const config::ConfigNode& root);
  static WorldOptions LoadFile(const std::string& path);
};

// The most grid nodes a world's map may have (its grids are several arrays of this size).
inline constexpr double kMaxWorldCells = 16.0e6;

// Golombek cumulative fractional area F(D) = k exp(-q D).
double GolombekCumulativeArea(double k, double diameter_m);
double GolombekQ(double k);
// Draws rocks with diameters in [min, max] over the axis-aligned box [lo, hi] so that
// their cumulative area follows F(D) - F(max). Positions uniform; no soil/exclusion test.
std::vector<Rock> SampleGolombekRocks(const RockFieldOptions& options, const Eigen::Vector2d& lo,
                                      const Eigen::Vector2d& hi, std::uint64_t seed);

class World {
 public:
  // Builds the grids. Throws std::invalid_argument on inconsistent options
  // (e.g. a map over 16 million cells).
  explicit World(WorldOptions options);

  // Elevation (m, up) of the surface including rocks; bilinear on the grid.
  double Elevation(double x, double y) const;
  // Elevation of the ground without rocks.
  double GroundElevation(double x, double y) const;
  // Site z (down) of the rover origin standing at x, y: on the ground, not on a rock there
  // (the rover stands on its wheels), origin_height_m above the wheel contacts. Where the
  // estimator starts in simulation.
  double StartHeight(double x, double y, double origin_height_m) const {
    return -GroundElevation(x, y) - origin_height_m;
  }
  // Ground (bilinear) plus the exact half-ellipsoid rock shapes instead of their
  // grid-sampled version: for rendering rocks smaller than a few grid cells. Equals
  // Elevation() at grid nodes. Slower (visits the rocks near the point).
  double ElevationDetailed(double x, double y) const;
  // d(elevation)/dx, d(elevation)/dy of the surface (central differences over one cell).
  Eigen::Vector2d Gradient(double x, double y) const;
  // Upward unit surface normal in site coordinates (x north, y east, z down: so z < 0).
  Eigen::Vector3d NormalUp(double x, double y) const;
  // Surface slope angle (rad) from the normal.
  double SlopeAngle(double x, double y) const;
  Soil SoilAt(double x, double y) const;
  // Surface albedo in (0, 1): soil texture from centimetres to metres, rock surfaces,
  // metre-scale mottling. Continuous in x, y (not tied to the grid); deterministic.
  // footprint_m: the size of the ground patch a pixel sees. Texture octaves shorter than
  // twice it are left out (their mean is zero), which filters them instead of aliasing
  // them, and makes distant pixels cheaper. 0 = every octave.
  double Albedo(double x, double y, double footprint_m = 0.0) const;
  // Albedo() of n points at once, the same values: the renderer's path (about two million
  // points a frame), vectorised over the points (albedo_noise.hpp).
  void AlbedoBatch(int n, const double* x, const double* y, const double* footprint_m, double* out) const;

  const std::vector<Rock>& rocks() const { return rocks_; }
  // Indices into rocks() of the rocks whose disc comes within `radius_m` of (x, y).
  // Appends to `out` (cleared first); reuses its capacity.
  void RocksNear(double x, double y, double radius_m, std::vector<int>& out) const;
  // The placed rock with this name, or nullptr.
  const Rock* FindRock(const std::string& name) const;

  bool Contains(double x, double y) const;
  double x_min() const { return x0_; }
  double y_min() const { return y0_; }
  double x_max() const { return x0_ + (nx_ - 1) * res_; }
  double y_max() const { return y0_ + (ny_ - 1) * res_; }
  double resolution() const { return res_; }
  // Grid nodes: node (i, j) is at (x_min + i*res, y_min + j*res); index i * ny() + j.
  int nx() const { return nx_; }
  int ny() const { return ny_; }
  const std::vector<float>& elevation_grid() const { return surface_; }
  const std::vector<float>& ground_grid() const { return ground_; }
  const std::vector<std::uint8_t>& soil_grid() const { return soil_; }
  const SunOptions& sun() const { return options_.sun; }
  // Unit vector toward the sun in the site frame (z < 0 when the sun is up).
  Eigen::Vector3d SunDirection() const;
  const WorldOptions& options() const { return options_; }

 private:
  double Bilinear(const std::vector<float>& grid, double x, double y) const;
  void BuildGround();
  void BuildSoil();
  void BuildRocks();
  void StampRocks();
  void IndexRocks();

  WorldOptions options_;
  double x0_ = 0, y0_ = 0, res_ = 0.05;
  int nx_ = 0, ny_ = 0;
  std::vector<float> ground_;
  std::vector<float> surface_;
  std::vector<std::uint8_t> soil_;
  std::vector<Rock> rocks_;
  // Rock buckets on a coarse grid for RocksNear / Albedo.
  double bucket_size_ = 1.0;
  int bx_ = 0, by_ = 0;
  std::vector<int> bucket_start_;
  std::vector<int> bucket_rocks_;
  // The same on a fine grid for Albedo, which asks for every pixel: a 1 m bucket of a
  // pebble field holds hundreds of rocks, one of kFineBucket a handful.
  static constexpr double kFineBucket = 0.125;
  int fbx_ = 0, fby_ = 0;
  std::vector<int> fine_start_;
  std::vector<int> fine_rocks_;
  double soil_texture_norm_[kNumSoils] = {1, 1, 1};
  double rock_texture_norm_ = 1.0;
  std::uint32_t albedo_seed_ = 0, rock_albedo_seed_ = 0, mottle_seed_ = 0;
};

}  // namespace rover::terrain
