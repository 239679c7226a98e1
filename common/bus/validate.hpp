// Field checks on decoded messages, before any callback sees them: numbers a receiver
// uses must be finite, enums known, counts sane. Each returns "" when the message is
// usable, else what is wrong (one phrase, for the Bus's drop line).
//
// Only what a receiver relies on is checked; free text and the fields a failure leaves
// unset (a failed VO update's delta) are not.
#pragma once

#include <rover_msgs/capture_request_t.hpp>
#include <rover_msgs/hazard_query_t.hpp>
#include <rover_msgs/hazard_reply_t.hpp>
#include <rover_msgs/traversability_map_t.hpp>
#include <rover_msgs/hazard_status_t.hpp>
#include <rover_msgs/heartbeat_t.hpp>
#include <rover_msgs/imu_t.hpp>
#include <rover_msgs/keepout_zones_t.hpp>
#include <rover_msgs/mobility_command_t.hpp>
#include <rover_msgs/mobility_status_t.hpp>
#include <rover_msgs/new_site_t.hpp>
#include <rover_msgs/pose_t.hpp>
#include <rover_msgs/rover_clock_t.hpp>
#include <rover_msgs/sequence_control_t.hpp>
#include <rover_msgs/sequence_status_t.hpp>
#include <rover_msgs/sequence_submit_t.hpp>
#include <rover_msgs/sim_truth_t.hpp>
#include <rover_msgs/step_report_t.hpp>
#include <rover_msgs/stereo_frame_t.hpp>
#include <rover_msgs/vo_update_t.hpp>
#include <rover_msgs/wheel_odometry_t.hpp>

#include <string>

namespace rover::bus {

std::string Problem(const rover_msgs::capture_request_t& m);
std::string Problem(const rover_msgs::hazard_query_t& m);
std::string Problem(const rover_msgs::hazard_reply_t& m);
std::string Problem(const rover_msgs::traversability_map_t& m);
std::string Problem(const rover_msgs::hazard_status_t& m);
std::string Problem(const rover_msgs::heartbeat_t& m);
std::string Problem(const rover_msgs::imu_t& m);
std::string Problem(const rover_msgs::keepout_zones_t& m);
std::string Problem(const rover_msgs::mobility_command_t& m);
std::string Problem(const rover_msgs::mobility_status_t& m);
std::string Problem(const rover_msgs::new_site_t& m);
std::string Problem(const rover_msgs::pose_t& m);
std::string Problem(const rover_msgs::rover_clock_t& m);
std::string Problem(const rover_msgs::sequence_control_t& m);
std::string Problem(const rover_msgs::sequence_status_t& m);
std::string Problem(const rover_msgs::sequence_submit_t& m);
std::string Problem(const rover_msgs::sim_truth_t& m);
std::string Problem(const rover_msgs::step_report_t& m);
std::string Problem(const rover_msgs::stereo_frame_t& m);
std::string Problem(const rover_msgs::vo_update_t& m);
std::string Problem(const rover_msgs::wheel_odometry_t& m);

}  // namespace rover::bus
