// Seeded random numbers and lattice noise that give the same bits on every platform.
//
// std::normal_distribution and friends are implementation-defined, so a world or a slip
// trace built with them could differ between standard libraries. Everything random in
// the simulated world and rover goes through these instead: same seed, same outputs.
#pragma once

#include <cmath>
#include <cstdint>

namespace rover::terrain {

// Mixes a 64-bit value (SplitMix64 finalizer); used to derive sub-seeds and lattice hashes.
inline std::uint64_t MixBits(std::uint64_t z) {
  z += 0x9E3779B97F4A7C15ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

// A seed for one feature of a world ("rocks", "roughness", ...) from the world seed.
inline std::uint64_t SubSeed(std::uint64_t seed, std::uint64_t tag) {
  return MixBits(seed ^ MixBits(tag + 0x51ED2701ull));
}

class Random {
 public:
  explicit Random(std::uint64_t seed) : state_(seed) {}

  std::uint64_t NextBits() {
    state_ += 0x9E3779B97F4A7C15ull;
    std::uint64_t z = state_;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  // Uniform in [0, 1).
  double Uniform() { return static_cast<double>(NextBits() >> 11) * 0x1.0p-53; }
  double Uniform(double lo, double hi) { return lo + (hi - lo) * Uniform(); }
  // Standard normal (Box-Muller; the second value is kept for the next call).
  double Normal() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    double u1 = Uniform();
    while (u1 <= 0.0) u1 = Uniform();
    const double u2 = Uniform();
    const double r = std::sqrt(-2.0 * std::log(u1));
    spare_ = r * std::sin(2.0 * M_PI * u2);
    has_spare_ = true;
    return r * std::cos(2.0 * M_PI * u2);
  }
  // Poisson-distributed count (normal approximation above 500, exact below).
  std::uint64_t Poisson(double mean) {
    if (mean <= 0.0) return 0;
    if (mean > 500.0) {
      const double v = std::round(mean + std::sqrt(mean) * Normal());
      return v < 0.0 ? 0 : static_cast<std::uint64_t>(v);
    }
    const double limit = std::exp(-mean);
    std::uint64_t k = 0;
    double p = Uniform();
    while (p > limit) {
      ++k;
      p *= Uniform();
    }
    return k;
  }

 private:
  std::uint64_t state_;
  bool has_spare_ = false;
  double spare_ = 0.0;
};

// Standard deviation of ValueNoise over the plane (measured over 4 million points).
inline constexpr double kValueNoiseStd = 0.45;

// Value noise on the unit lattice, smooth (quintic fade), in [-1, 1], mean about 0.
inline double ValueNoise(double x, double y, std::uint64_t seed) {
  const double fx = std::floor(x), fy = std::floor(y);
  const auto ix = static_cast<std::int64_t>(fx), iy = static_cast<std::int64_t>(fy);
  const double tx = x - fx, ty = y - fy;
  // One multiply-xorshift round per corner: cheap, and plenty for a texture lattice.
  auto corner = [seed](std::int64_t i, std::int64_t j) {
    std::uint64_t h = seed ^ (static_cast<std::uint64_t>(i) * 0x8CB92BA72F3D8DD7ull) ^
                      (static_cast<std::uint64_t>(j) * 0xD6E8FEB86659FD93ull);
    h ^= h >> 32;
    h *= 0xD6E8FEB86659FD93ull;
    h ^= h >> 29;
    return static_cast<double>(h >> 11) * 0x1.0p-52 - 1.0;
  };
  const double sx = tx * tx * tx * (tx * (tx * 6.0 - 15.0) + 10.0);
  const double sy = ty * ty * ty * (ty * (ty * 6.0 - 15.0) + 10.0);
  const double a = corner(ix, iy), b = corner(ix + 1, iy);
  const double c = corner(ix, iy + 1), d = corner(ix + 1, iy + 1);
  return (a + (b - a) * sx) + ((c + (d - c) * sx) - (a + (b - a) * sx)) * sy;
}

// Sum of value-noise octaves from `max_wavelength` down to `min_wavelength` (halving),
// octave amplitude (wavelength / max_wavelength)^hurst. Returns roughly unit-scale values.
inline double FractalNoise(double x, double y, double min_wavelength, double max_wavelength,
                           double hurst, std::uint64_t seed) {
  double sum = 0.0;
  int octave = 0;
  double amp = 1.0;
  const double amp_step = std::pow(0.5, hurst);
  for (double lambda = max_wavelength; lambda >= min_wavelength * 0.999;
       lambda *= 0.5, amp *= amp_step) {
    // Offsets decorrelate the octaves' lattices.
    sum += amp * ValueNoise(x / lambda + 17.31 * octave, y / lambda - 9.73 * octave,
                            seed + static_cast<std::uint64_t>(octave) * 0x9E37ull);
    ++octave;
  }
  return sum;
}

}  // namespace rover::terrain
