#include "vo_carry/track_carry.hpp"

#include "vo_eval/vo_evaluation.hpp"

#include <cmath>
#include <map>

namespace rover::vo_carry {

void CarryAccumulator::Add(std::int64_t track_id, const Eigen::Vector2d& left_error,
                           const Eigen::Vector2d& right_error, bool defining, const Eigen::Matrix2d* image_map) {
  const auto it = last_.find(track_id);
  if (!defining && it != last_.end()) {
    if (it->second.defining) {
      ++tracks_;  // its first match after the one that defines the point
    } else {
      // l_n-1 is itself a match's error (the defining one is 0 by construction).
      const Eigen::Vector2d& prev = it->second.left;
      s_prev_curr_ += prev.cwiseProduct(left_error);
      s_prev_prev_ += prev.cwiseProduct(prev);
      s_curr_curr_ += left_error.cwiseProduct(left_error);
      ++track_pairs_;
      if (image_map) {
        const Eigen::Vector2d mapped = *image_map * prev;
        s_mapped_curr_ += mapped.dot(left_error);
        s_mapped_mapped_ += mapped.squaredNorm();
        ++mapped_pairs_;
      }
    }
    s_left_right_ += left_error.cwiseProduct(right_error);
    s_left_left_ += left_error.cwiseProduct(left_error);
    ++stereo_pairs_;
  } else if (!defining) {
    return;  // a chain not started here (its defining observation was not seen)
  }
  last_[track_id] = {left_error, defining};
}

void CarryAccumulator::Merge(const CarryAccumulator& other) {
  tracks_ += other.tracks_;
  track_pairs_ += other.track_pairs_;
  stereo_pairs_ += other.stereo_pairs_;
  mapped_pairs_ += other.mapped_pairs_;
  s_mapped_curr_ += other.s_mapped_curr_;
  s_mapped_mapped_ += other.s_mapped_mapped_;
  s_prev_curr_ += other.s_prev_curr_;
  s_prev_prev_ += other.s_prev_prev_;
  s_curr_curr_ += other.s_curr_curr_;
  s_left_right_ += other.s_left_right_;
  s_left_left_ += other.s_left_left_;
}

CarryEstimate CarryAccumulator::Estimate() const {
  CarryEstimate e;
  e.tracks = tracks_;
  e.track_pairs = track_pairs_;
  e.stereo_pairs = stereo_pairs_;
  const auto ratio = [](double num, double den) { return den > 0 ? num / den : 0.0; };
  for (int a = 0; a < 2; ++a) {
    e.track_carry_xy(a) = ratio(s_prev_curr_(a), s_prev_prev_(a));
    e.stereo_carry_xy(a) = ratio(s_left_right_(a), s_left_left_(a));
  }
  e.track_carry = ratio(s_prev_curr_.sum(), s_prev_prev_.sum());
  e.stereo_carry = ratio(s_left_right_.sum(), s_left_left_.sum());
  e.track_carry_mapped = ratio(s_mapped_curr_, s_mapped_mapped_);
  e.mapped_pairs = mapped_pairs_;
  if (track_pairs_ > 1) {
    // sum |l_n - rho l_n-1|^2 from the sums, over 2 per pair less the one fitted.
    const double rho = e.track_carry;
    const double rss = s_curr_curr_.sum() - 2 * rho * s_prev_curr_.sum() + rho * rho * s_prev_prev_.sum();
    const double variance = std::max(0.0, rss) / (2.0 * track_pairs_ - 1.0);
    e.match_sigma_px = std::sqrt(variance);
    e.track_carry_stderr = std::sqrt(variance / s_prev_prev_.sum());
  }
  return e;
}

namespace {

// The true range along the ray of a (full-size) pixel, bilinear between the four pixel
// centres round it; false near a depth edge (a rock's silhouette, the sky), where the
// feature's 3-D point is not defined by its pixel.
bool RangeAt(const cv::Mat& depth, const Eigen::Vector2d& pixel, double* range) {
  const int x0 = static_cast<int>(std::floor(pixel.x())), y0 = static_cast<int>(std::floor(pixel.y()));
  if (x0 < 0 || y0 < 0 || x0 + 1 >= depth.cols || y0 + 1 >= depth.rows) return false;
  const double fx = pixel.x() - x0, fy = pixel.y() - y0;
  const double d00 = depth.at<float>(y0, x0), d01 = depth.at<float>(y0, x0 + 1);
  const double d10 = depth.at<float>(y0 + 1, x0), d11 = depth.at<float>(y0 + 1, x0 + 1);
  const double lo = std::min({d00, d01, d10, d11}), hi = std::max({d00, d01, d10, d11});
  if (lo <= 0 || hi - lo > 0.02 * lo) return false;
  *range = (1 - fy) * ((1 - fx) * d00 + fx * d01) + fy * ((1 - fx) * d10 + fx * d11);
  return true;
}

// A pixel of frame a carried to the true surface and into frame b (models at the working
// resolution, depth at the rendered size).
bool CarryPixel(const vo_eval::RenderedDriveSequence& drive, const geometry::CameraModel& left, double scale,
                const cv::Mat& depth_a, int a, int b, const Eigen::Vector2d& u, Eigen::Vector2d* out) {
  const Eigen::Vector2d full = ((u.array() + 0.5) / scale - 0.5).matrix();
  double range = 0;
  if (!RangeAt(depth_a, full, &range)) return false;
  Eigen::Vector3d origin, direction;
  drive.rig().left->BackProject(full, &origin, &direction);
  const Eigen::Vector3d X = drive.SitePose(a) * (origin + range * direction);
  return left.Project(drive.SitePose(b).inverse() * X, out);
}

// A_n: d(pixel in frame b) / d(pixel in frame a) round u, through the true surface
// (central differences of one pixel).
bool ImageMap(const vo_eval::RenderedDriveSequence& drive, const geometry::CameraModel& left, double scale,
              const cv::Mat& depth_a, int a, int b, const Eigen::Vector2d& u, Eigen::Matrix2d* A) {
  for (int c = 0; c < 2; ++c) {
    const Eigen::Vector2d d = Eigen::Vector2d::Unit(c);
    Eigen::Vector2d plus, minus;
    if (!CarryPixel(drive, left, scale, depth_a, a, b, u + d, &plus) ||
        !CarryPixel(drive, left, scale, depth_a, a, b, u - d, &minus)) {
      return false;
    }
    A->col(c) = (plus - minus) / 2.0;
  }
  return A->allFinite();
}

}  // namespace

DriveCount MeasureDrive(const vo_eval::RenderedDriveSequence& drive, const vo::VoOptions& vo, CarryAccumulator* acc,
                        double max_error_px, std::ostream* dump) {
  // The drive as vo_eval runs a rendered world (odometry prior), keeping each frame's
  // true depth, which only this measurement reads.
  std::map<int, cv::Mat> depth;
  vo_eval::EvalInput input = vo_eval::RenderedInput(drive);
  input.load = [&](int k, cv::Mat* left, cv::Mat* right) { drive.Render(k, left, right, &depth[k]); };
  vo_eval::EvalOptions options;
  options.vo = vo;
  options.odometry_prior = true;
  options.odometry_seed = drive.options().seed;
  const vo_eval::EvalReport report = vo_eval::RunEvaluation(input, options);

  // The VO's pixels are at the working resolution; the depth is at the rendered size.
  const double s = vo.working_scale;
  const auto full_pixel = [s](const Eigen::Vector2d& p) { return ((p.array() + 0.5) / s - 0.5).matrix().eval(); };
  const auto left = drive.rig().left->Scaled(s), right = drive.rig().right->Scaled(s);
  DriveCount count;
  std::unordered_map<std::int64_t, Eigen::Vector3d> X_site;  // each track's true point
  std::unordered_map<std::int64_t, int> age;                   // its keyframe observations since
  std::unordered_map<std::int64_t, int> last_frame;            // the keyframe it was last seen in
  int reference = 0;  // the frame the current pair was tracked from (the last keyframe)
  for (const vo_eval::FrameRecord& f : report.frames) {
    ++count.frames;
    const vo::VoResult& r = f.result;
    if (r.status == vo::VoStatus::kBaseline) reference = f.frame;
    if (r.status != vo::VoStatus::kOk || !r.keyframe) continue;
    ++count.keyframes;
    const Eigen::Isometry3d T_rover_site = drive.SitePose(f.frame).inverse();
    for (const vo::TrackedFeature& t : r.tracks) {
      if (t.track_id == 0) continue;  // frame-to-frame mode: no tracks
      if (!t.inlier) {
        acc->Drop(t.track_id);
        X_site.erase(t.track_id);
        continue;
      }
      auto it = X_site.find(t.track_id);
      if (it == X_site.end()) {
        // Born in the reference frame: its detected pixel on the true surface defines it.
        double range = 0;
        const Eigen::Vector2d u0 = full_pixel(t.prev_left);
        if (!RangeAt(depth[reference], u0, &range)) {
          ++count.undefined;
          continue;
        }
        Eigen::Vector3d origin, direction;
        drive.rig().left->BackProject(u0, &origin, &direction);
        it = X_site.emplace(t.track_id, drive.SitePose(reference) * (origin + range * direction)).first;
        Eigen::Vector2d ur;
        if (!right->Project(drive.SitePose(reference).inverse() * it->second, &ur)) continue;
        acc->Add(t.track_id, Eigen::Vector2d::Zero(), t.prev_right - ur, true);
        age[t.track_id] = 0;
        last_frame[t.track_id] = reference;
      }
      Eigen::Vector2d ul, ur;
      const Eigen::Vector3d P = T_rover_site * it->second;
      if (!left->Project(P, &ul) || !right->Project(P, &ur)) continue;
      const Eigen::Vector2d el = t.curr_left - ul, er = t.curr_right - ur;
      if (el.norm() > max_error_px || er.norm() > max_error_px) {
        acc->Drop(t.track_id);
        X_site.erase(t.track_id);
        continue;
      }
      // The surface's image map from the track's last keyframe, round where the truth
      // projects there.
      Eigen::Matrix2d A;
      Eigen::Vector2d u_last;
      const int last = last_frame[t.track_id];
      const bool mapped = left->Project(drive.SitePose(last).inverse() * it->second, &u_last) &&
                          ImageMap(drive, *left, s, depth[last], last, f.frame, u_last, &A);
      acc->Add(t.track_id, el, er, false, mapped ? &A : nullptr);
      last_frame[t.track_id] = f.frame;
      ++count.observations;
      if (dump) {
        *dump << drive.world_name() << ',' << f.frame << ',' << t.track_id << ',' << ++age[t.track_id] << ','
              << P.norm() << ',' << el.x() << ',' << el.y() << ',' << er.x() << ',' << er.y() << '\n';
      }
    }
    reference = f.frame;
  }
  return count;
}

}  // namespace rover::vo_carry
