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

namespace {

// visual_odometry's own section: the motion prior and the image limits.
struct VoProcessOptions {
  vo::MotionPriorOptions prior;
  imaging::ImageLimits limits;
};

VoProcessOptions LoadVoProcessOptions(const config::ConfigNode& section) {
  section.CheckKeys({"translation_sigma_fraction", "min_translation_sigma_m", "rotation_sigma_fraction",
                     "min_rotation_sigma_deg", "max_image_pixels", "min_image_side"});
  VoProcessOptions o;
  o.prior = vo::LoadMotionPriorOptions(section);
  int max_image_pixels = static_cast<int>(o.limits.max_pixels);
  section.Get("max_image_pixels", max_image_pixels, 1024, 1 << 28);  // up to a 16384^2 camera
  o.limits.max_pixels = max_image_pixels;
  section.Get("min_image_side", o.limits.min_side, 1, 4096);
  return o;
}

// The update a result becomes, from `previous` (none: a chain's first frame) to `frame`.
rover_msgs::vo_update_t ToUpdate(const rover_msgs::stereo_frame_t& frame,
                                 const std::optional<rover_msgs::stereo_frame_t>& previous, const vo::VoResult& result) {
  rover_msgs::vo_update_t out{};
  out.utime = frame.utime;
  out.to_frame_id = frame.frame_id;
  out.to_utime = frame.utime;
  out.from_frame_id = previous ? previous->frame_id : -1;
  out.from_utime = previous ? previous->utime : 0;
  out.delta_orientation[0] = 1.0;
  out.status = static_cast<std::int8_t>(result.status);
  out.reason = result.reason;
  if (result.status == vo::VoStatus::kOk) {
    for (int i = 0; i < 3; ++i) out.delta_position[i] = result.T_prev_curr.translation()[i];
    bus::QuaternionToArray(Eigen::Quaterniond(result.T_prev_curr.linear()), out.delta_orientation);
    bus::CovarianceToArray(result.covariance, out.covariance);
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
  return out;
}

// VO on the bus: each STEREO_FRAME against the last good one, its update published when
// the compute profile says the rover's computer would have it.
class VoNode {
 public:
  VoNode(bus::Process& proc, vo::VoOptions vo_options, VoProcessOptions options)
      : proc_(proc), vo_(std::move(vo_options)), options_(options) {
    // Answers wait until the compute profile's VO time has passed since their frame came
    // (virtual time; on a rover they go at once): the rover's computer is not this one.
    proc_.set_pending_work([this] {
      while (!answers_.empty() && proc_.now() >= answers_.front().first) {
        proc_.bus().Publish(channels::kVoUpdate, answers_.front().second);
        answers_.pop_front();
      }
      return false;
    });
    // Nothing of its own to do but the next answer (virtual time's idle strides).
    proc_.set_quiet_until(
        [this] { return answers_.empty() ? bus::Process::kQuietForGood : answers_.front().first; });
    proc_.bus().Subscribe<rover_msgs::stereo_frame_t>(
        channels::kStereoFrame, [this](const rover_msgs::stereo_frame_t& frame) { OnFrame(frame); }, 4);
  }

 private:
  void OnFrame(const rover_msgs::stereo_frame_t& frame) {
    proc_.ObserveTime(frame.utime);
    // Science pairs are for the operator, and a look (the mast pointed aside) for the map;
    // a baseline pair starts a new VO chain.
    if (frame.purpose == "science" || frame.purpose == "look") return;
    if (frame.purpose == "vo_baseline") {
      vo_.Reset();
      previous_.reset();
    }
    const std::optional<rover_msgs::stereo_frame_t> from = previous_;
    const vo::VoResult result = Process(frame);
    if (result.status != vo::VoStatus::kOk && result.status != vo::VoStatus::kBaseline) ++failures_;
    const rover_msgs::vo_update_t out = ToUpdate(frame, from, result);
    answers_.emplace_back(proc_.DueAt(std::max(proc_.now(), frame.utime), proc_.compute().vo_s), out);
    if (!proc_.virtual_time()) {
      proc_.bus().Publish(channels::kVoUpdate, out);
      answers_.clear();
    }
    // A bad frame does not become the reference for the next one.
    if (result.status != vo::VoStatus::kBadInput) {
      previous_ = frame;
      previous_->left = {};
      previous_->right = {};
    }
    proc_.SetHealth(0, std::to_string(failures_) + " failures");
  }

  // The frame's images checked, then VO against the last good frame with the motion its
  // pose estimates say as the prior. A bad frame, or VO's throw, is kBadInput with the
  // reason, and the frame is dropped on the bus's record.
  vo::VoResult Process(const rover_msgs::stereo_frame_t& frame) {
    const std::string where = "frame " + std::to_string(frame.frame_id) + ": ";
    vo::StereoImages images;
    vo::VoResult result;
    if (std::string error = bus::ToStereoImages(frame, options_.limits, images); !error.empty()) {
      result.status = vo::VoStatus::kBadInput;
      result.reason = where + error;
      Drop(result.reason);
      return result;
    }
    const geometry::Pose T_site_curr = bus::PoseFromMsg(frame.pose_at_capture);
    Eigen::Isometry3d prior_T = Eigen::Isometry3d::Identity();
    Eigen::Matrix<double, 6, 6> prior_cov = Eigen::Matrix<double, 6, 6>::Identity();
    if (previous_) {
      prior_T = bus::PoseFromMsg(previous_->pose_at_capture).inverse() * T_site_curr;
      prior_cov = vo::MotionPriorCovariance(prior_T, options_.prior);
    }
    try {
      result = vo_.Process(images, prior_T, prior_cov);
      if (result.status == vo::VoStatus::kBadInput) {  // VO's own input checks
        result.reason = where + result.reason;
        Drop(result.reason);
      }
    } catch (const std::exception& e) {
      // VO's state is unknown after a throw: its chain starts again.
      result = vo::VoResult{};
      result.status = vo::VoStatus::kBadInput;
      result.reason = where + "VO failed (its chain starts again): " + e.what();
      Drop(result.reason);
      vo_.Reset();
      previous_.reset();
    }
    return result;
  }

  void Drop(const std::string& why) {
    proc_.bus().Drop(channels::kStereoFrame, rover_msgs::stereo_frame_t::getTypeName(), why);
  }

  bus::Process& proc_;
  vo::VisualOdometry vo_;
  const VoProcessOptions options_;
  std::optional<rover_msgs::stereo_frame_t> previous_;  // images dropped; pose and ids kept
  int failures_ = 0;
  std::deque<std::pair<std::int64_t, rover_msgs::vo_update_t>> answers_;
};

}  // namespace

int main(int argc, char** argv) {
  return bus::RunMain("visual_odometry", [&]() -> int {
    bus::Process proc("visual_odometry",
                      "MER visual odometry between consecutive stereo frames.\n"
                      "Reads STEREO_FRAME; writes VO_UPDATE.\n"
                      "Config: the `vo:` section (configs/vo.yaml) and `visual_odometry:` (prior,\n"
                      "image limits).",
                      argc, argv, {}, {"visual_odometry"});
    auto vo_options = vo::LoadVoOptions(proc.config()["vo"]);
    VoNode node(proc, std::move(vo_options), LoadVoProcessOptions(proc.config()["visual_odometry"]));
    proc.DeclarePublications({{channels::kVoUpdate}});
    proc.Run();
    return 0;
  });
}
