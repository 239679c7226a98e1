#include "chessboard_render.hpp"

#include <opencv2/imgproc.hpp>

#include <cmath>
#include <limits>

namespace rover::calib::test {

namespace {

constexpr double kDark = 30, kLight = 220, kBackground = 120;

// The square cell of the board plane a point lies in: the board's value is constant on
// each cell (squares, the margin and the background all have edges on the same grid).
struct Cell {
  long i = 0, j = 0;
  bool valid = false;
  bool operator==(const Cell& o) const { return valid && o.valid && i == o.i && j == o.j; }
};

Cell CellOf(const Chessboard& board, const Eigen::Vector2d& uv) {
  if (!std::isfinite(uv.x()) || !std::isfinite(uv.y())) return {};
  return {static_cast<long>(std::floor(uv.x() / board.square)), static_cast<long>(std::floor(uv.y() / board.square)),
          true};
}

// Where the ray through each pixel corner (c - 0.5, r - 0.5) meets the board plane, in
// board coordinates; NaN where it does not (the board behind the camera, or a pixel
// outside the model's domain). (width + 1) x (height + 1) points.
cv::Mat_<cv::Vec2d> BoardAtPixelCorners(const geometry::CameraModel& camera, const Eigen::Isometry3d& T_ref_board,
                                        const cv::Rect& box) {
  const Eigen::Isometry3d T_board_ref = T_ref_board.inverse();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  cv::Mat_<cv::Vec2d> uv(box.height + 1, box.width + 1);
  for (int r = 0; r <= box.height; ++r) {
    for (int c = 0; c <= box.width; ++c) {
      Eigen::Vector3d origin, direction;
      camera.BackProject({box.x + c - 0.5, box.y + r - 0.5}, &origin, &direction);
      const Eigen::Vector3d o = T_board_ref * origin, d = T_board_ref.linear() * direction;
      const double t = -o.z() / d.z();
      if (!(t > 0) || !std::isfinite(t)) {
        uv(r, c) = {nan, nan};
        continue;
      }
      uv(r, c) = {o.x() + t * d.x(), o.y() + t * d.y()};
    }
  }
  return uv;
}

// The pixels the board (with its margin) can cover: the box round its outline, traced
// eight points a square, and two pixels beyond (the outline's curvature between points).
// Only these are rendered; the rest of the image is background.
cv::Rect BoardBox(const geometry::CameraModel& camera, const Chessboard& board, const Eigen::Isometry3d& T_ref_board) {
  const double u0 = -2 * board.square, u1 = (board.cols + 1) * board.square;
  const double v0 = -2 * board.square, v1 = (board.rows + 1) * board.square;
  std::vector<cv::Point2f> outline;
  auto add = [&](double u, double v) {
    Eigen::Vector2d px;
    if (camera.Project(T_ref_board * Eigen::Vector3d(u, v, 0), &px)) {
      outline.emplace_back(static_cast<float>(px.x()), static_cast<float>(px.y()));
    }
  };
  const int n = 8 * (board.cols + board.rows + 6);
  for (int k = 0; k <= n; ++k) {
    const double a = static_cast<double>(k) / n;
    add(u0 + a * (u1 - u0), v0);
    add(u0 + a * (u1 - u0), v1);
    add(u0, v0 + a * (v1 - v0));
    add(u1, v0 + a * (v1 - v0));
  }
  const cv::Rect image(0, 0, camera.width(), camera.height());
  if (outline.empty()) return image;
  const cv::Rect box = cv::boundingRect(outline);
  return cv::Rect(box.x - 2, box.y - 2, box.width + 4, box.height + 4) & image;
}

Eigen::Vector2d At(const cv::Mat_<cv::Vec2d>& uv, int r, int c) { return {uv(r, c)[0], uv(r, c)[1]}; }

// The mean of the board over one pixel. Within a pixel the map from the image to the board
// is bilinear in its four corners to far below a thousandth of a pixel, so the pixel is one
// value when its corners share a cell (a cell is convex), and otherwise the mean of n x n
// samples spread evenly over it.
double PixelValue(const Chessboard& board, const cv::Mat_<cv::Vec2d>& uv, int r, int c, int n) {
  const Eigen::Vector2d q00 = At(uv, r, c), q10 = At(uv, r, c + 1), q01 = At(uv, r + 1, c), q11 = At(uv, r + 1, c + 1);
  const Cell cell = CellOf(board, q00);
  if (!cell.valid) return kBackground;
  if (cell == CellOf(board, q10) && cell == CellOf(board, q01) && cell == CellOf(board, q11)) {
    const Eigen::Vector2d mid = 0.25 * (q00 + q10 + q01 + q11);
    return board.ValueAt(mid.x(), mid.y());
  }
  double sum = 0;
  for (int a = 0; a < n; ++a) {
    const double y = (a + 0.5) / n;
    for (int b = 0; b < n; ++b) {
      const double x = (b + 0.5) / n;
      const Eigen::Vector2d p = (1 - y) * ((1 - x) * q00 + x * q10) + y * ((1 - x) * q01 + x * q11);
      sum += board.ValueAt(p.x(), p.y());
    }
  }
  return sum / (n * n);
}

}  // namespace

double Chessboard::ValueAt(double u, double v) const {
  const double i = std::floor(u / square), j = std::floor(v / square);
  if (i < -2 || j < -2 || i > cols || j > rows) return kBackground;
  if (i < -1 || j < -1 || i > cols - 1 || j > rows - 1) return kLight;
  return static_cast<long>(i + j) % 2 == 0 ? kDark : kLight;
}

cv::Mat RenderChessboard(const geometry::CameraModel& camera, const Chessboard& board,
                         const Eigen::Isometry3d& T_ref_board, const RenderOptions& options) {
  const cv::Rect box = BoardBox(camera, board, T_ref_board);
  const cv::Mat_<cv::Vec2d> uv = BoardAtPixelCorners(camera, T_ref_board, box);
  cv::Mat_<float> image(camera.height(), camera.width(), static_cast<float>(kBackground));
  for (int r = 0; r < box.height; ++r) {
    for (int c = 0; c < box.width; ++c) {
      image(box.y + r, box.x + c) = static_cast<float>(PixelValue(board, uv, r, c, options.supersampling));
    }
  }
  if (options.blur_sigma > 0) {
    cv::GaussianBlur(image, image, cv::Size(0, 0), options.blur_sigma, options.blur_sigma, cv::BORDER_REPLICATE);
  }
  cv::Mat out;
  image.convertTo(out, CV_8U);  // rounds to the nearest level
  return out;
}

bool ExactCorners(const geometry::CameraModel& camera, const Chessboard& board, const Eigen::Isometry3d& T_ref_board,
                  std::vector<cv::Point2f>* corners, double margin_px) {
  auto inside = [&](const Eigen::Vector3d& p_board, Eigen::Vector2d* px) {
    return camera.Project(T_ref_board * p_board, px) && px->x() >= margin_px &&
           px->y() >= margin_px && px->x() <= camera.width() - 1 - margin_px &&
           px->y() <= camera.height() - 1 - margin_px;
  };
  Eigen::Vector2d px;
  // The light margin's outer edge, a point every square along it.
  for (int i = -2; i <= board.cols + 1; ++i) {
    for (int j : {-2, board.rows + 1}) {
      if (!inside(Eigen::Vector3d(i * board.square, j * board.square, 0), &px)) return false;
    }
  }
  for (int j = -2; j <= board.rows + 1; ++j) {
    for (int i : {-2, board.cols + 1}) {
      if (!inside(Eigen::Vector3d(i * board.square, j * board.square, 0), &px)) return false;
    }
  }
  corners->clear();
  for (int j = 0; j < board.rows; ++j) {
    for (int i = 0; i < board.cols; ++i) {
      if (!inside(board.Corner(i, j), &px)) return false;
      corners->emplace_back(static_cast<float>(px.x()), static_cast<float>(px.y()));
    }
  }
  return true;
}

}  // namespace rover::calib::test
