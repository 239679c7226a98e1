#include "traversability/dense_stereo.hpp"

#include <stdexcept>

namespace rover::traversability {

RectifiedRig Rectify(const geometry::StereoRig&, double) {
  throw std::invalid_argument("traversability: dense stereo not yet built");
}

StereoPoints DenseStereo(const cv::Mat&, const cv::Mat&, const geometry::StereoRig&,
                         const MapOptions&, UpdateStats*) {
  throw std::invalid_argument("traversability: dense stereo not yet built");
}

}  // namespace rover::traversability
