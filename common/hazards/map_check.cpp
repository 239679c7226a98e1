#include "hazards/map_check.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace rover::hazards {

namespace {
std::string Fixed(double v, int digits = 2) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}
}  // namespace

void MapCheckOptions::Validate() const {
  if (!(blind_margin_m >= 0.0) || !std::isfinite(blind_margin_m) || blind_margin_m > 5.0)
    throw std::invalid_argument("hazards.map.blind_margin_m " + std::to_string(blind_margin_m) +
                                " must be 0 to 5 m");
  if (!(max_unknown_fraction >= 0.0) || !(max_unknown_fraction <= 1.0))
    throw std::invalid_argument("hazards.map.max_unknown_fraction " + std::to_string(max_unknown_fraction) +
                                " must be 0 to 1");
  if (!(max_scattered_unknown_fraction >= 0.0) || !(max_scattered_unknown_fraction <= 1.0))
    throw std::invalid_argument("hazards.map.max_scattered_unknown_fraction " +
                                std::to_string(max_scattered_unknown_fraction) + " must be 0 to 1");
  if (!(driven_step_fraction > 0.0) || !(driven_step_fraction <= 1.0))
    throw std::invalid_argument("hazards.map.driven_step_fraction " + std::to_string(driven_step_fraction) +
                                " must be over 0 and at most 1 (1: off)");
  if (!(max_driven_step_m >= 0.0) || !std::isfinite(max_driven_step_m))
    throw std::invalid_argument("hazards.map: max_driven_step_m " + std::to_string(max_driven_step_m) +
                                " must be finite and >= 0 (0: off)");
  if (!(hidden_patch_m >= 0.0) || !(hidden_patch_m <= 5.0))
    throw std::invalid_argument("hazards.map.hidden_patch_m " + std::to_string(hidden_patch_m) +
                                " must be 0 to 5 m");
}

MapCheckOptions LoadMapCheckOptions(const config::ConfigNode& node, const std::vector<std::string>& extra_keys) {
  MapCheckOptions o;
  std::vector<std::string> keys = {"enabled", "blind_margin_m", "max_unknown_fraction", "hidden_patch_m",
                                   "max_scattered_unknown_fraction", "driven_step_fraction",
                                   "driven_step_refused"};
  keys.insert(keys.end(), extra_keys.begin(), extra_keys.end());
  node.CheckKeys(keys);
  node.Get("enabled", o.enabled);
  node.Get("blind_margin_m", o.blind_margin_m, 0.0, 5.0);
  node.Get("max_unknown_fraction", o.max_unknown_fraction, 0.0, 1.0);
  node.Get("hidden_patch_m", o.hidden_patch_m, 0.0, 5.0);
  node.Get("max_scattered_unknown_fraction", o.max_scattered_unknown_fraction, 0.0, 1.0);
  node.Get("driven_step_fraction", o.driven_step_fraction, 0.01, 1.0);
  node.Get("driven_step_refused", o.driven_step_refused);
  return o;
}

std::string MapTiltLimitProblem(double map_max_tilt_deg, const TiltLimits& rover) {
  const double rover_deg = std::min(rover.roll_limit_rad, rover.pitch_limit_rad) * 180.0 / M_PI;
  // Rounding of degrees read from YAML is not a difference.
  if (!(map_max_tilt_deg < rover_deg - 1e-6)) return "";
  return "hazards.map.traversability.max_tilt_deg " + Fixed(map_max_tilt_deg, 1) +
         " is tighter than the rover's own tilt limit " + Fixed(rover_deg, 1) +
         " deg (hazards.roll_limit_deg, pitch_limit_deg): the map refuses slopes the tilt check allows";
}

DrivenTrail::DrivenTrail(double cell_m) : cell_m_(cell_m) {
  if (!(cell_m > 0.0) || !std::isfinite(cell_m))
    throw std::invalid_argument("DrivenTrail: cell size " + std::to_string(cell_m) + " must be > 0");
}

std::int64_t DrivenTrail::Key(double x, double y) const {
  const auto i = static_cast<std::int64_t>(std::floor(x / cell_m_));
  const auto j = static_cast<std::int64_t>(std::floor(y / cell_m_));
  return (i << 32) ^ (j & 0xffffffffLL);
}

void DrivenTrail::Add(const Pose2& pose, const Footprint& footprint) {
  if (!std::isfinite(pose.x) || !std::isfinite(pose.y) || !std::isfinite(pose.yaw)) return;
  avoidance::Footprint body;
  body.length_m = footprint.length_m;
  body.width_m = footprint.width_m;
  body.center_forward_m = footprint.center_forward_m;
  const avoidance::Pose2 p{pose.x, pose.y, pose.yaw};
  const double reach = std::abs(footprint.center_forward_m) + 0.5 * std::hypot(footprint.length_m, footprint.width_m);
  const double i0 = std::floor((pose.x - reach) / cell_m_), i1 = std::floor((pose.x + reach) / cell_m_);
  const double j0 = std::floor((pose.y - reach) / cell_m_), j1 = std::floor((pose.y + reach) / cell_m_);
  for (double i = i0; i <= i1; ++i) {
    for (double j = j0; j <= j1; ++j) {
      const double x = (i + 0.5) * cell_m_, y = (j + 0.5) * cell_m_;
      if (body.Contains(p, x, y)) cells_.insert(Key(x, y));
    }
  }
}

int DrivenTrail::MarkDriven(avoidance::Grid* grid) const {
  int changed = 0;
  if (cells_.empty()) return 0;
  for (int i = 0; i < grid->rows; ++i) {
    for (int j = 0; j < grid->cols; ++j) {
      const std::size_t k = static_cast<std::size_t>(i) * grid->cols + j;
      if (grid->state[k] != avoidance::CellClass::kUnknown) continue;
      if (!cells_.count(Key(grid->CellCentreX(i), grid->CellCentreY(j)))) continue;
      grid->state[k] = avoidance::CellClass::kSafe;
      grid->goodness[k] = 1.0f;
      ++changed;
    }
  }
  return changed;
}

avoidance::Footprint GridFootprint(const Footprint& f) {
  avoidance::Footprint g;
  g.length_m = f.length_m + 2.0 * f.margin_m;
  g.width_m = f.width_m + 2.0 * f.margin_m;
  g.center_forward_m = f.center_forward_m;
  return g;
}

SweptCheck CheckPathOnMap(const avoidance::Grid& grid, const avoidance::Footprint& footprint,
                          const std::vector<Pose2>& path, const MapCheckOptions& options) {
  SweptCheck c;
  c.zone_name = kMapZoneName;
  bool finite = !path.empty();
  std::vector<avoidance::Pose2> p;
  for (const Pose2& q : path) {
    finite = finite && std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.yaw);
    p.push_back({q.x, q.y, q.yaw});
  }
  if (!finite) {
    c.verdict = Verdict::kUnknown;
    c.detail = std::string(kMapZoneName) + ": empty or non-finite path";
    return c;
  }
  if (const std::string bad = grid.Problem(); !bad.empty()) {
    c.verdict = Verdict::kUnknown;
    c.detail = std::string(kMapZoneName) + ": the map is invalid: " + bad;
    return c;
  }
  const avoidance::Sweep s =
      avoidance::SweepFootprint(grid, footprint, p, p.front(), options.blind_margin_m, options.hidden_patch_m);
  if (s.unsafe > 0) {
    c.verdict = Verdict::kUnsafe;
    c.min_clearance_m = 0.0;
    c.worst_pose_index = s.first_unsafe_pose < 0 ? 0 : static_cast<std::size_t>(s.first_unsafe_pose);
    c.worst_pose = path[c.worst_pose_index];
    c.detail = std::string(kMapZoneName) + ": step " + Fixed(s.worst_step_m) + " m" +
               (s.worst_tilt_deg >= 0.0 ? ", tilt " + Fixed(s.worst_tilt_deg, 1) + " deg" : std::string()) + " at " +
               Fixed(s.worst_x) + "," +
               Fixed(s.worst_y);
    return c;
  }
  if (options.driven_step_refused && options.max_driven_step_m > 0.0 && s.max_step_m >= options.max_driven_step_m) {
    // Caution, but too near the step limit to drive over (MapCheckOptions::driven_step_refused).
    c.verdict = Verdict::kUnsafe;
    c.min_clearance_m = 0.0;
    c.worst_pose_index = 0;
    c.worst_pose = path.front();
    c.detail = std::string(kMapZoneName) + ": step " + Fixed(s.max_step_m) + " m at " + Fixed(s.max_step_x) + "," +
               Fixed(s.max_step_y) + " is over the " + Fixed(options.max_driven_step_m) + " m a step drives over";
    return c;
  }
  const std::string share = Fixed(100.0 * s.UnknownFraction(), 0) + " % of the cells the step crosses are unknown";
  switch (avoidance::JudgeUnknown(s, options.Unknown())) {
    case avoidance::UnknownVerdict::kAcceptable: break;
    case avoidance::UnknownVerdict::kHidden:
      c.verdict = Verdict::kUnknown;
      c.detail = std::string(kMapZoneName) + ": unknown ground " + Fixed(options.hidden_patch_m) + " m across at " +
                 Fixed(s.hidden_x) + "," + Fixed(s.hidden_y) + " could hide a rock (" + share + ", limit " +
                 Fixed(100.0 * options.max_unknown_fraction, 0) + " %)";
      break;
    case avoidance::UnknownVerdict::kTooMuch:
      c.verdict = Verdict::kUnknown;
      c.detail = std::string(kMapZoneName) + ": unknown: " + share + " (limit " +
                 Fixed(100.0 * avoidance::UnknownLimit(options.Unknown()), 0) + " %)";
      break;
  }
  return c;
}

}  // namespace rover::hazards
