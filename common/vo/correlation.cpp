#include "vo/correlation.hpp"
#include "vo/simd.hpp"

#include <Eigen/LU>
#include <immintrin.h>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace rover::vo {

namespace {

// Symmetric filter of a row: dst[x] = c[0] p[x] + sum_j c[j] (p[x-j] + p[x+j]), all taps
// in one pass (separate passes per tap were bound by their stores). HK = 0: any width.
template <int HK>
__attribute__((always_inline)) inline void SymmetricRow(const float* c, int hk, const float* p,
                                                        int W, float* __restrict dst) {
  if constexpr (HK > 0) {
    for (int x = 0; x < W; ++x) {
      float v = c[0] * p[x];
      for (int j = 1; j <= HK; ++j) v += c[j] * (p[x - j] + p[x + j]);
      dst[x] = v;
    }
  } else {
    for (int x = 0; x < W; ++x) dst[x] = c[0] * p[x];
    for (int j = 1; j <= hk; ++j) {
      const float cj = c[j];
      for (int x = 0; x < W; ++x) dst[x] += cj * (p[x - j] + p[x + j]);
    }
  }
}

// o[x] -= inv * sum_{j=0}^{n-1} p[x+j], in one pass. N = 0: any n.
template <int N>
__attribute__((always_inline)) inline void SubtractBoxRow(const float* p, int n, float inv, int W,
                                                          float* __restrict o) {
  if constexpr (N > 0) {
    for (int x = 0; x < W; ++x) {
      float v = 0;
      for (int j = 0; j < N; ++j) v += p[x + j];
      o[x] -= v * inv;
    }
  } else {
    thread_local std::vector<float> acc;
    acc.resize(W);
    float* __restrict s = acc.data();
    std::copy(p, p + W, s);
    for (int j = 1; j < n; ++j) {
      const float* __restrict q = p + j;
      for (int x = 0; x < W; ++x) s[x] += q[x];
    }
    for (int x = 0; x < W; ++x) o[x] -= s[x] * inv;
  }
}

// One streaming pass, row by row, so each image is read once and written once (OpenCV's
// GaussianBlur followed by a second pass for the box took ~1.7 ms on 1226x370 on one
// core; this about a third of it):
//   out = Gaussian(taps, reflected borders, as cv::GaussianBlur with BORDER_REFLECT)
//         - box mean (side n, replicated borders; skipped when n < 3).
// The Gaussian filters rows into a ring of k rows, then combines them down the columns.
// The box sums columns with a running sum, then n shifted copies of the row in one pass
// (a running sum along the row would serialise on its latency).
__attribute__((target_clones("avx2,fma", "default")))
void BandPassRows(const cv::Mat& image, const std::vector<float>& taps, int n, cv::Mat* out) {
  const int W = image.cols, H = image.rows;
  const int k = static_cast<int>(taps.size()), hk = k / 2;
  const int h = n / 2;
  thread_local std::vector<float> ring, gpad, column, padded;
  auto reflect = [](int i, int len) {
    // BORDER_REFLECT: fedcba|abcdefgh|hgfedcb (images are wider than the kernel).
    if (i < 0) i = -i - 1;
    if (i >= len) i = 2 * len - i - 1;
    return std::clamp(i, 0, len - 1);
  };
  if (k > 0) {
    ring.resize(static_cast<std::size_t>(k) * W);
    gpad.resize(W + 2 * hk);
  }
  auto slot = [&](int y) { return ring.data() + static_cast<std::size_t>(y % k) * W; };
  auto filter_row = [&](int y) __attribute__((always_inline)) {
    const float* src = image.ptr<float>(y);
    float* __restrict p = gpad.data();
    std::copy(src, src + W, p + hk);
    for (int j = 1; j <= hk; ++j) {
      p[hk - j] = src[reflect(-j, W)];
      p[hk + W - 1 + j] = src[reflect(W - 1 + j, W)];
    }
    float* __restrict dst = slot(y);
    switch (hk) {
      case 1: SymmetricRow<1>(taps.data() + hk, hk, p + hk, W, dst); break;
      case 2: SymmetricRow<2>(taps.data() + hk, hk, p + hk, W, dst); break;
      case 3: SymmetricRow<3>(taps.data() + hk, hk, p + hk, W, dst); break;
      default: SymmetricRow<0>(taps.data() + hk, hk, p + hk, W, dst); break;
    }
  };
  int next_row = 0;
  const bool box = n >= 3;
  if (box) {
    column.assign(W, 0.0f);
    padded.resize(W + 2 * h);
  }
  auto row_at = [&](int y) { return image.ptr<float>(std::clamp(y, 0, H - 1)); };
  if (box) {
    for (int y = -h; y <= h; ++y) {
      const float* r = row_at(y);
      for (int x = 0; x < W; ++x) column[x] += r[x];
    }
  }
  const float inv = 1.0f / float(n * n);
  for (int y = 0; y < H; ++y) {
    float* __restrict o = out->ptr<float>(y);
    if (k > 0) {
      for (const int last = std::min(H - 1, y + hk); next_row <= last; ++next_row) {
        filter_row(next_row);
      }
      // Vertical: the ring rows at reflected offsets, all taps in one pass.
      const float* c = taps.data() + hk;
      const float* m = slot(y);
      if (hk == 2) {
        const float *u2 = slot(reflect(y - 2, H)), *u1 = slot(reflect(y - 1, H));
        const float *d1 = slot(reflect(y + 1, H)), *d2 = slot(reflect(y + 2, H));
        for (int x = 0; x < W; ++x) {
          o[x] = c[0] * m[x] + c[1] * (u1[x] + d1[x]) + c[2] * (u2[x] + d2[x]);
        }
      } else {
        for (int x = 0; x < W; ++x) o[x] = c[0] * m[x];
        for (int j = 1; j <= hk; ++j) {
          const float* __restrict up = slot(reflect(y - j, H));
          const float* __restrict down = slot(reflect(y + j, H));
          for (int x = 0; x < W; ++x) o[x] += c[j] * (up[x] + down[x]);
        }
      }
    } else {
      const float* src = image.ptr<float>(y);
      std::copy(src, src + W, o);
    }
    if (!box) continue;
    if (y > 0) {
      const float* add = row_at(y + h);
      const float* sub = row_at(y - h - 1);
      float* __restrict col = column.data();
      for (int x = 0; x < W; ++x) col[x] += add[x] - sub[x];
    }
    float* __restrict p = padded.data();
    for (int x = 0; x < h; ++x) {
      p[x] = column[0];
      p[W + h + x] = column[W - 1];
    }
    std::copy(column.begin(), column.end(), p + h);
    switch (n) {
      case 5: SubtractBoxRow<5>(p, n, inv, W, o); break;
      case 7: SubtractBoxRow<7>(p, n, inv, W, o); break;
      case 9: SubtractBoxRow<9>(p, n, inv, W, o); break;
      case 11: SubtractBoxRow<11>(p, n, inv, W, o); break;
      default: SubtractBoxRow<0>(p, n, inv, W, o); break;
    }
  }
}

}  // namespace

void BandPass(const cv::Mat& image, double sigma, int box_px, cv::Mat* out, cv::Mat* scratch) {
  CV_Assert(image.type() == CV_32FC1);
  (void)scratch;
  std::vector<float> taps;
  if (sigma > 0) {
    const int k = 2 * static_cast<int>(std::ceil(2.5 * sigma)) + 1;
    const int half = k / 2;
    if (image.cols <= half || image.rows <= half) {
      // Too small for one reflection: OpenCV's general path.
      cv::GaussianBlur(image, *out, cv::Size(k, k), sigma, sigma, cv::BORDER_REFLECT);
      if (box_px >= 3) {
        cv::Mat mean;
        cv::blur(image, mean, cv::Size(box_px, box_px), cv::Point(-1, -1), cv::BORDER_REPLICATE);
        *out -= mean;
      }
      return;
    }
    const cv::Mat kernel = cv::getGaussianKernel(k, sigma, CV_32F);
    taps.assign(kernel.ptr<float>(), kernel.ptr<float>() + k);
  }
  out->create(image.size(), CV_32F);
  BandPassRows(image, taps, box_px >= 3 ? box_px : 0, out);
}

cv::Mat BandPass(const cv::Mat& image, double sigma, int box_px) {
  cv::Mat out, scratch;
  BandPass(image, sigma, box_px, &out, &scratch);
  return out;
}

bool Template::Extract(const cv::Mat& band, int x, int y, int side) {
  if (!TemplateFits(x, y, side, band.cols, band.rows)) return false;
  n = side;
  pixels.resize(static_cast<std::size_t>(n) * n);
  const int h = n / 2;
  // Four partial sums: one running sum serialised on the add latency.
  double ss[4] = {0, 0, 0, 0};
  for (int r = 0; r < n; ++r) {
    const float* src = band.ptr<float>(y - h + r) + (x - h);
    std::copy(src, src + n, pixels.data() + r * n);
  }
  const float* p = pixels.data();
  const int total = n * n;
  int i = 0;
  for (; i + 4 <= total; i += 4) {
    for (int j = 0; j < 4; ++j) ss[j] += static_cast<double>(p[i + j]) * p[i + j];
  }
  for (; i < total; ++i) ss[0] += static_cast<double>(p[i]) * p[i];
  sum_sq = (ss[0] + ss[1]) + (ss[2] + ss[3]);
  return true;
}

bool Template::ExtractSubpixel(const cv::Mat& band, double x, double y, int side) {
  const int h = side / 2;
  if (x - h < 0 || y - h < 0 || x + h + 1 >= band.cols || y + h + 1 >= band.rows) return false;
  n = side;
  pixels.resize(static_cast<std::size_t>(n) * n);
  const int ix = static_cast<int>(std::floor(x)), iy = static_cast<int>(std::floor(y));
  const float fx = static_cast<float>(x - ix), fy = static_cast<float>(y - iy);
  const float w00 = (1 - fx) * (1 - fy), w01 = fx * (1 - fy), w10 = (1 - fx) * fy, w11 = fx * fy;
  double ss = 0;
  for (int r = 0; r < n; ++r) {
    const float* a = band.ptr<float>(iy - h + r) + (ix - h);
    const float* b = band.ptr<float>(iy - h + r + 1) + (ix - h);
    float* dst = pixels.data() + r * n;
    for (int c = 0; c < n; ++c) {
      dst[c] = w00 * a[c] + w01 * a[c + 1] + w10 * b[c] + w11 * b[c + 1];
      ss += static_cast<double>(dst[c]) * dst[c];
    }
  }
  sum_sq = ss;
  return true;
}

bool Template::ExtractWarped(const cv::Mat& band, double x, double y, const Eigen::Matrix2d& warp, int side) {
  const int h = side / 2;
  // The template's corners bound where it samples.
  const double reach_x = h * (std::abs(warp(0, 0)) + std::abs(warp(0, 1)));
  const double reach_y = h * (std::abs(warp(1, 0)) + std::abs(warp(1, 1)));
  if (!std::isfinite(reach_x) || !std::isfinite(reach_y) || x - reach_x < 0 || y - reach_y < 0 ||
      x + reach_x + 1 >= band.cols || y + reach_y + 1 >= band.rows) {
    return false;
  }
  n = side;
  pixels.resize(static_cast<std::size_t>(n) * n);
  double ss = 0;
  for (int r = 0; r < n; ++r) {
    for (int c = 0; c < n; ++c) {
      const double sx = x + warp(0, 0) * (c - h) + warp(0, 1) * (r - h);
      const double sy = y + warp(1, 0) * (c - h) + warp(1, 1) * (r - h);
      const int ix = static_cast<int>(std::floor(sx)), iy = static_cast<int>(std::floor(sy));
      const float fx = static_cast<float>(sx - ix), fy = static_cast<float>(sy - iy);
      const float* a = band.ptr<float>(iy) + ix;
      const float* b = band.ptr<float>(iy + 1) + ix;
      const float v = (1 - fx) * (1 - fy) * a[0] + fx * (1 - fy) * a[1] + (1 - fx) * fy * b[0] + fx * fy * b[1];
      pixels[static_cast<std::size_t>(r) * n + c] = v;
      ss += static_cast<double>(v) * v;
    }
  }
  sum_sq = ss;
  return true;
}

// Cross term sum(ab) for K adjacent centres on one row, the K sums held in registers
// (vectorised across the centres). Two sets (even and odd template rows) keep twice as
// many independent add chains in flight.
template <int K, int N = 0>
__attribute__((always_inline)) inline void CrossSmall(const Template& t, const cv::Mat& band,
                                                      int y, int x0, float* out) {
  // N > 0: the template side known at compile time (the defaults), loops fully unrolled.
  const int n = N > 0 ? N : t.n, h = n / 2;
  float even[K] = {}, odd[K] = {};
  auto add_row = [&](int r, float* acc) __attribute__((always_inline)) {
    const float* b = band.ptr<float>(y - h + r) + (x0 - h);
    const float* tr = t.pixels.data() + r * n;
    for (int c = 0; c < n; ++c) {
      const float a = tr[c];
      for (int k = 0; k < K; ++k) acc[k] += a * b[c + k];
    }
  };
  int r = 0;
  for (; r + 1 < n; r += 2) {
    add_row(r, even);
    add_row(r + 1, odd);
  }
  if (r < n) add_row(r, even);
  for (int k = 0; k < K; ++k) out[k] = even[k] + odd[k];
}

template <int K>
__attribute__((always_inline)) inline void CrossFew(const Template& t, const cv::Mat& band,
                                                    int y, int x0, float* out) {
  switch (t.n) {
    case 7: CrossSmall<K, 7>(t, band, y, x0, out); break;
    case 11: CrossSmall<K, 11>(t, band, y, x0, out); break;
    default: CrossSmall<K>(t, band, y, x0, out); break;
  }
}

// The cross terms of one row of centres, blocks of 32 and 8, then the few left over.
__attribute__((always_inline)) inline void CrossRow(const Template& t, const cv::Mat& band, int y, int x0,
                                                    int count, float* out) {
  int k = 0;
  for (; k + 32 <= count; k += 32) CrossSmall<32>(t, band, y, x0 + k, out + k);
  for (; k + 8 <= count; k += 8) CrossFew<8>(t, band, y, x0 + k, out + k);
  switch (count - k) {
    case 1: CrossFew<1>(t, band, y, x0 + k, out + k); break;
    case 2: CrossFew<2>(t, band, y, x0 + k, out + k); break;
    case 3: CrossFew<3>(t, band, y, x0 + k, out + k); break;
    case 4: CrossFew<4>(t, band, y, x0 + k, out + k); break;
    case 5: CrossFew<5>(t, band, y, x0 + k, out + k); break;
    case 6: CrossFew<6>(t, band, y, x0 + k, out + k); break;
    case 7: CrossFew<7>(t, band, y, x0 + k, out + k); break;
    default: break;
  }
}

// One template row's products added into R x V sums (CrossBlockAvx2).
template <int R, int V>
__attribute__((target("avx2"), always_inline)) inline void AddRowAvx2(const Template& t, const cv::Mat& band, int y,
                                                                    int x0, int r, __m256i mask,
                                                                    __m256 (&acc)[R][V]) {
  const int n = t.n, h = n / 2;
  const float* tr = t.pixels.data() + r * n;
  const float* b[R];
  for (int q = 0; q < R; ++q) b[q] = band.ptr<float>(y + q - h + r) + (x0 - h);
  for (int c = 0; c < n; ++c) {
    const __m256 a = _mm256_broadcast_ss(tr + c);
    for (int q = 0; q < R; ++q) {
      for (int v = 0; v < V; ++v) {
        const float* p = b[q] + c + 8 * v;
        const __m256 x = v + 1 < V ? _mm256_loadu_ps(p) : _mm256_maskload_ps(p, mask);
        acc[q][v] = _mm256_add_ps(acc[q][v], _mm256_mul_ps(a, x));
      }
    }
  }
}

// The cross terms with AVX2 written out: R rows of centres by V vectors of 8 adjacent
// centres, the last vector `last` centres wide (masked loads and stores, which never touch
// the masked-off pixels). Every sum is formed exactly as CrossSmall forms it: a product
// rounded, then added (no fused multiply-add: the build contracts none), template rows in
// order into an even and an odd sum, columns in order, the two added at the end. So the
// scores are bit for bit those of the portable path. What differs is that the 2 R V sums
// are independent chains in flight together: the compiler's code for a few centres kept
// two chains and broadcast the template through shuffles and the stack, about one
// product per cycle.
template <int R, int V>
__attribute__((target("avx2"), always_inline)) inline void CrossBlockAvx2(const Template& t, const cv::Mat& band,
                                                                        int y, int x0, int last, float* out,
                                                                        int stride) {
  const int n = t.n;
  alignas(32) static constexpr int kLanes[16] = {-1, -1, -1, -1, -1, -1, -1, -1, 0, 0, 0, 0, 0, 0, 0, 0};
  const __m256i mask = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(kLanes + 8 - last));
  __m256 even[R][V], odd[R][V];
  for (int q = 0; q < R; ++q) {
    for (int v = 0; v < V; ++v) even[q][v] = odd[q][v] = _mm256_setzero_ps();
  }
  int r = 0;
  for (; r + 1 < n; r += 2) {
    AddRowAvx2<R, V>(t, band, y, x0, r, mask, even);
    AddRowAvx2<R, V>(t, band, y, x0, r + 1, mask, odd);
  }
  if (r < n) AddRowAvx2<R, V>(t, band, y, x0, r, mask, even);
  for (int q = 0; q < R; ++q) {
    for (int v = 0; v < V; ++v) {
      const __m256 sum = _mm256_add_ps(even[q][v], odd[q][v]);
      float* o = out + q * stride + 8 * v;
      if (v + 1 < V) {
        _mm256_storeu_ps(o, sum);
      } else {
        _mm256_maskstore_ps(o, mask, sum);
      }
    }
  }
}

// The cross terms of rows y..y+rows-1 (row q's at out + q * count): rows of up to 8
// centres four at a time, longer rows (a stereo search along the epipolar line) one at a
// time by up to 32 centres.
__attribute__((target("avx2"))) void CrossRowsAvx2(const Template& t, const cv::Mat& band, int y, int rows, int x0,
                                                   int count, float* out) {
  int q = 0;
  if (count <= 8) {  // a few centres a row: four rows together
    for (; q + 4 <= rows; q += 4) CrossBlockAvx2<4, 1>(t, band, y + q, x0, count, out + q * count, count);
  }
  if (rows - q > 1 && count <= 8) {  // two or three rows of a few centres: together
    float* o = out + q * count;
    if (rows - q == 2) {
      CrossBlockAvx2<2, 1>(t, band, y + q, x0, count, o, count);
    } else {
      CrossBlockAvx2<3, 1>(t, band, y + q, x0, count, o, count);
    }
    return;
  }
  for (; q < rows; ++q) {
    float* o = out + q * count;
    int k = 0;
    for (; k + 32 <= count; k += 32) CrossBlockAvx2<1, 4>(t, band, y + q, x0 + k, 8, o + k, count);
    const int left = count - k;
    if (left > 24) {
      CrossBlockAvx2<1, 4>(t, band, y + q, x0 + k, left - 24, o + k, count);
    } else if (left > 16) {
      CrossBlockAvx2<1, 3>(t, band, y + q, x0 + k, left - 16, o + k, count);
    } else if (left > 8) {
      CrossBlockAvx2<1, 2>(t, band, y + q, x0 + k, left - 8, o + k, count);
    } else if (left > 0) {
      CrossBlockAvx2<1, 1>(t, band, y + q, x0 + k, left, o + k, count);
    }
  }
}

// The rest of ScoreRows with AVX2: each row's column sums of b^2 eight columns at a time
// (masked at the end), slid along the row in double as the portable path slides them (a
// serial chain, kept), then 2 sum(ab) / (sum(a^2) + sum(b^2)) four centres at a time.
// Every value is formed by the same roundings as the portable path's.
__attribute__((target("avx2"))) void NormaliseRowsAvx2(const Template& t, const cv::Mat& band, int y, int rows,
                                                       int x0, int count, float* out) {
  const int n = t.n, h = n / 2;
  const int span = count + n - 1;
  alignas(32) static constexpr int kLanes[16] = {-1, -1, -1, -1, -1, -1, -1, -1, 0, 0, 0, 0, 0, 0, 0, 0};
  thread_local std::vector<float> column_sq_heap;
  thread_local std::vector<double> den_heap;
  float column_sq_stack[520];
  double den_stack[512];
  float* column_sq = column_sq_stack;
  double* den = den_stack;
  if (span + 8 > 520) {
    column_sq_heap.resize(static_cast<std::size_t>(span) + 8);
    column_sq = column_sq_heap.data();
  }
  if (count > 512) {
    den_heap.resize(static_cast<std::size_t>(count));
    den = den_heap.data();
  }
  const double ta = t.sum_sq;
  const __m256d two = _mm256_set1_pd(2.0), tiny = _mm256_set1_pd(1e-20);
  for (int q = 0; q < rows; ++q) {
    for (int j = 0; j < span; j += 8) {
      const __m256i mask = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(kLanes + 8 - std::min(8, span - j)));
      __m256 acc = _mm256_setzero_ps();
      for (int r = 0; r < n; ++r) {
        const __m256 x = _mm256_maskload_ps(band.ptr<float>(y + q - h + r) + (x0 - h) + j, mask);
        acc = _mm256_add_ps(acc, _mm256_mul_ps(x, x));
      }
      _mm256_storeu_ps(column_sq + j, acc);
    }
    double window = 0;
    for (int j = 0; j < n - 1; ++j) window += column_sq[j];
    for (int i = 0; i < count; ++i) {
      window += column_sq[i + n - 1];
      den[i] = ta + window;
      window -= column_sq[i];
    }
    float* o = out + q * count;
    int i = 0;
    for (; i + 4 <= count; i += 4) {
      const __m256d d = _mm256_loadu_pd(den + i);
      const __m256d score = _mm256_div_pd(_mm256_mul_pd(two, _mm256_cvtps_pd(_mm_loadu_ps(o + i))), d);
      const __m256d keep = _mm256_cmp_pd(d, tiny, _CMP_GT_OQ);
      _mm_storeu_ps(o + i, _mm256_cvtpd_ps(_mm256_and_pd(score, keep)));
    }
    for (; i < count; ++i) o[i] = den[i] > 1e-20 ? static_cast<float>(2.0 * o[i] / den[i]) : 0.0f;
  }
}

// Compiled for AVX2+FMA as well as the baseline; the loader picks the best the CPU has.
// Scores for centres (x0..x0+count-1) on rows y..y+rows-1, row q's at out + q * count.
__attribute__((target_clones("avx2,fma", "default")))
void ScoreRows(const Template& t, const cv::Mat& band, int y, int rows, int x0, int count, float* out) {
  const int n = t.n, h = n / 2;
  const int span = count + n - 1;
  // The cross term in blocks of adjacent centres whose sums stay in registers (a run of
  // sums in memory was bound by its loads and stores).
  if (UseAvx2()) {
    CrossRowsAvx2(t, band, y, rows, x0, count, out);
    NormaliseRowsAvx2(t, band, y, rows, x0, count, out);
    return;
  }
  for (int q = 0; q < rows; ++q) CrossRow(t, band, y + q, x0, count, out + q * count);
  thread_local std::vector<float> column_sq_heap;
  float column_sq_stack[512];
  float* column_sq = column_sq_stack;
  if (span > 512) {
    column_sq_heap.resize(span);
    column_sq = column_sq_heap.data();
  }
  const double ta = t.sum_sq;
  for (int q = 0; q < rows; ++q) {
    std::fill(column_sq, column_sq + span, 0.0f);
    for (int r = 0; r < n; ++r) {
      const float* row = band.ptr<float>(y + q - h + r) + (x0 - h);
      float* __restrict cs = column_sq;
      for (int j = 0; j < span; ++j) cs[j] += row[j] * row[j];
    }
    // sum(b^2) over the window: slide n column sums along the row (double, no drift).
    double window = 0;
    for (int j = 0; j < n - 1; ++j) window += column_sq[j];
    float* o = out + q * count;
    for (int i = 0; i < count; ++i) {
      window += column_sq[i + n - 1];
      const double den = ta + window;
      o[i] = den > 1e-20 ? static_cast<float>(2.0 * o[i] / den) : 0.0f;
      window -= column_sq[i];
    }
  }
}

void ScoreRow(const Template& t, const cv::Mat& band, int y, int x0, int count, float* out) {
  ScoreRows(t, band, y, 1, x0, count, out);
}

float ScoreAt(const Template& t, const cv::Mat& band, int x, int y) {
  float s;
  ScoreRow(t, band, y, x, 1, &s);
  return s;
}

bool FitBiquadraticPeak(const float s[3][3], double covariance_scale, double min_sigma,
                        Eigen::Vector2d* offset, Eigen::Matrix2d* covariance) {
  // Least squares on the 3x3 grid, with orthogonal basis 1, x, y, x^2-2/3, xy, y^2-2/3.
  double sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0;
  double col_outer = 0, col_mid = 0, row_outer = 0, row_mid = 0;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      const double v = s[r][c];
      const int dx = c - 1, dy = r - 1;
      sx += dx * v;
      sy += dy * v;
      sxy += dx * dy * v;
      (dx == 0 ? col_mid : col_outer) += v;
      (dy == 0 ? row_mid : row_outer) += v;
    }
  }
  (void)sxx;
  (void)syy;
  const double b = sx / 6.0, c = sy / 6.0;
  const double d = (col_outer - 2.0 * col_mid) / 6.0;
  const double f = (row_outer - 2.0 * row_mid) / 6.0;
  const double e = sxy / 4.0;
  Eigen::Matrix2d H;
  H << 2 * d, e, e, 2 * f;
  // A peak needs a negative definite Hessian.
  if (!(H(0, 0) < 0 && H.determinant() > 0)) return false;
  const Eigen::Vector2d g(b, c);
  const Eigen::Matrix2d Hinv = H.inverse();
  const Eigen::Vector2d o = -Hinv * g;
  if (!(std::abs(o.x()) <= 1.0 && std::abs(o.y()) <= 1.0)) return false;
  *offset = o;
  Eigen::Matrix2d cov = -covariance_scale * Hinv;
  const double floor = min_sigma * min_sigma;
  // Floor each axis without breaking positive definiteness: add to the diagonal.
  for (int i = 0; i < 2; ++i) {
    if (cov(i, i) < floor) cov(i, i) = floor;
  }
  if (cov.determinant() <= 0) cov = Eigen::Vector2d(cov(0, 0), cov(1, 1)).asDiagonal();
  *covariance = cov;
  return true;
}

bool Correlator::SearchWindow(const Template& t, const cv::Mat& band,
                              int x_begin, int x_end, int y_begin, int y_end, int* best_x,
                              int* best_y, float* best_score) {
  const int h = t.n / 2;
  x_begin = std::max(x_begin, h);
  y_begin = std::max(y_begin, h);
  x_end = std::min(x_end, band.cols - 1 - h);
  y_end = std::min(y_end, band.rows - 1 - h);
  if (x_end < x_begin || y_end < y_begin) return false;
  const int count = x_end - x_begin + 1;
  const int rows = y_end - y_begin + 1;
  row_.resize(static_cast<std::size_t>(count) * rows);
  ScoreRows(t, band, y_begin, rows, x_begin, count, row_.data());
  float best = -std::numeric_limits<float>::infinity();
  for (int q = 0; q < rows; ++q) {
    const float* scores = row_.data() + static_cast<std::size_t>(q) * count;
    for (int k = 0; k < count; ++k) {
      if (scores[k] > best) {
        best = scores[k];
        *best_x = x_begin + k;
        *best_y = y_begin + q;
      }
    }
  }
  *best_score = best;
  return true;
}

bool Correlator::SearchSegment(const Template& t, const cv::Mat& band,
                               const Eigen::Vector2d& a, const Eigen::Vector2d& b, int band_px,
                               int* best_x, int* best_y, float* best_score) {
  const Eigen::Vector2d d = b - a;
  float best = -std::numeric_limits<float>::infinity();
  bool found = false;
  int bx = 0, by = 0;
  float bs = 0;
  if (std::abs(d.x()) >= std::abs(d.y())) {
    // Mostly horizontal (the usual side-by-side rig): each row holds one run of x.
    const int xa = static_cast<int>(std::floor(std::min(a.x(), b.x())));
    const int xb = static_cast<int>(std::ceil(std::max(a.x(), b.x())));
    const double slope = std::abs(d.x()) > 1e-9 ? d.y() / d.x() : 0.0;
    auto line_y = [&](int x) { return static_cast<int>(std::lround(a.y() + slope * (x - a.x()))); };
    const int ya = std::min(line_y(xa), line_y(xb)) - band_px;
    const int yb = std::max(line_y(xa), line_y(xb)) + band_px;
    if (std::abs(slope) < 1e-6) {
      if (SearchWindow(t, band, xa, xb, ya, yb, &bx, &by, &bs)) {
        *best_x = bx;
        *best_y = by;
        *best_score = bs;
        return true;
      }
      return false;
    }
    for (int y = ya; y <= yb; ++y) {
      // x run where |line_y(x) - y| <= band_px.
      int lo = std::numeric_limits<int>::max(), hi = std::numeric_limits<int>::min();
      for (int x = xa; x <= xb; ++x) {
        if (std::abs(line_y(x) - y) <= band_px) {
          lo = std::min(lo, x);
          hi = std::max(hi, x);
        }
      }
      if (lo > hi) continue;
      if (SearchWindow(t, band, lo, hi, y, y, &bx, &by, &bs) && bs > best) {
        best = bs;
        *best_x = bx;
        *best_y = by;
        found = true;
      }
    }
  } else {
    // Steep line (one camera above the other): a short run of x on each row.
    const int ya = static_cast<int>(std::floor(std::min(a.y(), b.y())));
    const int yb = static_cast<int>(std::ceil(std::max(a.y(), b.y())));
    const double slope = d.x() / d.y();
    for (int y = ya; y <= yb; ++y) {
      const int xc = static_cast<int>(std::lround(a.x() + slope * (y - a.y())));
      if (SearchWindow(t, band, xc - band_px, xc + band_px, y, y, &bx, &by, &bs) &&
          bs > best) {
        best = bs;
        *best_x = bx;
        *best_y = by;
        found = true;
      }
    }
  }
  if (found) *best_score = best;
  return found;
}

void Correlator::Iterate(const Template& t, const cv::Mat& band, int iterations,
                         double covariance_scale, double min_sigma, MatchResult* m) {
  // The biquadratic's bias (peak locking towards whole pixels) vanishes when the peak is
  // centred, so resample the image around the estimate and fit again.
  const int h = t.n / 2;
  for (int it = 0; it < iterations; ++it) {
    const Eigen::Vector2d p = m->position;
    if (p.x() - h - 2 < 0 || p.y() - h - 2 < 0 || p.x() + h + 3 >= band.cols ||
        p.y() + h + 3 >= band.rows) {
      return;
    }
    cv::getRectSubPix(band, cv::Size(t.n + 2, t.n + 2), cv::Point2f(float(p.x()), float(p.y())),
                      patch_, CV_32F);
    float s[3][3];
    ScoreRows(t, patch_, h, 3, h, 3, &s[0][0]);
    Eigen::Vector2d delta;
    Eigen::Matrix2d cov;
    if (!FitBiquadraticPeak(s, covariance_scale, min_sigma, &delta, &cov)) return;
    if (delta.norm() > 0.5) return;
    m->position = p + delta;
    m->covariance = cov;
    m->score = std::max(m->score, s[1][1]);
    if (delta.norm() < 0.01) return;
  }
}

MatchResult Correlator::Refine(const Template& t, const cv::Mat& band, int x, int y,
                               double covariance_scale, double min_sigma) {
  MatchResult m;
  // Hill-climb a few steps if the centre is not the 3x3 maximum (the search may have
  // been coarser, or clipped at its edge).
  float s[3][3];
  for (int step = 0; step < 4; ++step) {
    if (!TemplateFits(x - 1, y - 1, t.n, band.cols, band.rows) ||
        !TemplateFits(x + 1, y + 1, t.n, band.cols, band.rows)) {
      return m;
    }
    const int x0 = x - 1;
    ScoreRows(t, band, y - 1, 3, x0, 3, &s[0][0]);
    int br = 1, bc = 1;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) {
        if (s[r][c] > s[br][bc]) {
          br = r;
          bc = c;
        }
      }
    }
    if (br == 1 && bc == 1) {
      Eigen::Vector2d offset;
      if (!FitBiquadraticPeak(s, covariance_scale, min_sigma, &offset, &m.covariance)) return m;
      m.ok = true;
      m.position = Eigen::Vector2d(x, y) + offset;
      m.score = s[1][1];
      m.best_x = x;
      m.best_y = y;
      return m;
    }
    x += bc - 1;
    y += br - 1;
  }
  return m;
}

}  // namespace rover::vo
