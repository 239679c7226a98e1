// VO-3 stereo match along the epipolar line, and VO-4/VO-5 triangulation of the new
// pair's features with their covariances.
#include "vo/vo_state.hpp"

namespace rover::vo {

void VisualOdometry::State::MatchNewFeatures(Step* st) {
  Pair* pair = st->cur.get();
  // Windowed mode: stereo waits until tracking has shown where tracks are missing.
  if (!Windowed()) StereoMatchFresh(pair, pair->corners);
  st->res.num_matched = static_cast<int>(pair->features.size());
  const auto now = Clock::now();
  st->res.times.stereo_ms = Ms(st->t, now);
  st->t = now;
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
  std::vector<Feature> found(corners.size());
  std::vector<char> ok(corners.size(), 0);
  const auto at = [&](int i) { return Eigen::Vector2d(corners[i].x, corners[i].y); };
  for (const int i : TopToBottom(static_cast<int>(corners.size()), at)) {
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
    if (!TriangulateStereo(pair->rig, left, self.covariance, right, Sigma_right, limits, &sp, &J,
                           StereoCarry())) {
      continue;
    }
    found[i] = MakeFeature(left, self.covariance, right, Sigma_right, sp, J, TrackCarry(), StereoCarry());
    ok[i] = 1;
  }
  for (std::size_t i = 0; i < corners.size(); ++i) {
    if (!ok[i]) continue;
    found[i].track_id = next_track_id++;
    pair->features.push_back(found[i]);
  }
}

}  // namespace rover::vo
