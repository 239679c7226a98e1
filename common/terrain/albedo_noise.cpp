#include "terrain/albedo_noise.hpp"

#include <algorithm>
#include <bit>
#include <cmath>

namespace rover::terrain {

namespace {

// Lattice multipliers (odd, well mixed) and the per-octave seed step of FractalNoise.
constexpr std::uint32_t kLatticeX = 0x8CB92BA7u;
constexpr std::uint32_t kLatticeY = 0xD6E8FEB9u;
constexpr std::uint32_t kOctaveSeed = 0x9E37u;

// A 32-bit integer finaliser (xorshift-multiply, two rounds): every input bit reaches
// every output bit, which a lattice of neighbouring integers needs.
inline std::uint32_t Mix32(std::uint32_t h) {
  h ^= h >> 16;
  h *= 0x7FEB352Du;
  h ^= h >> 15;
  h *= 0x846CA68Bu;
  h ^= h >> 16;
  return h;
}

// Uniform in [-1, 1): the top 24 bits are exact in a float.
inline float Corner(std::uint32_t h) {
  return static_cast<float>(static_cast<std::int32_t>(Mix32(h) >> 8)) * (1.0f / 8388608.0f) - 1.0f;
}

inline float Fade(float t) { return t * t * t * (t * (t * 6.0f - 15.0f) + 10.0f); }

// floor(u) as an integer, for |u| < 2^31: truncate, then step down below zero. (std::floor
// is not vectorised unless trapping math is off for the whole file.)
inline std::int32_t Floor(float u) {
  const auto t = static_cast<std::int32_t>(u);
  return t - (static_cast<float>(t) > u ? 1 : 0);
}

inline float Value(float u, float v, std::uint32_t s) {
  const std::int32_t ju = Floor(u), jv = Floor(v);
  const float fu = static_cast<float>(ju), fv = static_cast<float>(jv);
  const auto iu = static_cast<std::uint32_t>(ju);
  const auto iv = static_cast<std::uint32_t>(jv);
  const float sx = Fade(u - fu), sy = Fade(v - fv);
  const std::uint32_t hx0 = iu * kLatticeX, hx1 = hx0 + kLatticeX;
  const std::uint32_t hy0 = iv * kLatticeY, hy1 = hy0 + kLatticeY;
  const float a = Corner(s ^ hx0 ^ hy0), b = Corner(s ^ hx1 ^ hy0);
  const float c = Corner(s ^ hx0 ^ hy1), d = Corner(s ^ hx1 ^ hy1);
  const float ab = a + (b - a) * sx, cd = c + (d - c) * sx;
  return ab + (cd - ab) * sy;
}

}  // namespace

float ValueNoise32(float x, float y, std::uint32_t seed) { return Value(x, y, seed); }

int OctaveCount(double min_wavelength, double max_wavelength) {
  // Octave k is kept while max / 2^k >= 0.999 min, i.e. 2^k <= r: k = 0 .. floor(log2 r),
  // and frexp gives floor(log2 r) + 1 exactly (r = f 2^e, f in [0.5, 1)).
  // The exponent is read from the bits (what frexp returns, without a library call per
  // pixel); r >= 1 is a normal number, or infinity, whose exponent field caps at 64 below.
  const double r = max_wavelength / (min_wavelength * 0.999);
  if (!(r >= 1.0)) return 0;
  const int e = static_cast<int>((std::bit_cast<std::uint64_t>(r) >> 52) & 0x7FF) - 1022;
  return std::min(e, 64);
}

namespace {

// One octave over all points: a separate loop with nothing but the points' own arrays,
// which the vectoriser takes.
__attribute__((target_clones("avx2", "default")))
void AddOctave(int n, const float* __restrict x, const float* __restrict y,
               const float* __restrict inv_max_wavelength, const std::uint32_t* __restrict seed,
               const int* __restrict octaves, int k, float amp, float scale, float* __restrict out) {
  const float ox = 17.31f * static_cast<float>(k), oy = -9.73f * static_cast<float>(k);
  const std::uint32_t sk = static_cast<std::uint32_t>(k) * kOctaveSeed;
  for (int p = 0; p < n; ++p) {
    const float f = inv_max_wavelength[p] * scale;
    const float value = Value(x[p] * f + ox, y[p] * f + oy, seed[p] + sk);
    out[p] += (k < octaves[p] ? amp : 0.0f) * value;
  }
}

}  // namespace

void FractalNoiseBatch(int n, const float* x, const float* y, const float* inv_max_wavelength,
                       const std::uint32_t* seed, const int* octaves, float amp_step, float* out) {
  int most = 0;
  for (int p = 0; p < n; ++p) {
    most = std::max(most, octaves[p]);
    out[p] = 0.0f;
  }
  float amp = 1.0f, scale = 1.0f;
  for (int k = 0; k < most; ++k, amp *= amp_step, scale *= 2.0f) {
    AddOctave(n, x, y, inv_max_wavelength, seed, octaves, k, amp, scale, out);
  }
}

}  // namespace rover::terrain
