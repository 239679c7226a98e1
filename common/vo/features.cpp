#include "vo/features.hpp"
#include "vo/simd.hpp"

#include <opencv2/imgproc.hpp>

#include <immintrin.h>

#include <algorithm>
#include <vector>
#include <cmath>

namespace rover::vo {

namespace {

// The grid pass (VO-2): the strongest 3x3 local maximum in each cell (the paper's grid,
// whose cells are smaller than the minimum distance, so no cell can hold two features),
// in `best` (gx cells a row, row-major; a cell without a peak keeps response 0). It runs
// row by row as the Harris response is made, three response rows at a time, so the
// response image is never written out and read back.
struct PeakScan {
  int x_begin = 0, x_end = 0, y_begin = 0, y_end = 0;  // ends exclusive
  int cell = 1, gx = 0;
  float floor = 0;
  Corner* best = nullptr;
  float* peak_value = nullptr;  // one row's scratch, the image's width
};

// The local-maximum test of one row, eight pixels at a time from x, as many as fit before
// x_end; returns where it stopped. std::max(p, q) is (p < q) ? q : p, which is
// _mm256_max_ps(q, p) exactly (NaN and signed zeros included), so the values are the
// portable loop's; the compiler left that loop scalar, with a branch per pixel.
__attribute__((target("avx2"), always_inline)) inline __m256 StdMax(__m256 p, __m256 q) { return _mm256_max_ps(q, p); }

__attribute__((target("avx2"))) int PeakValuesAvx2(const float* above, const float* row, const float* below, int x,
                                                   int x_end, float floor, float* pv) {
  const __m256 f = _mm256_set1_ps(floor);
  for (; x + 8 <= x_end; x += 8) {
    const __m256 v = _mm256_loadu_ps(row + x);
    __m256 m = StdMax(StdMax(_mm256_loadu_ps(above + x - 1), _mm256_loadu_ps(above + x)),
                   StdMax(_mm256_loadu_ps(above + x + 1), _mm256_loadu_ps(row + x - 1)));
    m = StdMax(m, StdMax(StdMax(_mm256_loadu_ps(row + x + 1), _mm256_loadu_ps(below + x - 1)),
                   StdMax(_mm256_loadu_ps(below + x), _mm256_loadu_ps(below + x + 1))));
    const __m256 peak = _mm256_and_ps(_mm256_cmp_ps(v, m, _CMP_GE_OQ), _mm256_cmp_ps(v, f, _CMP_GT_OQ));
    _mm256_storeu_ps(pv + x, _mm256_and_ps(peak, v));
  }
  return x;
}

// The grid pass's cells of eight (the default), as many whole ones as the row holds from
// *x0: the largest value of each (a maximum: any order gives it, pv holds no NaN and no
// -0), and the first pixel holding it when it beats the cell's best. Returns the next
// cell's index and leaves *x0 at its start.
__attribute__((target("avx2"))) int CellsOfEightAvx2(const float* pv, int y, int x_end, Corner* cell_row, int* x0) {
  int i = 0;
  for (; *x0 + 8 <= x_end; ++i, *x0 += 8) {
    const __m256 v = _mm256_loadu_ps(pv + *x0);
    __m128 m = _mm_max_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps(v, 1));
    m = _mm_max_ps(m, _mm_movehl_ps(m, m));
    m = _mm_max_ss(m, _mm_shuffle_ps(m, m, 1));
    const float run_max = _mm_cvtss_f32(m);
    Corner& b = cell_row[i];
    if (run_max <= b.response) continue;  // 0 (no peak) never beats a cell's start of 0
    int first = *x0;
    while (pv[first] != run_max) ++first;
    b.x = first;
    b.y = y;
    b.response = run_max;
  }
  return i;
}

// Row y of the grid pass, from the response rows above, at and below it. Per row, first
// (vectorised): a pixel's value where it is a 3x3 local maximum above the floor, else 0.
// Then per cell run: the largest, first on ties (raster order, as a pixel-by-pixel scan
// with a strict comparison would keep). Only comparisons: every build gives the same
// cells. (A dilation of the whole image and a branchy per-pixel scan each cost more than
// the Harris response.)
__attribute__((target_clones("avx2", "default")))
void PeakRow(const float* above, const float* row, const float* below, int y, const PeakScan& s) {
  float* __restrict pv = s.peak_value;
  int x = s.x_begin;
  if (UseAvx2()) x = PeakValuesAvx2(above, row, below, x, s.x_end, s.floor, pv);
  for (; x < s.x_end; ++x) {
    const float v = row[x];
    float m = std::max(std::max(above[x - 1], above[x]), std::max(above[x + 1], row[x - 1]));
    m = std::max(m, std::max(std::max(row[x + 1], below[x - 1]), std::max(below[x], below[x + 1])));
    pv[x] = (v >= m && v > s.floor) ? v : 0.0f;
  }
  Corner* cell_row = s.best + static_cast<std::size_t>((y - s.y_begin) / s.cell) * s.gx;
  int i = 0, x0 = s.x_begin;
  if (s.cell == 8 && UseAvx2()) i = CellsOfEightAvx2(pv, y, s.x_end, cell_row, &x0);
  for (; x0 < s.x_end; ++i, x0 += s.cell) {
    Corner& b = cell_row[i];
    const int x1 = std::min(x0 + s.cell, s.x_end);
    float m0 = pv[x0], m1 = m0, m2 = m0, m3 = m0;  // four chains, not one serial max
    int x = x0 + 1;
    for (; x + 4 <= x1; x += 4) {
      m0 = std::max(m0, pv[x]);
      m1 = std::max(m1, pv[x + 1]);
      m2 = std::max(m2, pv[x + 2]);
      m3 = std::max(m3, pv[x + 3]);
    }
    for (; x < x1; ++x) m0 = std::max(m0, pv[x]);
    const float run_max = std::max(std::max(m0, m1), std::max(m2, m3));
    if (run_max <= b.response) continue;  // 0 (no peak) never beats a cell's start of 0
    int first = x0;
    while (pv[first] != run_max) ++first;
    b.x = first;
    b.y = y;
    b.response = run_max;
  }
}

// The Harris response row by row, into `response` when given (else three rows kept), each
// row handed to the grid pass (`scan`) once the row below it is made.
__attribute__((target_clones("avx2", "default")))
void HarrisResponse(const cv::Mat& image, int n, float k, cv::Mat* response, const PeakScan& scan) {
  const int W = image.cols, H = image.rows, h = n / 2;
  // Binomial window weights (a Gaussian of sigma ~ sqrt(n-1)/2; 1 4 6 4 1 for n = 5).
  float w[64];
  w[0] = 1.0f;
  for (int i = 1; i < n; ++i) {
    w[i] = 0.0f;
    for (int j = i; j > 0; --j) w[j] += w[j - 1];
  }
  float total = 0;
  for (int i = 0; i < n; ++i) total += w[i];
  for (int i = 0; i < n; ++i) w[i] /= total;
  // Gradient products stream through a ring of n rows (gx^2 | gx*gy | gy^2, each W wide),
  // so the window pass reads from cache: the whole product image (5 MB at KITTI size) did
  // not fit, and memory traffic cost more than the arithmetic.
  thread_local std::vector<float> ring;
  ring.resize(static_cast<std::size_t>(n) * 3 * W);
  auto slot = [&](int y) { return ring.data() + static_cast<std::size_t>(y % n) * 3 * W; };
  auto products_of = [&](int y) __attribute__((always_inline)) {
    const float* up = image.ptr<float>(std::max(0, y - 1));
    const float* row = image.ptr<float>(y);
    const float* down = image.ptr<float>(std::min(H - 1, y + 1));
    float* __restrict xx = slot(y);
    float* __restrict xy = xx + W;
    float* __restrict yy = xy + W;
#pragma GCC ivdep
    for (int x = 1; x < W - 1; ++x) {
      // 3x3 Sobel, scaled to intensity per pixel.
      const float gx = 0.125f * ((up[x + 1] - up[x - 1]) + 2.0f * (row[x + 1] - row[x - 1]) +
                                 (down[x + 1] - down[x - 1]));
      const float gy = 0.125f * ((down[x - 1] - up[x - 1]) + 2.0f * (down[x] - up[x]) +
                                 (down[x + 1] - up[x + 1]));
      xx[x] = gx * gx;
      xy[x] = gx * gy;
      yy[x] = gy * gy;
    }
    xx[0] = xy[0] = yy[0] = xx[W - 1] = xy[W - 1] = yy[W - 1] = 0.0f;
  };
  int next_row = 0;  // the next image row whose products are not yet in the ring
  // Separable window: weighted rows, then weighted shifted columns, three planes at once.
  thread_local std::vector<float> column, sum;
  column.resize(3 * W);
  sum.resize(3 * W);
  auto plane_row = [&](int y) -> const float* { return slot(std::clamp(y, 0, H - 1)); };
  thread_local std::vector<float> kept_rows;
  if (response) {
    response->create(H, W, CV_32F);
  } else {
    kept_rows.resize(static_cast<std::size_t>(3) * W);
  }
  auto out_row = [&](int y) {
    return response ? response->ptr<float>(y) : kept_rows.data() + static_cast<std::size_t>(y % 3) * W;
  };
  for (int y = 0; y < H; ++y) {
    for (const int last = std::min(H - 1, y + h); next_row <= last; ++next_row) {
      products_of(next_row);
    }
    float* __restrict c = column.data();
    if (n == 5) {  // the default: one pass, one store per element
      const float* __restrict r0 = plane_row(y - 2);
      const float* __restrict r1 = plane_row(y - 1);
      const float* __restrict r2 = plane_row(y);
      const float* __restrict r3 = plane_row(y + 1);
      const float* __restrict r4 = plane_row(y + 2);
      for (int x = 0; x < 3 * W; ++x) {
        c[x] = w[0] * (r0[x] + r4[x]) + w[1] * (r1[x] + r3[x]) + w[2] * r2[x];
      }
    } else {
      std::fill(c, c + 3 * W, 0.0f);
      for (int j = -h; j <= h; ++j) {
        const float wj = w[j + h];
        const float* __restrict r = plane_row(y + j);
        for (int x = 0; x < 3 * W; ++x) c[x] += wj * r[x];
      }
    }
    float* __restrict s = sum.data();
    const bool five = n == 5 && W > 4;
    // Five taps write every column but the two at each edge, which stay 0 (inside the
    // feature border); any other width adds into zeros.
    if (five) {
      for (int p = 0; p < 3; ++p) s[p * W] = s[p * W + 1] = s[p * W + W - 2] = s[p * W + W - 1] = 0.0f;
    } else {
      std::fill(s, s + 3 * W, 0.0f);
    }
    for (int p = 0; p < 3; ++p) {
      const float* cp = column.data() + p * W;
      float* __restrict sp = s + p * W;
      if (five) {
        for (int x = 2; x < W - 2; ++x) {
          sp[x] = w[0] * (cp[x - 2] + cp[x + 2]) + w[1] * (cp[x - 1] + cp[x + 1]) + w[2] * cp[x];
        }
        continue;
      }
      for (int j = -h; j <= h; ++j) {
        const float wj = w[j + h];
        const int lo = std::max(0, -j), hi = std::min(W, W - j);
        const float* __restrict cj = cp + j;
        for (int x = lo; x < hi; ++x) sp[x] += wj * cj[x];
      }
    }
    const float* a = s;
    const float* b = s + W;
    const float* cc = s + 2 * W;
    float* __restrict r = out_row(y);
    for (int x = 0; x < W; ++x) {
      const float t = a[x] + cc[x];
      r[x] = a[x] * cc[x] - b[x] * b[x] - k * t * t;
    }
    if (y - 1 >= scan.y_begin && y - 1 < scan.y_end) PeakRow(out_row(y - 2), out_row(y - 1), r, y - 1, scan);
  }
}

}  // namespace

std::vector<Corner> DetectCorners(const cv::Mat& image, const CornerOptions& options,
                                  cv::Mat* response_out) {
  CV_Assert(image.type() == CV_32FC1);
  // Harris: structure tensor of 3x3 Sobel gradients (intensity per pixel), weighted by
  // a binomial (Gaussian-like) window of side harris_block, response det - k trace^2. Written out, fused
  // and vectorised: cv::cornerHarris took ~11 ms on a 1226x370 float image on one core.
  PeakScan scan;
  scan.cell = std::max(1, options.grid_cell_px);
  const int border = std::max(options.border_px, 1);
  scan.x_begin = border;
  scan.x_end = image.cols - border;
  scan.y_begin = border;
  scan.y_end = image.rows - border;
  std::vector<Corner> candidates;
  if (scan.x_end <= scan.x_begin || scan.y_end <= scan.y_begin) {
    // No room for a corner: the response alone, when asked for.
    if (response_out) {
      scan.y_end = scan.y_begin;
      HarrisResponse(image, options.harris_block | 1, static_cast<float>(options.harris_k), response_out, scan);
    }
    return candidates;
  }
  scan.gx = (scan.x_end - scan.x_begin + scan.cell - 1) / scan.cell;
  const int gy = (scan.y_end - scan.y_begin + scan.cell - 1) / scan.cell;
  std::vector<Corner> best(static_cast<std::size_t>(scan.gx) * gy);
  thread_local std::vector<float> peak_value;
  peak_value.assign(image.cols, 0.0f);
  scan.floor = static_cast<float>(options.min_response);
  scan.best = best.data();
  scan.peak_value = peak_value.data();
  HarrisResponse(image, options.harris_block | 1, static_cast<float>(options.harris_k), response_out, scan);
  for (const Corner& c : best) {
    if (c.response > 0) candidates.push_back(c);
  }
  std::sort(candidates.begin(), candidates.end(),
            [](const Corner& a, const Corner& b) { return a.response > b.response; });

  // Greedy selection with the minimum distance, through an occupancy grid whose cell
  // diagonal equals the distance: a cell holds at most one feature, and a neighbour
  // closer than the distance lies within two cells.
  const double dmin = std::max(1.0, options.min_distance_px);
  const double dmin2 = dmin * dmin;
  const int ocell = std::max(1, static_cast<int>(std::floor(dmin / std::sqrt(2.0))));
  const int ox = image.cols / ocell + 1, oy = image.rows / ocell + 1;
  std::vector<int> occupant(static_cast<std::size_t>(ox) * oy, -1);
  std::vector<Corner> kept;
  kept.reserve(options.count);
  for (const Corner& c : candidates) {
    if (static_cast<int>(kept.size()) >= options.count) break;
    const int cx = c.x / ocell, cy = c.y / ocell;
    bool free = true;
    for (int j = std::max(0, cy - 2); free && j <= std::min(oy - 1, cy + 2); ++j) {
      for (int i = std::max(0, cx - 2); i <= std::min(ox - 1, cx + 2); ++i) {
        const int k = occupant[j * ox + i];
        if (k < 0) continue;
        const double dx = kept[k].x - c.x, dy = kept[k].y - c.y;
        if (dx * dx + dy * dy < dmin2) {
          free = false;
          break;
        }
      }
    }
    if (!free) continue;
    occupant[cy * ox + cx] = static_cast<int>(kept.size());
    kept.push_back(c);
  }
  return kept;
}

}  // namespace rover::vo
