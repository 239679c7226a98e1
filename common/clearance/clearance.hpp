// Conservative rocker-bogie clearance in the manner of Perseverance's ACE (Approximate
// Clearance Evaluation; Otsu et al., "Fast approximate clearance evaluation for rovers with
// articulated suspension systems", J. Field Robotics 2020): from the height map under the
// wheels at a pose, bounds on the belly's clearance, the suspension's angles and the body's
// tilt that hold whatever the true heights within the map's uncertainty are.
//
// The suspension (MER): on each side a rocker carries the front wheel at one end and the
// bogie's pivot at the other; the bogie carries the middle and rear wheels; the rockers
// turn on the body, and a differential makes the body's pitch the mean of the two
// rockers'. A wheel rests on the highest ground in its patch, its centre a wheel radius
// above it. Every height the body takes (the bogie and rocker pivots, each point of the
// belly) is then, to first order in the angles, a fixed linear combination of the six
// wheel heights, so its extremes over the wheels' height intervals lie at the corners the
// signs of its coefficients pick: the bounds are exact for the linear model and need no
// search over the corners (ACE bounds its kinematic chain the same way, joint by joint).
// Angles are taken through atan of those linear forms; the relative angles (rocker to body,
// bogie to rocker) are bounded by subtracting intervals, which can only widen them.
//
// Frames: the site plane x north, y east (yaw 0 north, + clockwise from above), heights up.
// The rover frame: x forward, y right. Flat ground gives the nominal belly clearance and
// every angle 0; a uniform slope gives the body that tilt and the suspension angles 0.
//
// Optimistic never: a cell the map does not know under a wheel, or under the belly, may
// hold a rock `unknown_rise_m` tall above the highest known ground there; a wheel patch
// with no known cell at all stands that high above, or that deep below, the heights the
// rest of the rover stands on; with nothing known under the rover, the pose is undecided. The one exception is the ground
// the rover stands on and the ring round it that the mast cameras cannot see from where
// it stands (an `Excused` region, the same rule as the footprint sweep's blind ring in
// common/avoidance/grid.hpp): an unknown cell there adds no rock, and a wheel whose patch
// holds nothing else rests within the heights the other wheels rest on. And the ground
// under the rover where it stands is not held against the belly: the rover is on it (as
// the sweep leaves those cells out), so a false height there cannot pin it in place.
//
// Knows nothing of LCM or of how the map was made.
#pragma once

#include "config/yaml_config.hpp"

#include <array>
#include <string>
#include <vector>

namespace rover::clearance {

// The suspension's geometry on flat ground (rover frame: x forward from the rover origin,
// heights up from the ground the wheels stand on) and the limits it must stay within.
struct Suspension {
  bool enabled = true;               // false: the section is read and checked but not used
  double wheel_radius_m = 0.125;
  double wheel_patch_m = 0.2;        // side of the square under a wheel whose highest point carries it
  double track_m = 1.0;              // left wheel centres to right
  double front_wheel_x_m = 0.55;
  double middle_wheel_x_m = 0.0;
  double rear_wheel_x_m = -0.55;
  double bogie_pivot_x_m = -0.275;   // between the middle and rear wheels
  double rocker_pivot_x_m = 0.1;     // between the bogie pivot and the front wheel
  // Above the ground. To first order in the angles only the rocker pivot's height matters
  // (the body hangs from it); the bogie pivot's height moves nothing but its own.
  double rocker_pivot_height_m = 0.45;
  double belly_height_m = 0.30;      // nominal clearance under the belly
  double belly_min_x_m = -0.5;       // the belly: a rectangle in the rover frame
  double belly_max_x_m = 0.5;
  double belly_width_m = 0.7;        // between the wheels
  // Limits.
  double min_belly_clearance_m = 0.10;
  double max_rocker_deg = 20.0;      // rocker against the body
  double max_bogie_deg = 30.0;       // bogie against its rocker
  double max_tilt_deg = 30.0;        // roll and pitch against the vertical
  // Uncertainty: heights are taken as the map's height +- this many of its sigmas.
  double sigma_multiplier = 2.0;
  // The rock an unknown cell may hide: this tall above the highest known ground round it,
  // at most; and no taller than the unknown ground it lies in is narrow over
  // rock_width_per_height (rocks are about this many times as wide as tall: 2.5 for
  // MER-like rocks, so a speck of unknown between known cells hides no rock over the step
  // limit). 0: every unknown cell may hide unknown_rise_m.
  double unknown_rise_m = 0.25;
  double rock_width_per_height = 0.0;

  // "" when consistent; otherwise "<key>: expected ..." for the first key that is not.
  std::string Problem() const;
};

// Reads the `clearance:` section (key names = field names; absent keys keep the defaults,
// unknown keys are errors). Throws config::ConfigError "<where>: <key>: expected ...".
Suspension LoadSuspension(const config::ConfigNode& node);

// A height map: cell (i, j) covers x in [origin_x + i*cell_m, +cell_m), y in
// [origin_y + j*cell_m, +cell_m); row-major, index i*cols + j. A view: the arrays belong to
// the caller. sigma_m[k] < 0: the map holds no height for the cell.
struct HeightMap {
  double origin_x = 0.0, origin_y = 0.0, cell_m = 0.2;
  int rows = 0, cols = 0;
  const float* elevation_m = nullptr;
  const float* sigma_m = nullptr;
  // Optional: the rock each unknown cell may hide (HiddenRockHeights); nullptr: the
  // suspension's unknown_rise_m everywhere.
  const float* hidden_rock_m = nullptr;
};

// The tallest rock each unknown cell of `map` could hide: unknown_rise_m, or less where the
// unknown ground holding it (its 8-connected patch of unknown cells; off the map counts as
// unknown) is narrower than unknown_rise_m x rock_width_per_height: that patch's narrower
// side over rock_width_per_height. 0 for known cells.
std::vector<float> HiddenRockHeights(const Suspension& s, const HeightMap& map);

struct Pose {
  double x = 0.0, y = 0.0, yaw = 0.0;
};

// Ground whose unknown cells add no rock: the rectangle `length_m` x `width_m` whose centre
// lies `center_forward_m` ahead of `standing`, grown by `margin_m` (the rover's footprint
// where it stands, and the ring round it the mast cannot see).
struct Excused {
  Pose standing;
  double length_m = 0.0, width_m = 0.0, center_forward_m = 0.0, margin_m = 0.0;
  // Whether (x, y) lies in the rectangle grown by `grow_m`.
  bool Contains(double x, double y, double grow_m) const;
  bool Contains(double x, double y) const { return Contains(x, y, margin_m); }
};

// Wheels: left front, middle, rear, then right front, middle, rear.
enum Wheel { kLeftFront, kLeftMiddle, kLeftRear, kRightFront, kRightMiddle, kRightRear, kNumWheels };

struct Interval {
  double lo = 0.0, hi = 0.0;
};

// The map's heights at one pose: what ACE needs of the terrain.
struct PoseTerrain {
  bool decided = true;          // false: a wheel's patch holds no known cell, nor does the rest
  std::string undecided_why;    // which wheel
  // The ground each wheel rests on (the highest in its patch): [lowest it can be, highest].
  std::array<Interval, kNumWheels> wheel_ground;
  // The highest the ground can be under each belly cell, at its centre in the rover frame.
  struct BellyPoint {
    double x = 0.0, y = 0.0, ground_hi = 0.0;
  };
  std::vector<BellyPoint> belly;
};

// What ACE bounds at one pose. Angles in rad; the worst (largest magnitude) either side.
struct Bounds {
  bool decided = true;
  std::string undecided_why;
  double min_clearance_m = 0.0;  // the least clearance under the belly it can have
  double max_rocker_rad = 0.0;   // |rocker - body|
  double max_bogie_rad = 0.0;    // |bogie - rocker|
  double max_roll_rad = 0.0;
  double max_pitch_rad = 0.0;
  // "" when within every limit (and decided); else what is not, e.g.
  // "belly clearance 0.04 m under 0.10 m".
  std::string violation;
  bool Safe() const { return decided && violation.empty(); }
  // 1 at nominal, 0 at a limit: the smallest margin left of any bound (0 when not safe).
  double margin = 1.0;
};

// The terrain under the wheels and the belly at `pose` (nullptr `excused`: none).
PoseTerrain SampleTerrain(const Suspension& s, const HeightMap& map, const Pose& pose, const Excused* excused);
// ACE's bounds from that terrain.
Bounds Evaluate(const Suspension& s, const PoseTerrain& terrain);

// A path judged pose by pose.
struct PathBounds {
  int first_unsafe_pose = -1;  // -1: every pose safe
  Bounds first_unsafe;         // its bounds
  double min_margin = 1.0;     // over the poses before it
  double min_clearance_m = 0.0;
  double max_rocker_rad = 0.0, max_bogie_rad = 0.0, max_roll_rad = 0.0, max_pitch_rad = 0.0;  // same
};
PathBounds EvaluatePath(const Suspension& s, const HeightMap& map, const std::vector<Pose>& path,
                        const Excused* excused);

}  // namespace rover::clearance
