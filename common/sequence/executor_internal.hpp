// Helpers shared by the executor's source files (executor*.cpp), not part of its API.
#pragma once

#include "sequence/executor.hpp"

#include <numbers>
#include <sstream>
#include <string>
#include <vector>

namespace rover::sequence::internal {

inline constexpr double kDeg = std::numbers::pi / 180.0;

// Numbers in messages: fixed point, so that details read the same from run to run.
inline std::string Fixed(double v, int digits = 2) {
  std::ostringstream os;
  os.setf(std::ios::fixed);
  os.precision(digits);
  os << v;
  return os.str();
}

// x y z roll pitch yaw, the pose layout of sequence_status_t and step_report_t.
inline void XyzRpy(const PoseEstimate& p, double out[6]) {
  const Eigen::Vector3d rpy = geometry::RpyFromRotation(p.orientation.normalized().toRotationMatrix());
  out[0] = p.position.x();
  out[1] = p.position.y();
  out[2] = p.position.z();
  out[3] = rpy.x();
  out[4] = rpy.y();
  out[5] = rpy.z();
}

inline std::string Join(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
  return s;
}

}  // namespace rover::sequence::internal

namespace rover::sequence {

// What FinishStep learned about the step that ended, handed to each of its checks.
struct SequenceExecutor::StepEnd {
  PoseEstimate after;       // the pose after the step (including its VO update when it came)
  bool measured = false;    // VO measured the step's motion
  std::string slip_likely;  // why slip is likely here when VO did not measure it, else empty
  bool vo_lost = false;     // the `vo lost` policy applies to this step
  StepMotion motion;        // the estimated motion against the commanded
  std::string text;         // "step N: ", the prefix of every message about it
};

}  // namespace rover::sequence
