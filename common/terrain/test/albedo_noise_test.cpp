// The vectorised albedo noise against plain one-point arithmetic.
#include "terrain/albedo_noise.hpp"
#include "terrain/random.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace rover::terrain {
namespace {

// The octave count as FractalNoise's loop counts it.
int HalvingCount(double min_wavelength, double max_wavelength) {
  int n = 0;
  for (double lambda = max_wavelength; lambda >= min_wavelength * 0.999 && n < 64; lambda *= 0.5) ++n;
  return n;
}

TEST(AlbedoNoise, OctaveCountMatchesTheHalvingLoop) {
  int checked = 0;
  for (double max_wl : {0.16, 0.3, 1.0, 2.0, 4.0}) {
    for (double min_wl = 1e-4; min_wl < 10; min_wl *= 1.0137) {
      ASSERT_EQ(OctaveCount(min_wl, max_wl), HalvingCount(min_wl, max_wl)) << min_wl << " " << max_wl;
      ++checked;
    }
  }
  EXPECT_GT(checked, 4000);
  EXPECT_EQ(OctaveCount(0.01, 0.16), 5);  // 16, 8, 4, 2, 1 cm
  EXPECT_EQ(OctaveCount(1.0, 0.5), 0);
}

// Every point of a batch (any length, mixed octave counts and seeds) equals the sum of
// its octaves taken one point at a time.
TEST(AlbedoNoise, BatchEqualsOctavesSummedPointByPoint) {
  Random rng(3);
  const int n = 1037;  // not a multiple of any vector width
  std::vector<float> x(n), y(n), inv(n), out(n);
  std::vector<std::uint32_t> seed(n);
  std::vector<int> octaves(n);
  for (int p = 0; p < n; ++p) {
    x[p] = static_cast<float>(rng.Uniform(-40, 40));
    y[p] = static_cast<float>(rng.Uniform(-40, 40));
    inv[p] = static_cast<float>(1.0 / rng.Uniform(0.1, 4.0));
    seed[p] = static_cast<std::uint32_t>(rng.NextBits());
    octaves[p] = static_cast<int>(rng.Uniform(0, 9));
  }
  const float step = 0.8f;
  FractalNoiseBatch(n, x.data(), y.data(), inv.data(), seed.data(), octaves.data(), step, out.data());
  for (int p = 0; p < n; ++p) {
    float sum = 0.0f, amp = 1.0f, scale = 1.0f;
    for (int k = 0; k < octaves[p]; ++k, amp *= step, scale *= 2.0f) {
      const float f = inv[p] * scale;
      sum += amp * ValueNoise32(x[p] * f + 17.31f * static_cast<float>(k), y[p] * f - 9.73f * static_cast<float>(k),
                                seed[p] + static_cast<std::uint32_t>(k) * 0x9E37u);
    }
    // The same operations in the same order: the same bits.
    ASSERT_EQ(out[p], sum) << "point " << p;
  }
}

TEST(AlbedoNoise, ValueNoiseHasTheStatedSpreadAndNoLatticeCorrelation) {
  Random rng(9);
  double s = 0, s2 = 0, lag = 0;
  const int n = 200000;
  for (int i = 0; i < n; ++i) {
    const float v = ValueNoise32(static_cast<float>(rng.Uniform(-3000, 3000)),
                                 static_cast<float>(rng.Uniform(-3000, 3000)), 12345u);
    s += v;
    s2 += v * v;
    // Neighbouring lattice corners must be independent.
    lag += ValueNoise32(static_cast<float>(i), 7.0f, 1u) * ValueNoise32(static_cast<float>(i + 1), 7.0f, 1u);
  }
  const double mean = s / n, sd = std::sqrt(s2 / n - mean * mean);
  EXPECT_NEAR(mean, 0.0, 0.01);
  EXPECT_NEAR(sd, kValueNoise32Std, 0.01);
  // Corners are uniform on [-1, 1) (variance 1/3): correlation = E[ab] / (1/3).
  EXPECT_NEAR(lag / n * 3.0, 0.0, 0.02);
}

}  // namespace
}  // namespace rover::terrain
