#include "render/image_statistics.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace rover::render {

namespace {

cv::Mat ToFloat(const cv::Mat& image) {
  if (image.empty() || image.channels() != 1) {
    throw std::invalid_argument("image statistics: expected a non-empty one-channel image");
  }
  const int d = image.depth();
  if (d != CV_8U && d != CV_16U && d != CV_32F) {
    throw std::invalid_argument("image statistics: expected CV_8U, CV_16U or CV_32F");
  }
  cv::Mat f;
  image.convertTo(f, CV_32F);
  return f;
}

double Median(const cv::Mat& f) {
  std::vector<float> v;
  v.reserve(f.total());
  for (int r = 0; r < f.rows; ++r) v.insert(v.end(), f.ptr<float>(r), f.ptr<float>(r) + f.cols);
  auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

cv::Mat Scale(const cv::Mat& f, double median, double target) {
  if (!(median > 0)) throw std::invalid_argument("image statistics: the image's median is not positive");
  cv::Mat out;
  f.convertTo(out, CV_32F, target / median);
  return out;
}

}  // namespace

cv::Mat NormaliseToMedian(const cv::Mat& image, double target_median) {
  const cv::Mat f = ToFloat(image);
  return Scale(f, Median(f), target_median);
}

ImageStatistics MeasureImage(const cv::Mat& image, const ImageStatisticsOptions& options) {
  cv::Mat f = ToFloat(image);
  if (f.cols != options.working_width) {
    const double s = static_cast<double>(options.working_width) / f.cols;
    cv::resize(f, f, cv::Size(), s, s, s < 1 ? cv::INTER_AREA : cv::INTER_LINEAR);
  }
  ImageStatistics st;
  // A gain commutes with the (linear) resize, so the median of the working image serves.
  st.median_dn = Median(f);
  const cv::Mat dn = Scale(f, st.median_dn, options.target_median_dn);

  cv::Mat unit;
  dn.convertTo(unit, CV_32F, 1.0 / 255.0);
  cv::Mat harris;
  cv::cornerHarris(unit, harris, 5, 3, 0.04);
  cv::Mat dilated;
  const int d = 2 * options.min_distance_px + 1;
  cv::dilate(harris, dilated, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(d, d)));
  const int border = 8;
  for (int v = border; v < harris.rows - border; ++v) {
    for (int u = border; u < harris.cols - border; ++u) {
      const float r = harris.at<float>(v, u);
      if (r > options.harris_threshold && r >= dilated.at<float>(v, u)) ++st.corners;
    }
  }
  st.corners_per_mpix = st.corners / (harris.rows * static_cast<double>(harris.cols) / 1e6);

  cv::Mat g;
  dn.convertTo(g, CV_64F);
  const cv::Size w(options.window_px, options.window_px);
  cv::Mat mean, mean_sq;
  cv::boxFilter(g, mean, CV_64F, w, cv::Point(-1, -1), true, cv::BORDER_REFLECT);
  cv::boxFilter(g.mul(g), mean_sq, CV_64F, w, cv::Point(-1, -1), true, cv::BORDER_REFLECT);
  cv::Mat var = mean_sq - mean.mul(mean);
  cv::max(var, 0.0, var);
  cv::Mat local_std;
  cv::sqrt(var, local_std);
  cv::Scalar m, s;
  cv::meanStdDev(local_std, m, s);
  // In percent of the median whatever target_median_dn is.
  const double to_percent = 100.0 / options.target_median_dn;
  st.local_std_mean = m[0] * to_percent;
  st.local_std_spread = s[0] * to_percent;
  return st;
}

}  // namespace rover::render
