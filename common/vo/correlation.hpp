// VO-3: pseudo-normalized correlation, 2*sum(ab) / (sum(a^2) + sum(b^2)), on band-passed
// images, with a biquadratic sub-pixel peak whose curvatures give the match covariance.
//
// OpenCV's matchTemplate has no pseudo-normalized score (TM_CCOEFF_NORMED divides by the
// geometric mean, which rewards a weak patch matching a strong one), so the cross term is
// written here. It is computed for a whole run of positions on one row at a time: the
// template pixel is the outer loop and the positions the inner, contiguous loop, which
// the compiler vectorises. sum(b^2) comes from one box filter of the squared image.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <vector>

namespace rover::vo {

// Band-pass: Gaussian(sigma) minus box mean(box_px). Input CV_32F; output CV_32F.
// `out` and `scratch` are reused between calls (no allocation once sized).
void BandPass(const cv::Mat& image, double sigma, int box_px, cv::Mat* out, cv::Mat* scratch);
cv::Mat BandPass(const cv::Mat& image, double sigma, int box_px);

// A template of side n copied out of a band-passed image, with its sum of squares.
struct Template {
  int n = 0;
  std::vector<float> pixels;  // n*n, row-major
  double sum_sq = 0;
  // Integer centre. Returns false if the template does not fit.
  bool Extract(const cv::Mat& band, int x, int y, int side);
  // Bilinear, at a sub-pixel centre.
  bool ExtractSubpixel(const cv::Mat& band, double x, double y, int side);
  // Bilinear, at a sub-pixel centre, template pixel (dx, dy) from the centre taken at
  // centre + warp * (dx, dy) in the band: the patch as a camera that sees it distorted by
  // warp^-1 would see it. Sampled by hand, not with cv::warpAffine (or cv::remap), which
  // rounds the sampling position to 1/32 px (measured: a shift of 0.01 px gives no change,
  // 0.02 px gives 0.031 px): a tracked point is wanted to a few hundredths of a pixel. It
  // costs the same (0.9 us against 1.3 us for an 11x11 template).
  bool ExtractWarped(const cv::Mat& band, double x, double y, const Eigen::Matrix2d& warp, int side);
};

// Scores for centres (x0..x0+count-1, y). All centres must leave the template inside
// the image (the caller clips). `out` receives count scores. sum(b^2) is formed from
// column sums slid along the row, which costs 1/n of the cross term.
void ScoreRow(const Template& t, const cv::Mat& band, int y, int x0, int count, float* out);
// The same for rows y..y+rows-1 (row q's scores at out + q * count), each score exactly
// as ScoreRow gives it; the rows' cross terms are formed together, which a small window
// of centres (the tracker's 5x5, the refinement's 3x3) needs to keep the core busy.
void ScoreRows(const Template& t, const cv::Mat& band, int y, int rows, int x0, int count, float* out);
float ScoreAt(const Template& t, const cv::Mat& band, int x, int y);

// Whether a template centred at (x, y) fits inside an image of the given size.
inline bool TemplateFits(int x, int y, int n, int width, int height) {
  const int h = n / 2;
  return x - h >= 0 && y - h >= 0 && x + h < width && y + h < height;
}

// Biquadratic f = a + bx + cy + dx^2 + exy + fy^2 fitted by least squares to the 3x3
// scores s[row][col] (row = dy+1, col = dx+1). On success `offset` is the peak relative
// to the centre and `covariance` = scale * (-Hessian)^-1, each axis floored at
// min_sigma^2. Fails when the surface is not a peak or the peak is over 1 px away.
bool FitBiquadraticPeak(const float s[3][3], double covariance_scale, double min_sigma,
                        Eigen::Vector2d* offset, Eigen::Matrix2d* covariance);

struct MatchResult {
  bool ok = false;
  Eigen::Vector2d position;  // sub-pixel
  Eigen::Matrix2d covariance;
  float score = 0;
  int best_x = 0, best_y = 0;
};

class Correlator {
 public:
  // Searches the rectangle [x_begin, x_end] x [y_begin, y_end] of centres, clipped to the
  // image; returns the best integer centre and its score (no refinement).
  bool SearchWindow(const Template& t, const cv::Mat& band,
                    int x_begin, int x_end, int y_begin, int y_end, int* best_x, int* best_y,
                    float* best_score);
  // Searches the centres along a segment from a to b (image coordinates), `band_px` rows
  // (or columns, for a steep line) either side. Refine() then climbs to the 2-D peak.
  bool SearchSegment(const Template& t, const cv::Mat& band,
                     const Eigen::Vector2d& a, const Eigen::Vector2d& b, int band_px,
                     int* best_x, int* best_y, float* best_score);
  // Sub-pixel refinement around an integer centre.
  static MatchResult Refine(const Template& t, const cv::Mat& band, int x, int y,
                            double covariance_scale, double min_sigma);
  // Iterated refinement: resamples the image (bilinear) centred on the estimate and
  // refits, `iterations` times at most.
  void Iterate(const Template& t, const cv::Mat& band, int iterations, double covariance_scale,
               double min_sigma, MatchResult* m);

 private:
  std::vector<float> row_;
  cv::Mat patch_;
};

}  // namespace rover::vo
