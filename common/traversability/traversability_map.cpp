#include "traversability/traversability_map.hpp"

#include "traversability/dense_stereo.hpp"

#include <Eigen/LU>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <optional>
#include <random>
#include <sstream>
#include <stdexcept>

namespace rover::traversability {

namespace {

// The ground fit's triples come from a Mersenne twister seeded 7 afresh for every cell, so
// every fit draws the same stream: it is computed once and replayed. Seeding the twister
// and its first twist cost more than the draws (about 1 % of a long drive's CPU).
// The cell of an n x n grid from (origin_x, origin_y) holding a weighted point, or nothing:
// off the grid, not finite, or with no positive sigma (AddPoints and a pair's framed moments
// bin the same points the same way).
std::optional<std::size_t> PointCell(const Eigen::Vector3d& p, double sigma, double origin_x, double origin_y,
                                     double inv_cell, int n) {
  if (!p.allFinite() || !std::isfinite(sigma) || sigma <= 0) return std::nullopt;
  const double fi = std::floor((p.x() - origin_x) * inv_cell);
  const double fj = std::floor((p.y() - origin_y) * inv_cell);
  if (!(fi >= 0 && fj >= 0 && fi < n && fj < n)) return std::nullopt;
  return static_cast<std::size_t>(fi) * static_cast<std::size_t>(n) + static_cast<std::size_t>(fj);
}

class SeedSevenStream {
 public:
  using result_type = std::mt19937::result_type;
  static constexpr result_type min() { return std::mt19937::min(); }
  static constexpr result_type max() { return std::mt19937::max(); }
  result_type operator()() {
    if (next_ < kCached) return Cached()[next_++];
    if (!tail_) {
      tail_.emplace(7);
      tail_->discard(kCached);
    }
    ++next_;
    return (*tail_)();
  }

 private:
  static constexpr std::size_t kCached = 512;
  static const std::array<result_type, kCached>& Cached() {
    static const std::array<result_type, kCached> cached = [] {
      std::array<result_type, kCached> a{};
      std::mt19937 g(7);
      for (auto& x : a) x = g();
      return a;
    }();
    return cached;
  }
  std::size_t next_ = 0;
  std::optional<std::mt19937> tail_;
};

double SecondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

[[noreturn]] void Bad(const std::string& what) {
  throw std::invalid_argument("traversability map: " + what);
}

}  // namespace

const char* CellStateName(CellState state) {
  switch (state) {
    case CellState::kUnknown: return "unknown";
    case CellState::kSafe: return "safe";
    case CellState::kCaution: return "caution";
    case CellState::kUnsafe: return "unsafe";
  }
  return "?";
}

TraversabilityMap::TraversabilityMap(const MapOptions& options) : options_(options) {
  CheckMapOptions(options_);
  n_ = std::max(1, static_cast<int>(std::lround(options_.extent_m / options_.cell_size_m)));
  acc_.assign(static_cast<std::size_t>(n_) * n_, Accumulator{});
  framed_.assign(acc_.size(), 0);
  framed_acc_.assign(acc_.size(), FramedMoments{});
  Recentre(0, 0);
}

void CheckMapOptions(const MapOptions& o) {
  auto positive = [](double v) { return std::isfinite(v) && v > 0; };
  if (!positive(o.cell_size_m)) Bad("cell_size_m must be > 0");
  if (!positive(o.extent_m) || o.extent_m / o.cell_size_m > 2000)
    Bad("extent_m must be > 0 and at most 2000 cells");
  if (!std::isfinite(o.footprint_radius_m) || o.footprint_radius_m < 0 ||
      o.footprint_radius_m > o.extent_m / 2)
    Bad("footprint_radius_m must be in [0, extent_m / 2]");
  if (!std::isfinite(o.tilt_radius_m) || o.tilt_radius_m < 0 || o.tilt_radius_m > o.extent_m / 2)
    Bad("tilt_radius_m must be in [0, extent_m / 2]");
  if (!std::isfinite(o.max_face_deg) || o.max_face_deg < 0 || o.max_face_deg >= 90)
    Bad("max_face_deg must be in [0, 90)");
  if (!(o.ground_band_fraction >= 0 && o.ground_band_fraction <= 0.5))
    Bad("ground_band_fraction must be in [0, 0.5]");
  if (!positive(o.max_step_m) || !positive(o.max_tilt_deg) || o.max_tilt_deg >= 90 ||
      !positive(o.max_roughness_m))
    Bad("max_step_m, max_tilt_deg (< 90) and max_roughness_m must be > 0");
  if (!positive(o.max_range_m)) Bad("max_range_m must be > 0");
  if (o.min_points < 1) Bad("min_points must be >= 1");
  if (!(o.caution_fraction > 0 && o.caution_fraction <= 1)) Bad("caution_fraction must be in (0, 1]");
  if (!(o.min_patch_fraction > 0 && o.min_patch_fraction <= 1))
    Bad("min_patch_fraction must be in (0, 1]");
  if (o.stereo_width_px != 0 && (o.stereo_width_px < 32 || o.stereo_width_px > 8192))
    Bad("stereo_width_px must be 0 or in [32, 8192]");
  if (o.num_disparities < 16 || o.num_disparities > 512) Bad("num_disparities must be in [16, 512]");
  if (o.block_size < 1 || o.block_size > 21 || o.block_size % 2 == 0)
    Bad("block_size must be odd, in [1, 21]");
  if (o.uniqueness_ratio < 0 || o.uniqueness_ratio > 100) Bad("uniqueness_ratio must be in [0, 100]");
  if (o.speckle_window < 0 || o.speckle_range < 0) Bad("speckle_window and speckle_range must be >= 0");
  if (!positive(o.disparity_sigma_px)) Bad("disparity_sigma_px must be > 0");
  if (!std::isfinite(o.min_texture) || o.min_texture < 0) Bad("min_texture must be >= 0");
  if (!std::isfinite(o.texture_sigma_px) || o.texture_sigma_px < 0 || o.texture_sigma_px > 10)
    Bad("texture_sigma_px must be in [0, 10]");
  if (!std::isfinite(o.tilt_margin_sigmas) || o.tilt_margin_sigmas < 0 || o.tilt_margin_sigmas > 10)
    Bad("tilt_margin_sigmas must be in [0, 10]");
  if (!std::isfinite(o.dip_margin_sigmas) || o.dip_margin_sigmas < 0 || o.dip_margin_sigmas > 10)
    Bad("dip_margin_sigmas must be in [0, 10]");
  if (!std::isfinite(o.relief_sigmas) || o.relief_sigmas < 0 || o.relief_sigmas > 10)
    Bad("relief_sigmas must be in [0, 10]");
  if (!std::isfinite(o.cell_plane_sigmas) || o.cell_plane_sigmas < 0 || o.cell_plane_sigmas > 10)
    Bad("cell_plane_sigmas must be in [0, 10]");
  if (!(o.crest_view_range_m >= 0 && o.crest_view_range_m <= 100) || !(o.crest_view_height_m > 0 && o.crest_view_height_m <= 10) ||
      !(o.crest_rise_fraction > 0 && o.crest_rise_fraction <= 1))
    Bad("crest_view_range_m must be in [0, 100], crest_view_height_m in (0, 10] and crest_rise_fraction in (0, 1]");
  if (!std::isfinite(o.roughness_margin_sigmas) || o.roughness_margin_sigmas < 0 || o.roughness_margin_sigmas > 10)
    Bad("roughness_margin_sigmas must be in [0, 10]");
  if (!std::isfinite(o.min_texture_snr) || o.min_texture_snr < 0 || o.min_texture_snr > 100)
    Bad("min_texture_snr must be in [0, 100]");
  if (o.subsample < 1 || o.subsample > 16) Bad("subsample must be in [1, 16]");
  if (!std::isfinite(o.lr_max_diff_px) || o.lr_max_diff_px < 0 || o.lr_max_diff_px > 64)
    Bad("lr_max_diff_px must be in [0, 64]");
  if (!std::isfinite(o.max_disparity_jump) || o.max_disparity_jump < 0)
    Bad("max_disparity_jump must be >= 0");
  if (!std::isfinite(o.min_range_m) || o.min_range_m < 0 || o.min_range_m >= o.max_range_m)
    Bad("min_range_m must be in [0, max_range_m)");
  if (!(o.rectified_fov_deg >= 0 && o.rectified_fov_deg < 170)) Bad("rectified_fov_deg must be in [0, 170)");
  if (!std::isfinite(o.min_x_m)) Bad("min_x_m must be finite");
  if (!(o.min_depression_deg >= 0 && o.min_depression_deg < 90)) Bad("min_depression_deg must be in [0, 90)");
}

void TraversabilityMap::Clear() {
  std::fill(acc_.begin(), acc_.end(), Accumulator{});
  std::fill(framed_.begin(), framed_.end(), 0);
  std::fill(framed_acc_.begin(), framed_acc_.end(), FramedMoments{});
  MarkAllStale();
}

void TraversabilityMap::MarkAllStale() const {
  all_stale_ = true;
  dirty_ = true;
}

void TraversabilityMap::Recentre(double x, double y) {
  if (!std::isfinite(x) || !std::isfinite(y)) Bad("Recentre: expected a finite position");
  const double cell = options_.cell_size_m;
  // Snap the origin to whole cells so that re-centring never resamples.
  const long ox = std::lround(x / cell) - n_ / 2;
  const long oy = std::lround(y / cell) - n_ / 2;
  const long old_x = std::lround(origin_x_ / cell);
  const long old_y = std::lround(origin_y_ / cell);
  if (!acc_.empty() && ox == old_x && oy == old_y) return;
  // The ratings move with the moments: a cell's rating depends only on the cells of its
  // patch, at their offsets. Cells entering the grid count as changed; the edge cells,
  // whose patches lost the cells that left, are rated again too (Rate). A second move
  // before a rating would leave edges the first one's ring no longer names: rate all.
  const bool keep_ratings = !all_stale_ && !shifted_ && cells_.size() == acc_.size() && changed_.size() == acc_.size();
  std::vector<Accumulator> moved(acc_.size());
  std::vector<Cell> moved_cells(keep_ratings ? acc_.size() : 0);
  std::vector<char> moved_changed(keep_ratings ? acc_.size() : 0, 1);
  std::vector<std::uint8_t> moved_framed(framed_.size(), 0);
  std::vector<FramedMoments> moved_framed_acc(framed_acc_.size());
  const long di = ox - old_x, dj = oy - old_y;
  for (int i = 0; i < n_; ++i) {
    const long si = i + di;
    if (si < 0 || si >= n_) continue;
    for (int j = 0; j < n_; ++j) {
      const long sj = j + dj;
      if (sj < 0 || sj >= n_) continue;
      const std::size_t to = static_cast<std::size_t>(i) * n_ + j, from = static_cast<std::size_t>(si) * n_ + sj;
      moved[to] = acc_[from];
      moved_framed[to] = framed_[from];
      moved_framed_acc[to] = framed_acc_[from];
      if (keep_ratings) {
        moved_cells[to] = cells_[from];
        moved_changed[to] = changed_[from];
      }
    }
  }
  acc_ = std::move(moved);
  framed_ = std::move(moved_framed);
  framed_acc_ = std::move(moved_framed_acc);
  origin_x_ = ox * cell;
  origin_y_ = oy * cell;
  if (keep_ratings) {
    cells_ = std::move(moved_cells);
    changed_ = std::move(moved_changed);
    shifted_ = true;
    dirty_ = true;
  } else {
    MarkAllStale();
  }
}

void TraversabilityMap::AddPoints(const std::vector<Eigen::Vector3d>& points_site,
                                  const std::vector<double>& sigma_m) {
  if (points_site.size() != sigma_m.size()) {
    std::ostringstream s;
    s << "AddPoints: " << points_site.size() << " points but " << sigma_m.size() << " sigmas";
    Bad(s.str());
  }
  const double inv_cell = 1.0 / options_.cell_size_m;
  for (std::size_t k = 0; k < points_site.size(); ++k) {
    const Eigen::Vector3d& p = points_site[k];
    const double s = sigma_m[k];
    const auto cell = PointCell(p, s, origin_x_, origin_y_, inv_cell, n_);
    if (!cell) continue;
    Accumulator& a = acc_[*cell];
    if (!changed_.empty()) changed_[*cell] = 1;
    const double fi = static_cast<double>(*cell / static_cast<std::size_t>(n_));
    const double fj = static_cast<double>(*cell % static_cast<std::size_t>(n_));
    const double w = 1.0 / (s * s);
    const double h = -p.z();
    a.n += 1;
    a.sw += static_cast<float>(w);
    a.sh += static_cast<float>(w * h);
    a.shh += static_cast<float>(w * h * h);
    const double dx = p.x() - origin_x_ - (fi + 0.5) * options_.cell_size_m;
    const double dy = p.y() - origin_y_ - (fj + 0.5) * options_.cell_size_m;
    a.sx += static_cast<float>(w * dx);
    a.sy += static_cast<float>(w * dy);
    a.sxx += static_cast<float>(w * dx * dx);
    a.sxy += static_cast<float>(w * dx * dy);
    a.syy += static_cast<float>(w * dy * dy);
    a.sxh += static_cast<float>(w * dx * h);
    a.syh += static_cast<float>(w * dy * h);
  }
  dirty_ = true;
}

void PlaceStereoPoints(const StereoPoints& sp, const Eigen::Vector3d& lens, const geometry::Pose& T_site_rover,
                       const geometry::Matrix6d& pose_cov, const MapOptions& stereo,
                       std::vector<Eigen::Vector3d>* points_site, std::vector<double>* sigma_m) {
  // Height sigma: stereo plus the pose. Stereo: the point's error along its ray, turned into
  // the site frame at the capture attitude (the map holds site heights: a ray that grazes
  // the hillside the rover stands on, level in the rover frame, has its range error partly
  // vertical in the site frame). Position: z variance. Attitude: a roll or pitch error
  // dtheta moves a point at horizontal distance d by ~d * dtheta vertically; take the larger
  // of the two tilt variances for every direction.
  const Eigen::Matrix3d R_site_rover = T_site_rover.linear();
  const double var_z = pose_cov(2, 2);
  const double var_tilt = std::max(pose_cov(3, 3), pose_cov(4, 4));
  std::vector<Eigen::Vector3d>& pts = *points_site;
  std::vector<double>& sig = *sigma_m;
  pts.clear();
  sig.clear();
  pts.reserve(sp.points_rover.size());
  sig.reserve(sp.points_rover.size());
  // The horizon band: rays less than min_depression_deg below the site's horizontal (Z
  // down), judged at the capture attitude (a rover pitched up 14 deg on a climb sees the
  // horizon 14 deg below its own horizontal plane), or below the plane the rover stands on
  // (its own x-y plane): on a hillside that plane is the ground's, and rays that graze it
  // meet the ground far beyond the camera's range, over foreshortened rows where SGBM
  // mismatches. Rolled 20 deg across sol188_191's hillside, rays 3.8 deg below the rover's
  // plane (and 19 deg below the site's horizontal) to the downhill side put points 0.46 m
  // over the ground 1.7 m away, and the drive stopped on them.
  const double sin_min_depression = stereo.min_depression_deg > 0 ? std::sin(stereo.min_depression_deg * M_PI / 180.0) : -2.0;
  for (std::size_t k = 0; k < sp.points_rover.size(); ++k) {
    const Eigen::Vector3d& pr = sp.points_rover[k];
    const double d2 = pr.x() * pr.x() + pr.y() * pr.y();
    if (d2 > stereo.max_range_m * stereo.max_range_m) continue;
    const Eigen::Vector3d ray_rover = pr - lens;
    const Eigen::Vector3d ray_site = R_site_rover * ray_rover;
    const double min_down = sin_min_depression * ray_rover.norm();
    if (ray_site.z() < min_down || ray_rover.z() < min_down) continue;
    const double stereo_z = (R_site_rover * sp.error_rover[k]).z();
    const double s2 = stereo_z * stereo_z + var_z + d2 * var_tilt;
    pts.push_back(T_site_rover * pr);
    sig.push_back(std::sqrt(s2));
  }
}

void TraversabilityMap::AddStereoPair(const cv::Mat& left, const cv::Mat& right,
                                      const geometry::StereoRig& rig,
                                      const geometry::Pose& T_site_rover,
                                      const geometry::Matrix6d& pose_cov, const MapOptions* camera) {
  if (!T_site_rover.matrix().allFinite()) Bad("AddStereoPair: the pose is not finite");
  if (!pose_cov.allFinite()) Bad("AddStereoPair: the pose covariance is not finite");
  for (int k = 0; k < 6; ++k)
    if (pose_cov(k, k) < 0) Bad("AddStereoPair: the pose covariance has a negative variance");
  stats_ = UpdateStats{};
  if (camera) CheckMapOptions(*camera);
  const MapOptions& stereo = camera ? *camera : options_;
  StereoPoints sp = DenseStereo(left, right, rig, stereo, &stats_);
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<Eigen::Vector3d> pts;
  std::vector<double> sig;
  PlaceStereoPoints(sp, rig.left->Center(), T_site_rover, pose_cov, stereo, &pts, &sig);
  AddPoints(pts, sig);
  if (options_.crest_view_range_m > 0)
    MarkFramedBy(*PairRectification(rig, left.cols, stereo), T_site_rover, stereo, pts, sig);
  stats_.points = static_cast<int>(pts.size());
  Rate();
  stats_.seconds_grid = SecondsSince(t0);
}

// The cells whose column (crest_view_height_m over the rover's ground plane at the cell's
// centre, where the rover stands at capture) this pair saw to its top: a crest there was
// in both images, inside the stereo's range and filters (PairFrames), and on rays below
// the horizon band that PlaceStereoPoints drops. Framed within crest_view_range_m: kFramed;
// not framed but holding some of this pair's points (`points_site`): kCut.
void TraversabilityMap::MarkFramedBy(const RectifiedRig& rect, const geometry::Pose& T_site_rover,
                                     const MapOptions& stereo, const std::vector<Eigen::Vector3d>& points_site,
                                     const std::vector<double>& sigma_m) {
  const double cell = options_.cell_size_m;
  std::vector<std::uint8_t> touched(framed_.size(), 0);
  // framed_height: the cells this pair framed, whether or not another pair had already.
  const bool heights = options_.framed_height != MapOptions::FramedHeight::kOff;
  std::vector<char> framed_now(heights ? framed_.size() : 0, 0);
  for (const Eigen::Vector3d& p : points_site) {
    const double fi = std::floor((p.x() - origin_x_) / cell), fj = std::floor((p.y() - origin_y_) / cell);
    if (fi >= 0 && fj >= 0 && fi < n_ && fj < n_) touched[static_cast<std::size_t>(fi) * n_ + static_cast<std::size_t>(fj)] = 1;
  }
  const double reach = stereo.max_range_m + cell;
  const Eigen::Vector3d at = T_site_rover.translation();
  const geometry::Pose T_rover_site = T_site_rover.inverse();
  const Eigen::Matrix3d R_site_rover = T_site_rover.linear();
  const double sin_min_depression =
      stereo.min_depression_deg > 0 ? std::sin(stereo.min_depression_deg * M_PI / 180.0) : -2.0;
  const int r = static_cast<int>(std::ceil(reach / cell)) + 1;
  const long ci = static_cast<long>(std::floor((at.x() - origin_x_) / cell));
  const long cj = static_cast<long>(std::floor((at.y() - origin_y_) / cell));
  for (long i = std::max(0L, ci - r); i <= std::min<long>(n_ - 1, ci + r); ++i) {
    for (long j = std::max(0L, cj - r); j <= std::min<long>(n_ - 1, cj + r); ++j) {
      const std::size_t k = static_cast<std::size_t>(i) * n_ + j;
      if ((framed_[k] & kFramed) && !(heights && touched[k])) continue;
      const double x = origin_x_ + (i + 0.5) * cell, y = origin_y_ + (j + 0.5) * cell;
      const double range = std::hypot(x - at.x(), y - at.y());
      if (range > reach) continue;
      // The cell's centre on the rover's own plane (z 0, down), and the column's top.
      Eigen::Vector3d p = T_rover_site * Eigen::Vector3d(x, y, at.z());
      p.z() = -options_.crest_view_height_m;
      const Eigen::Vector3d ray = p - rect.left_centre;
      const double min_down = sin_min_depression * ray.norm();
      const bool frames =
          !(ray.z() < min_down || (R_site_rover * ray).z() < min_down) && PairFrames(rect, p, stereo);
      if (frames && range <= options_.crest_view_range_m) {
        framed_[k] |= kFramed;
        if (heights) framed_now[k] = 1;
      } else if (!frames && touched[k]) {
        framed_[k] |= kCut;
      }
    }
  }
  if (heights) AddFramedMoments(points_site, sigma_m, framed_now);
  // The crest rule reads the view flags of a patch's cells and their 8-neighbours, which
  // the incremental rating's changed cells do not track: rate every cell after a view.
  MarkAllStale();
}

void TraversabilityMap::AddFramedMoments(const std::vector<Eigen::Vector3d>& points_site,
                                         const std::vector<double>& sigma_m, const std::vector<char>& framed_now) {
  // The same cells, points and weights as AddPoints; this pair's own moments apart.
  const double inv_cell = 1.0 / options_.cell_size_m;
  std::vector<FramedMoments> pair(framed_acc_.size());
  std::vector<std::size_t> cells;
  for (std::size_t k = 0; k < points_site.size() && k < sigma_m.size(); ++k) {
    const Eigen::Vector3d& p = points_site[k];
    const double s = sigma_m[k];
    const auto cell = PointCell(p, s, origin_x_, origin_y_, inv_cell, n_);
    if (!cell || !framed_now[*cell]) continue;
    const std::size_t c = *cell;
    const double w = 1.0 / (s * s);
    FramedMoments& m = pair[c];
    if (m.n == 0) cells.push_back(c);
    m.n += 1;
    m.sw += static_cast<float>(w);
    m.sh += static_cast<float>(w * -p.z());
  }
  for (const std::size_t c : cells) {
    const FramedMoments& m = pair[c];
    FramedMoments& all = framed_acc_[c];
    all.n += m.n;
    all.sw += m.sw;
    all.sh += m.sh;
    // One pair's reading: its points' mean less their height sigma (the pair's pose share
    // of it is common to them all, so it does not average down).
    if (m.n >= options_.min_points && m.sw > 0) all.best = std::max(all.best, (m.sh - std::sqrt(m.n * m.sw)) / m.sw);
  }
}

void TraversabilityMap::AddViewedPoints(const std::vector<Eigen::Vector3d>& points_site,
                                        const std::vector<double>& sigma_m, bool framed) {
  AddPoints(points_site, sigma_m);
  const double inv_cell = 1.0 / options_.cell_size_m;
  std::vector<char> cells(framed_.size(), 0);
  for (const Eigen::Vector3d& p : points_site) {
    const double fi = std::floor((p.x() - origin_x_) * inv_cell), fj = std::floor((p.y() - origin_y_) * inv_cell);
    if (!p.allFinite() || !(fi >= 0 && fj >= 0 && fi < n_ && fj < n_)) continue;
    const std::size_t c = static_cast<std::size_t>(fi) * n_ + static_cast<std::size_t>(fj);
    cells[c] = 1;
    framed_[c] |= framed ? kFramed : kCut;
  }
  if (framed && options_.framed_height != MapOptions::FramedHeight::kOff) AddFramedMoments(points_site, sigma_m, cells);
  MarkAllStale();  // as after MarkFramedBy
}

void TraversabilityMap::MarkView(double x, double y, double radius_m, bool framed) {
  const double cell = options_.cell_size_m;
  for (int i = 0; i < n_; ++i)
    for (int j = 0; j < n_; ++j)
      if (std::hypot(origin_x_ + (i + 0.5) * cell - x, origin_y_ + (j + 0.5) * cell - y) <= radius_m)
        framed_[static_cast<std::size_t>(i) * n_ + j] |= framed ? kFramed : kCut;
  MarkAllStale();  // as after MarkFramedBy
}

std::uint8_t TraversabilityMap::ViewAt(double x, double y) const {
  const double inv_cell = 1.0 / options_.cell_size_m;
  const double fi = std::floor((x - origin_x_) * inv_cell);
  const double fj = std::floor((y - origin_y_) * inv_cell);
  if (!(fi >= 0 && fj >= 0 && fi < n_ && fj < n_)) return 0;
  return framed_[static_cast<std::size_t>(fi) * n_ + static_cast<std::size_t>(fj)];
}

bool TraversabilityMap::Framed(double x, double y) const { return (ViewAt(x, y) & kFramed) != 0; }
bool TraversabilityMap::Open(double x, double y) const { return ViewAt(x, y) == kCut; }

Cell TraversabilityMap::At(double x, double y) const {
  const double inv_cell = 1.0 / options_.cell_size_m;
  const double fi = std::floor((x - origin_x_) * inv_cell);
  const double fj = std::floor((y - origin_y_) * inv_cell);
  if (!(fi >= 0 && fj >= 0 && fi < n_ && fj < n_)) return Cell{};
  return cells()[static_cast<std::size_t>(fi) * n_ + static_cast<std::size_t>(fj)];
}

const std::vector<Cell>& TraversabilityMap::cells() const {
  if (dirty_) Rate();
  return cells_;
}

// How far a cell's top stands over its mean (cell_plane_sigmas): the plane through the
// cell's own points, from their moments, its gradient shrunk by `k_sigmas` standard errors
// along itself, at the corner of the cell where it is highest, less its value at the
// points' centroid (where the mean lies). The gradient's covariance is (sum w x x^T)^-1
// times the fit's reduced chi-square when over 1 (the points scatter about the plane more
// than their sigmas say: pairs that disagree, a mismatched streak). At most twice the
// points' height spread: a plane is no model of a cell holding a wall and its foot, and a
// ramp sampled evenly has its top 1.7 spreads over its mean. Written by hand: a weighted
// least-squares plane from running moments, which the map keeps per cell anyway.
double TraversabilityMap::CellPlaneRise(const Accumulator& a, double cell_m, double k_sigmas) {
  if (a.n < 6 || !(a.sw > 0)) return 0.0;
  const double sw = a.sw, mx = a.sx / sw, my = a.sy / sw, h = a.sh / sw;
  const double cxx = a.sxx / sw - mx * mx, cxy = a.sxy / sw - mx * my, cyy = a.syy / sw - my * my;
  const double cxh = a.sxh / sw - mx * h, cyh = a.syh / sw - my * h;
  const double spread2 = std::max(0.0, static_cast<double>(a.shh) / sw - h * h);
  const double det = cxx * cyy - cxy * cxy;
  // Points on a line (or one spot) across the cell: no plane.
  const double extent2 = 0.25 * cell_m * cell_m;
  if (!(det > 1e-4 * extent2 * extent2)) return 0.0;
  const Eigen::Vector2d g((cyy * cxh - cxy * cyh) / det, (cxx * cyh - cxy * cxh) / det);
  const double g_norm = g.norm();
  if (!(g_norm > 0) || !std::isfinite(g_norm)) return 0.0;
  const double residual2 = std::max(0.0, spread2 - (g.x() * cxh + g.y() * cyh));  // weighted mean r^2
  const double chi2 = residual2 * sw / std::max(1.0, static_cast<double>(a.n) - 3.0);
  const Eigen::Vector2d dir = g / g_norm;
  // (sum w x x^T)^-1 = C^-1 / sw, along dir.
  const double var_along = (dir.x() * dir.x() * cyy - 2 * dir.x() * dir.y() * cxy + dir.y() * dir.y() * cxx) /
                           (det * sw) * std::max(1.0, chi2);
  const double rated = std::max(0.0, g_norm - k_sigmas * std::sqrt(std::max(0.0, var_along)));
  if (rated <= 0) return 0.0;
  const Eigen::Vector2d gr = dir * rated;
  const double rise = 0.5 * cell_m * (std::abs(gr.x()) + std::abs(gr.y())) - (gr.x() * mx + gr.y() * my);
  return std::clamp(rise, 0.0, 2.0 * std::sqrt(spread2));
}

std::vector<char> TraversabilityMap::CellsInHoles(const std::vector<char>& has_points, double diameter_cells) const {
  if (!(diameter_cells > 0.0)) return {};
  // The disc's offsets, as avoidance's hidden ground: radius half the width, in cells.
  const double r = 0.5 * diameter_cells;
  const int n = static_cast<int>(std::floor(r));
  std::vector<std::pair<int, int>> disc;
  for (int di = -n; di <= n; ++di)
    for (int dj = -n; dj <= n; ++dj)
      if (di * di + dj * dj <= r * r + 1e-9) disc.emplace_back(di, dj);
  auto empty = [&](int i, int j) {  // off the grid counts as without points
    return i < 0 || j < 0 || i >= n_ || j >= n_ || !has_points[static_cast<std::size_t>(i) * n_ + j];
  };
  // Centres of all-empty discs, then every cell of such a disc.
  std::vector<char> deep(has_points.size(), 0), hole(has_points.size(), 0);
  for (int i = 0; i < n_; ++i)
    for (int j = 0; j < n_; ++j) {
      bool all = true;
      for (const auto& [di, dj] : disc) all = all && empty(i + di, j + dj);
      deep[static_cast<std::size_t>(i) * n_ + j] = all;
    }
  for (int i = 0; i < n_; ++i)
    for (int j = 0; j < n_; ++j) {
      if (!deep[static_cast<std::size_t>(i) * n_ + j]) continue;
      for (const auto& [di, dj] : disc) {
        const int a = i + di, b = j + dj;
        if (a >= 0 && b >= 0 && a < n_ && b < n_) hole[static_cast<std::size_t>(a) * n_ + b] = 1;
      }
    }
  return hole;
}

void TraversabilityMap::Rate() const {
  const MapOptions& o = options_;
  const std::size_t count = static_cast<std::size_t>(n_) * n_;
  // Cell heights (weighted means) and sigmas.
  std::vector<float> h(count, 0.0f), s(count, 0.0f), e(count, 0.0f), mx(count, 0.0f), my(count, 0.0f),
      relief(count, 0.0f), top(count, 0.0f), rise(count, 0.0f);
  std::vector<char> known(count, 0);
  const bool framed_mean = o.framed_height == MapOptions::FramedHeight::kMean && o.crest_view_range_m > 0;
  const bool framed_max = o.framed_height == MapOptions::FramedHeight::kMax && o.crest_view_range_m > 0;
  for (std::size_t k = 0; k < count; ++k) {
    const Accumulator& a = acc_[k];
    if (a.n < o.min_points || a.sw <= 0) continue;
    known[k] = 1;
    h[k] = a.sh / a.sw;
    mx[k] = a.sx / a.sw;  // the centroid of the cell's points, from the cell centre
    my[k] = a.sy / a.sw;
    s[k] = std::sqrt(a.n / a.sw);
    const double spread2 = std::max(0.0, static_cast<double>(a.shh) / a.sw - static_cast<double>(h[k]) * h[k]);
    // The uncertainty of the cell's height (its weighted mean): its points' sigma, which
    // averaging does not shrink (the pose's share is common to a pair's points), and the
    // standard error the points' own scatter gives. A few points of a mismatched streak
    // among good ones (or pairs that disagree) scatter far more than their sigma says.
    e[k] = static_cast<float>(std::sqrt(static_cast<double>(s[k]) * s[k] + spread2 / a.n));
    // The relief within the cell: the points' scatter beyond their own noise (relief_sigmas).
    relief[k] = static_cast<float>(std::sqrt(std::max(0.0, spread2 - static_cast<double>(s[k]) * s[k])));
    top[k] = static_cast<float>(h[k] + std::sqrt(spread2));
    if (o.cell_plane_sigmas > 0) rise[k] = static_cast<float>(CellPlaneRise(a, o.cell_size_m, o.cell_plane_sigmas));
    // framed_height: at least what the pairs that framed its top read.
    const FramedMoments& f = framed_acc_[k];
    if (framed_mean && f.n >= o.min_points && f.sw > 0) h[k] = std::max(h[k], f.sh / f.sw);
    if (framed_max) h[k] = std::max(h[k], f.best);
  }
  // The patch: cell offsets within the footprint radius.
  const double cell = o.cell_size_m;
  // Cell offsets within a radius.
  auto offsets = [cell](double radius) {
    const int r = static_cast<int>(std::floor(radius / cell + 1e-9));
    std::vector<std::pair<int, int>> out;
    for (int di = -r; di <= r; ++di)
      for (int dj = -r; dj <= r; ++dj)
        if ((di * di + dj * dj) * cell * cell <= radius * radius + 1e-12) out.emplace_back(di, dj);
    return out;
  };
  const std::vector<std::pair<int, int>> patch = offsets(o.footprint_radius_m);
  const bool own_tilt_patch = o.tilt_radius_m > 0;
  const std::vector<std::pair<int, int>> tilt_patch = own_tilt_patch ? offsets(o.tilt_radius_m) : patch;
  auto min_known_of = [&o](std::size_t size) {
    return std::max<std::size_t>(3, static_cast<std::size_t>(std::ceil(o.min_patch_fraction * size)));
  };
  // Which cells to rate: those within a patch of a changed cell (a square of the patches'
  // reach holds both), and after a move the edge ring, whose patches lost cells. A cell's
  // rating is a function of its patch's moments alone, so the others keep theirs: the
  // same cells, bit for bit, as rating every cell (traversability_map_test).
  int reach = 0;
  for (const auto* offs : {&patch, &tilt_patch})
    for (const auto& [di, dj] : *offs) reach = std::max({reach, std::abs(di), std::abs(dj)});
  std::vector<char> rate(count, 0);
  if (all_stale_ || cells_.size() != count || changed_.size() != count) {
    rate.assign(count, 1);
    cells_.assign(count, Cell{});
  } else {
    for (int i = 0; i < n_; ++i) {
      for (int j = 0; j < n_; ++j) {
        const bool edge = i < reach || j < reach || i >= n_ - reach || j >= n_ - reach;
        if (shifted_ && edge) rate[static_cast<std::size_t>(i) * n_ + j] = 1;
        if (!changed_[static_cast<std::size_t>(i) * n_ + j]) continue;
        for (int a = std::max(0, i - reach); a <= std::min(n_ - 1, i + reach); ++a)
          std::fill_n(rate.begin() + static_cast<std::ptrdiff_t>(a) * n_ + std::max(0, j - reach),
                      std::min(n_ - 1, j + reach) - std::max(0, j - reach) + 1, 1);
      }
    }
  }
  for (std::size_t k = 0; k < count; ++k) {
    if (!rate[k]) continue;
    cells_[k] = Cell{};
    if (!known[k]) continue;
    cells_[k].elevation_m = top[k];
    cells_[k].height_sigma_m = s[k];
  }
  changed_.assign(count, 0);
  shifted_ = false;
  all_stale_ = false;
  const std::size_t min_known = min_known_of(patch.size());
  const std::size_t min_known_tilt = min_known_of(tilt_patch.size());
  const double tan_max_tilt = std::tan(o.max_tilt_deg * M_PI / 180.0);
  const double max_face_rad = o.max_face_deg > 0 ? o.max_face_deg * M_PI / 180.0 : HUGE_VAL;
  std::vector<Eigen::Vector3d> xs, xt;  // (dx, dy, h)
  std::vector<float> ss, se, sr;
  std::vector<char> inlier;
  xs.reserve(patch.size());
  // The known cells of a patch round (i, j), as (dx, dy, h) from the cell centre.
  auto gather = [&](const std::vector<std::pair<int, int>>& offs, int i, int j, std::vector<Eigen::Vector3d>& out,
                    std::vector<float>* sigmas, std::vector<float>* errors = nullptr,
                    std::vector<float>* reliefs = nullptr, std::vector<std::size_t>* indices = nullptr) {
    out.clear();
    if (indices) indices->clear();
    if (sigmas) sigmas->clear();
    if (errors) errors->clear();
    if (reliefs) reliefs->clear();
    for (const auto& [di, dj] : offs) {
      const int a = i + di, b = j + dj;
      if (a < 0 || b < 0 || a >= n_ || b >= n_) continue;
      const std::size_t k = static_cast<std::size_t>(a) * n_ + b;
      if (!known[k]) continue;
      out.emplace_back(di * cell + mx[k], dj * cell + my[k], h[k]);
      if (sigmas) sigmas->push_back(s[k]);
      if (errors) errors->push_back(e[k]);
      if (reliefs) reliefs->push_back(relief[k]);
      if (indices) indices->push_back(k);
    }
  };
  // Plane h = c0 + c1 dx + c2 dy by least squares over the known cells, then again
  // without the cells more than half a step limit ABOVE it: rocks stand up from the
  // ground, so the plane settles on the ground around them even when a big rock fills
  // much of the patch, and the rock shows as a step rather than a tilt. `c_fit` gets that
  // plane (the roughness is the scatter about it).
  //
  // Then the ground plane, when ground_band_fraction > 0. Least squares through the ground
  // and a wall of rocks seen from one side (the closed end of a pocket, its far side
  // hidden) leans on the wall, and the rocks' lower flanks lie within half a step of the
  // leaning plane, so they are never let go of: the wall read as a tilt with a short step
  // (caution). The ground is the surface the rocks stand on: a plane that holds many cells
  // within a band (ground_band_fraction of the step limit, or two of a cell's height
  // sigmas) and has hardly any below it. A leaning plane has ground above it at one end and
  // below it at the other, a plane on the rocks' tops has the ground below it. Candidates:
  // the plane above and planes through 24 triples of cells (drawn with a fixed seed: the
  // same patch gives the same plane), each scored by the cells in its band less twice those
  // below it; the best, if it beats the plane above, is refitted to the cells not above its
  // band. Written by hand rather than with a RANSAC library: OpenCV's estimators fit
  // models to image correspondences, not planes to a score that tells above from below.
  Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();  // of fit's last solve: sum of row row^T
  // Least squares over the cells `inlier` holds; false when under 3 or singular.
  auto solve = [&](const std::vector<Eigen::Vector3d>& pts, Eigen::Vector3d* c) {
    Eigen::Matrix3d AtA = Eigen::Matrix3d::Zero();
    Eigen::Vector3d Atb = Eigen::Vector3d::Zero();
    int used = 0;
    for (std::size_t k = 0; k < pts.size(); ++k) {
      if (!inlier[k]) continue;
      const Eigen::Vector3d row(1.0, pts[k].x(), pts[k].y());
      AtA += row * row.transpose();
      Atb += row * pts[k].z();
      ++used;
    }
    if (used < 3) return false;
    const Eigen::Vector3d c_new = AtA.ldlt().solve(Atb);
    if (!c_new.allFinite()) return false;
    *c = c_new;
    normal = AtA;
    return true;
  };
  auto residual = [](const Eigen::Vector3d& p, const Eigen::Vector3d& c) {
    return p.z() - (c[0] + c[1] * p.x() + c[2] * p.y());
  };
  const double half_step = 0.5 * o.max_step_m;
  const double band = o.ground_band_fraction * o.max_step_m;
  auto fit = [&](const std::vector<Eigen::Vector3d>& pts, const std::vector<float>& sig, Eigen::Vector3d* c_fit) {
    inlier.assign(pts.size(), 1);
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    normal.setZero();
    for (int pass = 0; pass < 4; ++pass) {
      if (!solve(pts, &c)) break;
      std::size_t kept = 0, changed = 0;
      for (std::size_t k = 0; k < pts.size(); ++k) {
        const char in = residual(pts[k], c) <= half_step ? 1 : 0;
        kept += in;
        changed += in != inlier[k];
        inlier[k] = in;
      }
      if (changed == 0 || kept < 3) break;
    }
    *c_fit = c;
    if (band <= 0.0 || pts.size() < 4) return c;
    auto band_of = [&](std::size_t k) { return std::clamp(2.0 * sig[k], band, half_step); };
    auto score = [&](const Eigen::Vector3d& q) {
      int in = 0, below = 0;
      for (std::size_t k = 0; k < pts.size(); ++k) {
        const double r = residual(pts[k], q), b = band_of(k);
        in += std::abs(r) <= b;
        below += r < -b;
      }
      return in - 2 * below;
    };
    const int fitted_score = score(c);
    int best_score = fitted_score;
    Eigen::Vector3d best = c;
    SeedSevenStream triples;
    std::uniform_int_distribution<std::size_t> pick(0, pts.size() - 1);
    for (int t = 0; t < 24; ++t) {
      const Eigen::Vector3d& p0 = pts[pick(triples)];
      const Eigen::Vector3d& p1 = pts[pick(triples)];
      const Eigen::Vector3d& p2 = pts[pick(triples)];
      Eigen::Matrix3d A;
      A << 1.0, p0.x(), p0.y(), 1.0, p1.x(), p1.y(), 1.0, p2.x(), p2.y();
      if (std::abs(A.determinant()) < 1e-6) continue;  // repeated or collinear cells
      const Eigen::Vector3d q = A.partialPivLu().solve(Eigen::Vector3d(p0.z(), p1.z(), p2.z()));
      if (!q.allFinite()) continue;
      const int sc = score(q);
      if (sc > best_score) best_score = sc, best = q;
    }
    if (best_score == fitted_score) return c;
    // Refit to the cells not above the winner's band (twice: the refit moves a little).
    Eigen::Vector3d ground = best;
    const std::vector<char> kept_before = inlier;
    const Eigen::Matrix3d normal_before = normal;
    for (int pass = 0; pass < 2; ++pass) {
      for (std::size_t k = 0; k < pts.size(); ++k) inlier[k] = residual(pts[k], ground) <= band_of(k) ? 1 : 0;
      if (!solve(pts, &ground)) {
        inlier = kept_before;
        normal = normal_before;
        return c;
      }
    }
    return ground;
  };
  // The plane rated: the fitted one with its gradient shrunk, about the centroid of the
  // cells it was fitted to, by tilt_margin_sigmas standard errors of the gradient along its
  // own direction. The error comes from the cells' height sigma and how the cells of the
  // last fit spread over the patch (sigma^2 times the slope block of the inverse normal
  // matrix). A plane through cells in a line has any slope across the line: its error is
  // unbounded, so it is rated level, and steps are measured from a level plane rather than
  // from a slope the data never determined. Returns the rated gradient; must follow the
  // fit of `pts` (it reads that fit's normal matrix and inliers).
  auto rate_plane = [&](const std::vector<Eigen::Vector3d>& pts, Eigen::Vector3d& c, double sigma) {
    const double g = std::hypot(c[1], c[2]);
    if (o.tilt_margin_sigmas <= 0 || g <= 0) return g;
    double rated = 0.0;
    Eigen::FullPivLU<Eigen::Matrix3d> lu(normal);
    if (lu.isInvertible()) {
      const Eigen::Vector2d dir(c[1] / g, c[2] / g);
      const double var = sigma * sigma * dir.dot(lu.inverse().block<2, 2>(1, 1) * dir);
      if (std::isfinite(var) && var >= 0) rated = std::max(0.0, g - o.tilt_margin_sigmas * std::sqrt(var));
    }
    if (rated >= g) return g;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    int used = 0;
    for (std::size_t k = 0; k < pts.size(); ++k)
      if (inlier[k]) mean += pts[k], ++used;
    if (used == 0) return rated;
    mean /= used;
    const double f = rated / g;
    const double z_at_mean = c[0] + c[1] * mean.x() + c[2] * mean.y();
    c[1] *= f;
    c[2] *= f;
    c[0] = z_at_mean - c[1] * mean.x() - c[2] * mean.y();
    return rated;
  };
  auto rms = [](const std::vector<float>& v) {
    double sum = 0;
    for (float x : v) sum += static_cast<double>(x) * x;
    return v.empty() ? 0.0 : std::sqrt(sum / v.size());
  };
  // Crests out of frame (crest_view_range_m): a cell that is open (cut by a pair's frame,
  // never framed within range), or has an open 8-neighbour, may have a crest out of view.
  const bool crests = o.crest_view_range_m > 0;
  std::vector<char> open_side(crests ? count : 0, 0);
  if (crests) {
    for (int i = 0; i < n_; ++i)
      for (int j = 0; j < n_; ++j) {
        char open = 0;
        for (int di = -1; di <= 1 && !open; ++di)
          for (int dj = -1; dj <= 1 && !open; ++dj) {
            const int a = i + di, b = j + dj;
            open = a >= 0 && b >= 0 && a < n_ && b < n_ && framed_[static_cast<std::size_t>(a) * n_ + b] == kCut;
          }
        open_side[static_cast<std::size_t>(i) * n_ + j] = open;
      }
  }
  const double crest_rise = o.crest_rise_fraction * o.max_step_m;
  const bool open_unknown = crests && o.open_cells_unknown;
  const bool unframed_unknown = crests && o.unframed_unknown;
  const std::vector<char> in_hole = CellsInHoles(known, o.hole_unknown_m / o.cell_size_m);
  std::vector<std::size_t> xi;
  std::vector<float> st;
  for (int i = 0; i < n_; ++i) {
    for (int j = 0; j < n_; ++j) {
      if (!rate[static_cast<std::size_t>(i) * n_ + j]) continue;
      gather(patch, i, j, xs, &ss, &se, &sr, &xi);
      if (xs.size() < min_known) continue;
      Eigen::Vector3d c_fit;  // roughness: the scatter about the plane fitted
      Eigen::Vector3d c = fit(xs, ss, &c_fit);
      // The tilt: of the wheel patch's own plane, or of the plane over the rover's size
      // when that patch is known well enough (else the wheel patch's, the only one there is).
      double grad = rate_plane(xs, c, rms(ss));
      double face = 0.0;
      // The step is measured from the ground plane under the rover's size when there is
      // one: a rock that fills much of the wheel patch tilts that patch's own plane, which
      // would absorb the rock as a tilt; the body-scale plane stays on the ground.
      Eigen::Vector3d ground = c;
      if (own_tilt_patch) {
        gather(tilt_patch, i, j, xt, &st);
        if (xt.size() >= min_known_tilt) {
          Eigen::Vector3d ct_fit;
          Eigen::Vector3d ct = fit(xt, st, &ct_fit);
          // How much steeper the wheel patch is than the body's plane: never more than the
          // wheel patch's own tilt (a rock's flank on level ground rates as it always did,
          // although the body plane there leans a little on the rock's foot), and nothing
          // on a uniform slope.
          const double body = rate_plane(xt, ct, rms(st));
          face = std::max(0.0, std::atan(grad) - std::atan(body));
          grad = body;
          ground = ct;
        }
      }
      // The step: the highest cell above the ground plane less the lowest below it. A rock
      // stands above the ground, and the highest cell counts in full. The ground plane is
      // the surface the rocks stand on, so a cell below it is a hole or the ground's own
      // error, and it counts only by as much as `dip_margin_sigmas` of its height uncertainty
      // cannot explain: the lowest of a patch's cells lies under the ground by its error
      // alone (a cell of 7 HAZCAM points, 3 of them a mismatched streak 0.25 m low, took
      // a 0.19 m cobble's step to 0.25 m). A hole deeper than its error still counts.
      double lo = 0, hi = 0, sum2 = 0, sig2 = 0;
      bool crest_unseen = false;
      for (std::size_t k = 0; k < xs.size(); ++k) {
        const double res = xs[k].z() - (c_fit[0] + c_fit[1] * xs[k].x() + c_fit[2] * xs[k].y());
        const double above = xs[k].z() - (ground[0] + ground[1] * xs[k].x() + ground[2] * xs[k].y());
        // Rising toward a side no pair framed: the crest may stand there, higher.
        if (crests && above >= crest_rise && open_side[xi[k]]) crest_unseen = true;
        lo = std::min(lo, above + o.dip_margin_sigmas * se[k]);
        hi = std::max(hi, above + o.relief_sigmas * sr[k] + rise[xi[k]]);
        // The roughness: how far each cell lies off the plane beyond what its own height
        // error explains (roughness_margin_sigmas of it).
        const double off = std::max(0.0, std::abs(res) - o.roughness_margin_sigmas * se[k]);
        sum2 += off * off;
        sig2 += static_cast<double>(ss[k]) * ss[k];
      }
      Cell& out = cells_[static_cast<std::size_t>(i) * n_ + j];
      out.step_m = static_cast<float>(hi - lo);
      out.tilt_rad = static_cast<float>(std::atan(grad));
      out.face_rad = static_cast<float>(face);
      out.roughness_m = static_cast<float>(std::sqrt(sum2 / xs.size()));
      const std::size_t centre = static_cast<std::size_t>(i) * n_ + j;
      out.sigma_m = known[centre] ? s[centre] : static_cast<float>(std::sqrt(sig2 / xs.size()));
      const double worst = std::max({out.step_m / o.max_step_m, grad / tan_max_tilt,
                                     out.roughness_m / o.max_roughness_m, face / max_face_rad});
      out.goodness = static_cast<float>(std::clamp(1.0 - worst, 0.0, 1.0));
      out.state = worst >= 1.0                  ? CellState::kUnsafe
                  : worst >= o.caution_fraction ? CellState::kCaution
                                                : CellState::kSafe;
      // The step read is a lower bound only: the cell is at least caution, and its step
      // reads the limit itself (a crest up to it may stand there unseen), which no rated
      // cell short of unsafe reaches otherwise; the vote drives a step over such a cell only
      // when no other is allowed (hazards.map: DrivenStepLimit). An unsafe cell stays
      // unsafe. Not unknown: the vote lets a step cross a few unknown cells, and a rock's
      // flank is a few cells (navbench seed 7 k0.20_r05 put a body corner on a 0.30 m rock
      // so). Nor goodness 0: the vote's look-ahead takes its worst cell, and arcs that all
      // met one were told apart by the goal alone (k0.20_r02 drove into a rock so).
      if (crest_unseen && out.state != CellState::kUnsafe) {
        out.state = CellState::kCaution;
        out.goodness = std::min(out.goodness, static_cast<float>(o.CautionGoodness()));
        out.step_m = static_cast<float>(o.max_step_m);
        out.crest_unseen = true;
      }
      // Open: its top was never in view, so short of unsafe its rating is a guess: unknown
      // (open_cells_unknown). Never better: unsafe stays unsafe. Its own height stays, for
      // the clearance model. Not the cells with no points of their own beside it: most are
      // the ground hidden behind a rock, and unknown they box a rover in among rocks.
      if (open_unknown && out.state != CellState::kUnsafe && framed_[centre] == kCut) {
        const float elevation = out.elevation_m, height_sigma = out.height_sigma_m;
        out = Cell{};
        out.elevation_m = elevation;
        out.height_sigma_m = height_sigma;
      }
      // In a hole in the points wide enough to hold a rock, with none of its own: its
      // rating is the ground round the hole (hole_unknown_m).
      if (!in_hole.empty() && in_hole[centre] && out.state != CellState::kUnsafe) out = Cell{};
      // Without points of its own and never framed: nothing looked at it (unframed_unknown).
      if (unframed_unknown && !known[centre] && !(framed_[centre] & kFramed) && out.state != CellState::kUnsafe)
        out = Cell{};
    }
  }
  dirty_ = false;
}

namespace {

// Sets the options `node` holds over `o` (keys already checked).
MapOptions ReadMapOptions(const config::ConfigNode& node, MapOptions o) {
  node.Get("cell_size_m", o.cell_size_m, 0.01, 10.0);
  node.Get("extent_m", o.extent_m, 0.1, 200.0);
  node.Get("footprint_radius_m", o.footprint_radius_m, 0.0, 10.0);
  node.Get("tilt_radius_m", o.tilt_radius_m, 0.0, 10.0);
  node.Get("max_step_m", o.max_step_m, 1e-3, 10.0);
  node.Get("max_tilt_deg", o.max_tilt_deg, 0.1, 89.0);
  node.Get("max_face_deg", o.max_face_deg, 0.0, 89.0);
  node.Get("max_roughness_m", o.max_roughness_m, 1e-4, 10.0);
  node.Get("max_range_m", o.max_range_m, 0.1, 100.0);
  node.Get("min_points", o.min_points, 1, 100000);
  node.Get("caution_fraction", o.caution_fraction, 0.01, 1.0);
  node.Get("min_patch_fraction", o.min_patch_fraction, 0.01, 1.0);
  node.Get("stereo_width_px", o.stereo_width_px, 0, 8192);
  if (o.stereo_width_px != 0 && o.stereo_width_px < 32)
    node.Fail("stereo_width_px: expected 0 (the images' own width) or at least 32");
  node.Get("num_disparities", o.num_disparities, 16, 512);
  node.Get("block_size", o.block_size, 1, 21);
  if (o.block_size % 2 == 0) node.Fail("block_size: expected an odd number, got " + std::to_string(o.block_size));
  node.Get("uniqueness_ratio", o.uniqueness_ratio, 0, 100);
  node.Get("speckle_window", o.speckle_window, 0, 10000);
  node.Get("speckle_range", o.speckle_range, 0, 100);
  node.Get("disparity_sigma_px", o.disparity_sigma_px, 1e-3, 10.0);
  node.Get("texture_sigma_px", o.texture_sigma_px, 0.0, 10.0);
  node.Get("subsample", o.subsample, 1, 16);
  node.Get("min_range_m", o.min_range_m, 0.0, 100.0);
  node.Get("max_disparity_jump", o.max_disparity_jump, 0.0, 10.0);
  node.Get("min_texture", o.min_texture, 0.0, 255.0);
  node.Get("min_texture_snr", o.min_texture_snr, 0.0, 100.0);
  node.Get("tilt_margin_sigmas", o.tilt_margin_sigmas, 0.0, 10.0);
  node.Get("dip_margin_sigmas", o.dip_margin_sigmas, 0.0, 10.0);
  node.Get("roughness_margin_sigmas", o.roughness_margin_sigmas, 0.0, 10.0);
  node.Get("relief_sigmas", o.relief_sigmas, 0.0, 10.0);
  node.Get("cell_plane_sigmas", o.cell_plane_sigmas, 0.0, 10.0);
  node.Get("crest_view_range_m", o.crest_view_range_m, 0.0, 100.0);
  node.Get("crest_view_height_m", o.crest_view_height_m, 1e-3, 10.0);
  node.Get("crest_rise_fraction", o.crest_rise_fraction, 1e-3, 1.0);
  node.Get("open_cells_unknown", o.open_cells_unknown);
  node.Get("hole_unknown_m", o.hole_unknown_m, 0.0, 10.0);
  node.Get("unframed_unknown", o.unframed_unknown);
  std::string framed = o.framed_height == MapOptions::FramedHeight::kMean  ? "mean"
                       : o.framed_height == MapOptions::FramedHeight::kMax ? "max"
                                                                           : "off";
  node.GetEnum("framed_height", framed, {"off", "mean", "max"});
  o.framed_height = framed == "mean" ? MapOptions::FramedHeight::kMean
                    : framed == "max" ? MapOptions::FramedHeight::kMax
                                      : MapOptions::FramedHeight::kOff;
  node.Get("drop_unseen_border", o.drop_unseen_border);
  node.Get("lr_max_diff_px", o.lr_max_diff_px, 0.0, 64.0);
  node.Get("ground_band_fraction", o.ground_band_fraction, 0.0, 0.5);
  node.Get("rectified_fov_deg", o.rectified_fov_deg, 0.0, 169.0);
  node.Get("min_x_m", o.min_x_m, -100.0, 100.0);
  node.Get("min_depression_deg", o.min_depression_deg, 0.0, 89.0);
  if (o.min_range_m >= o.max_range_m)
    node.Fail("min_range_m: expected less than max_range_m");
  if (o.footprint_radius_m > o.extent_m / 2)
    node.Fail("footprint_radius_m: expected at most extent_m / 2");
  if (o.tilt_radius_m > o.extent_m / 2) node.Fail("tilt_radius_m: expected at most extent_m / 2");
  return o;
}

const std::vector<std::string> kMapOnlyKeys = {
    "cell_size_m", "extent_m", "footprint_radius_m", "tilt_radius_m", "max_step_m", "max_tilt_deg", "max_face_deg",
    "max_roughness_m", "min_points", "caution_fraction", "min_patch_fraction", "tilt_margin_sigmas", "dip_margin_sigmas",
    "roughness_margin_sigmas", "relief_sigmas", "cell_plane_sigmas", "ground_band_fraction", "crest_view_range_m", "crest_view_height_m",
    "crest_rise_fraction", "open_cells_unknown", "hole_unknown_m", "unframed_unknown", "framed_height"};

}  // namespace

const std::vector<std::string>& CameraOptionKeys() {
  static const std::vector<std::string> keys = {
      "max_range_m", "min_range_m", "stereo_width_px", "num_disparities", "block_size", "uniqueness_ratio",
      "speckle_window", "speckle_range", "disparity_sigma_px", "texture_sigma_px", "subsample", "max_disparity_jump", "min_texture",
      "min_texture_snr", "drop_unseen_border", "lr_max_diff_px", "rectified_fov_deg", "min_x_m", "min_depression_deg"};
  return keys;
}

MapOptions LoadMapOptions(const config::ConfigNode& node) {
  if (node.IsNull()) return MapOptions{};
  if (!node.IsMap()) node.Fail("expected a map of traversability options");
  std::vector<std::string> keys = kMapOnlyKeys;
  keys.insert(keys.end(), CameraOptionKeys().begin(), CameraOptionKeys().end());
  node.CheckKeys(keys);
  return ReadMapOptions(node, MapOptions{});
}

MapOptions LoadCameraOptions(const config::ConfigNode& node, const MapOptions& base) {
  if (node.IsNull()) return base;
  if (!node.IsMap()) node.Fail("expected a map of one camera's stereo options");
  node.CheckKeys(CameraOptionKeys());
  return ReadMapOptions(node, base);
}

MapOptions LoadMapOptions(const YAML::Node& node, const std::string& where) {
  return LoadMapOptions(config::ConfigNode(node, where, ""));
}

}  // namespace rover::traversability
