// Splitting metric commands into steps, steering a goto, sampling a step's swept path, and
// measuring what a step achieved. Plane geometry in the site frame (X north, Y east, yaw
// clockwise from north); a step's motion is measured in 3-D (see MeasureStep).
#pragma once

#include "geometry/pose.hpp"

#include <Eigen/Core>

#include <vector>

namespace rover::sequence {

// One mobility motion: an arc (curvature 0 = straight) or a turn in place.
struct PlannedStep {
  enum class Kind { kArc, kTurn };
  Kind kind = Kind::kArc;
  double distance_m = 0.0;       // arc: signed arc length
  double curvature_per_m = 0.0;  // arc: + curves right
  double turn_rad = 0.0;         // turn: + clockwise
  // Heading change of this step (arc: curvature * distance; turn: turn_rad).
  double HeadingChange() const { return kind == Kind::kTurn ? turn_rad : curvature_per_m * distance_m; }
};

// Splits a drive or arc into the fewest equal steps with |length| <= step_m and
// |heading change| <= max_turn_rad (2.34 m at 0.6 m -> 4 steps of 0.585 m).
std::vector<PlannedStep> SplitArc(double distance_m, double curvature_per_m, double step_m,
                                  double max_turn_rad);
// Splits a turn in place into the fewest equal steps with |turn| <= max_turn_rad.
std::vector<PlannedStep> SplitTurn(double turn_rad, double max_turn_rad);
// The signed turn from `yaw` to `heading`, the shortest way, in (-pi, pi].
double ShortestTurn(double yaw, double heading);

// A plane pose in the site frame.
struct PlanePose {
  double x = 0.0, y = 0.0, yaw = 0.0;
};
// Where a step ends from `start`, on flat ground.
PlanePose EndOfStep(const PlanePose& start, const PlannedStep& step);
// Goto steering from the current pose, re-planned at every step (OPERATIONS.md step 5).
struct GotoDecision {
  bool arrived = false;        // inside the tolerance disc: the goto is done
  double remaining_m = 0.0;    // to the target
  double bearing_error_rad = 0.0;
  PlannedStep step;            // the next step when !arrived
};
// Turns toward the target when the bearing error exceeds `turn_threshold_rad` (one step of
// at most `max_turn_rad`), otherwise drives straight min(step_m, remaining).
GotoDecision SteerToward(const PlanePose& pose, const Eigen::Vector2d& target, double tolerance_m,
                         double step_m, double max_turn_rad, double turn_threshold_rad);

// What a step achieved, from the (VO-corrected) poses before and after it.
struct StepMotion {
  double estimated_distance_m = 0.0;  // arc steps: progress along the commanded chord, scaled
                                      // to arc length, with the commanded sign
  double estimated_turn_rad = 0.0;    // yaw change
  double progress_fraction = 0.0;     // estimated / commanded (distance for arcs, turn for turns)
  double slip_pct = 0.0;              // 100 * (1 - progress_fraction)
};
// The displacement is taken in the rover frame at the start (3-D), so that driving up a
// slope is not mistaken for slip: the commanded distance is along the ground.
StepMotion MeasureStep(const geometry::Pose& T_site_before, const geometry::Pose& T_site_after,
                       const PlannedStep& step);

}  // namespace rover::sequence
