#include "sequence/stepping.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>

namespace rover::sequence {

namespace {

int StepsFor(double amount, double max_per_step) {
  // The tolerance keeps 1.2 m at 0.6 m steps to two steps despite rounding.
  return std::max(1, static_cast<int>(std::ceil(std::abs(amount) / max_per_step - 1e-9)));
}

// Rover-frame chord of an arc step from the origin, heading 0.
Eigen::Vector2d Chord(double s, double k) {
  if (std::abs(k * s) < 1e-9) return {s, 0.5 * k * s * s};
  return {std::sin(k * s) / k, (1.0 - std::cos(k * s)) / k};
}

}  // namespace

std::vector<PlannedStep> SplitArc(double distance_m, double curvature_per_m, double step_m,
                                  double max_turn_rad) {
  if (!(step_m > 0.0) || !(max_turn_rad > 0.0) || !std::isfinite(distance_m) ||
      !std::isfinite(curvature_per_m)) {
    throw std::invalid_argument("SplitArc: step_m " + std::to_string(step_m) + " and max_turn_rad " +
                                std::to_string(max_turn_rad) + " must be > 0, distance finite");
  }
  if (distance_m == 0.0) return {};
  const int n = std::max(StepsFor(distance_m, step_m),
                         StepsFor(distance_m * curvature_per_m, max_turn_rad));
  PlannedStep s;
  s.kind = PlannedStep::Kind::kArc;
  s.distance_m = distance_m / n;
  s.curvature_per_m = curvature_per_m;
  return std::vector<PlannedStep>(n, s);
}

std::vector<PlannedStep> SplitTurn(double turn_rad, double max_turn_rad) {
  if (!(max_turn_rad > 0.0) || !std::isfinite(turn_rad)) {
    throw std::invalid_argument("SplitTurn: max_turn_rad " + std::to_string(max_turn_rad) +
                                " must be > 0, turn finite");
  }
  if (turn_rad == 0.0) return {};
  const int n = StepsFor(turn_rad, max_turn_rad);
  PlannedStep s;
  s.kind = PlannedStep::Kind::kTurn;
  s.turn_rad = turn_rad / n;
  return std::vector<PlannedStep>(n, s);
}

double ShortestTurn(double yaw, double heading) { return geometry::WrapAngle(heading - yaw); }

PlanePose EndOfStep(const PlanePose& start, const PlannedStep& step) {
  PlanePose end = start;
  if (step.kind == PlannedStep::Kind::kTurn) {
    end.yaw = geometry::WrapAngle(start.yaw + step.turn_rad);
    return end;
  }
  const Eigen::Vector2d c = Chord(step.distance_m, step.curvature_per_m);
  const double cy = std::cos(start.yaw), sy = std::sin(start.yaw);
  // Rover X forward, Y right; site X north, Y east; yaw clockwise from north.
  end.x = start.x + cy * c.x() - sy * c.y();
  end.y = start.y + sy * c.x() + cy * c.y();
  end.yaw = geometry::WrapAngle(start.yaw + step.HeadingChange());
  return end;
}

GotoDecision SteerToward(const PlanePose& pose, const Eigen::Vector2d& target, double tolerance_m,
                         double step_m, double max_turn_rad, double turn_threshold_rad) {
  GotoDecision d;
  const Eigen::Vector2d to_goal = target - Eigen::Vector2d(pose.x, pose.y);
  d.remaining_m = to_goal.norm();
  if (d.remaining_m <= tolerance_m) {
    d.arrived = true;
    return d;
  }
  d.bearing_error_rad = ShortestTurn(pose.yaw, std::atan2(to_goal.y(), to_goal.x()));
  if (std::abs(d.bearing_error_rad) > turn_threshold_rad) {
    d.step.kind = PlannedStep::Kind::kTurn;
    d.step.turn_rad = std::clamp(d.bearing_error_rad, -max_turn_rad, max_turn_rad);
  } else {
    d.step.kind = PlannedStep::Kind::kArc;
    d.step.distance_m = std::min(step_m, d.remaining_m);
  }
  return d;
}

ArrivalDisc ArrivalRadius(double tolerance_m, double sigma_m, double sigmas, double min_fraction) {
  ArrivalDisc d;
  d.tolerance_m = tolerance_m;
  d.sigmas = sigmas;
  d.margin_m = std::isfinite(sigma_m) ? sigmas * std::max(0.0, sigma_m) : std::numeric_limits<double>::infinity();
  d.radius_m = tolerance_m - d.margin_m;
  if (!(d.radius_m >= min_fraction * tolerance_m)) {
    d.radius_m = min_fraction * tolerance_m;
    d.fits = false;
  }
  return d;
}

std::string ArrivalDisc::Describe() const {
  char buf[256];
  if (fits) {
    std::snprintf(buf, sizeof buf, "inside the %.2f m disc less %g sigma (%.2f m)", tolerance_m, sigmas, margin_m);
  } else {
    std::snprintf(buf, sizeof buf,
                  "the estimate's %g sigma (%.2f m) does not fit in the %.2f m disc: stopped within %.2f m of the "
                  "target by the estimate; the truth may lie outside the disc",
                  sigmas, margin_m, tolerance_m, radius_m);
  }
  return buf;
}

StepMotion MeasureStep(const geometry::Pose& T_site_before, const geometry::Pose& T_site_after,
                       const PlannedStep& step) {
  StepMotion m;
  const double yaw_before = geometry::RpyFromRotation(T_site_before.linear()).z();
  const double yaw_after = geometry::RpyFromRotation(T_site_after.linear()).z();
  m.estimated_turn_rad = geometry::WrapAngle(yaw_after - yaw_before);
  if (step.kind == PlannedStep::Kind::kTurn) {
    m.progress_fraction = step.turn_rad != 0.0 ? m.estimated_turn_rad / step.turn_rad : 1.0;
  } else {
    const Eigen::Vector3d d_rover =
        T_site_before.linear().transpose() * (T_site_after.translation() - T_site_before.translation());
    const Eigen::Vector2d c = Chord(step.distance_m, step.curvature_per_m);
    const double c2 = c.squaredNorm();
    m.estimated_distance_m = c2 > 0.0 ? d_rover.head<2>().dot(c) / c2 * step.distance_m : 0.0;
    m.progress_fraction = step.distance_m != 0.0 ? m.estimated_distance_m / step.distance_m : 1.0;
  }
  m.slip_pct = 100.0 * (1.0 - m.progress_fraction);
  return m;
}

StepDrift DriftOfStep(const PlanePose& before, const PlanePose& after, const PlannedStep& step) {
  StepDrift d;
  const double length = std::abs(step.distance_m);
  if (step.kind != PlannedStep::Kind::kArc || length <= 0.0) return d;
  const PlanePose commanded = EndOfStep(before, step);
  const Eigen::Vector2d error(after.x - commanded.x, after.y - commanded.y);
  d.error_per_m = error / length;
  d.yaw_error_per_m = geometry::WrapAngle(after.yaw - commanded.yaw) / length;
  const Eigen::Vector2d chord(commanded.x - before.x, commanded.y - before.y);
  if (chord.norm() > 0.0) {
    const Eigen::Vector2d u = chord.normalized();
    d.along_pct = -100.0 * error.dot(u) / length;
    d.cross_pct = 100.0 * std::abs(u.x() * error.y() - u.y() * error.x()) / length;
  }
  return d;
}

DriftPrediction PredictDrift(const std::vector<StepDrift>& recent, double distance_m) {
  DriftPrediction p;
  if (recent.empty()) return p;
  const double length = std::abs(distance_m);
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  double mean_yaw = 0.0;
  for (const StepDrift& d : recent) {
    mean += d.error_per_m;
    mean_yaw += d.yaw_error_per_m;
  }
  mean /= static_cast<double>(recent.size());
  mean_yaw /= static_cast<double>(recent.size());
  double spread = 0.0;
  for (const StepDrift& d : recent) spread = std::max(spread, (d.error_per_m - mean).norm());
  p.shift = mean * length;
  p.yaw_shift = mean_yaw * length;
  p.spread_m = spread * length;
  return p;
}

std::vector<PlanePose> PathWithDrift(const std::vector<PlanePose>& commanded,
                                     const DriftPrediction& drift) {
  std::vector<PlanePose> path = commanded;
  if (commanded.size() < 2 || !drift.Any()) return path;
  std::vector<double> along(commanded.size(), 0.0);
  for (std::size_t i = 1; i < commanded.size(); ++i) {
    along[i] = along[i - 1] + std::hypot(commanded[i].x - commanded[i - 1].x,
                                         commanded[i].y - commanded[i - 1].y);
  }
  const double total = along.back();
  for (std::size_t k = commanded.size(); k-- > 0;) {
    // A turn in place has no length: its samples share the start, so t follows the index.
    const double t = total > 0.0 ? along[k] / total
                                 : static_cast<double>(k) / static_cast<double>(commanded.size() - 1);
    PlanePose p = commanded[k];
    p.x += t * drift.shift.x();
    p.y += t * drift.shift.y();
    p.yaw = geometry::WrapAngle(p.yaw + t * drift.yaw_shift);
    path.push_back(p);
  }
  return path;
}

double StepSigmaGrowth(double sigma_m, double distance_m, double growth_fraction) {
  const double added = growth_fraction * std::abs(distance_m);
  return std::sqrt(sigma_m * sigma_m + added * added) - sigma_m;
}

double TiltAngle(const Eigen::Matrix3d& R_site_rover) {
  // Column 2 is the rover's down axis in the site frame; its z is cos(tilt).
  return std::acos(std::clamp(R_site_rover(2, 2), -1.0, 1.0));
}

}  // namespace rover::sequence
