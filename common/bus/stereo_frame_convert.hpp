// stereo_frame_t -> vo::StereoImages, shared by visual_odometry and the plot tool. Each
// image is checked against the camera model in the same frame and the limits before it
// is decoded (common/imaging). Header-only so that rover_bus itself does not depend on
// rover_imaging or rover_vo.
#pragma once

#include "bus/convert.hpp"
#include "bus/image_view.hpp"
#include "geometry/camera_model.hpp"
#include "imaging/image_check.hpp"
#include "vo/visual_odometry.hpp"

#include <rover_msgs/stereo_frame_t.hpp>

#include <string>

namespace rover::bus {

// Fills `out` (images, rig, time, id, attitude at capture). Returns "" or why the frame
// cannot be used ("left image: ...", "camera model: ...").
inline std::string ToStereoImages(const rover_msgs::stereo_frame_t& frame, const imaging::ImageLimits& limits,
                                  vo::StereoImages& out) {
  if (std::string bad = imaging::DecodeCheckedImage(ImageViewOf(frame.left), frame.left_model.width,
                                                    frame.left_model.height, limits, out.left);
      !bad.empty()) {
    return "left image: " + bad;
  }
  if (std::string bad = imaging::DecodeCheckedImage(ImageViewOf(frame.right), frame.right_model.width,
                                                    frame.right_model.height, limits, out.right);
      !bad.empty()) {
    return "right image: " + bad;
  }
  if (out.left.size() != out.right.size()) {
    return "right image is " + std::to_string(out.right.cols) + "x" + std::to_string(out.right.rows) +
           " but the left is " + std::to_string(out.left.cols) + "x" + std::to_string(out.left.rows) +
           " (expected a pair of one size)";
  }
  try {
    out.rig.left = geometry::CameraModelFromParams(frame.left_model.type, frame.left_model.width,
                                                   frame.left_model.height, frame.left_model.params);
    out.rig.right = geometry::CameraModelFromParams(frame.right_model.type, frame.right_model.width,
                                                    frame.right_model.height, frame.right_model.params);
  } catch (const std::exception& e) {
    return std::string("camera model: ") + e.what();
  }
  out.utime = frame.utime;
  out.frame_id = frame.frame_id;
  out.R_site_ref = PoseFromMsg(frame.pose_at_capture).linear();
  return "";
}

}  // namespace rover::bus
