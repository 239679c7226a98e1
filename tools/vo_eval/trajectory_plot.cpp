#include "vo_eval/trajectory_plot.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <vector>

namespace rover::vo_eval {

double GridSpacing(double range, int target_lines) {
  if (!(range > 0.0) || target_lines < 1) return 1.0;
  const double raw = range / target_lines;
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    if (m * p >= raw) return m * p;
  }
  return 10.0 * p;
}

cv::Mat DrawTopView(const PoseList& truth, const PoseList& estimate,
                    const TopViewOptions& options) {
  const Eigen::Vector3d down = options.down.normalized();
  Eigen::Vector3d fwd = options.forward - options.forward.dot(down) * down;
  if (fwd.norm() < 1e-6) throw std::invalid_argument("DrawTopView: down and forward are parallel");
  fwd.normalize();
  const Eigen::Vector3d right = down.cross(fwd);

  auto to2d = [&](const PoseList& poses) {
    std::vector<Eigen::Vector2d> pts;
    for (const auto& T : poses) pts.emplace_back(T.translation().dot(right), T.translation().dot(fwd));
    return pts;
  };
  const std::vector<Eigen::Vector2d> pt = to2d(truth), pe = to2d(estimate);

  Eigen::Vector2d lo(0, 0), hi(0, 0);
  bool first = true;
  for (const auto* v : {&pt, &pe}) {
    for (const Eigen::Vector2d& p : *v) {
      if (!p.allFinite()) continue;
      lo = first ? p : lo.cwiseMin(p);
      hi = first ? p : hi.cwiseMax(p);
      first = false;
    }
  }
  // Equal scale: a square window around the data, at least 2 m wide.
  const Eigen::Vector2d centre = 0.5 * (lo + hi);
  const double span = std::max({hi.x() - lo.x(), hi.y() - lo.y(), 2.0}) * 1.1;
  const int S = std::max(200, options.size_px);
  const int margin_left = 70, margin_bottom = 50, margin_top = 40, margin_right = 20;
  const int plot = S - std::max(margin_left + margin_right, margin_top + margin_bottom);
  const double scale = plot / span;
  const double x0 = centre.x() - 0.5 * span, y0 = centre.y() - 0.5 * span;
  auto px = [&](const Eigen::Vector2d& p) {
    return cv::Point(static_cast<int>(std::lround(margin_left + (p.x() - x0) * scale)),
                     static_cast<int>(std::lround(margin_top + plot - (p.y() - y0) * scale)));
  };

  cv::Mat img(S, S, CV_8UC3, cv::Scalar(255, 255, 255));
  const cv::Scalar grid(225, 225, 225), axis(60, 60, 60), text(30, 30, 30);
  const cv::Scalar truth_colour(40, 150, 40), est_colour(30, 30, 220);
  const double spacing = GridSpacing(span);
  char label[64];
  for (double g = std::ceil(x0 / spacing) * spacing; g <= x0 + span; g += spacing) {
    const int x = px({g, y0}).x;
    cv::line(img, {x, margin_top}, {x, margin_top + plot}, grid, 1);
    std::snprintf(label, sizeof(label), "%g", std::abs(g) < 1e-9 ? 0.0 : g);
    cv::putText(img, label, {x - 12, margin_top + plot + 18}, cv::FONT_HERSHEY_SIMPLEX, 0.4, text, 1,
                cv::LINE_AA);
  }
  for (double g = std::ceil(y0 / spacing) * spacing; g <= y0 + span; g += spacing) {
    const int y = px({x0, g}).y;
    cv::line(img, {margin_left, y}, {margin_left + plot, y}, grid, 1);
    std::snprintf(label, sizeof(label), "%g", std::abs(g) < 1e-9 ? 0.0 : g);
    cv::putText(img, label, {8, y + 4}, cv::FONT_HERSHEY_SIMPLEX, 0.4, text, 1, cv::LINE_AA);
  }
  cv::rectangle(img, {margin_left, margin_top}, {margin_left + plot, margin_top + plot}, axis, 1);
  cv::putText(img, "right of start heading (m)", {margin_left + plot / 2 - 100, S - 12},
              cv::FONT_HERSHEY_SIMPLEX, 0.45, text, 1, cv::LINE_AA);
  cv::putText(img, "forward (m)", {8, margin_top - 10}, cv::FONT_HERSHEY_SIMPLEX, 0.45, text, 1,
              cv::LINE_AA);
  if (!options.title.empty()) {
    cv::putText(img, options.title, {margin_left + 100, margin_top - 12}, cv::FONT_HERSHEY_SIMPLEX,
                0.5, text, 1, cv::LINE_AA);
  }

  auto polyline = [&](const std::vector<Eigen::Vector2d>& pts, const cv::Scalar& colour, int width) {
    std::vector<cv::Point> cv_pts;
    for (const auto& p : pts) {
      if (p.allFinite()) cv_pts.push_back(px(p));
    }
    if (cv_pts.size() >= 2) cv::polylines(img, cv_pts, false, colour, width, cv::LINE_AA);
    if (!cv_pts.empty()) cv::circle(img, cv_pts.front(), 5, colour, 2, cv::LINE_AA);
  };
  // The truth is drawn wider, underneath, so that it stays visible where the two agree.
  polyline(pt, truth_colour, 5);
  polyline(pe, est_colour, 2);

  // Legend, top left inside the plot.
  const int lx = margin_left + 12, ly = margin_top + 20;
  cv::rectangle(img, {lx - 6, ly - 14}, {lx + 150, ly + (truth.empty() ? 10 : 30)},
                cv::Scalar(255, 255, 255), cv::FILLED);
  cv::rectangle(img, {lx - 6, ly - 14}, {lx + 150, ly + (truth.empty() ? 10 : 30)}, axis, 1);
  cv::line(img, {lx, ly - 4}, {lx + 30, ly - 4}, est_colour, 2, cv::LINE_AA);
  cv::putText(img, "VO estimate", {lx + 38, ly}, cv::FONT_HERSHEY_SIMPLEX, 0.45, text, 1, cv::LINE_AA);
  if (!truth.empty()) {
    cv::line(img, {lx, ly + 16}, {lx + 30, ly + 16}, truth_colour, 2, cv::LINE_AA);
    cv::putText(img, "ground truth", {lx + 38, ly + 20}, cv::FONT_HERSHEY_SIMPLEX, 0.45, text, 1,
                cv::LINE_AA);
  }
  return img;
}

}  // namespace rover::vo_eval
