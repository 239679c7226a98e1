#include "vo_eval/synthetic_terrain.hpp"

#include "geometry/pinhole_camera.hpp"
#include "geometry/pose.hpp"

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>

namespace rover::vo_eval {
namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr int kOctaves = 9;
constexpr double kCoarsestWavelength_m = 2.0;
constexpr double kMaxRange_m = 80.0;
constexpr double kSkyBrightness = 190.0;
constexpr int kLattice = 256;  // power of two
// Octave amplitude ~ wavelength^slope and the overall gain: a nearly flat spectrum keeps
// centimetre-scale detail (grains, pebbles) as strong as the metre-scale shading, as in
// NAVCAM images of Martian soil, so corners exist at every range.
constexpr double kSpectrumSlope = 0.1;
constexpr double kContrast = 320.0;

std::uint64_t SplitMix(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

// A lattice value in [-1, 1] for cell (i, j) of octave o.
double LatticeValue(std::int64_t i, std::int64_t j, int o, std::uint64_t seed) {
  std::uint64_t h = SplitMix(seed ^ (static_cast<std::uint64_t>(o) * 0x632BE59BD9B4E019ull));
  h = SplitMix(h ^ static_cast<std::uint64_t>(i));
  h = SplitMix(h ^ (static_cast<std::uint64_t>(j) * 0x8CB92BA72F3D8DD7ull));
  return static_cast<double>(h >> 11) * (2.0 / 9007199254740992.0) - 1.0;
}

void Require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("SyntheticTerrainOptions: " + what);
}

}  // namespace

SyntheticTerrainSequence::SyntheticTerrainSequence(const SyntheticTerrainOptions& o)
    : options_(o) {
  Require(o.width >= 16 && o.height >= 16,
          "width and height must be >= 16, got " + std::to_string(o.width) + "x" +
              std::to_string(o.height));
  Require(o.hfov_deg > 1.0 && o.hfov_deg < 170.0,
          "hfov_deg must be in (1, 170), got " + std::to_string(o.hfov_deg));
  Require(o.baseline_m > 0.0, "baseline_m must be > 0, got " + std::to_string(o.baseline_m));
  Require(o.camera_height_m > 2.0 * o.relief_m,
          "camera_height_m must exceed twice relief_m, got " + std::to_string(o.camera_height_m));
  Require(o.camera_pitch_deg > -89.0 && o.camera_pitch_deg < 89.0,
          "camera_pitch_deg must be in (-89, 89), got " + std::to_string(o.camera_pitch_deg));
  Require(o.relief_m >= 0.0, "relief_m must be >= 0, got " + std::to_string(o.relief_m));
  Require(o.noise_dn >= 0.0, "noise_dn must be >= 0, got " + std::to_string(o.noise_dn));

  const double f = 0.5 * o.width / std::tan(0.5 * o.hfov_deg * kDeg);
  const double cx = 0.5 * (o.width - 1), cy = 0.5 * (o.height - 1);
  Eigen::Isometry3d T_left_right = Eigen::Isometry3d::Identity();
  T_left_right.translation() = Eigen::Vector3d(o.baseline_m, 0.0, 0.0);
  rig_.left = std::make_shared<geometry::PinholeCamera>(o.width, o.height, f, f, cx, cy);
  rig_.right = std::make_shared<geometry::PinholeCamera>(o.width, o.height, f, f, cx, cy,
                                                         std::vector<double>{}, T_left_right);

  // Left camera on the mast, pitched down: camera z (optical axis) is forward and down,
  // camera x is the rover's right, camera y completes the frame.
  const double th = o.camera_pitch_deg * kDeg;
  Eigen::Matrix3d R_rover_cam;
  R_rover_cam.col(0) = Eigen::Vector3d(0, 1, 0);
  R_rover_cam.col(1) = Eigen::Vector3d(-std::sin(th), 0, std::cos(th));
  R_rover_cam.col(2) = Eigen::Vector3d(std::cos(th), 0, std::sin(th));
  T_rover_ref_ = Eigen::Isometry3d::Identity();
  T_rover_ref_.linear() = R_rover_cam;
  T_rover_ref_.translation() = Eigen::Vector3d(0.3, -0.5 * o.baseline_m, -o.camera_height_m);

  lattice_.resize(static_cast<std::size_t>(kOctaves) * kLattice * kLattice);
  for (int oct = 0; oct < kOctaves; ++oct) {
    for (int j = 0; j < kLattice; ++j) {
      for (int i = 0; i < kLattice; ++i) {
        lattice_[(static_cast<std::size_t>(oct) * kLattice + j) * kLattice + i] =
            static_cast<float>(LatticeValue(i, j, oct, o.seed));
      }
    }
    amplitude_.push_back(std::pow(kCoarsestWavelength_m * std::pow(0.5, oct), kSpectrumSlope));
  }
  for (int i = 0; i < 4; ++i) {
    relief_phase_[i] = 2.0 * M_PI * LatticeValue(i, 7, 99, o.seed);
  }
  // |grad h| bound of TerrainZ's sinusoids, for safe ray-marching steps.
  relief_slope_bound_ = o.relief_m * std::sqrt(2.0) *
                        (0.5 * 2.0 * M_PI / 5.0 + 0.5 * 2.0 * M_PI / 11.0 + 0.5 * 2.0 * M_PI / 7.0);
}

Eigen::Isometry3d SyntheticTerrainSequence::SitePose(int k) const {
  if (k < 0) throw std::invalid_argument("SyntheticTerrainSequence: frame " + std::to_string(k));
  double x = 0.0, y = 0.0, yaw = 0.0;
  for (int i = 1; i <= k; ++i) {
    yaw += options_.yaw_step_deg * kDeg * std::sin(0.35 * i);
    x += options_.step_m * std::cos(yaw);
    y += options_.step_m * std::sin(yaw);
  }
  const double roll = 1.0 * kDeg * std::sin(0.7 * k);
  const double pitch = 0.8 * kDeg * std::sin(0.45 * k + 1.0);
  const double z = 0.02 * std::sin(0.4 * k);
  return geometry::PoseFromXyzRpy(x, y, z, roll, pitch, yaw) * T_rover_ref_;
}

Eigen::Isometry3d SyntheticTerrainSequence::TruthPose(int k) const {
  return SitePose(0).inverse() * SitePose(k);
}

Eigen::Isometry3d SyntheticTerrainSequence::TruthMotion(int k) const {
  if (k < 1) throw std::invalid_argument("TruthMotion: frame must be >= 1, got " + std::to_string(k));
  return SitePose(k - 1).inverse() * SitePose(k);
}

Eigen::Vector3d SyntheticTerrainSequence::DownInWorld() const {
  return SitePose(0).linear().transpose() * Eigen::Vector3d::UnitZ();
}

Eigen::Vector3d SyntheticTerrainSequence::ForwardInWorld() const {
  const Eigen::Isometry3d T_site_rover0 = SitePose(0) * T_rover_ref_.inverse();
  return SitePose(0).linear().transpose() * T_site_rover0.linear().col(0);
}

double SyntheticTerrainSequence::TerrainZ(double x, double y) const {
  const double A = options_.relief_m;
  if (A == 0.0) return 0.0;
  const double* p = relief_phase_;
  return A * (0.5 * std::sin(2.0 * M_PI * x / 7.0 + p[0]) * std::cos(2.0 * M_PI * y / 5.0 + p[1]) +
              0.5 * std::sin(2.0 * M_PI * (x + y) / 11.0 + p[2]));
}

double SyntheticTerrainSequence::Brightness(double x, double y, double footprint_m) const {
  double sum = 0.0, norm = 0.0;
  double wavelength = kCoarsestWavelength_m;
  constexpr std::int64_t mask = kLattice - 1;
  for (int o = 0; o < kOctaves; ++o, wavelength *= 0.5) {
    const double amplitude = amplitude_[static_cast<std::size_t>(o)];
    norm += amplitude;
    // Fade an octave out as its wavelength approaches two footprints (Nyquist).
    const double w = std::clamp(wavelength / (2.0 * footprint_m) - 1.0, 0.0, 1.0);
    if (w == 0.0) continue;
    const double u = x / wavelength, v = y / wavelength;
    const double fu = std::floor(u), fv = std::floor(v);
    const auto i = static_cast<std::int64_t>(fu) & mask;
    const auto j = static_cast<std::int64_t>(fv) & mask;
    const auto i1 = (i + 1) & mask, j1 = (j + 1) & mask;
    const float* L = lattice_.data() + static_cast<std::size_t>(o) * kLattice * kLattice;
    const double a = u - fu, b = v - fv;
    const double n = (1 - a) * (1 - b) * L[j * kLattice + i] + a * (1 - b) * L[j * kLattice + i1] +
                     (1 - a) * b * L[j1 * kLattice + i] + a * b * L[j1 * kLattice + i1];
    sum += w * amplitude * n;
  }
  return 128.0 + kContrast * sum / norm;
}

cv::Mat SyntheticTerrainSequence::RenderView(const geometry::CameraModel& camera,
                                             const Eigen::Isometry3d& T_site_ref,
                                             std::uint64_t noise_seed) const {
  const int W = camera.width(), H = camera.height();
  // Angular size of a pixel at the image centre, for the ground footprint.
  Eigen::Vector3d o0, d0, o1, d1;
  camera.BackProject(Eigen::Vector2d(0.5 * W, 0.5 * H), &o0, &d0);
  camera.BackProject(Eigen::Vector2d(0.5 * W + 1.0, 0.5 * H), &o1, &d1);
  const double pixel_angle = std::acos(std::clamp(d0.dot(d1), -1.0, 1.0));
  const double top = -options_.relief_m;  // highest terrain (Z down)

  cv::Mat image(H, W, CV_32F);
  for (int r = 0; r < H; ++r) {
    float* row = image.ptr<float>(r);
    for (int c = 0; c < W; ++c) {
      Eigen::Vector3d o_ref, d_ref;
      camera.BackProject(Eigen::Vector2d(c, r), &o_ref, &d_ref);
      const Eigen::Vector3d o = T_site_ref * o_ref;
      const Eigen::Vector3d d = T_site_ref.linear() * d_ref;
      double value = kSkyBrightness;
      if (d.z() > 1e-3) {
        // March down to the height field with steps that cannot overshoot it: the gap to
        // the surface shrinks by at most (d.z + slope * |d_xy|) per unit of t.
        double t = std::max(0.0, (top - o.z()) / d.z());
        const double rate = d.z() + relief_slope_bound_ * d.head<2>().norm();
        double prev_t = t, prev_gap = 0.0;
        for (int it = 0; it < 60 && t < kMaxRange_m; ++it) {
          const Eigen::Vector3d p = o + t * d;
          const double gap = TerrainZ(p.x(), p.y()) - p.z();
          if (gap < 1e-6) break;
          double step = gap / rate;
          // Near the surface the gap is nearly linear in t: a secant step converges in
          // two or three iterations where the safe step would crawl.
          if (it > 0 && gap < 1e-2 && prev_gap > gap) {
            step = std::min(gap * (t - prev_t) / (prev_gap - gap), 4.0 * step);
          }
          prev_t = t;
          prev_gap = gap;
          t += step;
        }
        if (t < kMaxRange_m) {
          const Eigen::Vector3d p = o + t * d;
          const double footprint = t * pixel_angle / std::max(d.z(), 0.05);
          value = Brightness(p.x(), p.y(), footprint);
        }
      }
      row[c] = static_cast<float>(value);
    }
  }
  if (options_.noise_dn > 0.0) {
    cv::Mat noise(H, W, CV_32F);
    cv::RNG rng(noise_seed);
    rng.fill(noise, cv::RNG::NORMAL, 0.0, options_.noise_dn);
    image += noise;
  }
  cv::Mat out;
  image.convertTo(out, CV_8U);  // rounds and saturates
  return out;
}

void SyntheticTerrainSequence::Render(int k, cv::Mat* left, cv::Mat* right) const {
  const Eigen::Isometry3d T_site_ref = SitePose(k);
  const std::uint64_t base = SplitMix(options_.seed * 1000003ull + static_cast<std::uint64_t>(k));
  *left = RenderView(*rig_.left, T_site_ref, base);
  *right = RenderView(*rig_.right, T_site_ref, base ^ 0x5bd1e995ull);
}

}  // namespace rover::vo_eval
