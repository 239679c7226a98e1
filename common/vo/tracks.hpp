// Feature tracks over many pairs (common/vo/README.md, "VO with memory"): which tracked
// features live on into the next pair, and where detection (VO-2) tops them up.
//
// SOFT-style selection (Cvisic and Petrovic 2015): long-lived tracks are preferred, since
// each pair they survive ties one more pose to the same point, and the set is kept spread
// over the image: a track closer than a minimum distance to an older one is dropped, and
// fresh corners fill only the parts of the image that tracks left, strongest first.
#pragma once

#include "vo/features.hpp"

#include <Eigen/Core>

#include <vector>

namespace rover::vo {

// Indices of the tracks kept, oldest first (ties: the given order), each at least
// min_distance_px from every track kept before it; at most max_count.
std::vector<int> SelectTracks(const std::vector<Eigen::Vector2d>& positions, const std::vector<int>& ages,
                              double min_distance_px, int max_count);

// Indices of the corners (given strongest first) that top up `kept` tracks to `count`
// features, each at least min_distance_px from every track and every corner taken.
std::vector<int> TopUpCorners(const std::vector<Eigen::Vector2d>& kept, const std::vector<Corner>& corners,
                              double min_distance_px, int count);

}  // namespace rover::vo
