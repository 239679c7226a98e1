#include "conformance/camera_checks.hpp"

#include "bus/image_view.hpp"
#include "bus/validate.hpp"
#include "geometry/camera_model.hpp"
#include "imaging/image_check.hpp"

#include <algorithm>
#include <cmath>
#include <map>

namespace rover::conformance {

namespace {

using rover_msgs::heartbeat_t;
using rover_msgs::stereo_frame_t;

std::string Size(int w, int h) { return std::to_string(w) + "x" + std::to_string(h); }

// Every request: its frame, or the capture process saying DEGRADED or FAULT with a detail
// while it was being served.
void CheckAnswers(const CameraTrace& trace, const CameraLimits& limits, Report& report) {
  std::map<std::int64_t, int> frames_of;
  for (const auto& f : trace.frames) ++frames_of[f.msg.frame_id];
  for (std::size_t i = 0; i < trace.requests.size(); ++i) {
    const auto& r = trace.requests[i];
    const double until = std::min(r.wall_s + limits.answer_s,
                                  i + 1 < trace.requests.size() ? trace.requests[i + 1].wall_s : trace.end_wall_s);
    const bool framed = std::any_of(trace.frames.begin(), trace.frames.end(), [&](const auto& f) {
      return f.msg.frame_id == r.frame_id && f.at.wall_s >= r.wall_s && f.at.wall_s <= until;
    });
    const bool reported = std::any_of(trace.capture_heartbeats.begin(), trace.capture_heartbeats.end(), [&](const auto& h) {
      return h.at.wall_s >= r.wall_s && h.at.wall_s <= until + 0.5 && h.msg.state != heartbeat_t::STATE_OK &&
             !h.msg.detail.empty();
    });
    report.Expect(framed || reported, "camera.answer",
                  "STEREO_FRAME " + std::to_string(r.frame_id) + ", or a DEGRADED or FAULT heartbeat naming the failure, within " +
                      Num(limits.answer_s, 1) + " s",
                  trace.capture_heartbeats.empty() ? "neither, and no heartbeat from the capture process"
                                                   : "neither in " + Num(until - r.wall_s, 1) + " s");
    if (frames_of[r.frame_id] > 1) {
      report.Fail("camera.once", "one frame for request " + std::to_string(r.frame_id),
                  std::to_string(frames_of[r.frame_id]) + " frames");
    }
  }
  if (!trace.requests.empty()) report.Pass("camera.once");
  report.Expect(!trace.frames.empty(), "camera.frames", "at least one STEREO_FRAME",
                "none for " + std::to_string(trace.requests.size()) + " requests");
}

void CheckFrame(const Received<stereo_frame_t>& f, const SentRequest* request, const CameraLimits& limits,
                Report& report) {
  const auto& m = f.msg;
  const std::string which = "frame " + std::to_string(m.frame_id);
  if (request) {
    report.Expect(m.purpose == request->purpose, "camera.purpose", "purpose \"" + request->purpose + "\"",
                  which + ": \"" + m.purpose + "\"");
  }
  if (std::string p = bus::Problem(m); !p.empty()) {
    report.Fail("camera.fields", "models and encodings the bus accepts", which + ": " + p);
    return;
  }
  report.Pass("camera.fields");
  const imaging::ImageLimits image_limits;
  for (const auto& [img, model, side] : {std::tuple{&m.left, &m.left_model, "left"},
                                         std::tuple{&m.right, &m.right_model, "right"}}) {
    std::string bad = imaging::CheckImage(bus::ImageViewOf(*img), model->width, model->height, image_limits);
    if (bad.empty() && limits.width > 0 && (img->width != limits.width || img->height != limits.height)) {
      bad = Size(img->width, img->height) + " (expected " + Size(limits.width, limits.height) + ")";
    }
    report.Expect(bad.empty(), "camera.size",
                  "images of their models' size" +
                      (limits.width > 0 ? " and " + Size(limits.width, limits.height) : std::string()),
                  which + " " + side + ": " + bad);
  }

  std::string pairing;
  if (m.left.width != m.right.width || m.left.height != m.right.height) {
    pairing = "left " + Size(m.left.width, m.left.height) + ", right " + Size(m.right.width, m.right.height);
  } else if (m.left.encoding != m.right.encoding) {
    pairing = "left " + imaging::EncodingName(m.left.encoding) + ", right " + imaging::EncodingName(m.right.encoding);
  } else {
    try {
      const auto left = geometry::CameraModelFromParams(m.left_model.type, m.left_model.width, m.left_model.height,
                                                        m.left_model.params);
      const auto right = geometry::CameraModelFromParams(m.right_model.type, m.right_model.width,
                                                         m.right_model.height, m.right_model.params);
      // The rover frame's Y points right: the right camera's centre has the larger Y.
      const double dy = right->Center().y() - left->Center().y();
      if (!(dy > 0.01)) pairing = "the right camera " + Num(dy, 3) + " m to the right of the left (rover Y)";
    } catch (const std::exception& e) {
      pairing = std::string("camera model: ") + e.what();
    }
  }
  report.Expect(pairing.empty(), "camera.pairing", "left and right alike, the right camera to the right",
                which + ": " + pairing);

  // The pair taken at once: each image's own exposure time, the two within the pairing
  // tolerance of each other and both near the frame's capture time (a source that leaves
  // them unset, 0, fails here rather than passing as "equal").
  const double skew_ms = static_cast<double>(m.right_utime - m.left_utime) / 1e3;
  const auto near_us = static_cast<std::int64_t>(limits.clock_tolerance_s * 1e6);
  std::string pair_time;
  if (std::llabs(m.left_utime - m.utime) > near_us || std::llabs(m.right_utime - m.utime) > near_us) {
    pair_time = which + ": left_utime " + std::to_string(m.left_utime) + ", right_utime " +
                std::to_string(m.right_utime) + " with utime " + std::to_string(m.utime);
  } else if (!(std::abs(skew_ms) <= limits.pair_tolerance_ms)) {
    pair_time = which + ": right exposed " + Num(skew_ms, 3) + " ms after left";
  }
  report.Expect(pair_time.empty(), "camera.time.pair",
                "left_utime and right_utime within " + Num(limits.pair_tolerance_ms, 3) + " ms of each other, both within " +
                    Num(limits.clock_tolerance_s, 2) + " s of utime",
                pair_time);

  if (request) {
    const auto tolerance = static_cast<std::int64_t>(limits.clock_tolerance_s * 1e6);
    report.Expect(m.utime >= request->utime - tolerance && m.utime <= f.at.clock_utime + tolerance,
                  "camera.time.capture",
                  "utime from the request's " + std::to_string(request->utime) + " to rover time at arrival " +
                      std::to_string(f.at.clock_utime) + " (" + Num(limits.clock_tolerance_s, 2) + " s)",
                  which + ": utime " + std::to_string(m.utime));
  }
}

}  // namespace

void CheckCamera(const CameraTrace& trace, const CameraLimits& limits, Report& report) {
  CheckAnswers(trace, limits, report);
  const Received<stereo_frame_t>* previous = nullptr;
  for (const auto& f : trace.frames) {
    const SentRequest* request = nullptr;
    for (const auto& r : trace.requests)
      if (r.frame_id == f.msg.frame_id) request = &r;
    CheckFrame(f, request, limits, report);
    if (previous) {
      report.Expect(f.msg.utime > previous->msg.utime, "camera.time.order", "frame utimes that increase",
                    "frame " + std::to_string(f.msg.frame_id) + " at " + std::to_string(f.msg.utime) + " after frame " +
                        std::to_string(previous->msg.frame_id) + " at " + std::to_string(previous->msg.utime));
    }
    previous = &f;
  }
}

}  // namespace rover::conformance
