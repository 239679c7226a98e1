// The camera contract (docs/HARDWARE.md, "Contracts"): CAPTURE_REQUEST in, STEREO_FRAME out,
// and a heartbeat that says when a capture failed. The probe sends requests one at a time
// and records the frames and the capture process's heartbeats; this judges the record.
#pragma once

#include "conformance/report.hpp"

#include <rover_msgs/heartbeat_t.hpp>
#include <rover_msgs/stereo_frame_t.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace rover::conformance {

struct SentRequest {
  std::int64_t frame_id = 0;
  std::string purpose;
  std::int64_t utime = 0;  // rover time it was stamped with
  double wall_s = 0;
};

struct CameraTrace {
  std::vector<SentRequest> requests;
  std::vector<Received<rover_msgs::stereo_frame_t>> frames;
  std::vector<Received<rover_msgs::heartbeat_t>> capture_heartbeats;  // from the capture process
  double end_wall_s = 0;
};

struct CameraLimits {
  double answer_s = 20.0;          // a request's frame, or the failure status
  double clock_tolerance_s = 0.5;
  int width = 0, height = 0;       // expected image size; 0: any
  double pair_tolerance_ms = 2.0;  // left_utime and right_utime at most this far apart
};

void CheckCamera(const CameraTrace& trace, const CameraLimits& limits, Report& report);

}  // namespace rover::conformance
