#include "vo/features.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

namespace rover::vo {

std::vector<Corner> DetectCorners(const cv::Mat& image, const CornerOptions& options,
                                  cv::Mat* response_out) {
  CV_Assert(image.type() == CV_32FC1);
  // Harris: structure tensor of Sobel gradients (scaled to intensity per pixel), summed
  // over a Gaussian window of side harris_block. Written out because cv::cornerHarris
  // took ~11 ms on a 1226x370 float image on one core; this takes about 4.
  thread_local cv::Mat dx, dy, xx, xy, yy, sxx, sxy, syy;
  cv::Mat local_response;
  cv::Mat& response = response_out ? *response_out : local_response;
  cv::Sobel(image, dx, CV_32F, 1, 0, 3, 1.0 / 8.0, 0, cv::BORDER_REFLECT);
  cv::Sobel(image, dy, CV_32F, 0, 1, 3, 1.0 / 8.0, 0, cv::BORDER_REFLECT);
  cv::multiply(dx, dx, xx);
  cv::multiply(dx, dy, xy);
  cv::multiply(dy, dy, yy);
  const int block = options.harris_block | 1;
  cv::GaussianBlur(xx, sxx, cv::Size(block, block), 0, 0, cv::BORDER_REFLECT);
  cv::GaussianBlur(xy, sxy, cv::Size(block, block), 0, 0, cv::BORDER_REFLECT);
  cv::GaussianBlur(yy, syy, cv::Size(block, block), 0, 0, cv::BORDER_REFLECT);
  response.create(image.size(), CV_32F);
  const float k = static_cast<float>(options.harris_k);
  for (int y = 0; y < image.rows; ++y) {
    const float* a = sxx.ptr<float>(y);
    const float* b = sxy.ptr<float>(y);
    const float* c = syy.ptr<float>(y);
    float* __restrict r = response.ptr<float>(y);
    for (int x = 0; x < image.cols; ++x) {
      r[x] = a[x] * c[x] - b[x] * b[x] - k * (a[x] + c[x]) * (a[x] + c[x]);
    }
  }

  // Grid pass: the strongest 3x3 local maximum in each cell (the paper's grid, whose
  // cells are smaller than the minimum distance, so no cell can hold two features).
  const int cell = std::max(1, options.grid_cell_px);
  const int border = std::max(options.border_px, 1);
  const int x_begin = border, x_end = image.cols - border;  // exclusive
  const int y_begin = border, y_end = image.rows - border;
  std::vector<Corner> candidates;
  if (x_end <= x_begin || y_end <= y_begin) return candidates;
  const int gx = (x_end - x_begin + cell - 1) / cell, gy = (y_end - y_begin + cell - 1) / cell;
  std::vector<Corner> best(static_cast<std::size_t>(gx) * gy);
  const float floor = static_cast<float>(options.min_response);
  for (int y = y_begin; y < y_end; ++y) {
    const float* up = response.ptr<float>(y - 1);
    const float* row = response.ptr<float>(y);
    const float* down = response.ptr<float>(y + 1);
    Corner* cell_row = best.data() + static_cast<std::size_t>((y - y_begin) / cell) * gx;
    for (int x = x_begin; x < x_end; ++x) {
      const float v = row[x];
      if (v <= floor) continue;
      Corner& b = cell_row[(x - x_begin) / cell];
      if (v <= b.response) continue;
      if (v < row[x - 1] || v < row[x + 1] || v < up[x - 1] || v < up[x] || v < up[x + 1] ||
          v < down[x - 1] || v < down[x] || v < down[x + 1]) {
        continue;
      }
      b.x = x;
      b.y = y;
      b.response = v;
    }
  }
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
