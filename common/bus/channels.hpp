// Every LCM channel name, in one place. Channels are in CAPS.
#pragma once

namespace rover::channels {

inline constexpr const char* kHeartbeat = "HEARTBEAT";            // heartbeat_t, every process
inline constexpr const char* kClock = "ROVER_CLOCK";              // rover_clock_t (rover_sim owns it)
inline constexpr const char* kImu = "IMU";                        // imu_t
inline constexpr const char* kWheelOdometry = "WHEEL_ODOMETRY";   // wheel_odometry_t
inline constexpr const char* kPose = "POSE";                      // pose_t (state_estimator)
inline constexpr const char* kNewSite = "NEW_SITE";               // new_site_t (executor -> estimator)
inline constexpr const char* kMobilityCommand = "MOBILITY_COMMAND";  // mobility_command_t
inline constexpr const char* kMobilityStatus = "MOBILITY_STATUS";    // mobility_status_t
inline constexpr const char* kCaptureRequest = "CAPTURE_REQUEST";    // capture_request_t
inline constexpr const char* kStereoFrame = "STEREO_FRAME";          // stereo_frame_t
inline constexpr const char* kHazcamFrame = "HAZCAM_FRAME";          // stereo_frame_t (the front HAZCAM pair; the map only, never VO)
inline constexpr const char* kVoUpdate = "VO_UPDATE";                // vo_update_t
inline constexpr const char* kKeepOutZones = "KEEPOUT_ZONES";        // keepout_zones_t
inline constexpr const char* kHazardStatus = "HAZARD_STATUS";        // hazard_status_t
inline constexpr const char* kHazardQuery = "HAZARD_QUERY";          // hazard_query_t
inline constexpr const char* kHazardReply = "HAZARD_REPLY";          // hazard_reply_t
inline constexpr const char* kTraversabilityMap = "TRAVERSABILITY_MAP";  // traversability_map_t (hazard_monitor)
inline constexpr const char* kSequenceSubmit = "SEQUENCE_SUBMIT";    // sequence_submit_t
inline constexpr const char* kSequenceControl = "SEQUENCE_CONTROL";  // sequence_control_t
inline constexpr const char* kSequenceStatus = "SEQUENCE_STATUS";    // sequence_status_t
inline constexpr const char* kStepReport = "STEP_REPORT";            // step_report_t
inline constexpr const char* kSimTruth = "SIM_TRUTH";                // sim_truth_t (tests/evaluation only)

}  // namespace rover::channels
