// image_t -> imaging::ImageView: the message's image as the image checks read it (the
// declared encoding, size and byte count, and the bytes present). Header-only and light,
// so that a tool which checks images (the conformance kit, the web console) needs neither
// rover_vo nor the stereo frame conversion.
#pragma once

#include "imaging/image_check.hpp"

#include <rover_msgs/image_t.hpp>

namespace rover::bus {

inline imaging::ImageView ImageViewOf(const rover_msgs::image_t& img) {
  imaging::ImageView v;
  v.encoding = img.encoding;
  v.width = img.width;
  v.height = img.height;
  v.declared_size = img.size;
  v.data = img.data.data();
  v.data_size = img.data.size();
  return v;
}

}  // namespace rover::bus
