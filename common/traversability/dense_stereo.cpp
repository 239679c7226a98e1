#include "traversability/dense_stereo.hpp"

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <sstream>
#include <stdexcept>

namespace rover::traversability {

namespace {

double SecondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

[[noreturn]] void Bad(const std::string& what) {
  throw std::invalid_argument("traversability stereo: " + what);
}

// The optical axis of a model: the ray through its image centre.
Eigen::Vector3d Axis(const geometry::CameraModel& m) {
  Eigen::Vector3d o, d;
  m.BackProject(Eigen::Vector2d((m.width() - 1) / 2.0, (m.height() - 1) / 2.0), &o, &d);
  return d.normalized();
}

// Focal length (px) at the image centre, from the angle between neighbouring pixels' rays.
double CentreFocal(const geometry::CameraModel& m) {
  const double cx = (m.width() - 1) / 2.0, cy = (m.height() - 1) / 2.0;
  Eigen::Vector3d o, a, b, c, d;
  m.BackProject(Eigen::Vector2d(cx - 1, cy), &o, &a);
  m.BackProject(Eigen::Vector2d(cx + 1, cy), &o, &b);
  m.BackProject(Eigen::Vector2d(cx, cy - 1), &o, &c);
  m.BackProject(Eigen::Vector2d(cx, cy + 1), &o, &d);
  const double ax = std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0));
  const double ay = std::acos(std::clamp(c.normalized().dot(d.normalized()), -1.0, 1.0));
  return 1.0 / std::tan(0.25 * (ax + ay));  // 2 px span each: tan(half angle per px)
}

std::vector<double> RigKey(const geometry::StereoRig& rig, double scale, double fov_deg) {
  std::vector<double> key{scale, fov_deg, static_cast<double>(rig.left->width()),
                          static_cast<double>(rig.left->height()),
                          static_cast<double>(rig.right->width()),
                          static_cast<double>(rig.right->height())};
  for (const auto* m : {rig.left.get(), rig.right.get()}) {
    key.push_back(static_cast<double>(m->type().size()) + 100.0 * m->type()[0]);
    for (double v : m->Params()) key.push_back(v);
  }
  return key;
}

// Levels of 2x Gaussian reduction applied before remapping, for a scale <= 1.
int PyramidLevels(double scale) {
  int levels = 0;
  while (scale * (1 << (levels + 1)) <= 1.0 + 1e-9 && levels < 4) ++levels;
  return levels;
}

void FillMap(const geometry::CameraModel& model, const RectifiedRig& r,
             const Eigen::Vector3d& centre, int levels, cv::Mat* mx, cv::Mat* my) {
  mx->create(r.height, r.width, CV_32FC1);
  my->create(r.height, r.width, CV_32FC1);
  const double k = 1.0 / (1 << levels);
  for (int v = 0; v < r.height; ++v) {
    float* px = mx->ptr<float>(v);
    float* py = my->ptr<float>(v);
    for (int u = 0; u < r.width; ++u) {
      const Eigen::Vector3d d_rect((u - r.cx) / r.f, (v - r.cy) / r.f, 1.0);
      const Eigen::Vector3d p = centre + 10.0 * (r.R_rover_rect * d_rect).normalized();
      Eigen::Vector2d pix;
      if (model.Project(p, &pix) && pix.allFinite()) {
        // Pixel in the pyramid level the remap reads (centres stay centres).
        px[u] = static_cast<float>((pix.x() + 0.5) * k - 0.5);
        py[u] = static_cast<float>((pix.y() + 0.5) * k - 0.5);
      } else {
        px[u] = py[u] = -1e6f;
      }
    }
  }
}

// The image's noise sigma (grey levels) by Immerkaer's method: the response to the
// difference of two Laplacians, blind to intensity ramps and curvature, whose median
// absolute value over the image is 0.6745 * 6 sigma for Gaussian noise (the median keeps
// edges and texture from counting). Pixels outside the source image (0 after remapping)
// and their neighbours are skipped. Never under the 8-bit quantisation noise, 1/sqrt(12).
double ImageNoiseSigma(const cv::Mat& f, const cv::Mat& grey) {
  static const float k[9] = {1, -2, 1, -2, 4, -2, 1, -2, 1};
  const cv::Mat kernel(3, 3, CV_32F, const_cast<float*>(k));
  cv::Mat resp, outside;
  cv::filter2D(f, resp, CV_32F, kernel, cv::Point(-1, -1), 0, cv::BORDER_REPLICATE);
  cv::dilate(grey == 0, outside, cv::Mat());
  // The responses of an 8-bit image are whole numbers up to 16 x 255: a histogram gives the
  // median, interpolated within its bin (a bare whole-number median would step sigma by
  // 1/4 grey level).
  std::vector<int> hist(16 * 255 + 2, 0);
  int count = 0;
  for (int v = 1; v < f.rows - 1; ++v) {
    const float* r = resp.ptr<float>(v);
    const std::uint8_t* out = outside.ptr<std::uint8_t>(v);
    for (int u = 1; u < f.cols - 1; ++u) {
      if (out[u]) continue;
      ++hist[std::min<int>(static_cast<int>(hist.size()) - 1, static_cast<int>(std::lround(std::abs(r[u]))))];
      ++count;
    }
  }
  const double quantisation = 1.0 / std::sqrt(12.0);
  if (count == 0) return quantisation;
  const double half = 0.5 * count;
  double below = 0, median = 0;
  for (std::size_t b = 0; b < hist.size(); ++b) {
    if (below + hist[b] >= half) {
      // Bin b holds |response| in [b - 0.5, b + 0.5) (bin 0: [0, 0.5)).
      const double lo = b == 0 ? 0.0 : b - 0.5, width = b == 0 ? 0.5 : 1.0;
      median = lo + width * (half - below) / hist[b];
      break;
    }
    below += hist[b];
  }
  return std::max(quantisation, median / (0.6745 * 6.0));
}

}  // namespace

cv::Ptr<cv::StereoSGBM> RightViewMatcher(const cv::StereoSGBM& left) {
  const int min_disparity = left.getMinDisparity(), disparities = left.getNumDisparities();
  cv::Ptr<cv::StereoSGBM> right = cv::StereoSGBM::create(-(min_disparity + disparities) + 1, disparities,
                                                         left.getBlockSize());
  right->setUniquenessRatio(0);
  right->setP1(left.getP1());
  right->setP2(left.getP2());
  right->setMode(left.getMode());
  right->setPreFilterCap(left.getPreFilterCap());
  right->setDisp12MaxDiff(1000000);
  right->setSpeckleWindowSize(0);
  return right;
}

namespace {

// The left-right consistency check: the right image matched against the left by the same
// matcher (RightViewMatcher, whose disparities are the negated right-view ones), and
// every left pixel u with disparity d whose match u - d in the right view carries a
// disparity more than max_diff_px from d is unmatched (set to -16). The check itself is a
// loop over the pixels: OpenCV's only one (ximgproc's DisparityWLSFilter) comes with its
// edge-aware smoothing of the disparities, which would move the depths the map rates.
void CheckLeftRight(const cv::Ptr<cv::StereoSGBM>& left_matcher, const cv::Mat& padL, const cv::Mat& padR,
                    double max_diff_px, cv::Mat* disp16) {
  cv::Ptr<cv::StereoMatcher> right_matcher = RightViewMatcher(*left_matcher);
  cv::Mat right16;
  right_matcher->compute(padR, padL, right16);
  const int unmatched_right = (right_matcher->getMinDisparity() - 1) * 16;
  const double max_diff16 = 16.0 * max_diff_px;
  for (int v = 0; v < disp16->rows; ++v) {
    std::int16_t* dl = disp16->ptr<std::int16_t>(v);
    const std::int16_t* dr = right16.ptr<std::int16_t>(v);
    for (int u = 0; u < disp16->cols; ++u) {
      if (dl[u] <= 0) continue;
      const int ur = static_cast<int>(std::lround(u - dl[u] / 16.0));
      const bool consistent = ur >= 0 && dr[ur] != unmatched_right && std::abs(dl[u] + dr[ur]) <= max_diff16;
      if (!consistent) dl[u] = -16;
    }
  }
}

// The rectifications of the last few rigs this thread has seen, newest first: a rover
// with two pairs (NAVCAM and HAZCAM) alternates between them, and building one costs as
// much as matching a pair.
thread_local std::size_t rectifications_built = 0;

std::shared_ptr<const RectifiedRig> CachedRectification(const geometry::StereoRig& rig, double scale,
                                                        double fov_deg) {
  constexpr std::size_t kRigs = 4;
  thread_local std::vector<std::pair<std::vector<double>, std::shared_ptr<const RectifiedRig>>> cache;
  std::vector<double> key = RigKey(rig, scale, fov_deg);
  auto it = std::find_if(cache.begin(), cache.end(), [&](const auto& e) { return e.first == key; });
  if (it == cache.end()) {
    if (cache.size() >= kRigs) cache.pop_back();
    cache.emplace(cache.begin(), std::move(key), std::make_shared<const RectifiedRig>(Rectify(rig, scale, fov_deg)));
    ++rectifications_built;
  } else if (it != cache.begin()) {
    std::rotate(cache.begin(), it, it + 1);
  }
  return cache.front().second;
}

}  // namespace

cv::Mat TextureSnr2(const cv::Mat& rect_left, double texture_noise_gain, int block_size) {
  if (rect_left.empty() || rect_left.type() != CV_8UC1) Bad("TextureSnr2: expected an 8-bit grey image");
  if (!(texture_noise_gain > 0) || block_size < 1) Bad("TextureSnr2: expected a positive noise gain and block");
  cv::Mat f, gx, e;
  rect_left.convertTo(f, CV_32F);
  cv::Sobel(f, gx, CV_32F, 1, 0, 3, 1.0, 0.0, cv::BORDER_REFLECT_101);
  cv::boxFilter(gx.mul(gx), e, CV_32F, cv::Size(block_size, block_size));
  const double sigma = ImageNoiseSigma(f, rect_left);
  return e / static_cast<float>(texture_noise_gain * sigma * sigma);
}

double DisparitySigmaPx(double snr2, const MapOptions& o) {
  if (o.texture_sigma_px <= 0) return o.disparity_sigma_px;
  // The block-matching error model (e.g. Matthies 1992; Kanade & Okutomi 1994): matching a
  // block of N pixels whose horizontal gradients are I_x, with noise sigma_n in both
  // images, misplaces it by a disparity of variance 2 sigma_n^2 / sum(I_x^2). The Sobel
  // energy over the block holds the noise's own (snr2 = 1 for noise alone), so the
  // texture's is snr2 - 1 times the noise's; texture_sigma_px is the sigma where the two
  // are equal. It adds to the matching error textured ground has anyway
  // (disparity_sigma_px: sub-pixel interpolation, calibration).
  const double rho = std::max(std::isfinite(snr2) ? snr2 - 1.0 : 0.0, 0.01);
  return std::sqrt(o.disparity_sigma_px * o.disparity_sigma_px + o.texture_sigma_px * o.texture_sigma_px / rho);
}

double SourceStretch(const RectifiedRig& r, int u, int v) {
  const int u0 = std::max(0, u - 1), u1 = std::min(r.width - 1, u + 1);
  if (u1 <= u0) return 1.0;
  const float* mx = r.map_lx.ptr<float>(v);
  const float* my = r.map_ly.ptr<float>(v);
  if (mx[u0] < -0.5f || mx[u1] < -0.5f) return 1.0;
  const double per_column = std::hypot(mx[u1] - mx[u0], my[u1] - my[u0]) / (u1 - u0);
  return per_column > 0 ? std::max(1.0, 1.0 / per_column) : 1.0;
}

std::size_t RectificationsBuilt() { return rectifications_built; }

std::shared_ptr<const RectifiedRig> PairRectification(const geometry::StereoRig& rig, int image_width,
                                                      const MapOptions& o) {
  const double scale = o.stereo_width_px > 0 && image_width > o.stereo_width_px
                           ? static_cast<double>(o.stereo_width_px) / image_width
                           : 1.0;
  return CachedRectification(rig, scale, o.rectified_fov_deg);
}

bool PairFrames(const RectifiedRig& r, const Eigen::Vector3d& p_rover, const MapOptions& o) {
  if (p_rover.x() < o.min_x_m) return false;
  const Eigen::Vector3d rel = p_rover - r.left_centre;
  const double range2 = rel.squaredNorm();
  if (range2 > o.max_range_m * o.max_range_m || range2 < o.min_range_m * o.min_range_m) return false;
  const Eigen::Vector3d q = r.R_rover_rect.transpose() * rel;  // rectified optical frame
  if (!(q.z() > 1e-6)) return false;
  const double u = r.cx + r.f * q.x() / q.z(), v = r.cy + r.f * q.y() / q.z();
  const double d = r.f * r.baseline_m / q.z();
  const int num_disp = ((o.num_disparities + 15) / 16) * 16;
  if (d >= num_disp) return false;  // nearer than the disparity search reaches
  const double margin = o.block_size / 2 + 1;
  const double ur = u - d;
  if (!(v >= margin && v <= r.height - 1 - margin && ur >= margin && u <= r.width - 1 - margin)) return false;
  const int iv = static_cast<int>(std::lround(v));
  const int iu = static_cast<int>(std::lround(u)), iur = static_cast<int>(std::lround(ur));
  // Rectified pixels whose ray leaves the source image (a fish-eye's corners) hold nothing.
  return r.map_lx.at<float>(iv, iu) >= -0.5f && r.map_rx.at<float>(iv, iur) >= -0.5f;
}

RectifiedRig Rectify(const geometry::StereoRig& rig, double scale, double fov_deg) {
  if (!rig.left || !rig.right) Bad("the rig has no left or right model");
  if (!(scale > 0 && scale <= 1)) Bad("the rectification scale must be in (0, 1]");
  if (!(fov_deg >= 0 && fov_deg < 170)) Bad("the rectified field must be in [0, 170) deg");
  const geometry::CameraModel& L = *rig.left;
  const geometry::CameraModel& R = *rig.right;
  if (L.width() != R.width() || L.height() != R.height())
    Bad("the left and right models differ in size");
  RectifiedRig r;
  r.left_centre = L.Center();
  const Eigen::Vector3d b = R.Center() - L.Center();
  r.baseline_m = b.norm();
  if (!(r.baseline_m > 1e-6)) Bad("the rig's baseline is zero");
  const Eigen::Vector3d aL = Axis(L), aR = Axis(R);
  if (aL.dot(aR) < std::cos(10.0 * M_PI / 180.0)) Bad("the rig's optical axes differ by over 10 deg");
  const Eigen::Vector3d x = b / r.baseline_m;
  Eigen::Vector3d z = (aL + aR).normalized();
  z = (z - z.dot(x) * x);
  if (z.norm() < 0.5) Bad("the rig's baseline runs along its optical axis");
  z.normalize();
  const Eigen::Vector3d y = z.cross(x);
  r.R_rover_rect.col(0) = x;
  r.R_rover_rect.col(1) = y;
  r.R_rover_rect.col(2) = z;
  r.width = std::max(8, static_cast<int>(std::lround(L.width() * scale)));
  r.height = std::max(8, static_cast<int>(std::lround(L.height() * scale)));
  const double s_x = static_cast<double>(r.width) / L.width();
  r.f = 0.5 * (CentreFocal(L) + CentreFocal(R)) * s_x;
  // A wider field across: the same focal length (the centre's resolution, and so its
  // depth precision, is kept) over more columns, up to 4 times the matching width.
  if (fov_deg > 0)
    r.width = std::max(r.width, std::min(4 * r.width, static_cast<int>(std::lround(2.0 * r.f * std::tan(0.5 * fov_deg * M_PI / 180.0)))));
  r.cx = (r.width - 1) / 2.0;
  r.cy = (r.height - 1) / 2.0;
  const int levels = PyramidLevels(s_x);
  r.pyramid_levels = levels;
  FillMap(L, r, L.Center(), levels, &r.map_lx, &r.map_ly);
  FillMap(R, r, R.Center(), levels, &r.map_rx, &r.map_ry);
  // What read noise alone gives the texture measure: white noise of a known sigma through
  // the same reduction and resampling as the images (both smooth it, and not equally at
  // all frequencies), then the noise estimate and the mean squared Sobel gradient on it.
  {
    cv::Mat noise(L.height(), L.width(), CV_8UC1), tmp;
    cv::RNG rng(20021);
    rng.fill(noise, cv::RNG::NORMAL, 128, 8);
    for (int k = 0; k < levels; ++k) {
      cv::pyrDown(noise, tmp);
      noise = tmp;
    }
    cv::Mat rect, f, gx;
    cv::remap(noise, rect, r.map_lx, r.map_ly, cv::INTER_LINEAR, cv::BORDER_CONSTANT, 0);
    rect.convertTo(f, CV_32F);
    cv::Sobel(f, gx, CV_32F, 1, 0, 3, 1.0, 0.0, cv::BORDER_REFLECT_101);
    cv::Mat inside;
    cv::erode(rect > 0, inside, cv::Mat());
    const double sigma = ImageNoiseSigma(f, rect);
    const double mean_g2 = cv::mean(gx.mul(gx), inside)[0];
    if (sigma > 0 && mean_g2 > 0) r.texture_noise_gain = mean_g2 / (sigma * sigma);
  }
  return r;
}

cv::Mat MatchDisparity(const cv::Mat& rectL, const cv::Mat& rectR, const MapOptions& o) {
  if (rectL.empty() || rectL.type() != CV_8UC1 || rectR.type() != CV_8UC1 || rectL.size() != rectR.size())
    Bad("MatchDisparity: expected two 8-bit grey images of the same size");
  const int num_disp = ((o.num_disparities + 15) / 16) * 16;
  const int bs = o.block_size;
  cv::Ptr<cv::StereoSGBM> sgbm = cv::StereoSGBM::create(
      0, num_disp, bs, 8 * bs * bs, 32 * bs * bs, 1, 31, o.uniqueness_ratio, o.speckle_window,
      o.speckle_range, cv::StereoSGBM::MODE_SGBM_3WAY);
  // SGBM leaves the left num_disp columns unmatched: pad both images on the left so that
  // the whole left image is matched, then crop. The right view's match leaves its right
  // num_disp columns unmatched the same way: with the check, pad on the right as well.
  const bool check = o.lr_max_diff_px > 0;
  const int right_pad = check ? num_disp : 0;
  cv::Mat padL, padR, padded;
  cv::copyMakeBorder(rectL, padL, 0, 0, num_disp, right_pad, cv::BORDER_CONSTANT, 0);
  cv::copyMakeBorder(rectR, padR, 0, 0, num_disp, right_pad, cv::BORDER_CONSTANT, 0);
  sgbm->compute(padL, padR, padded);
  if (check) CheckLeftRight(sgbm, padL, padR, o.lr_max_diff_px, &padded);
  return padded.colRange(num_disp, num_disp + rectL.cols).clone();
}

StereoPoints DenseStereo(const cv::Mat& left, const cv::Mat& right,
                         const geometry::StereoRig& rig, const MapOptions& o,
                         UpdateStats* stats) {
  if (!rig.left || !rig.right) Bad("the rig has no left or right model");
  for (const auto& [name, img, model] :
       {std::tuple<const char*, const cv::Mat*, const geometry::CameraModel*>{"left", &left, rig.left.get()},
        {"right", &right, rig.right.get()}}) {
    if (img->empty()) Bad(std::string(name) + " image: empty");
    if (img->type() != CV_8UC1) Bad(std::string(name) + " image: expected 8-bit grey (CV_8UC1)");
    if (img->cols != model->width() || img->rows != model->height()) {
      std::ostringstream s;
      s << name << " image: " << img->cols << "x" << img->rows << ", expected the model's "
        << model->width() << "x" << model->height();
      Bad(s.str());
    }
  }
  auto t0 = std::chrono::steady_clock::now();
  const std::shared_ptr<const RectifiedRig> cached = PairRectification(rig, left.cols, o);
  const RectifiedRig& r = *cached;
  const int levels = r.pyramid_levels;
  cv::Mat srcL = left, srcR = right, tmp;
  for (int k = 0; k < levels; ++k) {
    cv::pyrDown(srcL, tmp);
    srcL = tmp.clone();
    cv::pyrDown(srcR, tmp);
    srcR = tmp.clone();
  }
  cv::Mat rectL, rectR;
  cv::remap(srcL, rectL, r.map_lx, r.map_ly, cv::INTER_LINEAR, cv::BORDER_CONSTANT, 0);
  cv::remap(srcR, rectR, r.map_rx, r.map_ry, cv::INTER_LINEAR, cv::BORDER_CONSTANT, 0);
  if (stats) stats->seconds_rectify = SecondsSince(t0);

  t0 = std::chrono::steady_clock::now();
  const int num_disp = ((o.num_disparities + 15) / 16) * 16;
  const int bs = o.block_size;
  const cv::Mat disp16 = MatchDisparity(rectL, rectR, o);
  // Depth edges: the range of matched disparities over each pixel's 5x5 neighbourhood.
  cv::Mat edge;
  if (o.max_disparity_jump > 0) {
    cv::Mat dmax, dmin, valid;
    const cv::Mat kernel = cv::getStructuringElement(cv::MORPH_RECT, cv::Size(5, 5));
    cv::Mat d = cv::max(disp16, 0);
    cv::dilate(d, dmax, kernel);  // unmatched pixels (0) never raise the maximum
    cv::Mat d_for_min = d.clone();
    d_for_min.setTo(cv::Scalar(32767), d <= 0);  // holes do not pull the minimum down
    cv::erode(d_for_min, dmin, kernel);
    cv::Mat spread, dfloat;
    cv::Mat(dmax - dmin).convertTo(spread, CV_32F);
    d.convertTo(dfloat, CV_32F);
    edge = spread > dfloat * o.max_disparity_jump;
  }
  // Texture: where the left image is blank over the matching block, SGBM still returns a
  // disparity (the image noise, or the smoothness term, picks one) and its depth is
  // anything; blank sand gave 1.7 m "steps". Such pixels are not matched.
  cv::Mat blank;
  if (o.min_texture > 0) {
    cv::Mat f, mean, mean2;
    rectL.convertTo(f, CV_32F);
    const cv::Size win(bs, bs);
    cv::boxFilter(f, mean, CV_32F, win);
    cv::boxFilter(f.mul(f), mean2, CV_32F, win);
    cv::Mat var = mean2 - mean.mul(mean);
    blank = var < static_cast<float>(o.min_texture * o.min_texture);
  }
  // Texture along the epipolar line, against the image's own noise: SGBM can only find a
  // disparity from intensity that changes along the rows. Horizontal bands (ripple crests
  // across the view, the brightness falling off with range) have variance but no such
  // change, and in a dark shadow the ground's texture sinks under the read noise; on both
  // SGBM's disparity is noise. A pixel is kept where the mean squared horizontal gradient
  // (Sobel) over its block stands min_texture_snr^2 times above what noise alone gives.
  // The same measure sets each point's disparity sigma (texture_sigma_px, below).
  cv::Mat snr2;
  if (o.min_texture_snr > 0 || o.texture_sigma_px > 0) snr2 = TextureSnr2(rectL, r.texture_noise_gain, bs);
  if (o.min_texture_snr > 0) {
    cv::Mat low = snr2 < static_cast<float>(o.min_texture_snr * o.min_texture_snr);
    blank = blank.empty() ? low : (blank | low);
  }
  // The left border: padding lets SGBM match the left num_disp columns, but a pixel there
  // whose true disparity exceeds its column shows ground the right camera never saw; SGBM
  // then settles on a smaller disparity elsewhere in the row, and the point lands far
  // beyond and below the ground (a metre below it at the image's bottom-left corner). The
  // largest disparity matched in the interior of the nearby rows (where every disparity
  // can be matched) bounds what the border's pixels can truly have; a pixel left of that
  // bound is dropped. Rows with no interior match keep only what SGBM alone would match.
  // So is every pixel within half a block (and the one pixel of SGBM's gradient prefilter)
  // of the image's edges: its block runs off the image, SGBM matches a partial one there
  // and its paths start there with nothing behind them; a top row of bland sand gave
  // points a metre up, a shadow's edge leaving the image's right side 0.4 m.
  std::vector<int> min_column;
  if (o.drop_unseen_border) {
    const int h = disp16.rows, w = disp16.cols;
    std::vector<int> row_max(h, 0);
    for (int v = 0; v < h; ++v) {
      const std::int16_t* dp = disp16.ptr<std::int16_t>(v);
      const std::uint8_t* bp = blank.empty() ? nullptr : blank.ptr<std::uint8_t>(v);
      int m = 0;
      for (int u = num_disp; u < w; ++u)
        if (dp[u] > m && !(bp && bp[u])) m = dp[u];
      row_max[v] = m;
    }
    min_column.assign(h, num_disp);
    const int reach = std::max(bs, 8);
    for (int v = 0; v < h; ++v) {
      int m = 0;
      for (int k = std::max(0, v - reach); k <= std::min(h - 1, v + reach); ++k) m = std::max(m, row_max[k]);
      if (m > 0) min_column[v] = std::min(num_disp, (m + 15) / 16 + 1);
    }
  }
  if (stats) stats->seconds_match = SecondsSince(t0);

  // Triangulate: z = f B / d along the common axis.
  StereoPoints out;
  const double fB = r.f * r.baseline_m;
  const int step = o.subsample;
  const double max_range2 = o.max_range_m * o.max_range_m;
  const double min_range2 = o.min_range_m * o.min_range_m;
  out.points_rover.reserve(static_cast<std::size_t>(r.width / step) * (r.height / step));
  out.error_rover.reserve(out.points_rover.capacity());
  for (int v = 0; v < r.height; v += step) {
    const std::int16_t* dp = disp16.ptr<std::int16_t>(v);
    const float* mlx = r.map_lx.ptr<float>(v);
    const float* mrx = r.map_rx.ptr<float>(v);
    const std::uint8_t* ep = edge.empty() ? nullptr : edge.ptr<std::uint8_t>(v);
    const std::uint8_t* bp = blank.empty() ? nullptr : blank.ptr<std::uint8_t>(v);
    const float* sp = o.texture_sigma_px > 0 ? snr2.ptr<float>(v) : nullptr;
    const int margin = min_column.empty() ? 0 : bs / 2 + 1;
    if (v < margin || v >= r.height - margin) continue;
    const int u_first = min_column.empty() ? 0 : std::max(margin, min_column[v]);
    for (int u = 0; u < r.width - margin; u += step) {
      if (u < u_first) continue;  // its match may lie outside the right image
      if (dp[u] <= 0 || u - dp[u] / 16 < 0 || mlx[u] < -0.5f || mrx[u - dp[u] / 16] < -0.5f) continue;  // no match, or off the source images
      if (ep && ep[u]) continue;  // on a depth edge
      if (bp && bp[u]) continue;  // no texture to match
      const double d = dp[u] / 16.0;
      const double z = fB / d;
      const Eigen::Vector3d ray((u - r.cx) / r.f, (v - r.cy) / r.f, 1.0);
      const Eigen::Vector3d dir = r.R_rover_rect * ray;
      const Eigen::Vector3d p = r.left_centre + z * dir;
      const double range2 = (z * dir).squaredNorm();
      if (range2 > max_range2 || range2 < min_range2) continue;
      if (p.x() < o.min_x_m) continue;  // hidden from this camera by the rover's own body
      // The matching error on the source image (bland texture matches worse), in rectified
      // pixels where the pinhole stretches the source's.
      const double sigma_d = sp ? DisparitySigmaPx(sp[u], o) : o.disparity_sigma_px;
      const double sigma_z = z * z / fB * sigma_d * SourceStretch(r, u, v);
      out.points_rover.push_back(p);
      out.error_rover.push_back(sigma_z * dir);
    }
  }
  return out;
}

}  // namespace rover::traversability
