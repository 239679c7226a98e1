// Splitting metric commands into steps, steering a goto, sampling a step's swept path, and
// measuring what a step achieved. Plane geometry in the site frame (X north, Y east, yaw
// clockwise from north); a step's motion is measured in 3-D (see MeasureStep).
#pragma once

#include "geometry/pose.hpp"

#include <Eigen/Core>

#include <string>
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
// Goto steering from the current pose, re-planned at every step (LANGUAGE.md, goto).
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

// The goal disc judged with the estimate's uncertainty: a goto ends when its estimate lies
// within radius_m of the target, the tolerance less sigmas x the horizontal position sigma,
// so that the truth lies in the tolerance disc with that confidence. When the margin leaves
// less than min_fraction of the tolerance, radius_m is min_fraction x tolerance and `fits`
// is false: the disc is smaller than the estimate can promise.
struct ArrivalDisc {
  double tolerance_m = 0.0;
  double radius_m = 0.0;
  double margin_m = 0.0;  // sigmas x sigma
  double sigmas = 0.0;
  bool fits = true;
  // "inside 0.30 m less 3 sigma 0.12 m" or the warning that the margin does not fit.
  std::string Describe() const;
};
ArrivalDisc ArrivalRadius(double tolerance_m, double sigma_m, double sigmas, double min_fraction);

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

// ---- Drift, for the predictive keep-out check ----
// What a VO-corrected arc step did that was not commanded, in the site plane, per metre of
// commanded length: the end position's error against the commanded end (downslope drift
// and slip), and the heading error. Also the error's share of the step, in %, across the
// commanded chord (sideways drift) and along it (slip: + = short of the commanded end).
struct StepDrift {
  Eigen::Vector2d error_per_m = Eigen::Vector2d::Zero();  // site x, y
  double yaw_error_per_m = 0.0;
  double cross_pct = 0.0;  // |sideways error| / |commanded| * 100
  double along_pct = 0.0;  // shortfall along the commanded chord / |commanded| * 100
};
// `step` must be an arc of non-zero length (otherwise the drift is zero).
StepDrift DriftOfStep(const PlanePose& before, const PlanePose& after, const PlannedStep& step);

// The drift expected over the next step of |distance_m| from the recent steps: the mean
// error per metre (the site-fixed part: downslope drift, steady slip) scaled to the step,
// and the spread, the largest deviation of one step's error from that mean, scaled alike.
struct DriftPrediction {
  Eigen::Vector2d shift = Eigen::Vector2d::Zero();  // end-of-step position error, site
  double yaw_shift = 0.0;                           // end-of-step heading error
  double spread_m = 0.0;
  bool Any() const { return shift.norm() > 1e-3 || std::abs(yaw_shift) > 1e-4; }
};
DriftPrediction PredictDrift(const std::vector<StepDrift>& recent, double distance_m);

// The commanded samples followed, when drift is predicted, by the same samples shifted by
// t * shift and turned by t * yaw_shift (t: the fraction of the path's length at the sample),
// from the end back to the start: the closed outline of every path between "no drift" and
// "the measured drift", so that a footprint swept along it covers both.
std::vector<PlanePose> PathWithDrift(const std::vector<PlanePose>& commanded,
                                     const DriftPrediction& drift);

// Position 1-sigma added by a step of |distance_m| whose odometry error grows by
// `growth_fraction` of the distance, on top of `sigma_m` (independent errors add in
// quadrature): sqrt(sigma^2 + (f d)^2) - sigma.
double StepSigmaGrowth(double sigma_m, double distance_m, double growth_fraction);

// The rover's tilt from level (rad): the angle between its down axis and the site's,
// from roll and pitch together.
double TiltAngle(const Eigen::Matrix3d& R_site_rover);

}  // namespace rover::sequence
