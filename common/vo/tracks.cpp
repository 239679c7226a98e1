#include "vo/tracks.hpp"

#include <algorithm>
#include <numeric>

namespace rover::vo {

namespace {

bool FarFromAll(const Eigen::Vector2d& p, const std::vector<Eigen::Vector2d>& taken, double d2) {
  for (const Eigen::Vector2d& q : taken) {
    if ((p - q).squaredNorm() < d2) return false;
  }
  return true;
}

}  // namespace

std::vector<int> SelectTracks(const std::vector<Eigen::Vector2d>& positions, const std::vector<int>& ages,
                              double min_distance_px, int max_count) {
  std::vector<int> order(positions.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return ages[static_cast<std::size_t>(a)] > ages[static_cast<std::size_t>(b)];
  });
  const double d2 = min_distance_px * min_distance_px;
  std::vector<int> kept;
  std::vector<Eigen::Vector2d> taken;
  for (int i : order) {
    if (static_cast<int>(kept.size()) >= max_count) break;
    const Eigen::Vector2d& p = positions[static_cast<std::size_t>(i)];
    if (!FarFromAll(p, taken, d2)) continue;
    kept.push_back(i);
    taken.push_back(p);
  }
  return kept;
}

std::vector<int> TopUpCorners(const std::vector<Eigen::Vector2d>& kept, const std::vector<Corner>& corners,
                              double min_distance_px, int count) {
  std::vector<int> out;
  std::vector<Eigen::Vector2d> taken = kept;
  const double d2 = min_distance_px * min_distance_px;
  for (int i = 0; i < static_cast<int>(corners.size()); ++i) {
    if (static_cast<int>(taken.size()) >= count) break;
    const Eigen::Vector2d p(corners[static_cast<std::size_t>(i)].x, corners[static_cast<std::size_t>(i)].y);
    if (!FarFromAll(p, taken, d2)) continue;
    out.push_back(i);
    taken.push_back(p);
  }
  return out;
}

}  // namespace rover::vo
