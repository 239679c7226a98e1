// visual_odometry: the MER algorithm (common/vo) between consecutive stereo frames.
// Reads STEREO_FRAME, writes VO_UPDATE. The prior is the motion between the two
// frames' on-board pose estimates (wheel odometry + IMU); a failure leaves it in force
// (VO-10), which the update says with its status and reason.
#include "bus/channels.hpp"
#include "bus/convert.hpp"
#include "bus/process.hpp"
#include "geometry/camera_model.hpp"
#include "vo/visual_odometry.hpp"

#include <rover_msgs/stereo_frame_t.hpp>
#include <rover_msgs/vo_update_t.hpp>

#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <iostream>
#include <optional>

using namespace rover;

namespace {

// Decodes an image_t. Returns an error text naming what was wrong, or empty.
std::string DecodeImage(const rover_msgs::image_t& img, cv::Mat& out) {
  const std::size_t pixels = static_cast<std::size_t>(std::max(0, img.width)) *
                             static_cast<std::size_t>(std::max(0, img.height));
  switch (img.encoding) {
    case rover_msgs::image_t::ENCODING_GRAY8:
      if (img.data.size() != pixels) return "GRAY8 image holds " + std::to_string(img.data.size()) +
                                            " bytes (expected width*height = " + std::to_string(pixels) + ")";
      out = cv::Mat(img.height, img.width, CV_8UC1, const_cast<std::uint8_t*>(img.data.data())).clone();
      return "";
    case rover_msgs::image_t::ENCODING_GRAY16:
      if (img.data.size() != 2 * pixels) return "GRAY16 image holds " + std::to_string(img.data.size()) +
                                                " bytes (expected 2*width*height = " + std::to_string(2 * pixels) + ")";
      out = cv::Mat(img.height, img.width, CV_16UC1, const_cast<std::uint8_t*>(img.data.data())).clone();
      return "";
    case rover_msgs::image_t::ENCODING_PNG:
      out = cv::imdecode(img.data, cv::IMREAD_UNCHANGED);
      if (out.empty()) return "PNG image does not decode (expected a valid PNG)";
      if (out.channels() != 1) return "PNG image has " + std::to_string(out.channels()) +
                                      " channels (expected 1, gray)";
      if (out.cols != img.width || out.rows != img.height) {
        return "PNG image is " + std::to_string(out.cols) + "x" + std::to_string(out.rows) +
               " (expected " + std::to_string(img.width) + "x" + std::to_string(img.height) + ")";
      }
      return "";
    default:
      return "unknown image encoding " + std::to_string(img.encoding) + " (expected 0, 1 or 2)";
  }
}

struct PriorOptions {
  // The prior's uncertainty: wheel odometry can be wrong by more than 100 % on loose sand
  // (Sol 206), so the search must allow it.
  double translation_sigma_fraction = 0.6;
  double min_translation_sigma_m = 0.05;
  double rotation_sigma_fraction = 0.3;
  double min_rotation_sigma_deg = 2.0;
};

}  // namespace

int main(int argc, char** argv) {
  return bus::RunMain("visual_odometry", [&]() -> int {
    bus::Process proc("visual_odometry",
                      "MER visual odometry between consecutive stereo frames.\n"
                      "Reads STEREO_FRAME; writes VO_UPDATE.\n"
                      "Config: the `vo:` section (configs/vo.yaml) and `visual_odometry:` (prior).",
                      argc, argv, {}, {"visual_odometry"});
    vo::VisualOdometry vo(vo::LoadVoOptions(proc.config()["vo"]));
    PriorOptions prior;
    const auto section = proc.config()["visual_odometry"];
    section.CheckKeys({"translation_sigma_fraction", "min_translation_sigma_m",
                       "rotation_sigma_fraction", "min_rotation_sigma_deg"});
    section.Get("translation_sigma_fraction", prior.translation_sigma_fraction, 0.0, 10.0);
    section.Get("min_translation_sigma_m", prior.min_translation_sigma_m, 0.0, 10.0);
    section.Get("rotation_sigma_fraction", prior.rotation_sigma_fraction, 0.0, 10.0);
    section.Get("min_rotation_sigma_deg", prior.min_rotation_sigma_deg, 0.0, 90.0);

    std::optional<rover_msgs::stereo_frame_t> previous;  // images dropped; pose and ids kept
    int failures = 0;

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
          images.utime = frame.utime;
          images.frame_id = frame.frame_id;
          std::string error = DecodeImage(frame.left, images.left);
          if (error.empty()) error = DecodeImage(frame.right, images.right);
          if (!error.empty()) error = "frame " + std::to_string(frame.frame_id) + ": " + error;
          if (error.empty()) {
            try {
              images.rig.left = geometry::CameraModelFromParams(
                  frame.left_model.type, frame.left_model.width, frame.left_model.height,
                  frame.left_model.params);
              images.rig.right = geometry::CameraModelFromParams(
                  frame.right_model.type, frame.right_model.width, frame.right_model.height,
                  frame.right_model.params);
            } catch (const std::exception& e) {
              error = "frame " + std::to_string(frame.frame_id) + ": camera model: " + e.what();
            }
          }
          const geometry::Pose T_site_curr = bus::PoseFromMsg(frame.pose_at_capture);
          images.R_site_ref = T_site_curr.linear();

          vo::VoResult result;
          if (!error.empty()) {
            result.status = vo::VoStatus::kBadInput;
            result.reason = error;
            std::cerr << "visual_odometry: " << error << "\n";
          } else {
            Eigen::Isometry3d prior_T = Eigen::Isometry3d::Identity();
            Eigen::Matrix<double, 6, 6> prior_cov = Eigen::Matrix<double, 6, 6>::Identity();
            if (previous) {
              prior_T = bus::PoseFromMsg(previous->pose_at_capture).inverse() * T_site_curr;
              const double t_sigma = std::max(prior.min_translation_sigma_m,
                                              prior.translation_sigma_fraction * prior_T.translation().norm());
              const double r_sigma = std::max(prior.min_rotation_sigma_deg * M_PI / 180.0,
                                              prior.rotation_sigma_fraction *
                                                  Eigen::AngleAxisd(prior_T.linear()).angle());
              prior_cov.setZero();
              prior_cov.diagonal() << t_sigma * t_sigma, t_sigma * t_sigma, t_sigma * t_sigma,
                  r_sigma * r_sigma, r_sigma * r_sigma, r_sigma * r_sigma;
            }
            result = vo.Process(images, prior_T, prior_cov);
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
          proc.bus().Publish(channels::kVoUpdate, out);
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
