// VO-2: Harris corners on a grid, then a fixed number of the strongest, each at least a
// minimum distance from the others, so that features span the image.
#pragma once

#include <opencv2/core.hpp>

#include <vector>

namespace rover::vo {

struct Corner {
  int x = 0, y = 0;
  float response = 0;
};

struct CornerOptions {
  double harris_k = 0.04;
  int harris_block = 5;
  int grid_cell_px = 8;
  double min_distance_px = 20.0;
  int count = 300;
  double min_response = 1e-7;
  int border_px = 12;
};

// `image` is CV_32F scaled to [0, 1]. Returns at most options.count corners, strongest
// first, pairwise at least min_distance_px apart. `response` (optional) receives the
// Harris response image.
std::vector<Corner> DetectCorners(const cv::Mat& image, const CornerOptions& options,
                                  cv::Mat* response = nullptr);

}  // namespace rover::vo
