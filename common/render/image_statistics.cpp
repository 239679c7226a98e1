#include "render/image_statistics.hpp"

#include <opencv2/imgproc.hpp>

#include <cmath>
#include <stdexcept>

namespace rover::render {

cv::Mat To8Bit(const cv::Mat& image) {
  if (image.channels() != 1) throw std::invalid_argument("To8Bit: expected a one-channel image");
  if (image.depth() == CV_8U) return image;
  double lo = 0, hi = 0;
  cv::minMaxLoc(image, &lo, &hi);
  if (hi <= lo) hi = lo + 1;
  cv::Mat out;
  image.convertTo(out, CV_8U, 255.0 / (hi - lo), -255.0 * lo / (hi - lo));
  return out;
}

ImageStatistics MeasureImage(const cv::Mat& image, const ImageStatisticsOptions& options) {
  cv::Mat img8 = To8Bit(image);
  if (img8.cols != options.working_width) {
    const double s = static_cast<double>(options.working_width) / img8.cols;
    cv::resize(img8, img8, cv::Size(), s, s, s < 1 ? cv::INTER_AREA : cv::INTER_LINEAR);
  }
  cv::Mat f;
  img8.convertTo(f, CV_32F, 1.0 / 255.0);
  ImageStatistics st;

  cv::Mat harris;
  cv::cornerHarris(f, harris, 5, 3, 0.04);
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
  img8.convertTo(g, CV_64F);
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
  st.local_std_mean = m[0];
  st.local_std_spread = s[0];
  return st;
}

}  // namespace rover::render
