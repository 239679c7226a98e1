// The state estimator's inputs from their messages: what state_estimator subscribes to and
// what estimator_replay reads back from a log go into the estimator the same way.
#pragma once

#include "bus/convert.hpp"
#include "estimation/pose_estimator.hpp"

#include <rover_msgs/vo_update_t.hpp>
#include <rover_msgs/wheel_odometry_t.hpp>

namespace rover::state_estimator {

inline estimation::WheelOdometrySample FromMsg(const rover_msgs::wheel_odometry_t& m) {
  estimation::WheelOdometrySample s;
  s.utime = m.utime;
  s.distance_m = m.distance_m;
  s.wheel_distance_m = m.wheel_distance_m;
  s.curvature_per_m = m.curvature_per_m;
  s.turning_in_place = m.turning_in_place != 0;
  return s;
}

inline estimation::VoUpdate FromMsg(const rover_msgs::vo_update_t& m) {
  estimation::VoUpdate u;
  u.from_utime = m.from_utime;
  u.to_utime = m.to_utime;
  u.from_frame_id = m.from_frame_id;
  u.to_frame_id = m.to_frame_id;
  u.T_from_to.linear() = bus::QuaternionFromArray(m.delta_orientation).toRotationMatrix();
  u.T_from_to.translation() = Eigen::Vector3d(m.delta_position[0], m.delta_position[1], m.delta_position[2]);
  u.covariance = bus::CovarianceFromArray(m.covariance);
  return u;
}

}  // namespace rover::state_estimator
