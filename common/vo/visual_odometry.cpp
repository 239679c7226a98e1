#include "vo/visual_odometry.hpp"

#include "geometry/pose.hpp"
#include "vo/correlation.hpp"
#include "vo/features.hpp"
#include "vo/motion_estimation.hpp"
#include "vo/tracks.hpp"
#include "vo/triangulation.hpp"
#include "vo/window.hpp"

#include <Eigen/Eigenvalues>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <tuple>

namespace rover::vo {

namespace {

using Clock = std::chrono::steady_clock;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

double Ms(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

constexpr double kDeg = M_PI / 180.0;

struct Feature {
  Eigen::Vector2d left;  // working-resolution pixel (integer for a fresh corner)
  Eigen::Vector3d P;
  Eigen::Matrix3d Sigma;
  Eigen::Vector3d dP_ddisparity;  // dP / d(right x): a disparity offset (VO-13)
  // Windowed mode: the stereo match behind P, and the track (id, pairs seen so far).
  Eigen::Vector2d right = Eigen::Vector2d::Zero();
  Eigen::Matrix2d Sigma_left = Eigen::Matrix2d::Identity(), Sigma_right = Eigen::Matrix2d::Identity();
  std::int64_t track_id = 0;
  int age = 1;
};

// One stereo pair at the working resolution.
struct Pair {
  geometry::StereoRig rig;
  std::vector<cv::Mat> left_band;  // band-passed pyramid, level 0 = working resolution
  cv::Mat right_band;
  cv::Mat right_band_half;  // level 1, for coarse-to-fine stereo of new features
  // Reused buffers (a Pair is recycled every other frame, so nothing is reallocated).
  cv::Mat left, right, right_half, scratch, response;
  std::vector<cv::Mat> left_levels;
  std::vector<Feature> features;
  std::vector<Corner> corners;  // windowed mode: VO-2's corners, stereo-matched later
  std::int64_t frame_id = 0;
  int width = 0, height = 0;
  double pixel_angle = 1e-3;  // radians per pixel near the left image centre
  double far_range = 1e6;     // range at stereo_min_disparity_px
};

void ToFloat(const cv::Mat& image, double scale_to_working, cv::Mat* out, cv::Mat* scratch) {
  const double unit = image.depth() == CV_16U ? 1.0 / 65535.0 : 1.0 / 255.0;
  if (scale_to_working == 1.0) {
    image.convertTo(*out, CV_32F, unit);
    return;
  }
  image.convertTo(*scratch, CV_32F, unit);
  const cv::Size size(static_cast<int>(std::lround(image.cols * scale_to_working)),
                      static_cast<int>(std::lround(image.rows * scale_to_working)));
  cv::resize(*scratch, *out, size, 0, 0, cv::INTER_AREA);
}

// Pixel coordinate at pyramid level l (area halving keeps pixel centres as centres).
inline double ToLevel(double x, int l) { return (x + 0.5) / double(1 << l) - 0.5; }

std::string Format(const char* fmt, double a, double b = 0) {
  char buf[256];
  std::snprintf(buf, sizeof(buf), fmt, a, b);
  return buf;
}

}  // namespace

struct VisualOdometry::State {
  VoOptions o;
  std::unique_ptr<Pair> prev;
  std::unique_ptr<Pair> spare;  // the pair before prev, recycled for its buffers
  Correlator correlator;
  Template tmpl, coarse_tmpl;
  std::uint64_t calls = 0;
  // Windowed mode: `prev` is the last keyframe (the reference pair); the window; the
  // last call's pair as published, in the window's frame (the deltas VO publishes compose
  // to the window's latest estimate); the next track id.
  SlidingWindow window;
  Eigen::Isometry3d T_w_last = Eigen::Isometry3d::Identity();
  // The covariance of the last call's pair against the reference pair (zero when it was
  // the reference): a delta from it carries that pair's error too.
  Matrix6d last_ref_cov = Matrix6d::Zero();
  std::int64_t next_track_id = 1;
  bool Windowed() const { return o.window_size >= 2; }
  // Windowed mode: gives `pair` the carried tracks plus fresh corners stereo-matched where
  // tracks are missing (VO-2 top-up), and counts its features in res.
  void CompleteFeatures(Pair* pair, std::vector<Feature> carried, VoResult* res);
  // Windowed mode: the window restarts on `pair` (first pair, a failure, a refused
  // refinement), which becomes the reference pair.
  void RestartWindow(Pair* pair);
  void Accept(std::int64_t frame_id, const geometry::StereoRig& rig, const std::vector<int>& corr_source,
              const std::vector<int>& inliers, const MotionUncertainty& u, std::vector<Feature>* carried,
              std::unique_ptr<Pair>* cur, std::unique_ptr<Pair>* ref, VoResult* res);

  std::string CheckInput(const StereoImages& im) const;
  std::unique_ptr<Pair> Prepare(const StereoImages& im, VoResult* res, Clock::time_point* t);
  void StereoMatchFresh(Pair* pair, const std::vector<Corner>& corners);
  bool MatchRight(const Pair& pair, const Eigen::Vector3d& C1, const Eigen::Vector3d& r1,
                  double range_near, double range_far, double margin_px,
                  const Template* coarse, Eigen::Vector2d* right, Eigen::Matrix2d* Sigma_right);
  TriangulationLimits Limits(const Pair& pair) const {
    TriangulationLimits l;
    l.max_gap_rad = o.triangulation_max_gap_px * pair.pixel_angle;
    l.min_parallax_rad = o.stereo_min_disparity_px * pair.pixel_angle;
    l.max_range_m = o.triangulation_max_range_m;
    return l;
  }
};

std::string VisualOdometry::State::CheckInput(const StereoImages& im) const {
  if (!im.rig.left || !im.rig.right) return "stereo rig has no camera model";
  if (im.left.empty() || im.right.empty()) return "empty image";
  for (const cv::Mat* m : {&im.left, &im.right}) {
    if (m->type() != CV_8UC1 && m->type() != CV_16UC1) {
      return "image type " + std::to_string(m->type()) + " (expected CV_8UC1 or CV_16UC1)";
    }
  }
  if (im.left.size() != im.right.size()) return "left and right images differ in size";
  if (im.left.cols != im.rig.left->width() || im.left.rows != im.rig.left->height() ||
      im.right.cols != im.rig.right->width() || im.right.rows != im.rig.right->height()) {
    std::ostringstream os;
    os << "image size " << im.left.cols << "x" << im.left.rows << " does not match camera "
       << im.rig.left->width() << "x" << im.rig.left->height();
    return os.str();
  }
  const int min_side = static_cast<int>(std::min(im.left.cols, im.left.rows) * o.working_scale);
  if (min_side < 2 * o.feature_border_px + 8) return "image too small for the working scale";
  return "";
}

std::unique_ptr<Pair> VisualOdometry::State::Prepare(const StereoImages& im, VoResult* res,
                                                     Clock::time_point* t) {
  std::unique_ptr<Pair> pair = spare ? std::move(spare) : std::make_unique<Pair>();
  pair->features.clear();
  if (o.working_scale == 1.0) {
    pair->rig = im.rig;
  } else {
    pair->rig.left = im.rig.left->Scaled(o.working_scale);
    pair->rig.right = im.rig.right->Scaled(o.working_scale);
  }
  ToFloat(im.left, o.working_scale, &pair->left, &pair->scratch);
  ToFloat(im.right, o.working_scale, &pair->right, &pair->scratch);
  const cv::Mat& left = pair->left;
  const cv::Mat& right = pair->right;
  pair->width = left.cols;
  pair->height = left.rows;
  {
    Eigen::Vector3d c, d0, d1;
    const Eigen::Vector2d centre(0.5 * (left.cols - 1), 0.5 * (left.rows - 1));
    pair->rig.left->BackProject(centre, &c, &d0);
    pair->rig.left->BackProject(centre + Eigen::Vector2d(1, 0), &c, &d1);
    pair->pixel_angle = std::max(1e-9, std::acos(std::clamp(d0.dot(d1), -1.0, 1.0)));
    const double baseline = pair->rig.Baseline();
    pair->far_range = o.stereo_min_disparity_px > 0
                          ? baseline / (o.stereo_min_disparity_px * pair->pixel_angle)
                          : 1e6 * baseline;
  }
  // Pyramid of the left image, band-passed level by level (VO-3 prefilter), for
  // coarse-to-fine tracking (VO-6).
  const int n = o.match_template_px;
  pair->left_band.resize(o.track_pyramid_levels);
  pair->left_levels.resize(o.track_pyramid_levels);
  int levels = 0;
  for (int l = 0; l < o.track_pyramid_levels; ++l) {
    const cv::Mat& level = l == 0 ? left : pair->left_levels[l];
    if (l > 0) {
      const cv::Mat& finer = l == 1 ? left : pair->left_levels[l - 1];
      if (finer.cols / 2 < n + 4 || finer.rows / 2 < n + 4) break;
      cv::resize(finer, pair->left_levels[l], cv::Size(finer.cols / 2, finer.rows / 2), 0, 0,
                 cv::INTER_AREA);
    }
    BandPass(level, o.match_prefilter_sigma, o.match_prefilter_box_px, &pair->left_band[l],
             &pair->scratch);
    ++levels;
  }
  pair->left_band.resize(levels);
  BandPass(right, o.match_prefilter_sigma, o.match_prefilter_box_px, &pair->right_band,
           &pair->scratch);
  if (o.stereo_coarse_to_fine && pair->left_band.size() > 1) {
    cv::resize(right, pair->right_half, pair->left_band[1].size(), 0, 0, cv::INTER_AREA);
    BandPass(pair->right_half, o.match_prefilter_sigma, o.match_prefilter_box_px,
             &pair->right_band_half, &pair->scratch);
  } else {
    pair->right_band_half.release();
  }

  CornerOptions co;
  co.harris_k = o.feature_harris_k;
  co.harris_block = o.feature_harris_block;
  co.grid_cell_px = o.feature_grid_cell_px;
  co.min_distance_px = o.feature_min_distance_px;
  co.count = o.feature_count;
  co.min_response = o.feature_min_response;
  co.border_px = o.feature_border_px;
  pair->frame_id = im.frame_id;
  pair->corners = DetectCorners(left, co, &pair->response);
  const std::vector<Corner>& corners = pair->corners;
  res->num_detected = static_cast<int>(corners.size());
  const auto t_detect = Clock::now();
  res->times.detect_ms = Ms(*t, t_detect);
  *t = t_detect;

  // Windowed mode: stereo waits until tracking has shown where tracks are missing.
  if (!Windowed()) StereoMatchFresh(pair.get(), corners);
  res->num_matched = static_cast<int>(pair->features.size());
  const auto t_stereo = Clock::now();
  res->times.stereo_ms = Ms(*t, t_stereo);
  *t = t_stereo;
  return pair;
}

bool VisualOdometry::State::MatchRight(const Pair& pair, const Eigen::Vector3d& C1,
                                       const Eigen::Vector3d& r1, double range_near,
                                       double range_far, double margin_px,
                                       const Template* coarse, Eigen::Vector2d* right,
                                       Eigen::Matrix2d* Sigma_right) {
  // VO-3: the epipolar segment is the projection of the left ray between the two ranges.
  Eigen::Vector2d a, b;
  if (!pair.rig.right->Project(C1 + r1 * range_far, &a)) return false;
  if (!pair.rig.right->Project(C1 + r1 * range_near, &b)) return false;
  if (margin_px > 0) {
    Eigen::Vector2d dir = b - a;
    if (dir.norm() < 1e-6) {
      Eigen::Vector2d far_end;
      if (!pair.rig.right->Project(C1 + r1 * pair.far_range, &far_end)) return false;
      dir = b - far_end;
      if (dir.norm() < 1e-6) dir = Eigen::Vector2d(-1, 0);
    }
    dir.normalize();
    a -= margin_px * dir;
    b += margin_px * dir;
  }
  // The line itself is searched; the refinement then climbs to the 2-D peak, which must
  // stay within the band above and below the line (a few pixels, VO-3).
  int bx = 0, by = 0;
  float score = 0;
  if (coarse && !pair.right_band_half.empty() && (b - a).norm() > 8) {
    // Coarse to fine: the whole segment at half resolution, then +-2 px at full.
    const Eigen::Vector2d half(0.5, 0.5);
    int cx = 0, cy = 0;
    if (!correlator.SearchSegment(*coarse, pair.right_band_half, (a + half) / 2 - half,
                                  (b + half) / 2 - half, 0, &cx, &cy, &score)) {
      return false;
    }
    if (!correlator.SearchWindow(tmpl, pair.right_band, 2 * cx - 2, 2 * cx + 3, 2 * cy - 1,
                                 2 * cy + 2, &bx, &by, &score)) {
      return false;
    }
  } else if (!correlator.SearchSegment(tmpl, pair.right_band, a, b, 0, &bx, &by, &score)) {
    return false;
  }
  MatchResult m = Correlator::Refine(tmpl, pair.right_band, bx, by, o.match_covariance_scale,
                                     o.match_min_sigma_px);
  if (!m.ok || m.score < o.match_min_score) return false;
  correlator.Iterate(tmpl, pair.right_band, o.match_subpixel_iterations,
                     o.match_covariance_scale, o.match_min_sigma_px, &m);
  const Eigen::Vector2d line = (b - a).norm() > 1e-9 ? (b - a).normalized() : Eigen::Vector2d(1, 0);
  const Eigen::Vector2d off = m.position - a;
  if (std::abs(off.x() * line.y() - off.y() * line.x()) > o.stereo_epipolar_band_px + 0.5) {
    return false;
  }
  *right = m.position;
  *Sigma_right = m.covariance;
  return true;
}

void VisualOdometry::State::StereoMatchFresh(Pair* pair, const std::vector<Corner>& corners) {
  const TriangulationLimits limits = Limits(*pair);
  pair->features.reserve(corners.size());
  // Visit the corners top to bottom, so the correlation windows stream through the images
  // instead of jumping about (the corners come strongest first); the features are kept in
  // the corners' order, on which RANSAC's draws depend.
  std::vector<int> order(corners.size());
  for (int i = 0; i < static_cast<int>(order.size()); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    return std::tie(corners[a].y, corners[a].x) < std::tie(corners[b].y, corners[b].x);
  });
  std::vector<Feature> found(corners.size());
  std::vector<char> ok(corners.size(), 0);
  for (const int i : order) {
    const Corner& c = corners[i];
    if (!tmpl.Extract(pair->left_band[0], c.x, c.y, o.match_template_px)) continue;
    // The left location's covariance comes from the template's own correlation peak
    // (its sharpness), fitted the same way as the right match (VO-3, VO-5).
    const MatchResult self = Correlator::Refine(tmpl, pair->left_band[0], c.x, c.y, o.match_covariance_scale,
                                                o.match_min_sigma_px);
    if (!self.ok) continue;
    const Eigen::Vector2d left(c.x, c.y);
    Eigen::Vector3d C1, r1;
    pair->rig.left->BackProject(left, &C1, &r1);
    Eigen::Vector2d right;
    Eigen::Matrix2d Sigma_right;
    const bool coarse =
        !pair->right_band_half.empty() &&
        coarse_tmpl.Extract(pair->left_band[1], static_cast<int>(std::lround(ToLevel(c.x, 1))),
                            static_cast<int>(std::lround(ToLevel(c.y, 1))), o.match_template_px);
    if (!MatchRight(*pair, C1, r1, o.stereo_min_range_m, pair->far_range, 0.0,
                    coarse ? &coarse_tmpl : nullptr, &right, &Sigma_right)) {
      continue;
    }
    StereoPoint sp;
    Eigen::Matrix<double, 3, 4> J;
    if (!TriangulateStereo(pair->rig, left, self.covariance, right, Sigma_right, limits, &sp, &J)) {
      continue;
    }
    Feature& f = found[i];
    f.left = left;
    f.P = sp.P;
    f.Sigma = sp.Sigma;
    f.dP_ddisparity = J.col(2);
    f.right = right;
    f.Sigma_left = self.covariance;
    f.Sigma_right = Sigma_right;
    ok[i] = 1;
  }
  for (std::size_t i = 0; i < corners.size(); ++i) {
    if (!ok[i]) continue;
    found[i].track_id = next_track_id++;
    pair->features.push_back(found[i]);
  }
}

void VisualOdometry::State::CompleteFeatures(Pair* pair, std::vector<Feature> carried, VoResult* res) {
  const auto t0 = Clock::now();
  std::vector<Eigen::Vector2d> pos;
  std::vector<int> ages;
  for (const Feature& f : carried) {
    pos.push_back(f.left);
    ages.push_back(f.age);
  }
  const std::vector<int> keep = SelectTracks(pos, ages, o.track_min_distance_px, o.feature_count);
  std::vector<Eigen::Vector2d> kept_pos;
  pair->features.clear();
  for (int i : keep) {
    pair->features.push_back(carried[static_cast<std::size_t>(i)]);
    kept_pos.push_back(carried[static_cast<std::size_t>(i)].left);
  }
  std::vector<Feature> tracks = std::move(pair->features);
  pair->features.clear();
  const std::vector<int> top = TopUpCorners(kept_pos, pair->corners, o.feature_min_distance_px, o.feature_count);
  std::vector<Corner> fresh;
  fresh.reserve(top.size());
  for (int i : top) fresh.push_back(pair->corners[static_cast<std::size_t>(i)]);
  StereoMatchFresh(pair, fresh);
  // Tracks first (the order RANSAC draws in), then the fresh features.
  tracks.insert(tracks.end(), pair->features.begin(), pair->features.end());
  pair->features = std::move(tracks);
  res->num_matched = static_cast<int>(pair->features.size());
  res->times.stereo_ms += Ms(t0, Clock::now());
}

void VisualOdometry::State::RestartWindow(Pair* pair) {
  window.Reset();
  std::vector<WindowObservation> obs;
  obs.reserve(pair->features.size());
  for (const Feature& f : pair->features) {
    obs.push_back({f.track_id, f.left, f.right, f.Sigma_left, f.Sigma_right, f.P, f.Sigma});
  }
  window.AddFrame(pair->frame_id, Eigen::Isometry3d::Identity(), std::move(obs));
  T_w_last = Eigen::Isometry3d::Identity();
  last_ref_cov.setZero();
}

VisualOdometry::VisualOdometry(VoOptions options) : state_(std::make_unique<State>()) {
  ValidateVoOptions(options);
  state_->o = options;
  WindowOptions w;
  w.max_frames = std::max(2, options.window_size);
  w.max_iterations = options.window_max_iterations;
  w.huber_sigmas = options.window_huber_sigmas;
  w.disparity_offset_sigma_px = options.window_disparity_offset_sigma_px;
  state_->window = SlidingWindow(w);
}
VisualOdometry::~VisualOdometry() = default;
VisualOdometry::VisualOdometry(VisualOdometry&&) noexcept = default;
VisualOdometry& VisualOdometry::operator=(VisualOdometry&&) noexcept = default;

void VisualOdometry::Reset() {
  state_->prev.reset();
  state_->spare.reset();
  state_->calls = 0;
  state_->window = SlidingWindow(state_->window.options());
  state_->T_w_last = Eigen::Isometry3d::Identity();
  state_->last_ref_cov.setZero();
}

const VoOptions& VisualOdometry::options() const { return state_->o; }

VoResult VisualOdometry::Process(const StereoImages& images,
                                 const Eigen::Isometry3d& prior_T_prev_curr,
                                 const Eigen::Matrix<double, 6, 6>& prior_covariance) {
  State& s = *state_;
  const VoOptions& o = s.o;
  VoResult res;
  const auto t_start = Clock::now();
  auto t = t_start;
  const bool windowed = s.Windowed();
  // The new pair, and the pair it is measured against (the previous one; in windowed
  // mode the last keyframe).
  std::unique_ptr<Pair> cur, prev;
  auto finish = [&](VoStatus status, std::string reason) {
    if (windowed && cur) {
      // Every outcome but an accepted measurement restarts the tracks and the window on
      // the new pair, which becomes the reference (as VO-10 makes it the previous pair).
      s.CompleteFeatures(cur.get(), {}, &res);
      s.RestartWindow(cur.get());
      s.prev = std::move(cur);
    }
    res.status = status;
    res.reason = std::move(reason);
    res.times.total_ms = Ms(t_start, Clock::now());
    return res;
  };

  if (std::string bad = s.CheckInput(images); !bad.empty()) {
    return finish(VoStatus::kBadInput, bad);
  }
  if (!prior_T_prev_curr.matrix().allFinite() || !prior_covariance.allFinite()) {
    return finish(VoStatus::kBadInput, "prior motion or covariance is not finite");
  }
  ++s.calls;

  cur = s.Prepare(images, &res, &t);
  prev = std::move(s.prev);
  if (!windowed) s.prev = std::move(cur);  // every outcome below makes this pair the previous one
  const Pair& c = windowed ? *cur : *s.prev;
  // Windowed mode: the prior from the reference pair (the last keyframe).
  const Eigen::Isometry3d prior_ref =
      windowed && prev && s.window.size() > 0
          ? s.window.pose(s.window.size() - 1).inverse() * s.T_w_last * prior_T_prev_curr
          : prior_T_prev_curr;
  struct Recycle {  // hands the old pair's buffers to the next call, on every return path
    State& s;
    std::unique_ptr<Pair>& p;
    ~Recycle() { if (p) s.spare = std::move(p); }
  } recycle{s, prev};

  if (!prev) return finish(VoStatus::kBaseline, "first pair: features kept for the next");
  if (static_cast<int>(prev->features.size()) < o.min_features) {
    return finish(VoStatus::kTooFewFeatures,
                  Format("previous pair has %.0f stereo features (need %.0f)",
                         prev->features.size(), o.min_features));
  }

  // ---- VO-10: motion too large for the overlap (checked on the prior) ----
  const Eigen::Vector3d prior_t = prior_ref.translation();
  const double prior_angle = Eigen::AngleAxisd(prior_ref.linear()).angle();
  if (o.motion_max_translation_m > 0 && prior_t.norm() > o.motion_max_translation_m) {
    return finish(VoStatus::kMotionTooLarge,
                  Format("prior step %.3f m exceeds %.3f m; re-initialised", prior_t.norm(),
                         o.motion_max_translation_m));
  }
  if (o.motion_max_rotation_deg > 0 && prior_angle > o.motion_max_rotation_deg * kDeg) {
    return finish(VoStatus::kMotionTooLarge,
                  Format("prior turn %.1f deg exceeds %.1f deg; re-initialised",
                         prior_angle / kDeg, o.motion_max_rotation_deg));
  }

  // ---- VO-6: tracking through the motion prior ----
  const Eigen::Matrix3d R_pc = prior_ref.linear();
  const Eigen::Vector3d rpy = geometry::RpyFromRotation(R_pc);
  Eigen::Matrix3d dR[3];
  geometry::RotationFromRpyDerivatives(rpy, nullptr, dR);
  const Eigen::Matrix3d R_cp = R_pc.transpose();
  const TriangulationLimits limits = s.Limits(c);
  const int levels = static_cast<int>(std::min(prev->left_band.size(), c.left_band.size()));
  const int border = o.feature_border_px;

  std::vector<Correspondence> corr;
  corr.reserve(prev->features.size());
  std::vector<char> fixed;  // VO-11: stayed put in the image while predicted to move
  fixed.reserve(prev->features.size());
  int predicted_inside = 0;
  double stereo_ms = 0;
  // Top to bottom through the images, for the cache; results kept in feature order (as
  // for the fresh features), which RANSAC's draws depend on.
  const int nprev = static_cast<int>(prev->features.size());
  std::vector<int> order(nprev);
  for (int i = 0; i < nprev; ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    const Eigen::Vector2d& pa = prev->features[a].left;
    const Eigen::Vector2d& pb = prev->features[b].left;
    return std::tie(pa.y(), pa.x()) < std::tie(pb.y(), pb.x());
  });
  std::vector<Correspondence> tracked(nprev);
  std::vector<char> tracked_ok(nprev, 0), tracked_fixed(nprev, 0);
  std::vector<Feature> carried(windowed ? nprev : 0);  // windowed: the tracks as seen now
  std::vector<int> corr_source;                          // corr index -> prev feature
  for (const int fi : order) {
    const Feature& f = prev->features[fi];
    const Eigen::Vector3d d = f.P - prior_t;
    const Eigen::Vector3d P_pred = R_cp * d;
    Eigen::Matrix<double, 3, 6> Jm;
    Jm.leftCols<3>() = -R_cp;
    for (int i = 0; i < 3; ++i) Jm.col(3 + i) = dR[i].transpose() * d;
    const Eigen::Matrix3d Sigma_pred =
        R_cp * f.Sigma * R_cp.transpose() + Jm * prior_covariance * Jm.transpose();
    Eigen::Vector2d u_pred;
    Eigen::Matrix<double, 2, 3> Jp;
    if (!c.rig.left->Project(P_pred, &u_pred, &Jp)) continue;
    if (u_pred.x() < border || u_pred.y() < border || u_pred.x() > c.width - 1 - border ||
        u_pred.y() > c.height - 1 - border) {
      continue;
    }
    ++predicted_inside;
    const Eigen::Matrix2d Sigma_u = Jp * Sigma_pred * Jp.transpose();
    const double sigma_u = std::sqrt(std::max(0.0, Sigma_u.selfadjointView<Eigen::Upper>().eigenvalues().maxCoeff()));
    const int radius = std::clamp(static_cast<int>(std::ceil(o.track_window_sigmas * sigma_u)),
                                  o.track_min_radius_px, o.track_max_radius_px);
    int L = 0;
    while (L + 1 < levels && radius > o.track_coarse_radius_px * (1 << L)) ++L;

    // Coarse to fine: search the whole window at level L, then +-2 px at each finer one.
    int bx = 0, by = 0;
    float score = 0;
    bool ok = true;
    for (int l = L; l >= 0 && ok; --l) {
      const int tx = static_cast<int>(std::lround(ToLevel(f.left.x(), l)));
      const int ty = static_cast<int>(std::lround(ToLevel(f.left.y(), l)));
      const int side = l == 0 ? o.match_template_px : o.track_coarse_template_px;
      // A track's position is sub-pixel: its template is cut at the nearest pixel (not
      // resampled, which would blur it a little more every pair) and the match moved by
      // the same sub-pixel offset afterwards.
      if (!s.tmpl.Extract(prev->left_band[l], tx, ty, side)) {
        ok = false;
        break;
      }
      int cx, cy, r;
      if (l == L) {
        cx = static_cast<int>(std::lround(ToLevel(u_pred.x(), l)));
        cy = static_cast<int>(std::lround(ToLevel(u_pred.y(), l)));
        r = (radius + (1 << l) - 1) >> l;
      } else {
        cx = 2 * bx;
        cy = 2 * by;
        r = 2;
      }
      ok = s.correlator.SearchWindow(s.tmpl, c.left_band[l], cx - r, cx + r,
                                     cy - r, cy + r, &bx, &by, &score);
    }
    if (!ok || score < o.track_min_score) continue;
    MatchResult m = Correlator::Refine(s.tmpl, c.left_band[0], bx, by,
                                       o.match_covariance_scale, o.match_min_sigma_px);
    if (!m.ok || m.score < o.track_min_score) continue;
    s.correlator.Iterate(s.tmpl, c.left_band[0], o.match_subpixel_iterations,
                         o.match_covariance_scale, o.match_min_sigma_px, &m);
    m.position += f.left - Eigen::Vector2d(std::lround(f.left.x()), std::lround(f.left.y()));

    // Stereo match of the tracked feature, its disparity narrowed by the known 3-D
    // position (VO-6).
    const auto t_s = Clock::now();
    if (!s.tmpl.ExtractSubpixel(c.left_band[0], m.position.x(), m.position.y(),
                                o.match_template_px)) {
      continue;
    }
    Eigen::Vector3d C1, r1;
    c.rig.left->BackProject(m.position, &C1, &r1);
    const double range = (P_pred - C1).dot(r1);
    const double sigma_range = std::sqrt(std::max(0.0, r1.dot(Sigma_pred * r1)));
    const double near = std::max(o.stereo_min_range_m, range - o.track_window_sigmas * sigma_range);
    const double far = std::min(c.far_range, range + o.track_window_sigmas * sigma_range);
    Eigen::Vector2d right;
    Eigen::Matrix2d Sigma_right;
    const bool matched = far > near && s.MatchRight(c, C1, r1, near, far,
                                                    o.track_stereo_margin_px, nullptr, &right,
                                                    &Sigma_right);
    stereo_ms += Ms(t_s, Clock::now());
    if (!matched) continue;
    StereoPoint sp;
    Eigen::Matrix<double, 3, 4> J;
    if (!TriangulateStereo(c.rig, m.position, m.covariance, right, Sigma_right, limits, &sp, &J)) {
      continue;
    }
    // Drop features whose 3-D positions disagree beyond their uncertainty (VO-6).
    const Eigen::Vector3d diff = sp.P - P_pred;
    const Eigen::Matrix3d S = sp.Sigma + Sigma_pred;
    if (o.track_max_chi2 > 0 && diff.dot(S.ldlt().solve(diff)) > o.track_max_chi2) continue;
    Correspondence x;
    x.P_prev = f.P;
    x.Sigma_prev = f.Sigma;
    x.P_curr = sp.P;
    x.Sigma_curr = sp.Sigma;
    x.left = m.position;
    x.right = right;
    // The right match follows the left one (its template is cut at the left match), so a
    // shift of the match moves both; a disparity offset moves the right one only.
    x.dPcurr_dshift.col(0) = J.col(0) + J.col(2);
    x.dPcurr_dshift.col(1) = J.col(1) + J.col(3);
    x.dPcurr_ddisparity = J.col(2);
    x.dPprev_ddisparity = f.dP_ddisparity;
    tracked[fi] = x;
    tracked_ok[fi] = 1;
    if (windowed) {
      Feature& n = carried[fi];
      n.left = m.position;
      n.P = sp.P;
      n.Sigma = sp.Sigma;
      n.dP_ddisparity = J.col(2);
      n.right = right;
      n.Sigma_left = m.covariance;
      n.Sigma_right = Sigma_right;
      n.track_id = f.track_id;
      n.age = f.age + 1;
    }
    tracked_fixed[fi] = (m.position - f.left).norm() < o.shadow_fixed_px &&
                        (u_pred - f.left).norm() > o.shadow_min_predicted_px;
  }
  for (int i = 0; i < nprev; ++i) {
    if (!tracked_ok[i]) continue;
    corr.push_back(tracked[i]);
    corr_source.push_back(i);
    res.tracks.push_back({prev->features[i].left, tracked[i].left, false});
    fixed.push_back(tracked_fixed[i]);
  }
  res.num_tracked = static_cast<int>(corr.size());
  {
    const auto now = Clock::now();
    res.times.track_ms = Ms(t, now) - stereo_ms;
    res.times.stereo_ms += stereo_ms;
    t = now;
  }
  const double overlap = double(predicted_inside) / double(prev->features.size());
  if (overlap < o.motion_min_overlap) {
    return finish(VoStatus::kMotionTooLarge,
                  Format("prior leaves %.0f %% of features in view (need %.0f %%); re-initialised",
                         100 * overlap, 100 * o.motion_min_overlap));
  }
  if (res.num_tracked < o.min_tracked) {
    return finish(VoStatus::kTooFewMatches, Format("%.0f features tracked (need %.0f)",
                                                   res.num_tracked, o.min_tracked));
  }

  // ---- VO-7: weighted least squares inside RANSAC ----
  RansacOptions ro;
  ro.iterations = o.ransac_iterations;
  ro.sample_size = o.ransac_sample_size;
  ro.inlier_px = o.ransac_inlier_px;
  ro.seed = o.ransac_seed + 0x9E3779B97F4A7C15ull * s.calls;
  RansacOutcome rs = RansacMotion(corr, c.rig, ro);

  // ---- VO-11: the rover's shadow (features fixed in the image) ----
  if (o.shadow_check) {
    int fixed_inliers = 0;
    for (int k : rs.inliers) fixed_inliers += fixed[k];
    if (2 * fixed_inliers > static_cast<int>(rs.inliers.size())) {
      // The winning motion rests on image-fixed features. If the other features agree on
      // a different motion, the two explanations compete: refuse rather than guess.
      std::vector<char> in(corr.size(), 0);
      for (int k : rs.inliers) in[k] = 1;
      std::vector<int> rest;
      for (int k = 0; k < static_cast<int>(corr.size()); ++k) {
        if (!in[k] && !fixed[k]) rest.push_back(k);
      }
      if (static_cast<int>(rest.size()) >= o.min_inliers) {
        const RansacOutcome alt = RansacMotion(corr, c.rig, ro, rest);
        if (static_cast<int>(alt.inliers.size()) >= o.min_inliers) {
          res.times.ransac_ms = Ms(t, Clock::now());
          return finish(VoStatus::kShadowAmbiguous,
                        Format("%.0f inliers fixed in the image against %.0f features moving "
                               "otherwise",
                               fixed_inliers, alt.inliers.size()));
        }
      }
    }
  }
  {
    const auto now = Clock::now();
    res.times.ransac_ms = Ms(t, now);
    t = now;
  }
  if (static_cast<int>(rs.inliers.size()) < o.min_inliers) {
    res.num_inliers = static_cast<int>(rs.inliers.size());
    return finish(VoStatus::kTooFewInliers, Format("%.0f RANSAC inliers (need %.0f)",
                                                   rs.inliers.size(), o.min_inliers));
  }

  // ---- VO-8: maximum likelihood ----
  std::vector<int> inliers = rs.inliers;
  MlOutcome ml = MaximumLikelihoodMotion(corr, inliers, rs.T_curr_prev.inverse(),
                                         o.ml_max_iterations, o.ml_tolerance);
  int iterations = ml.iterations;
  if (ml.converged && o.ml_outlier_chi2 > 0) {
    std::vector<int> kept;
    for (int k : inliers) {
      if (MahalanobisSquared(corr[k], ml.T_prev_curr) <= o.ml_outlier_chi2) kept.push_back(k);
    }
    if (kept.size() < inliers.size() && static_cast<int>(kept.size()) >= o.min_inliers) {
      inliers = std::move(kept);
      ml = MaximumLikelihoodMotion(corr, inliers, ml.T_prev_curr, o.ml_max_iterations,
                                   o.ml_tolerance);
      iterations += ml.iterations;
    }
  }
  res.iterations = iterations;
  res.num_inliers = static_cast<int>(inliers.size());
  for (int k : inliers) res.tracks[k].inlier = true;
  res.times.ml_ms = Ms(t, Clock::now());
  if (!ml.converged) {
    return finish(VoStatus::kNoConvergence,
                  Format("maximum likelihood did not converge in %.0f iterations",
                         o.ml_max_iterations));
  }
  res.T_prev_curr = ml.T_prev_curr;

  // ---- VO-13: the covariance from what the data shows (timed with the ML) ----
  MotionUncertainty u;
  {
    const auto t_u = Clock::now();
    const int grid = o.covariance_cluster_grid;
    std::vector<int> cluster;
    if (grid >= 2) {
      cluster.assign(corr.size(), 0);
      for (int k : inliers) {
        const int gx = std::clamp(static_cast<int>(corr[k].left.x() * grid / c.width), 0, grid - 1);
        const int gy = std::clamp(static_cast<int>(corr[k].left.y() * grid / c.height), 0, grid - 1);
        cluster[k] = gy * grid + gx;
      }
    }
    SharedErrors shared;
    shared.field_sigma_px = o.covariance_field_sigma_px;
    shared.disparity_sigma_px = o.covariance_disparity_sigma_px;
    shared.cell_shift_sigma_px = o.covariance_cell_shift_sigma_px;
    shared.cell_disparity_sigma_px = o.covariance_cell_disparity_sigma_px;
    shared.centre_px = Eigen::Vector2d(0.5 * (c.width - 1), 0.5 * (c.height - 1));
    shared.half_size_px = 0.5 * std::max(c.width, c.height);
    u = EstimateMotionUncertainty(corr, inliers, ml.T_prev_curr, cluster, grid * grid, shared);
    if (!u.ok) {
      res.T_prev_curr = Eigen::Isometry3d::Identity();
      return finish(VoStatus::kDegenerate, "motion undetermined: the normal matrix is singular");
    }
    res.covariance = u.covariance;
    res.variance_factor = u.variance_factor;
    res.cluster_factor = u.cluster_factor;
    res.times.ml_ms += Ms(t_u, Clock::now());
  }

  // ---- VO-10 on the estimate, VO-9 sanity ----
  const Eigen::Vector3d dt = ml.T_prev_curr.translation();
  const Eigen::Vector3d drpy = geometry::RpyFromRotation(ml.T_prev_curr.linear());
  const double angle = Eigen::AngleAxisd(ml.T_prev_curr.linear()).angle();
  auto reject = [&](VoStatus st, std::string why) {
    res.T_prev_curr = Eigen::Isometry3d::Identity();
    res.covariance.setZero();
    return finish(st, std::move(why));
  };
  if (o.motion_max_translation_m > 0 && dt.norm() > o.motion_max_translation_m) {
    return reject(VoStatus::kMotionTooLarge, Format("step %.3f m exceeds %.3f m; re-initialised",
                                                    dt.norm(), o.motion_max_translation_m));
  }
  if (o.motion_max_rotation_deg > 0 && angle > o.motion_max_rotation_deg * kDeg) {
    return reject(VoStatus::kMotionTooLarge, Format("turn %.1f deg exceeds %.1f deg; re-initialised",
                                                    angle / kDeg, o.motion_max_rotation_deg));
  }
  if (o.sanity_max_translation_m > 0 && dt.norm() > o.sanity_max_translation_m) {
    return reject(VoStatus::kSanityFailed, Format("update %.3f m exceeds %.3f m", dt.norm(),
                                                  o.sanity_max_translation_m));
  }
  const char* axis[3] = {"roll", "pitch", "yaw"};
  const double limit_deg[3] = {o.sanity_max_roll_deg, o.sanity_max_pitch_deg, o.sanity_max_yaw_deg};
  for (int i = 0; i < 3; ++i) {
    if (limit_deg[i] > 0 && std::abs(drpy[i]) > limit_deg[i] * kDeg) {
      return reject(VoStatus::kSanityFailed,
                    std::string(axis[i]) + Format(" update %.2f deg exceeds %.2f deg",
                                                  std::abs(drpy[i]) / kDeg, limit_deg[i]));
    }
  }
  if (images.R_site_ref) {
    const Eigen::Vector3d site = *images.R_site_ref * dt;
    if (o.sanity_max_site_dx_m > 0 && std::abs(site.x()) > o.sanity_max_site_dx_m) {
      return reject(VoStatus::kSanityFailed, Format("site X update %.3f m exceeds %.3f m",
                                                    site.x(), o.sanity_max_site_dx_m));
    }
    if (o.sanity_max_site_dy_m > 0 && std::abs(site.y()) > o.sanity_max_site_dy_m) {
      return reject(VoStatus::kSanityFailed, Format("site Y update %.3f m exceeds %.3f m",
                                                    site.y(), o.sanity_max_site_dy_m));
    }
    if (o.sanity_max_downslope_angle_deg > 0 && site.norm() > 0.01) {
      // Downslope: gravity (site +Z) projected on the ground plane, whose normal is the
      // reference frame's z axis (rover frame, Z down).
      const Eigen::Vector3d normal = images.R_site_ref->col(2);
      const Eigen::Vector3d g(0, 0, 1);
      const Eigen::Vector3d down = g - g.dot(normal) * normal;
      if (down.norm() > std::sin(2.0 * kDeg)) {
        const double a = std::acos(std::clamp(site.normalized().dot(down.normalized()), -1.0, 1.0));
        if (a > o.sanity_max_downslope_angle_deg * kDeg) {
          return reject(VoStatus::kSanityFailed,
                        Format("update is %.1f deg from downslope (limit %.1f deg)", a / kDeg,
                               o.sanity_max_downslope_angle_deg));
        }
      }
    }
  }

  // ---- VO-12: degenerate geometry ----
  {
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    for (int k : inliers) mean += corr[k].left;
    mean /= double(inliers.size());
    Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
    for (int k : inliers) scatter += (corr[k].left - mean) * (corr[k].left - mean).transpose();
    scatter /= double(inliers.size());
    const double spread = std::sqrt(std::max(0.0, scatter.selfadjointView<Eigen::Upper>().eigenvalues().minCoeff())) /
                          std::min(c.width, c.height);
    if (spread < o.degenerate_min_spread) {
      return reject(VoStatus::kDegenerate,
                    Format("inliers clustered: spread %.3f of the image (need %.3f)", spread,
                           o.degenerate_min_spread));
    }
    const double sigma_t = std::sqrt(res.covariance.topLeftCorner<3, 3>().trace());
    const double sigma_r = std::sqrt(res.covariance.bottomRightCorner<3, 3>().trace());
    if (o.degenerate_max_translation_sigma_m > 0 && sigma_t > o.degenerate_max_translation_sigma_m) {
      return reject(VoStatus::kDegenerate, Format("translation poorly determined: sigma %.3f m "
                                                  "(limit %.3f m)",
                                                  sigma_t, o.degenerate_max_translation_sigma_m));
    }
    if (o.degenerate_max_rotation_sigma_deg > 0 && sigma_r > o.degenerate_max_rotation_sigma_deg * kDeg) {
      return reject(VoStatus::kDegenerate, Format("rotation poorly determined: sigma %.2f deg "
                                                  "(limit %.2f deg)",
                                                  sigma_r / kDeg, o.degenerate_max_rotation_sigma_deg));
    }
  }
  if (windowed) s.Accept(images.frame_id, c.rig, corr_source, inliers, u, &carried, &cur, &prev, &res);
  return finish(VoStatus::kOk, "");
}

// Windowed mode, an accepted measurement of the new pair against the reference pair
// (res->T_prev_curr, covariance res->covariance): keyframe or not, the window's
// refinement, and the delta from the last call's pair.
void VisualOdometry::State::Accept(std::int64_t frame_id, const geometry::StereoRig& rig,
                                   const std::vector<int>& corr_source, const std::vector<int>& inliers,
                                   const MotionUncertainty& u, std::vector<Feature>* carried,
                                   std::unique_ptr<Pair>* cur, std::unique_ptr<Pair>* ref, VoResult* res) {
  const Eigen::Isometry3d T_ref_cur = res->T_prev_curr;
  const Matrix6d pair_cov = res->covariance;
  double age_sum = 0;
  for (int k : inliers) {
    const int age = (*carried)[static_cast<std::size_t>(corr_source[static_cast<std::size_t>(k)])].age;
    age_sum += age;
    res->track_length_max = std::max(res->track_length_max, age);
  }
  res->track_length_mean = inliers.empty() ? 0.0 : age_sum / double(inliers.size());
  const double moved = T_ref_cur.translation().norm();
  const double turned = Eigen::AngleAxisd(T_ref_cur.linear()).angle();
  // A pair that moved too little is measured against the reference and forgotten; one
  // that kept too few of the reference's features becomes a keyframe anyway.
  const bool keyframe = moved >= o.keyframe_min_translation_m || turned >= o.keyframe_min_rotation_deg * kDeg ||
                        2 * static_cast<int>(inliers.size()) < static_cast<int>((*ref)->features.size());
  res->keyframe = keyframe;
  const Eigen::Isometry3d T_w_ref = window.pose(window.size() - 1);
  if (!keyframe) {
    const Eigen::Isometry3d T_w_cur = T_w_ref * T_ref_cur;
    res->T_prev_curr = T_w_last.inverse() * T_w_cur;
    T_w_last = T_w_cur;
    // Both pairs are measured against the reference: the delta holds both errors. Their
    // sum bounds it (the reference's share cancels), which keeps the NEES honest.
    res->covariance = pair_cov + last_ref_cov;
    last_ref_cov = pair_cov;
    prev = std::move(*ref);
    spare = std::move(*cur);
    res->window_frames = window.size();
    return;
  }
  // The tracks VO-8 used live on; detection tops them up.
  std::vector<Feature> tracks;
  tracks.reserve(inliers.size());
  for (int k : inliers) tracks.push_back((*carried)[static_cast<std::size_t>(corr_source[static_cast<std::size_t>(k)])]);
  CompleteFeatures(cur->get(), std::move(tracks), res);

  const auto t0 = Clock::now();
  std::vector<WindowObservation> obs;
  obs.reserve((*cur)->features.size());
  for (const Feature& f : (*cur)->features) {
    obs.push_back({f.track_id, f.left, f.right, f.Sigma_left, f.Sigma_right, f.P, f.Sigma});
  }
  window.AddFrame(frame_id, T_w_ref * T_ref_cur, std::move(obs));
  const WindowSolution w = window.Refine(rig);
  res->window_frames = window.size();
  res->window_points = w.points;
  res->window_iterations = w.iterations;
  res->disparity_offset_px = w.disparity_offset_px;
  bool used = false;
  if (w.ok) {
    // The refined delta's covariance: the pair's VO-13 covariance, not shrunk by the
    // window (tracked features share errors over pairs that the window's own inverse
    // normal matrix does not see: it was overconfident on rendered sand, NEES 35), plus
    // the previous pose's correction (WindowSolution::correction), scaled like the fit
    // part of VO-13 (the larger of the variance and cluster factors).
    // The window's model of that correction sees match noise only; it is scaled by how much
    // the pair's full VO-13 covariance exceeds its own match-noise model, tr(H C) / 6.
    {
      const double factor = std::max({1.0, u.variance_factor, u.cluster_factor});
      const Eigen::LDLT<Matrix6d> Hp(u.inverse_normal);
      const double excess = Hp.info() == Eigen::Success ? Hp.solve(pair_cov).trace() / 6.0 : factor;
      Matrix6d cov = pair_cov + std::max(factor, excess) * w.correction;
      cov = 0.5 * (cov + cov.transpose()).eval();
      const geometry::Vector6d a = geometry::XyzRpyFromPose(w.T_prev_last);
      const geometry::Vector6d b = geometry::XyzRpyFromPose(T_ref_cur);
      geometry::Vector6d d = a - b;
      for (int i = 3; i < 6; ++i) d(i) = geometry::WrapAngle(d(i));
      const double chi2 = d.dot(pair_cov.ldlt().solve(d));
      if (cov.allFinite() && (o.window_max_chi2 <= 0 || chi2 <= o.window_max_chi2)) {
        res->covariance = cov;
        used = true;
      }
    }
  }
  // Published: the window's estimate of this pair against the last call's pair as it
  // was published, so that the deltas compose to the window's latest estimate and its
  // corrections of the poses before reach the user (the window's oldest pose is fixed).
  if (used) {
    const Eigen::Isometry3d T_w_cur = window.pose(window.size() - 1);
    res->T_prev_curr = T_w_last.inverse() * T_w_cur;
    T_w_last = T_w_cur;
  } else {
    // Refused: the pair's own estimate is published and the window restarts on this pair.
    window.PopNewest();
    res->T_prev_curr = T_w_last.inverse() * window.pose(window.size() - 1) * T_ref_cur;
    RestartWindow(cur->get());
  }
  res->covariance += last_ref_cov;
  last_ref_cov.setZero();
  res->window_used = used;
  res->times.window_ms = Ms(t0, Clock::now());
  prev = std::move(*cur);
}

}  // namespace rover::vo
