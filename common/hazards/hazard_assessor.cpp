#include "hazards/hazard_assessor.hpp"

#include <Eigen/Eigenvalues>

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace rover::hazards {

namespace {

constexpr double kDeg = M_PI / 180.0;

std::string Deg(double rad) {
  std::ostringstream os;
  os.precision(3);
  os << std::fixed << rad / kDeg << " deg";
  return os.str();
}

void CheckLimits(const TiltLimits& t) {
  for (auto [name, v] : {std::pair{"roll_limit_rad", t.roll_limit_rad},
                         std::pair{"pitch_limit_rad", t.pitch_limit_rad}}) {
    if (!std::isfinite(v) || v <= 0.0 || v > M_PI / 2) {
      std::ostringstream os;
      os << "TiltLimits." << name << " = " << v << ": expected a value in (0, pi/2]";
      throw std::invalid_argument(os.str());
    }
  }
}

}  // namespace

TiltCheck CheckTilt(double roll_rad, double pitch_rad, const TiltLimits& limits) {
  TiltCheck check;
  std::string detail;
  if (!std::isfinite(roll_rad) || !std::isfinite(pitch_rad)) {
    check.violated = true;
    check.detail = "tilt unknown: roll or pitch is not finite";
    return check;
  }
  if (std::abs(roll_rad) > limits.roll_limit_rad) {
    detail = "roll " + Deg(roll_rad) + " beyond limit " + Deg(limits.roll_limit_rad);
  }
  if (std::abs(pitch_rad) > limits.pitch_limit_rad) {
    detail += (detail.empty() ? "" : "; ") + std::string("pitch ") + Deg(pitch_rad) +
              " beyond limit " + Deg(limits.pitch_limit_rad);
  }
  check.violated = !detail.empty();
  check.detail = detail;
  return check;
}

double HorizontalSigma(const geometry::Matrix6d& covariance) {
  const Eigen::Matrix2d P = covariance.topLeftCorner<2, 2>();
  if (!P.allFinite()) return std::numeric_limits<double>::infinity();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(0.5 * (P + P.transpose()));
  return std::sqrt(std::max(0.0, es.eigenvalues().maxCoeff()));
}

PoseSnapshot SnapshotFromPose(int64_t utime, const geometry::Pose& T_site_rover,
                              const geometry::Matrix6d& covariance) {
  const Eigen::Vector3d rpy = geometry::RpyFromRotation(T_site_rover.linear());
  PoseSnapshot s;
  s.utime = utime;
  s.x = T_site_rover.translation().x();
  s.y = T_site_rover.translation().y();
  s.roll = rpy.x();
  s.pitch = rpy.y();
  s.yaw = rpy.z();
  s.position_sigma_m = HorizontalSigma(covariance);
  return s;
}

const char* ToString(HazardState state) {
  switch (state) {
    case HazardState::kSafe: return "SAFE";
    case HazardState::kViolation: return "VIOLATION";
    case HazardState::kUnknown: return "UNKNOWN";
  }
  return "UNKNOWN";
}

void HazardOptions::Validate() const {
  footprint.Validate();
  CheckLimits(tilt);
  if (!std::isfinite(sigma_multiplier) || sigma_multiplier < 0.0) {
    throw std::invalid_argument("HazardOptions.sigma_multiplier = " +
                                std::to_string(sigma_multiplier) + ": expected a value >= 0");
  }
  if (!std::isfinite(max_pose_age_s) || max_pose_age_s <= 0.0) {
    throw std::invalid_argument("HazardOptions.max_pose_age_s = " +
                                std::to_string(max_pose_age_s) + ": expected a value > 0");
  }
  ValidateZones(zones);
}

KeepOutZone LoadKeepOutZone(const config::ConfigNode& node) {
  if (!node.IsMap()) node.Fail("expected a zone mapping {name, circle: ...} or {name, polygon: ...}");
  node.CheckKeys({"name", "circle", "polygon"});
  KeepOutZone z;
  z.name = node.RequireString("name");
  const bool circle = node.Has("circle"), polygon = node.Has("polygon");
  if (circle == polygon) node.Fail("expected exactly one of 'circle' or 'polygon'");
  if (circle) {
    const config::ConfigNode c = node["circle"];
    c.CheckKeys({"center", "radius_m"});
    const std::vector<double> center = c.RequireVector("center", 2);
    z.shape = KeepOutZone::Shape::kCircle;
    z.center = Eigen::Vector2d(center[0], center[1]);
    z.radius_m = c.RequireDouble("radius_m", 0.0);
  } else {
    const config::ConfigNode p = node["polygon"];
    if (!p.IsSequence()) p.Fail("expected a list of [x, y] vertices");
    z.shape = KeepOutZone::Shape::kPolygon;
    for (std::size_t i = 0; i < p.size(); ++i) {
      const std::vector<double> v = p.at(i).AsVector(2);
      z.vertices.emplace_back(v[0], v[1]);
    }
  }
  const std::string problem = ZoneProblem(z);
  if (!problem.empty()) node.Fail(problem);
  return z;
}

std::vector<KeepOutZone> LoadKeepOutZones(const config::ConfigNode& list) {
  std::vector<KeepOutZone> zones;
  if (list.IsNull()) return zones;
  if (!list.IsSequence()) list.Fail("expected a list of zones");
  for (std::size_t i = 0; i < list.size(); ++i) {
    zones.push_back(LoadKeepOutZone(list.at(i)));
    for (std::size_t j = 0; j + 1 < zones.size(); ++j) {
      if (zones[j].name == zones.back().name) {
        list.at(i).Fail("duplicate zone name '" + zones.back().name + "'");
      }
    }
  }
  return zones;
}

HazardOptions LoadHazardOptions(const config::ConfigNode& section,
                                const std::vector<std::string>& extra_keys) {
  HazardOptions o;
  if (section.IsNull()) return o;
  // `map` (the traversability map) is read by LoadMapCheckOptions (map_check.hpp).
  std::vector<std::string> keys = {"footprint",      "sigma_multiplier", "roll_limit_deg",
                                   "pitch_limit_deg", "max_pose_age_s",  "zones", "map"};
  keys.insert(keys.end(), extra_keys.begin(), extra_keys.end());
  section.CheckKeys(keys);
  const config::ConfigNode fp = section["footprint"];
  fp.CheckKeys({"length_m", "width_m", "margin_m", "center_forward_m"});
  fp.Get("length_m", o.footprint.length_m, 1e-3, 100.0);
  fp.Get("width_m", o.footprint.width_m, 1e-3, 100.0);
  fp.Get("margin_m", o.footprint.margin_m, 0.0, 100.0);
  fp.Get("center_forward_m", o.footprint.center_forward_m, -100.0, 100.0);
  section.Get("sigma_multiplier", o.sigma_multiplier, 0.0, 100.0);
  double roll_deg = o.tilt.roll_limit_rad / kDeg, pitch_deg = o.tilt.pitch_limit_rad / kDeg;
  section.Get("roll_limit_deg", roll_deg, 0.1, 90.0);
  section.Get("pitch_limit_deg", pitch_deg, 0.1, 90.0);
  o.tilt.roll_limit_rad = roll_deg * kDeg;
  o.tilt.pitch_limit_rad = pitch_deg * kDeg;
  section.Get("max_pose_age_s", o.max_pose_age_s, 1e-3, 3600.0);
  o.zones = LoadKeepOutZones(section["zones"]);
  return o;
}

HazardAssessor::HazardAssessor(const HazardOptions& options) : options_(options) {
  options_.Validate();
  zones_ = options_.zones;
}

void HazardAssessor::SetZones(const std::vector<KeepOutZone>& zones) {
  ValidateZones(zones);
  zones_ = zones;
}

void HazardAssessor::SetTiltLimits(const TiltLimits& limits) {
  CheckLimits(limits);
  options_.tilt = limits;
}

void HazardAssessor::set_clock_rate(double rover_s_per_guard_s) {
  if (!std::isfinite(rover_s_per_guard_s) || rover_s_per_guard_s <= 0.0)
    throw std::invalid_argument("HazardAssessor: clock rate " + std::to_string(rover_s_per_guard_s) +
                                ": expected a finite value > 0");
  clock_rate_ = rover_s_per_guard_s;
}

void HazardAssessor::OnPose(const PoseSnapshot& pose) {
  pose_ = pose;
  if (!has_attitude_ || pose.utime >= attitude_utime_) {
    roll_ = pose.roll;
    pitch_ = pose.pitch;
    attitude_utime_ = pose.utime;
    has_attitude_ = true;
  }
}

void HazardAssessor::OnAttitude(int64_t utime, double roll_rad, double pitch_rad) {
  if (has_attitude_ && utime < attitude_utime_) return;
  roll_ = roll_rad;
  pitch_ = pitch_rad;
  attitude_utime_ = utime;
  has_attitude_ = true;
}

std::string HazardAssessor::Staleness(int64_t now_utime) const {
  if (!pose_) return "no pose received yet: cannot decide (treated as unsafe)";
  const double rover_age_s = static_cast<double>(now_utime - pose_->utime) * 1e-6;
  const double age_s = rover_age_s / clock_rate_;
  if (age_s > options_.max_pose_age_s) {
    std::ostringstream os;
    os << "pose is " << age_s << " s old";
    if (clock_rate_ != 1.0) os << " in wall time (" << rover_age_s << " s of rover time at " << clock_rate_ << "x)";
    os << " (limit " << options_.max_pose_age_s << " s): cannot decide (treated as unsafe)";
    return os.str();
  }
  const bool finite = std::isfinite(pose_->x) && std::isfinite(pose_->y) &&
                      std::isfinite(pose_->yaw) && std::isfinite(pose_->position_sigma_m) &&
                      pose_->position_sigma_m >= 0.0;
  if (!finite) return "pose or its sigma is not finite: cannot decide (treated as unsafe)";
  return "";
}

HazardStatus HazardAssessor::Assess(int64_t now_utime) const {
  HazardStatus s;
  s.utime = now_utime;
  s.roll_limit_rad = options_.tilt.roll_limit_rad;
  s.pitch_limit_rad = options_.tilt.pitch_limit_rad;
  s.roll_rad = roll_;
  s.pitch_rad = pitch_;
  std::vector<std::string> parts;
  // Tilt needs only a fresh attitude (the IMU may outlive the estimator): a known tilt
  // violation is reported as such even when keep-out cannot be decided.
  const double attitude_age_s = static_cast<double>(now_utime - attitude_utime_) * 1e-6 / clock_rate_;
  if (has_attitude_ && attitude_age_s <= options_.max_pose_age_s) {
    const TiltCheck tilt = CheckTilt(roll_, pitch_, options_.tilt);
    s.tilt_violated = tilt.violated;
    if (tilt.violated) parts.push_back(tilt.detail);
  }
  const std::string stale = Staleness(now_utime);
  if (!stale.empty()) {
    s.state = s.tilt_violated ? HazardState::kViolation : HazardState::kUnknown;
    parts.push_back(stale);
    for (std::size_t i = 0; i < parts.size(); ++i) s.detail += (i ? "; " : "") + parts[i];
    return s;
  }

  const Pose2 here{pose_->x, pose_->y, pose_->yaw};
  const SweptCheck keepout = CheckSweptPath(zones_, options_.footprint, {here},
                                            pose_->position_sigma_m, options_.sigma_multiplier);
  s.min_clearance_m = keepout.min_clearance_m;
  s.zone_name = keepout.zone_name;
  s.keepout_violated = keepout.verdict != Verdict::kSafe;
  if (s.keepout_violated) {
    parts.push_back("keep-out: " + keepout.detail);
  }

  s.state = (s.tilt_violated || s.keepout_violated) ? HazardState::kViolation
                                                    : HazardState::kSafe;
  if (parts.empty()) {
    std::ostringstream os;
    os << "safe: roll " << Deg(roll_) << ", pitch " << Deg(pitch_) << "; ";
    if (zones_.empty()) {
      os << "no keep-out zones";
    } else {
      os << "nearest zone '" << s.zone_name << "' at " << s.min_clearance_m << " m";
    }
    s.detail = os.str();
  } else {
    for (std::size_t i = 0; i < parts.size(); ++i) s.detail += (i ? "; " : "") + parts[i];
  }
  return s;
}

SweptCheck HazardAssessor::CheckStep(const std::vector<Pose2>& path, int64_t now_utime,
                                     double margin_m) const {
  const std::string stale = Staleness(now_utime);
  if (!stale.empty()) {
    SweptCheck check;
    check.verdict = Verdict::kUnknown;
    check.detail = stale;
    return check;
  }
  return CheckSweptPath(zones_, options_.footprint, path, pose_->position_sigma_m,
                        options_.sigma_multiplier, margin_m);
}

}  // namespace rover::hazards
