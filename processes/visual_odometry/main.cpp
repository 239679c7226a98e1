// visual_odometry: the MER algorithm (common/vo) between consecutive stereo frames.
// Reads STEREO_FRAME, writes VO_UPDATE. The prior is the motion between the two
// frames' on-board pose estimates (wheel odometry + IMU); a failure leaves it in force
// (VO-10), which the update says with its status and reason.
//
// Every image is checked before it is decoded (common/imaging): encoding, sides against
// the camera model in the same frame and `visual_odometry.max_image_pixels`, byte count,
// and a PNG's own header. A bad frame gets a VO_UPDATE with STATUS_BAD_INPUT and the
// reason, and is forgotten: the next good frame pairs with the last good one. If VO itself
// fails on a frame, its chain starts again at the next good frame.
#include "bus/channels.hpp"
#include "bus/convert.hpp"
#include "bus/process.hpp"
#include "bus/stereo_frame_convert.hpp"
#include "imaging/image_check.hpp"
#include "vo/motion_prior.hpp"
#include "vo/visual_odometry.hpp"

#include <rover_msgs/stereo_frame_t.hpp>
#include <rover_msgs/vo_update_t.hpp>

#include <algorithm>
#include <cmath>
#include <deque>
#include <iostream>
#include <optional>

using namespace rover;

int main(int argc, char** argv) {
  return bus::RunMain("visual_odometry", [&]() -> int {
    bus::Process proc("visual_odometry",
                      "MER visual odometry between consecutive stereo frames.\n"
                      "Reads STEREO_FRAME; writes VO_UPDATE.\n"
                      "Config: the `vo:` section (configs/vo.yaml) and `visual_odometry:` (prior,\n"
                      "image limits).",
                      argc, argv, {}, {"visual_odometry"});
    vo::VisualOdometry vo(vo::LoadVoOptions(proc.config()["vo"]));
    const auto section = proc.config()["visual_odometry"];
    section.CheckKeys({"translation_sigma_fraction", "min_translation_sigma_m",
                       "rotation_sigma_fraction", "min_rotation_sigma_deg", "max_image_pixels",
                       "min_image_side"});
    const vo::MotionPriorOptions prior = vo::LoadMotionPriorOptions(section);
    imaging::ImageLimits limits;
    int max_image_pixels = static_cast<int>(limits.max_pixels);
    section.Get("max_image_pixels", max_image_pixels, 1024, 1 << 28);  // up to a 16384^2 camera
    limits.max_pixels = max_image_pixels;
    section.Get("min_image_side", limits.min_side, 1, 4096);

    std::optional<rover_msgs::stereo_frame_t> previous;  // images dropped; pose and ids kept
    int failures = 0;
    // Answers wait until the compute profile's VO time has passed since their frame came
    // (virtual time; on a rover they go at once): the rover's computer is not this one.
    std::deque<std::pair<std::int64_t, rover_msgs::vo_update_t>> answers;
    proc.set_pending_work([&] {
      while (!answers.empty() && proc.now() >= answers.front().first) {
        proc.bus().Publish(channels::kVoUpdate, answers.front().second);
        answers.pop_front();
      }
      return false;
    });

    proc.bus().Subscribe<rover_msgs::stereo_frame_t>(
        channels::kStereoFrame,
        [&](const rover_msgs::stereo_frame_t& frame) {
          proc.ObserveTime(frame.utime);
          // Science pairs are for the operator; a baseline pair starts a new VO chain.
          if (frame.purpose == "science") return;
          if (frame.purpose == "vo_baseline") {
            vo.Reset();
            previous.reset();
          }
          rover_msgs::vo_update_t out{};
          out.utime = frame.utime;
          out.to_frame_id = frame.frame_id;
          out.to_utime = frame.utime;
          out.from_frame_id = previous ? previous->frame_id : -1;
          out.from_utime = previous ? previous->utime : 0;
          out.delta_orientation[0] = 1.0;

          vo::StereoImages images;
          std::string error = bus::ToStereoImages(frame, limits, images);
          if (!error.empty()) error = "frame " + std::to_string(frame.frame_id) + ": " + error;
          const geometry::Pose T_site_curr = bus::PoseFromMsg(frame.pose_at_capture);

          vo::VoResult result;
          if (!error.empty()) {
            result.status = vo::VoStatus::kBadInput;
            result.reason = error;
            proc.bus().Drop(channels::kStereoFrame, rover_msgs::stereo_frame_t::getTypeName(), error);
          } else {
            Eigen::Isometry3d prior_T = Eigen::Isometry3d::Identity();
            Eigen::Matrix<double, 6, 6> prior_cov = Eigen::Matrix<double, 6, 6>::Identity();
            if (previous) {
              prior_T = bus::PoseFromMsg(previous->pose_at_capture).inverse() * T_site_curr;
              prior_cov = vo::MotionPriorCovariance(prior_T, prior);
            }
            try {
              result = vo.Process(images, prior_T, prior_cov);
              if (result.status == vo::VoStatus::kBadInput) {  // VO's own input checks
                result.reason = "frame " + std::to_string(frame.frame_id) + ": " + result.reason;
                proc.bus().Drop(channels::kStereoFrame, rover_msgs::stereo_frame_t::getTypeName(), result.reason);
              }
            } catch (const std::exception& e) {
              // VO's state is unknown after a throw: its chain starts again.
              result = vo::VoResult{};
              result.status = vo::VoStatus::kBadInput;
              result.reason = "frame " + std::to_string(frame.frame_id) +
                              ": VO failed (its chain starts again): " + e.what();
              proc.bus().Drop(channels::kStereoFrame, rover_msgs::stereo_frame_t::getTypeName(), result.reason);
              vo.Reset();
              previous.reset();
            }
          }

          out.status = static_cast<std::int8_t>(result.status);
          out.reason = result.reason;
          if (result.status == vo::VoStatus::kOk) {
            for (int i = 0; i < 3; ++i) out.delta_position[i] = result.T_prev_curr.translation()[i];
            bus::QuaternionToArray(Eigen::Quaterniond(result.T_prev_curr.linear()), out.delta_orientation);
            bus::CovarianceToArray(result.covariance, out.covariance);
          } else if (result.status != vo::VoStatus::kBaseline) {
            ++failures;
          }
          out.num_detected = result.num_detected;
          out.num_matched = result.num_matched;
          out.num_tracked = result.num_tracked;
          out.num_inliers = result.num_inliers;
          out.iterations = result.iterations;
          out.ms_detect = result.times.detect_ms;
          out.ms_stereo = result.times.stereo_ms;
          out.ms_track = result.times.track_ms;
          out.ms_ransac = result.times.ransac_ms;
          out.ms_ml = result.times.ml_ms;
          out.ms_total = result.times.total_ms;
          answers.emplace_back(proc.DueAt(std::max(proc.now(), frame.utime), proc.compute().vo_s), out);
          if (!proc.virtual_time()) {
            proc.bus().Publish(channels::kVoUpdate, out);
            answers.clear();
          }
          // A bad frame does not become the reference for the next one.
          if (result.status != vo::VoStatus::kBadInput) {
            previous = frame;
            previous->left = {};
            previous->right = {};
          }
          proc.SetHealth(0, std::to_string(failures) + " failures");
        },
        4);
    proc.Run();
    return 0;
  });
}
