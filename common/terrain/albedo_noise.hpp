// Fractal value noise for surface albedo, evaluated for a whole batch of ground points.
//
// The renderer asks for the albedo of about two million ground points per stereo pair,
// each a sum of up to nine octaves of value noise: the single largest cost of a frame.
// No library offers seeded, platform-independent lattice noise, so it is written here in
// a form the compiler vectorises: single precision (ample: lattice coordinates below
// 10^5 keep 2 um at a 1 cm wavelength), a 32-bit lattice hash, and one loop over points
// per octave with no branches. The function is compiled twice (target_clones): for AVX2,
// eight points at a time, and for the x86-64 baseline. Neither clone contracts to FMA
// and both do the same IEEE operations in the same order, so every machine gets the same
// bits.
//
// Semantics match terrain::FractalNoise (random.hpp): octave k has wavelength
// max_wavelength / 2^k, amplitude amp_step^k, a lattice offset (17.31 k, -9.73 k), and
// its own seed; the value noise is smooth (quintic fade) with corners uniform in [-1, 1).
#pragma once

#include <cstdint>

namespace rover::terrain {

// Standard deviation of ValueNoise32 over the plane (uniform corners, quintic fade; the
// same as the 64-bit ValueNoise's, kValueNoiseStd).
inline constexpr double kValueNoise32Std = 0.45;

// out[p] = sum_{k < octaves[p]} amp_step^k * ValueNoise32(x[p] * inv_max_wavelength[p] * 2^k
//          + 17.31 k, y[p] * ... - 9.73 k, seed[p] + k * 0x9E37), for p in [0, n).
// octaves[p] may be 0 (out[p] = 0). Points are any site coordinates within +-10^5
// wavelengths of the origin.
void FractalNoiseBatch(int n, const float* x, const float* y, const float* inv_max_wavelength,
                       const std::uint32_t* seed, const int* octaves, float amp_step, float* out);

// The 32-bit value noise at one point (the batch's octave 0 with one octave).
float ValueNoise32(float x, float y, std::uint32_t seed);

// Octaves from max_wavelength down to min_wavelength (halving), the count FractalNoise
// would sum: wavelengths >= min * 0.999. 0 when min > max.
int OctaveCount(double min_wavelength, double max_wavelength);

}  // namespace rover::terrain
