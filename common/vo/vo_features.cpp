// VO-2 features: the corners of the new left image, and in windowed mode their top-up
// around the tracks carried on from the last keyframe.
#include "vo/tracks.hpp"
#include "vo/vo_state.hpp"

namespace rover::vo {

void VisualOdometry::State::DetectFeatures(Step* st) {
  CornerOptions co;
  co.harris_k = o.feature_harris_k;
  co.harris_block = o.feature_harris_block;
  co.grid_cell_px = o.feature_grid_cell_px;
  co.min_distance_px = o.feature_min_distance_px;
  co.count = o.feature_count;
  co.min_response = o.feature_min_response;
  co.border_px = o.feature_border_px;
  Pair* pair = st->cur.get();
  pair->corners = DetectCorners(pair->left, co);
  st->res.num_detected = static_cast<int>(pair->corners.size());
  // Timed from the call's start: the input's conversion and pyramid count as detection.
  const auto now = Clock::now();
  st->res.times.detect_ms = Ms(st->t, now);
  st->t = now;
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

}  // namespace rover::vo
