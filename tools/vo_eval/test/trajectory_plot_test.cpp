#include "vo_eval/trajectory_plot.hpp"

#include "plot/gnuplot.hpp"

#include <gtest/gtest.h>

namespace rover::vo_eval {
namespace {

int CountColour(const cv::Mat& img, const cv::Vec3b& colour) {
  int n = 0;
  for (int r = 0; r < img.rows; ++r) {
    for (int c = 0; c < img.cols; ++c) n += img.at<cv::Vec3b>(r, c) == colour;
  }
  return n;
}

TEST(TrajectoryPlot, GridSpacingIsNice) {
  EXPECT_DOUBLE_EQ(GridSpacing(12.0), 2.0);
  EXPECT_DOUBLE_EQ(GridSpacing(37.0), 10.0);
  EXPECT_DOUBLE_EQ(GridSpacing(0.9), 0.2);
  EXPECT_DOUBLE_EQ(GridSpacing(250.0), 50.0);
}

TEST(TrajectoryPlot, DrawsBothPathsWhereTheyAre) {
  if (plot::PngTerminal().empty()) GTEST_SKIP() << "gnuplot is not installed (Debian gnuplot-nox; ./rover setup installs it)";
  PoseList truth, estimate;
  for (int k = 0; k < 50; ++k) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation() = Eigen::Vector3d(0, 0, k);  // straight ahead (KITTI z forward)
    truth.push_back(T);
    T.translation().x() = 0.2 * k;  // drifting right
    estimate.push_back(T);
  }
  const cv::Mat img = DrawTopView(truth, estimate);
  ASSERT_EQ(img.type(), CV_8UC3);
  const int green = CountColour(img, {40, 150, 40});
  const int red = CountColour(img, {30, 30, 220});
  EXPECT_GT(green, 200);
  EXPECT_GT(red, 200);
  // The estimate ends to the right of the truth, both at the top (forward is up).
  int red_top_col = -1, green_top_col = -1;
  for (int r = 0; r < img.rows && (red_top_col < 0 || green_top_col < 0); ++r) {
    for (int c = 0; c < img.cols; ++c) {
      if (red_top_col < 0 && img.at<cv::Vec3b>(r, c) == cv::Vec3b(30, 30, 220) && r > 80) red_top_col = c;
      if (green_top_col < 0 && img.at<cv::Vec3b>(r, c) == cv::Vec3b(40, 150, 40) && r > 80) green_top_col = c;
    }
  }
  EXPECT_GT(red_top_col, green_top_col + 50);
}

TEST(TrajectoryPlot, ParallelAxesThrow) {
  TopViewOptions o;
  o.forward = o.down;
  EXPECT_THROW(DrawTopView({}, {}, o), std::invalid_argument);
}

}  // namespace
}  // namespace rover::vo_eval
