#include "hazards/keepout.hpp"

#include <algorithm>
#include <cmath>
#include <set>
#include <sstream>
#include <stdexcept>

#include "geometry/pose.hpp"

namespace rover::hazards {

namespace {

using Vec = Eigen::Vector2d;
using Polygon = std::vector<Vec>;

constexpr double kEps = 1e-12;

double Cross(const Vec& a, const Vec& b) { return a.x() * b.y() - a.y() * b.x(); }

double Orient(const Vec& a, const Vec& b, const Vec& c) { return Cross(b - a, c - a); }

bool OnSegment(const Vec& a, const Vec& b, const Vec& p) {
  return std::min(a.x(), b.x()) - kEps <= p.x() && p.x() <= std::max(a.x(), b.x()) + kEps &&
         std::min(a.y(), b.y()) - kEps <= p.y() && p.y() <= std::max(a.y(), b.y()) + kEps;
}

// Closed segments ab and cd share at least one point.
bool SegmentsIntersect(const Vec& a, const Vec& b, const Vec& c, const Vec& d) {
  const double o1 = Orient(a, b, c), o2 = Orient(a, b, d);
  const double o3 = Orient(c, d, a), o4 = Orient(c, d, b);
  if (((o1 > kEps && o2 < -kEps) || (o1 < -kEps && o2 > kEps)) &&
      ((o3 > kEps && o4 < -kEps) || (o3 < -kEps && o4 > kEps))) {
    return true;
  }
  if (std::abs(o1) <= kEps && OnSegment(a, b, c)) return true;
  if (std::abs(o2) <= kEps && OnSegment(a, b, d)) return true;
  if (std::abs(o3) <= kEps && OnSegment(c, d, a)) return true;
  if (std::abs(o4) <= kEps && OnSegment(c, d, b)) return true;
  return false;
}

double PointSegmentDistance(const Vec& p, const Vec& a, const Vec& b) {
  const Vec ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0.0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (a + t * ab - p).norm();
}

double SegmentDistance(const Vec& a, const Vec& b, const Vec& c, const Vec& d) {
  if (SegmentsIntersect(a, b, c, d)) return 0.0;
  return std::min({PointSegmentDistance(a, c, d), PointSegmentDistance(b, c, d),
                   PointSegmentDistance(c, a, b), PointSegmentDistance(d, a, b)});
}

// Even-odd rule; points on the boundary may go either way (their distance is 0 anyway).
bool Contains(const Polygon& poly, const Vec& p) {
  bool inside = false;
  for (std::size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
    const Vec& a = poly[i];
    const Vec& b = poly[j];
    if ((a.y() > p.y()) != (b.y() > p.y())) {
      const double x = a.x() + (p.y() - a.y()) * (b.x() - a.x()) / (b.y() - a.y());
      if (p.x() < x) inside = !inside;
    }
  }
  return inside;
}

double SignedArea(const Polygon& poly) {
  double a = 0.0;
  for (std::size_t i = 0; i < poly.size(); ++i) {
    a += Cross(poly[i], poly[(i + 1) % poly.size()]);
  }
  return 0.5 * a;
}

bool IsConvex(const Polygon& poly) {
  bool pos = false, neg = false;
  const std::size_t n = poly.size();
  for (std::size_t i = 0; i < n; ++i) {
    const double c = Orient(poly[i], poly[(i + 1) % n], poly[(i + 2) % n]);
    if (c > kEps) pos = true;
    if (c < -kEps) neg = true;
  }
  return !(pos && neg);
}

// Penetration depth of two convex polygons by separating axes: the shortest push along any
// edge normal that separates the projections (min(amax - bmin, bmax - amin), which also
// counts containment right); <= 0 when some axis already separates them.
double ConvexPenetration(const Polygon& A, const Polygon& B) {
  double depth = std::numeric_limits<double>::infinity();
  for (const Polygon* P : {&A, &B}) {
    for (std::size_t i = 0; i < P->size(); ++i) {
      const Vec e = (*P)[(i + 1) % P->size()] - (*P)[i];
      if (e.norm() < kEps) continue;
      const Vec n(-e.y() / e.norm(), e.x() / e.norm());
      double amin = INFINITY, amax = -INFINITY, bmin = INFINITY, bmax = -INFINITY;
      for (const Vec& v : A) amin = std::min(amin, v.dot(n)), amax = std::max(amax, v.dot(n));
      for (const Vec& v : B) bmin = std::min(bmin, v.dot(n)), bmax = std::max(bmax, v.dot(n));
      depth = std::min(depth, std::min(amax - bmin, bmax - amin));
      if (depth <= 0.0) return depth;
    }
  }
  return depth;
}

// Ear clipping of a simple polygon into triangles.
std::vector<Polygon> Triangulate(Polygon poly) {
  if (SignedArea(poly) < 0.0) std::reverse(poly.begin(), poly.end());
  std::vector<Polygon> triangles;
  while (poly.size() > 3) {
    const std::size_t n = poly.size();
    bool clipped = false;
    for (std::size_t i = 0; i < n && !clipped; ++i) {
      const Vec& a = poly[(i + n - 1) % n];
      const Vec& b = poly[i];
      const Vec& c = poly[(i + 1) % n];
      if (Orient(a, b, c) <= kEps) continue;  // reflex or flat: not an ear
      bool empty = true;
      for (std::size_t j = 0; j < n && empty; ++j) {
        if (j == i || j == (i + 1) % n || j == (i + n - 1) % n) continue;
        const Vec& p = poly[j];
        if (Orient(a, b, p) >= -kEps && Orient(b, c, p) >= -kEps && Orient(c, a, p) >= -kEps) {
          empty = false;
        }
      }
      if (empty) {
        triangles.push_back({a, b, c});
        poly.erase(poly.begin() + static_cast<std::ptrdiff_t>(i));
        clipped = true;
      }
    }
    if (!clipped) {
      // Only flat vertices left to remove (collinear runs): drop one, area unchanged.
      std::size_t flat = n;
      for (std::size_t i = 0; i < n && flat == n; ++i) {
        if (std::abs(Orient(poly[(i + n - 1) % n], poly[i], poly[(i + 1) % n])) <= kEps) flat = i;
      }
      if (flat == n) break;  // not simple; validation rejects such polygons
      poly.erase(poly.begin() + static_cast<std::ptrdiff_t>(flat));
    }
  }
  if (poly.size() == 3) triangles.push_back(poly);
  return triangles;
}

std::string Quoted(const std::string& name) { return "zone '" + name + "'"; }

std::string Num(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

}  // namespace

KeepOutZone KeepOutZone::Circle(const std::string& name, double x, double y, double radius_m) {
  KeepOutZone z;
  z.name = name;
  z.shape = Shape::kCircle;
  z.center = Vec(x, y);
  z.radius_m = radius_m;
  const std::string problem = ZoneProblem(z);
  if (!problem.empty()) throw std::invalid_argument(problem);
  return z;
}

KeepOutZone KeepOutZone::Polygon(const std::string& name, const std::vector<Vec>& vertices) {
  KeepOutZone z;
  z.name = name;
  z.shape = Shape::kPolygon;
  z.vertices = vertices;
  const std::string problem = ZoneProblem(z);
  if (!problem.empty()) throw std::invalid_argument(problem);
  return z;
}

std::string ZoneProblem(const KeepOutZone& z) {
  if (z.name.empty()) return "keep-out zone without a name (expected a non-empty name)";
  const std::string who = Quoted(z.name);
  if (z.shape == KeepOutZone::Shape::kCircle) {
    if (!z.center.allFinite()) return who + ": centre is not finite";
    if (!std::isfinite(z.radius_m) || z.radius_m <= 0.0) {
      return who + ": radius " + Num(z.radius_m) + " m (expected a finite radius > 0)";
    }
    return "";
  }
  const auto& v = z.vertices;
  const std::size_t n = v.size();
  if (n < 3) {
    return who + ": polygon has " + std::to_string(n) + " vertices (expected at least 3)";
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (!v[i].allFinite()) return who + ": vertex " + std::to_string(i) + " is not finite";
  }
  for (std::size_t i = 0; i < n; ++i) {
    if ((v[i] - v[(i + 1) % n]).norm() < 1e-9) {
      return who + ": vertices " + std::to_string(i) + " and " + std::to_string((i + 1) % n) +
             " coincide (expected distinct consecutive vertices)";
    }
  }
  if (std::abs(SignedArea(v)) < 1e-9) {
    return who + ": polygon has zero area (expected vertices that enclose a region)";
  }
  for (std::size_t i = 0; i < n; ++i) {
    const Vec& a = v[i];
    const Vec& b = v[(i + 1) % n];
    // An adjacent edge that folds back over this one.
    const Vec& c = v[(i + 2) % n];
    if (std::abs(Orient(a, b, c)) <= kEps && (b - a).dot(c - b) < 0.0) {
      return who + ": polygon folds back on itself at vertex " + std::to_string((i + 1) % n) +
             " (expected a simple polygon)";
    }
    for (std::size_t j = i + 2; j < n; ++j) {
      if (i == 0 && j == n - 1) continue;  // adjacent through vertex 0
      if (SegmentsIntersect(a, b, v[j], v[(j + 1) % n])) {
        return who + ": polygon edges " + std::to_string(i) + " and " + std::to_string(j) +
               " cross (expected a simple, non-self-intersecting polygon)";
      }
    }
  }
  return "";
}

std::string ZoneSetProblem(const std::vector<KeepOutZone>& zones) {
  std::set<std::string> names;
  for (const KeepOutZone& z : zones) {
    const std::string problem = ZoneProblem(z);
    if (!problem.empty()) return problem;
    if (!names.insert(z.name).second) return Quoted(z.name) + ": duplicate zone name";
  }
  return "";
}

void ValidateZones(const std::vector<KeepOutZone>& zones) {
  const std::string problem = ZoneSetProblem(zones);
  if (!problem.empty()) throw std::invalid_argument(problem);
}

void Footprint::Validate() const {
  auto check = [](const char* field, double v, bool positive) {
    if (!std::isfinite(v) || (positive ? v <= 0.0 : v < 0.0)) {
      throw std::invalid_argument(std::string("Footprint.") + field + " = " + Num(v) +
                                  (positive ? ": expected a finite value > 0"
                                            : ": expected a finite value >= 0"));
    }
  };
  check("length_m", length_m, true);
  check("width_m", width_m, true);
  check("margin_m", margin_m, false);
  if (!std::isfinite(center_forward_m)) {
    throw std::invalid_argument("Footprint.center_forward_m = " + Num(center_forward_m) +
                                ": expected a finite value");
  }
}

std::vector<Vec> Footprint::Corners(const Pose2& p) const {
  const Vec fwd(std::cos(p.yaw), std::sin(p.yaw));
  const Vec right(-std::sin(p.yaw), std::cos(p.yaw));
  const Vec c = Vec(p.x, p.y) + center_forward_m * fwd;
  const double hl = 0.5 * length_m, hw = 0.5 * width_m;
  return {c + hl * fwd - hw * right, c + hl * fwd + hw * right, c - hl * fwd + hw * right,
          c - hl * fwd - hw * right};
}

double Clearance(const KeepOutZone& zone, const Footprint& fp, double x, double y, double yaw) {
  const Pose2 pose{x, y, yaw};
  if (zone.shape == KeepOutZone::Shape::kCircle) {
    // Signed distance from the circle's centre to the box, in the rover's axes, less r.
    const Vec fwd(std::cos(yaw), std::sin(yaw));
    const Vec right(-std::sin(yaw), std::cos(yaw));
    const Vec d = zone.center - (Vec(x, y) + fp.center_forward_m * fwd);
    const Vec q = Vec(std::abs(d.dot(fwd)), std::abs(d.dot(right))) -
                  Vec(0.5 * fp.length_m, 0.5 * fp.width_m);
    const double box = q.cwiseMax(0.0).norm() + std::min(std::max(q.x(), q.y()), 0.0);
    return box - zone.radius_m - fp.margin_m;
  }

  const Polygon rect = fp.Corners(pose);
  const Polygon& poly = zone.vertices;
  bool overlap = false;
  double gap = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < rect.size() && !overlap; ++i) {
    const Vec& a = rect[i];
    const Vec& b = rect[(i + 1) % rect.size()];
    for (std::size_t j = 0; j < poly.size(); ++j) {
      const double d = SegmentDistance(a, b, poly[j], poly[(j + 1) % poly.size()]);
      if (d == 0.0) {
        overlap = true;
        break;
      }
      gap = std::min(gap, d);
    }
  }
  // No edge contact: either apart, or one inside the other.
  if (!overlap) overlap = Contains(poly, rect[0]) || Contains(rect, poly[0]);
  if (!overlap) return gap - fp.margin_m;

  double depth = 0.0;
  if (IsConvex(poly)) {
    depth = std::max(0.0, ConvexPenetration(rect, poly));
  } else {
    for (const Polygon& tri : Triangulate(poly)) {
      depth = std::max(depth, ConvexPenetration(rect, tri));
    }
  }
  return -depth - fp.margin_m;
}

const char* ToString(Verdict verdict) {
  switch (verdict) {
    case Verdict::kSafe: return "safe";
    case Verdict::kUnsafe: return "unsafe";
    case Verdict::kUnknown: return "unknown";
  }
  return "unknown";
}

SweptCheck CheckSweptPath(const std::vector<KeepOutZone>& zones, const Footprint& footprint,
                          const std::vector<Pose2>& path, double position_sigma_m,
                          double sigma_multiplier, double extra_margin_m,
                          double max_corner_step_m) {
  SweptCheck check;
  auto unknown = [&](const std::string& why) {
    check.verdict = Verdict::kUnknown;
    check.detail = why;
    return check;
  };
  if (path.empty()) return unknown("empty path: nothing to check (treated as unsafe)");
  if (!std::isfinite(position_sigma_m) || position_sigma_m < 0.0) {
    return unknown("position sigma " + Num(position_sigma_m) + " m is not a finite value >= 0");
  }
  if (!std::isfinite(sigma_multiplier) || sigma_multiplier < 0.0) {
    return unknown("sigma multiplier " + Num(sigma_multiplier) + " is not a finite value >= 0");
  }
  if (!std::isfinite(extra_margin_m) || extra_margin_m < 0.0) {
    return unknown("extra margin " + Num(extra_margin_m) + " m is not a finite value >= 0");
  }
  if (!std::isfinite(max_corner_step_m) || max_corner_step_m <= 0.0) {
    return unknown("max corner step " + Num(max_corner_step_m) + " m is not a finite value > 0");
  }
  for (std::size_t i = 0; i < path.size(); ++i) {
    if (!std::isfinite(path[i].x) || !std::isfinite(path[i].y) || !std::isfinite(path[i].yaw)) {
      return unknown("path pose " + std::to_string(i) + " is not finite");
    }
  }
  if (zones.empty()) {
    check.detail = "no keep-out zones";
    return check;
  }
  const double uncertainty = sigma_multiplier * position_sigma_m + extra_margin_m;
  // The farthest footprint point from the rover origin sets how far a turn sweeps.
  const double reach = std::hypot(std::abs(footprint.center_forward_m) + 0.5 * footprint.length_m,
                                  0.5 * footprint.width_m);
  auto visit = [&](const Pose2& p, std::size_t segment) {
    for (const KeepOutZone& z : zones) {
      const double c = Clearance(z, footprint, p) - uncertainty;
      if (c < check.min_clearance_m) {
        check.min_clearance_m = c;
        check.zone_name = z.name;
        check.worst_pose_index = segment;
        check.worst_pose = p;
      }
    }
  };
  for (std::size_t i = 0; i < path.size(); ++i) {
    visit(path[i], i);
    if (i + 1 == path.size()) break;
    const Pose2& a = path[i];
    const Pose2& b = path[i + 1];
    const double dyaw = geometry::WrapAngle(b.yaw - a.yaw);
    const double corner_move = std::hypot(b.x - a.x, b.y - a.y) + std::abs(dyaw) * reach;
    const int n = static_cast<int>(std::ceil(corner_move / max_corner_step_m));
    for (int k = 1; k < n; ++k) {
      const double f = static_cast<double>(k) / n;
      visit({a.x + f * (b.x - a.x), a.y + f * (b.y - a.y), geometry::WrapAngle(a.yaw + f * dyaw)},
            i);
    }
  }
  const Pose2& w = check.worst_pose;
  std::ostringstream os;
  os << (check.min_clearance_m < 0.0 ? "enters " : "clears ") << Quoted(check.zone_name)
     << ": clearance " << check.min_clearance_m << " m (" << check.min_clearance_m + uncertainty
     << " m less " << sigma_multiplier << " x " << position_sigma_m << " m"
     << (extra_margin_m > 0.0 ? " and a margin of " + Num(extra_margin_m) + " m" : std::string())
     << ") at pose "
     << check.worst_pose_index << " of " << path.size() << " (x " << w.x << ", y " << w.y
     << ", yaw " << w.yaw << ")";
  check.detail = os.str();
  check.verdict = check.min_clearance_m < 0.0 ? Verdict::kUnsafe : Verdict::kSafe;
  return check;
}

std::vector<Pose2> SampleStepPath(const Pose2& start, double distance_m, double curvature_per_m,
                                  double turn_rad, double max_spacing_m,
                                  double max_angle_step_rad) {
  auto require = [](bool ok, const std::string& what) {
    if (!ok) throw std::invalid_argument("SampleStepPath: " + what);
  };
  require(std::isfinite(start.x) && std::isfinite(start.y) && std::isfinite(start.yaw),
          "start pose is not finite");
  require(std::isfinite(distance_m), "distance_m = " + Num(distance_m) + " is not finite");
  require(std::isfinite(curvature_per_m),
          "curvature_per_m = " + Num(curvature_per_m) + " is not finite");
  require(std::isfinite(turn_rad), "turn_rad = " + Num(turn_rad) + " is not finite");
  require(std::isfinite(max_spacing_m) && max_spacing_m > 0.0,
          "max_spacing_m = " + Num(max_spacing_m) + " (expected a finite value > 0)");
  require(std::isfinite(max_angle_step_rad) && max_angle_step_rad > 0.0,
          "max_angle_step_rad = " + Num(max_angle_step_rad) + " (expected a finite value > 0)");

  std::vector<Pose2> path{start};
  if (turn_rad != 0.0) {
    const int n = std::max(1, static_cast<int>(std::ceil(std::abs(turn_rad) / max_angle_step_rad)));
    for (int i = 1; i <= n; ++i) {
      path.push_back({start.x, start.y, geometry::WrapAngle(start.yaw + turn_rad * i / n)});
    }
  }
  if (distance_m != 0.0) {
    const Pose2 s0 = path.back();
    const double total_turn = std::abs(curvature_per_m * distance_m);
    const int n = std::max({1, static_cast<int>(std::ceil(std::abs(distance_m) / max_spacing_m)),
                            static_cast<int>(std::ceil(total_turn / max_angle_step_rad))});
    for (int i = 1; i <= n; ++i) {
      const double s = distance_m * i / n;
      const double half = 0.5 * curvature_per_m * s;
      // Chord of the arc: length s * sin(half) / half, along the mean heading.
      const double sinc = std::abs(half) < 1e-6 ? 1.0 - half * half / 6.0 : std::sin(half) / half;
      const double heading = s0.yaw + half;
      path.push_back({s0.x + s * sinc * std::cos(heading), s0.y + s * sinc * std::sin(heading),
                      geometry::WrapAngle(s0.yaw + 2.0 * half)});
    }
  }
  return path;
}

}  // namespace rover::hazards
