// Keep-out zones and the rover footprint, in the site frame's horizontal plane.
//
// Plane conventions (geometry/pose.hpp projected on the ground): x north, y east, yaw 0
// faces north and +yaw turns clockwise seen from above (toward east). The rover's forward
// axis is (cos yaw, sin yaw), its right axis (-sin yaw, cos yaw).
//
// Why a swept check: on Mars, keep-out zones around rocks stopped the rover before it got
// too close; near the rock Wopmay, Opportunity halted correctly when VO showed it sliding
// toward the rock. A step whose swept footprint, grown by the position uncertainty and by
// the drift measured over the recent steps, would enter a zone is not commanded at all.
#pragma once

#include <Eigen/Core>

#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace rover::hazards {

struct Pose2 {
  double x = 0.0;    // m, north
  double y = 0.0;    // m, east
  double yaw = 0.0;  // rad, 0 = north, + = clockwise from above
};

// Mirrors keepout_zone_t.
struct KeepOutZone {
  enum class Shape { kCircle = 0, kPolygon = 1 };
  std::string name;
  Shape shape = Shape::kCircle;
  Eigen::Vector2d center = Eigen::Vector2d::Zero();  // circle
  double radius_m = 0.0;                             // circle
  std::vector<Eigen::Vector2d> vertices;             // polygon, either winding

  // Validated constructors: throw std::invalid_argument with a one-line message naming the
  // zone and the bad value.
  static KeepOutZone Circle(const std::string& name, double x, double y, double radius_m);
  static KeepOutZone Polygon(const std::string& name, const std::vector<Eigen::Vector2d>& vertices);
};

// Why a zone is invalid ("zone 'rock1': radius -1 m must be > 0"), or empty when valid.
// Checks: non-empty name, finite numbers, radius > 0; polygon with >= 3 vertices, no repeated
// consecutive vertex, non-zero area, and no self-intersection.
std::string ZoneProblem(const KeepOutZone& zone);
// As ZoneProblem for each zone, plus duplicate names.
std::string ZoneSetProblem(const std::vector<KeepOutZone>& zones);
// Throws std::invalid_argument with ZoneSetProblem's message when it is not empty.
void ValidateZones(const std::vector<KeepOutZone>& zones);

// The rover footprint: a length x width rectangle (along x forward, y right of the rover)
// whose centre sits `center_forward_m` ahead of the rover origin, grown by `margin_m` all
// round (a rounded border: clearances are the rectangle's less the margin).
// Defaults: MER, 1.6 m long and 2.3 m wide with the solar array.
struct Footprint {
  double length_m = 1.6;
  double width_m = 2.3;
  double margin_m = 0.0;
  double center_forward_m = 0.0;

  // Throws std::invalid_argument naming the field.
  void Validate() const;
  // The rectangle's corners in the site plane at pose p (without the margin), in order.
  std::vector<Eigen::Vector2d> Corners(const Pose2& p) const;
};

// Signed distance between the footprint at pose p and the zone: positive is the gap,
// negative means overlap. Exact for circles (box signed distance less the radius) and for
// the gap to polygons (segment distances + containment). When the footprint overlaps a
// polygon the value is minus the penetration depth (separating axes): exact for convex
// polygons; for concave ones the polygon is split into triangles and the deepest
// penetration into any one of them is reported (a lower bound of the depth, but always < 0).
double Clearance(const KeepOutZone& zone, const Footprint& footprint, double x, double y,
                 double yaw);
inline double Clearance(const KeepOutZone& zone, const Footprint& footprint, const Pose2& p) {
  return Clearance(zone, footprint, p.x, p.y, p.yaw);
}

// Mirrors hazard_reply_t.VERDICT_*.
enum class Verdict { kSafe = 0, kUnsafe = 1, kUnknown = 2 };
const char* ToString(Verdict verdict);

struct SweptCheck {
  Verdict verdict = Verdict::kSafe;
  bool safe() const { return verdict == Verdict::kSafe; }
  std::string zone_name;  // the zone of the smallest clearance (the entered one if unsafe)
  double min_clearance_m = std::numeric_limits<double>::infinity();  // less k * sigma
  // Where the smallest clearance occurs: the path segment starting at input pose
  // worst_pose_index, at pose worst_pose (an input pose or one interpolated after it).
  std::size_t worst_pose_index = 0;
  Pose2 worst_pose;
  std::string detail;
};

// Checks a sampled path against every zone: clearance less
// sigma_multiplier * position_sigma_m less extra_margin_m (what the asker adds: the drift VO
// measured and the uncertainty the step itself adds). Unsafe when any is < 0. So that coarse
// samples cannot step over a small rock, poses are interpolated between consecutive inputs
// (x, y linearly, yaw the short way) until no footprint corner moves more than
// max_corner_step_m between checks. Unknown (never safe) for an empty path, a non-finite
// pose, sigma or margin, or a negative sigma or margin. With no zones the path is safe.
SweptCheck CheckSweptPath(const std::vector<KeepOutZone>& zones, const Footprint& footprint,
                          const std::vector<Pose2>& path, double position_sigma_m,
                          double sigma_multiplier, double extra_margin_m = 0.0,
                          double max_corner_step_m = 0.02);

// Poses along one planned step, start and end included: first a turn in place by turn_rad
// (+ = clockwise from above), then an arc of signed length distance_m (negative = backward)
// with curvature curvature_per_m (+ = turning right, i.e. yaw increases; 0 = straight).
// Consecutive poses are at most max_spacing_m and max_angle_step_rad apart. Throws
// std::invalid_argument for non-finite input or non-positive spacing.
std::vector<Pose2> SampleStepPath(const Pose2& start, double distance_m, double curvature_per_m,
                                  double turn_rad, double max_spacing_m,
                                  double max_angle_step_rad);

}  // namespace rover::hazards
