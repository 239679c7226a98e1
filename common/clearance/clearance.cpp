#include "clearance/clearance.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace rover::clearance {

namespace {

constexpr double kDeg = M_PI / 180.0;

std::string Fixed(double v, int digits = 2) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}

// A height the body takes: c0 + sum_k c[k] * (centre height of wheel k), linear in the
// six wheel heights (see the header).
struct LinearForm {
  std::array<double, kNumWheels> c{};
  double c0 = 0.0;

  LinearForm operator+(const LinearForm& o) const {
    LinearForm r;
    for (int k = 0; k < kNumWheels; ++k) r.c[k] = c[k] + o.c[k];
    r.c0 = c0 + o.c0;
    return r;
  }
  LinearForm operator*(double f) const {
    LinearForm r;
    for (int k = 0; k < kNumWheels; ++k) r.c[k] = c[k] * f;
    r.c0 = c0 * f;
    return r;
  }
  LinearForm operator-(const LinearForm& o) const { return *this + o * -1.0; }
  // Its extremes over the wheel centres' intervals: each coefficient's sign picks the end.
  Interval Over(const std::array<Interval, kNumWheels>& w) const {
    Interval out{c0, c0};
    for (int k = 0; k < kNumWheels; ++k) {
      out.lo += c[k] * (c[k] >= 0 ? w[k].lo : w[k].hi);
      out.hi += c[k] * (c[k] >= 0 ? w[k].hi : w[k].lo);
    }
    return out;
  }
};

LinearForm WheelHeight(int k) {
  LinearForm f;
  f.c[k] = 1.0;
  return f;
}

// One side's chain (wheel centre heights f, m, r): the tangents of the bogie and the
// rocker against the level, and the rocker pivot's height.
struct SideChain {
  LinearForm tan_bogie, tan_rocker, rocker_pivot;
};

SideChain Chain(const Suspension& s, int front, int middle, int rear) {
  const LinearForm f = WheelHeight(front), m = WheelHeight(middle), r = WheelHeight(rear);
  // The bogie's axle line, at the bogie pivot's x.
  const double u_b = (s.middle_wheel_x_m - s.bogie_pivot_x_m) / (s.middle_wheel_x_m - s.rear_wheel_x_m);
  const LinearForm bogie_axle = m * (1.0 - u_b) + r * u_b;
  SideChain out;
  out.tan_bogie = (m - r) * (1.0 / (s.middle_wheel_x_m - s.rear_wheel_x_m));
  // The rocker's line runs from the bogie's axle line to the front axle, parallel to the
  // line through its pivots.
  out.tan_rocker = (f - bogie_axle) * (1.0 / (s.front_wheel_x_m - s.bogie_pivot_x_m));
  const double u_r = (s.rocker_pivot_x_m - s.bogie_pivot_x_m) / (s.front_wheel_x_m - s.bogie_pivot_x_m);
  out.rocker_pivot = bogie_axle * (1.0 - u_r) + f * u_r;
  out.rocker_pivot.c0 += s.rocker_pivot_height_m - s.wheel_radius_m;
  return out;
}

Interval Atan(const Interval& t) { return {std::atan(t.lo), std::atan(t.hi)}; }
double Magnitude(const Interval& a) { return std::max(std::abs(a.lo), std::abs(a.hi)); }
Interval Minus(const Interval& a, const Interval& b) { return {a.lo - b.hi, a.hi - b.lo}; }
Interval Half(const Interval& a) { return {0.5 * a.lo, 0.5 * a.hi}; }
Interval Plus(const Interval& a, const Interval& b) { return {a.lo + b.lo, a.hi + b.hi}; }

// Cells of `map` that a disc of radius r at (x, y) touches, as (i, j), on the grid or off it.
template <typename F>
void ForCellsInDisc(const HeightMap& map, double x, double y, double r, F&& f) {
  const double c = map.cell_m;
  const long i0 = static_cast<long>(std::floor((x - r - map.origin_x) / c));
  const long i1 = static_cast<long>(std::floor((x + r - map.origin_x) / c));
  const long j0 = static_cast<long>(std::floor((y - r - map.origin_y) / c));
  const long j1 = static_cast<long>(std::floor((y + r - map.origin_y) / c));
  for (long i = i0; i <= i1; ++i)
    for (long j = j0; j <= j1; ++j) {
      const double cx = map.origin_x + (i + 0.5) * c, cy = map.origin_y + (j + 0.5) * c;
      const double dx = std::max(std::abs(cx - x) - 0.5 * c, 0.0), dy = std::max(std::abs(cy - y) - 0.5 * c, 0.0);
      if (dx * dx + dy * dy <= r * r + 1e-12) f(i, j, cx, cy);
    }
}

// A cell's height: false when the map holds none (or the cell is off the map).
bool HeightAt(const HeightMap& map, long i, long j, float* h, float* sigma) {
  if (i < 0 || j < 0 || i >= map.rows || j >= map.cols) return false;
  const std::size_t k = static_cast<std::size_t>(i) * map.cols + j;
  if (!(map.sigma_m[k] >= 0.0f)) return false;
  *h = map.elevation_m[k];
  *sigma = map.sigma_m[k];
  return true;
}

// The rock unknown cell (i, j) may hide.
double HiddenRock(const Suspension& s, const HeightMap& map, long i, long j) {
  if (!map.hidden_rock_m || i < 0 || j < 0 || i >= map.rows || j >= map.cols) return s.unknown_rise_m;
  return map.hidden_rock_m[static_cast<std::size_t>(i) * map.cols + j];
}

const char* WheelName(int k) {
  static const char* names[] = {"left front", "left middle", "left rear", "right front", "right middle", "right rear"};
  return names[k];
}

Interval Hull(const std::vector<Interval>& v) {
  Interval h{std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
  for (const Interval& i : v) h = {std::min(h.lo, i.lo), std::max(h.hi, i.hi)};
  return h;
}

}  // namespace

std::string Suspension::Problem() const {
  auto finite = [](double v) { return std::isfinite(v); };
  const std::pair<const char*, double> positive[] = {
      {"wheel_radius_m", wheel_radius_m}, {"wheel_patch_m", wheel_patch_m}, {"track_m", track_m},
      {"rocker_pivot_height_m", rocker_pivot_height_m},
      {"belly_height_m", belly_height_m}, {"belly_width_m", belly_width_m}, {"max_rocker_deg", max_rocker_deg},
      {"max_bogie_deg", max_bogie_deg}, {"max_tilt_deg", max_tilt_deg}};
  for (const auto& [key, v] : positive)
    if (!finite(v) || !(v > 0.0)) return std::string(key) + ": expected a finite value > 0, got " + Fixed(v, 3);
  if (!(front_wheel_x_m > middle_wheel_x_m) || !(middle_wheel_x_m > rear_wheel_x_m))
    return "middle_wheel_x_m: expected front_wheel_x_m > middle_wheel_x_m > rear_wheel_x_m";
  if (!(bogie_pivot_x_m > rear_wheel_x_m && bogie_pivot_x_m < middle_wheel_x_m))
    return "bogie_pivot_x_m: expected between rear_wheel_x_m and middle_wheel_x_m";
  if (!(rocker_pivot_x_m > bogie_pivot_x_m && rocker_pivot_x_m < front_wheel_x_m))
    return "rocker_pivot_x_m: expected between bogie_pivot_x_m and front_wheel_x_m";
  if (!finite(belly_min_x_m) || !finite(belly_max_x_m) || !(belly_max_x_m > belly_min_x_m))
    return "belly_max_x_m: expected a finite value over belly_min_x_m";
  if (!(belly_width_m <= 2.0 * track_m)) return "belly_width_m: expected at most twice track_m";
  if (!finite(min_belly_clearance_m) || min_belly_clearance_m < 0 || !(min_belly_clearance_m < belly_height_m))
    return "min_belly_clearance_m: expected in [0, belly_height_m)";
  if (max_rocker_deg >= 90 || max_bogie_deg >= 90 || max_tilt_deg >= 90)
    return "max_tilt_deg: expected the angle limits under 90 deg";
  if (!finite(sigma_multiplier) || sigma_multiplier < 0) return "sigma_multiplier: expected a finite value >= 0";
  if (!finite(unknown_rise_m) || unknown_rise_m < 0) return "unknown_rise_m: expected a finite value >= 0";
  if (!finite(rock_width_per_height) || rock_width_per_height < 0)
    return "rock_width_per_height: expected a finite value >= 0";
  return "";
}

Suspension LoadSuspension(const config::ConfigNode& node) {
  Suspension s;
  if (node.IsNull()) return s;
  if (!node.IsMap()) node.Fail("expected a map of the suspension's geometry and limits");
  node.CheckKeys({"enabled", "wheel_radius_m", "wheel_patch_m", "track_m", "front_wheel_x_m", "middle_wheel_x_m",
                  "rear_wheel_x_m", "bogie_pivot_x_m", "rocker_pivot_x_m",
                  "rocker_pivot_height_m", "belly_height_m", "belly_min_x_m", "belly_max_x_m", "belly_width_m",
                  "min_belly_clearance_m", "max_rocker_deg", "max_bogie_deg", "max_tilt_deg", "sigma_multiplier",
                  "unknown_rise_m", "rock_width_per_height"});
  node.Get("enabled", s.enabled);
  node.Get("wheel_radius_m", s.wheel_radius_m, 0.01, 2.0);
  node.Get("wheel_patch_m", s.wheel_patch_m, 0.01, 2.0);
  node.Get("track_m", s.track_m, 0.1, 10.0);
  node.Get("front_wheel_x_m", s.front_wheel_x_m, -10.0, 10.0);
  node.Get("middle_wheel_x_m", s.middle_wheel_x_m, -10.0, 10.0);
  node.Get("rear_wheel_x_m", s.rear_wheel_x_m, -10.0, 10.0);
  node.Get("bogie_pivot_x_m", s.bogie_pivot_x_m, -10.0, 10.0);
  node.Get("rocker_pivot_x_m", s.rocker_pivot_x_m, -10.0, 10.0);
  node.Get("rocker_pivot_height_m", s.rocker_pivot_height_m, 0.01, 5.0);
  node.Get("belly_height_m", s.belly_height_m, 0.01, 5.0);
  node.Get("belly_min_x_m", s.belly_min_x_m, -10.0, 10.0);
  node.Get("belly_max_x_m", s.belly_max_x_m, -10.0, 10.0);
  node.Get("belly_width_m", s.belly_width_m, 0.01, 10.0);
  node.Get("min_belly_clearance_m", s.min_belly_clearance_m, 0.0, 5.0);
  node.Get("max_rocker_deg", s.max_rocker_deg, 0.1, 89.0);
  node.Get("max_bogie_deg", s.max_bogie_deg, 0.1, 89.0);
  node.Get("max_tilt_deg", s.max_tilt_deg, 0.1, 89.0);
  node.Get("sigma_multiplier", s.sigma_multiplier, 0.0, 10.0);
  node.Get("unknown_rise_m", s.unknown_rise_m, 0.0, 5.0);
  node.Get("rock_width_per_height", s.rock_width_per_height, 0.0, 100.0);
  if (const std::string p = s.Problem(); !p.empty()) node.Fail(p);
  return s;
}

std::vector<float> HiddenRockHeights(const Suspension& s, const HeightMap& map) {
  const std::size_t n = static_cast<std::size_t>(map.rows) * static_cast<std::size_t>(map.cols);
  std::vector<float> out(n, 0.0f);
  std::vector<char> done(n, 0);
  std::vector<std::size_t> patch, stack;
  for (std::size_t start = 0; start < n; ++start) {
    if (done[start] || map.sigma_m[start] >= 0.0f) continue;
    // The 8-connected patch of unknown cells, its bounding box, and whether it runs off the map.
    patch.clear();
    stack.assign(1, start);
    done[start] = 1;
    int i0 = map.rows, i1 = -1, j0 = map.cols, j1 = -1;
    bool open = false;
    while (!stack.empty()) {
      const std::size_t k = stack.back();
      stack.pop_back();
      patch.push_back(k);
      const int i = static_cast<int>(k / map.cols), j = static_cast<int>(k % map.cols);
      i0 = std::min(i0, i), i1 = std::max(i1, i), j0 = std::min(j0, j), j1 = std::max(j1, j);
      for (int di = -1; di <= 1; ++di)
        for (int dj = -1; dj <= 1; ++dj) {
          const int a = i + di, b = j + dj;
          if (a < 0 || b < 0 || a >= map.rows || b >= map.cols) {
            open = true;
            continue;
          }
          const std::size_t q = static_cast<std::size_t>(a) * map.cols + b;
          if (!done[q] && map.sigma_m[q] < 0.0f) {
            done[q] = 1;
            stack.push_back(q);
          }
        }
    }
    // A rock inside the patch is no wider than its narrower side.
    const double narrow_m = std::min(i1 - i0 + 1, j1 - j0 + 1) * map.cell_m;
    double rise = s.unknown_rise_m;
    if (!open && s.rock_width_per_height > 0) rise = std::min(rise, narrow_m / s.rock_width_per_height);
    for (std::size_t k : patch) out[k] = static_cast<float>(rise);
  }
  return out;
}

bool Excused::Contains(double x, double y, double grow_m) const {
  const double c = std::cos(standing.yaw), s = std::sin(standing.yaw);
  const double dx = x - (standing.x + center_forward_m * c), dy = y - (standing.y + center_forward_m * s);
  return std::abs(c * dx + s * dy) <= 0.5 * length_m + grow_m && std::abs(-s * dx + c * dy) <= 0.5 * width_m + grow_m;
}

PoseTerrain SampleTerrain(const Suspension& s, const HeightMap& map, const Pose& pose, const Excused* excused) {
  PoseTerrain t;
  const double c = std::cos(pose.yaw), sn = std::sin(pose.yaw);
  auto to_site = [&](double fx, double ry, double* x, double* y) {
    *x = pose.x + c * fx - sn * ry;
    *y = pose.y + sn * fx + c * ry;
  };
  auto is_excused = [&](double x, double y) { return excused && excused->Contains(x, y); };
  const double k = s.sigma_multiplier;
  // The wheels: each rests on the highest ground in its patch.
  const double wheel_x[3] = {s.front_wheel_x_m, s.middle_wheel_x_m, s.rear_wheel_x_m};
  std::array<bool, kNumWheels> rests_on_others{};
  std::array<double, kNumWheels> unknown_rise{};  // > 0: the wheel's patch is all unknown ground
  std::array<std::string, kNumWheels> where;
  std::vector<Interval> known_wheels;
  for (int w = 0; w < kNumWheels; ++w) {
    double x, y;
    to_site(wheel_x[w % 3], (w < 3 ? -0.5 : 0.5) * s.track_m, &x, &y);
    double max_lo = -std::numeric_limits<double>::infinity(), max_hi = max_lo;
    int known = 0, unknown = 0;
    double rise = 0.0;
    ForCellsInDisc(map, x, y, 0.5 * s.wheel_patch_m, [&](long i, long j, double cx, double cy) {
      float h, sigma;
      if (HeightAt(map, i, j, &h, &sigma)) {
        ++known;
        max_lo = std::max(max_lo, static_cast<double>(h) - k * sigma);
        max_hi = std::max(max_hi, static_cast<double>(h) + k * sigma);
      } else if (!is_excused(cx, cy)) {
        ++unknown;
        rise = std::max(rise, HiddenRock(s, map, i, j));
      }
    });
    if (known > 0) {
      // A rock in an unknown cell would lift the wheel; a hole would not lower it.
      t.wheel_ground[w] = {max_lo, max_hi + rise};
      known_wheels.push_back(t.wheel_ground[w]);
    } else if (unknown > 0) {
      unknown_rise[w] = std::max(rise, 1e-9);
      where[w] = Fixed(x) + "," + Fixed(y);
    } else {
      rests_on_others[w] = true;
    }
  }
  // The belly: cells partly under it (centre inside it grown by half a cell).
  const double grow = 0.5 * map.cell_m;
  const double half_w = 0.5 * s.belly_width_m;
  const double reach = std::hypot(std::max(std::abs(s.belly_min_x_m), std::abs(s.belly_max_x_m)), half_w) + grow;
  std::vector<PoseTerrain::BellyPoint> unknown_points;
  double belly_known_hi = -std::numeric_limits<double>::infinity();
  std::vector<Interval> belly_known;
  ForCellsInDisc(map, pose.x, pose.y, reach, [&](long i, long j, double cx, double cy) {
    const double dx = cx - pose.x, dy = cy - pose.y;
    const double fx = c * dx + sn * dy, ry = -sn * dx + c * dy;
    if (fx < s.belly_min_x_m - grow || fx > s.belly_max_x_m + grow || std::abs(ry) > half_w + grow) return;
    if (excused && excused->Contains(cx, cy, 0.0)) return;  // under the rover where it stands
    const PoseTerrain::BellyPoint p{std::clamp(fx, s.belly_min_x_m, s.belly_max_x_m), std::clamp(ry, -half_w, half_w), 0.0};
    float h, sigma;
    if (HeightAt(map, i, j, &h, &sigma)) {
      t.belly.push_back({p.x, p.y, h + k * sigma});
      belly_known_hi = std::max(belly_known_hi, t.belly.back().ground_hi);
      belly_known.push_back({h - k * sigma, h + k * sigma});
    } else if (!is_excused(cx, cy)) {
      unknown_points.push_back({p.x, p.y, HiddenRock(s, map, i, j)});
    }
  });
  // Wheels on excused ground alone rest within the heights the others rest on (or, with
  // none, within the belly's known ground; with nothing known at all, on level ground: the
  // rover stands there).
  Interval others{0.0, 0.0};
  if (!known_wheels.empty()) others = Hull(known_wheels);
  else if (!belly_known.empty()) others = Hull(belly_known);
  for (int w = 0; w < kNumWheels; ++w)
    if (rests_on_others[w]) t.wheel_ground[w] = others;
  // A wheel on unknown ground alone may stand on the rock the ground could hide, or in a
  // hole as deep, about the heights the rest of the rover stands on; with nothing known
  // at all the pose cannot be decided.
  for (int w = 0; w < kNumWheels; ++w) {
    if (unknown_rise[w] <= 0.0) continue;
    if (known_wheels.empty() && belly_known.empty()) {
      t.decided = false;
      if (t.undecided_why.empty())
        t.undecided_why = std::string("the ground under the ") + WheelName(w) + " wheel at " + where[w] + " is unknown";
      continue;
    }
    t.wheel_ground[w] = {others.lo - unknown_rise[w], others.hi + unknown_rise[w]};
  }
  // Unknown belly cells may hold a rock unknown_rise_m above the highest known ground there
  // (or the highest the wheels may rest on).
  if (!unknown_points.empty()) {
    double base = belly_known_hi;
    for (int w = 0; w < kNumWheels; ++w) base = std::max(base, t.wheel_ground[w].hi);
    for (PoseTerrain::BellyPoint p : unknown_points) {
      p.ground_hi = base + p.ground_hi;  // it holds the rock the cell may hide
      t.belly.push_back(p);
    }
  }
  return t;
}

Bounds Evaluate(const Suspension& s, const PoseTerrain& t) {
  Bounds b;
  if (!t.decided) {
    b.decided = false;
    b.undecided_why = t.undecided_why;
    b.violation = "cannot decide: " + t.undecided_why;
    b.margin = 0.0;
    return b;
  }
  std::array<Interval, kNumWheels> centre;
  for (int w = 0; w < kNumWheels; ++w)
    centre[w] = {t.wheel_ground[w].lo + s.wheel_radius_m, t.wheel_ground[w].hi + s.wheel_radius_m};
  const SideChain left = Chain(s, kLeftFront, kLeftMiddle, kLeftRear);
  const SideChain right = Chain(s, kRightFront, kRightMiddle, kRightRear);
  // Suspension angles against the level, then against each other.
  const Interval bogie_l = Atan(left.tan_bogie.Over(centre)), bogie_r = Atan(right.tan_bogie.Over(centre));
  const Interval rocker_l = Atan(left.tan_rocker.Over(centre)), rocker_r = Atan(right.tan_rocker.Over(centre));
  // The differential: the body pitches by the mean of the rockers, each rocker turns
  // against it by half their difference.
  const Interval pitch = Half(Plus(rocker_l, rocker_r));
  b.max_pitch_rad = Magnitude(pitch);
  b.max_rocker_rad = Magnitude(Half(Minus(rocker_l, rocker_r)));
  b.max_bogie_rad = std::max(Magnitude(Minus(bogie_l, rocker_l)), Magnitude(Minus(bogie_r, rocker_r)));
  const LinearForm tan_roll = (left.rocker_pivot - right.rocker_pivot) * (1.0 / s.track_m);
  b.max_roll_rad = Magnitude(Atan(tan_roll.Over(centre)));
  // The belly: a plane through the rocker pivots' midpoint, pitched and rolled with the
  // body (first order in the angles); left (y < 0) rises with the roll.
  const LinearForm body_centre = (left.rocker_pivot + right.rocker_pivot) * 0.5;
  const LinearForm tan_pitch = (left.tan_rocker + right.tan_rocker) * 0.5;
  b.min_clearance_m = s.belly_height_m;
  for (const PoseTerrain::BellyPoint& p : t.belly) {
    LinearForm belly = body_centre + tan_pitch * (p.x - s.rocker_pivot_x_m) - tan_roll * p.y;
    belly.c0 += s.belly_height_m - s.rocker_pivot_height_m;
    b.min_clearance_m = std::min(b.min_clearance_m, belly.Over(centre).lo - p.ground_hi);
  }
  // Against the limits.
  auto add = [&b](const std::string& v) { b.violation += (b.violation.empty() ? "" : ", ") + v; };
  if (b.min_clearance_m < s.min_belly_clearance_m)
    add("belly clearance " + Fixed(b.min_clearance_m) + " m under " + Fixed(s.min_belly_clearance_m) + " m");
  if (b.max_rocker_rad > s.max_rocker_deg * kDeg)
    add("rocker " + Fixed(b.max_rocker_rad / kDeg, 1) + " deg over " + Fixed(s.max_rocker_deg, 1));
  if (b.max_bogie_rad > s.max_bogie_deg * kDeg)
    add("bogie " + Fixed(b.max_bogie_rad / kDeg, 1) + " deg over " + Fixed(s.max_bogie_deg, 1));
  if (std::max(b.max_roll_rad, b.max_pitch_rad) > s.max_tilt_deg * kDeg)
    add("tilt " + Fixed(std::max(b.max_roll_rad, b.max_pitch_rad) / kDeg, 1) + " deg over " + Fixed(s.max_tilt_deg, 1));
  b.margin = std::min({(b.min_clearance_m - s.min_belly_clearance_m) / (s.belly_height_m - s.min_belly_clearance_m),
                       1.0 - b.max_rocker_rad / (s.max_rocker_deg * kDeg), 1.0 - b.max_bogie_rad / (s.max_bogie_deg * kDeg),
                       1.0 - std::max(b.max_roll_rad, b.max_pitch_rad) / (s.max_tilt_deg * kDeg)});
  b.margin = b.violation.empty() ? std::clamp(b.margin, 0.0, 1.0) : 0.0;
  return b;
}

PathBounds EvaluatePath(const Suspension& s, const HeightMap& map, const std::vector<Pose>& path, const Excused* excused) {
  PathBounds out;
  out.min_clearance_m = s.belly_height_m;
  for (std::size_t n = 0; n < path.size(); ++n) {
    const Bounds b = Evaluate(s, SampleTerrain(s, map, path[n], excused));
    if (!b.Safe()) {
      out.first_unsafe_pose = static_cast<int>(n);
      out.first_unsafe = b;
      return out;
    }
    out.min_margin = std::min(out.min_margin, b.margin);
    out.min_clearance_m = std::min(out.min_clearance_m, b.min_clearance_m);
    out.max_rocker_rad = std::max(out.max_rocker_rad, b.max_rocker_rad);
    out.max_bogie_rad = std::max(out.max_bogie_rad, b.max_bogie_rad);
    out.max_roll_rad = std::max(out.max_roll_rad, b.max_roll_rad);
    out.max_pitch_rad = std::max(out.max_pitch_rad, b.max_pitch_rad);
  }
  return out;
}

}  // namespace rover::clearance
