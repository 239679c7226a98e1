// `goto ... avoid on`: the executor's use of arc voting (common/avoidance) on the hazard
// monitor's traversability map, and the pair taken before a step the map cannot judge.
// MER drove this way under autonomous navigation: image, map, then drive one step.
#include "avoidance/arc_voting.hpp"
#include "sequence/executor.hpp"
#include "sequence/executor_internal.hpp"

#include <cmath>
#include <stdexcept>

namespace rover::sequence {

using internal::Fixed;

void SequenceExecutor::OnTraversabilityMap(const TraversabilityMap& map) {
  map_ = map;
  Advance();
}

SequenceExecutor::AvoidOutcome SequenceExecutor::AvoidStep(PlannedStep* step) {
  const PlanePose p = CurrentPlanePose();
  const double remaining = (goto_.target - Eigen::Vector2d(p.x, p.y)).norm();
  if (remaining <= goto_.tolerance_m) {
    detail_ = "goto reached the disc: " + Fixed(remaining) + " m from the target";
    return AvoidOutcome::kDone;
  }
  // 1. A pair where the rover stands. With VO on, NextStepOfCommand takes VO's baseline
  //    pair before the first step and VO takes one after every step; otherwise a science pair.
  if (pair_here_id_ < 0) {
    if (VoActive() && !vo_frame_valid_) {
      step->kind = PlannedStep::Kind::kTurn;  // placeholder: the baseline pair comes first
      step->turn_rad = 0.0;
      return AvoidOutcome::kStep;
    }
    StartCapture("science");
    science_frame_seen_ = false;
    EnterPhase(Phase::kImages);
    return AvoidOutcome::kWait;
  }
  // 2. The map that includes it (the monitor maps a pair before it answers anything after).
  if (!map_ || map_->last_frame_id < pair_here_id_) {
    if (PhaseAge() <= options_.map_wait_s) return AvoidOutcome::kWait;
    if (!map_) {
      AbortWith(abort_reason::kHazardUnknown, "no traversability map within " + Fixed(options_.map_wait_s) +
                                                  " s (is the hazard monitor's map on: hazards.map.enabled or --map on? is a camera running?)");
      return AvoidOutcome::kAborted;
    }
    step_note_ += "map without frame " + std::to_string(pair_here_id_) + "; ";
  }
  // 3. Vote.
  avoidance::VoteOptions o;
  o.footprint = map_->footprint;
  const double margin = options_.avoid_margin_m * (avoid_refused_ ? 3.0 : 1.0);
  o.footprint.length_m += 2.0 * margin;
  o.footprint.width_m += 2.0 * margin;
  o.num_arcs = options_.avoid_num_arcs;
  o.max_curvature_per_m = options_.avoid_max_curvature_per_m;
  o.lookahead_m = options_.avoid_lookahead_m;
  o.step_m = StepLength();
  o.max_turn_rad = MaxTurn();
  o.blind_margin_m = map_->blind_margin_m;
  o.unknown = map_->unknown;
  o.suspension = map_->suspension;
  o.backup_m = std::min(options_.avoid_backup_m, StepLength());
  o.previous_turn_rad = last_turn_rad_;
  // Near the goal (inside the look-ahead) with a clear line to it: steer straight at it as
  // a plain goto does, so that the vote's look-ahead, longer than the way left, cannot
  // carry the rover past the disc.
  if (remaining < o.lookahead_m) {
    const GotoDecision direct = SteerToward(p, goto_.target, goto_.tolerance_m, StepLength(), MaxTurn(),
                                            options_.goto_turn_threshold_deg * M_PI / 180.0);
    const avoidance::Pose2 here{p.x, p.y, p.yaw};
    const bool turn = direct.step.kind == PlannedStep::Kind::kTurn;
    const auto step_path = avoidance::SamplePath(here, turn ? direct.step.turn_rad : 0.0,
                                                 turn ? 0.0 : direct.step.distance_m, 0.0);
    const double bearing = std::atan2(goto_.target.y() - p.y, goto_.target.x() - p.x);
    const auto line = avoidance::SamplePath(here, geometry::WrapAngle(bearing - p.yaw), remaining, 0.0);
    const auto s =
        avoidance::SweepFootprint(map_->grid, o.footprint, step_path, here, o.blind_margin_m, o.unknown.hidden_patch_m);
    const auto l = avoidance::SweepFootprint(map_->grid, o.footprint, line, here, o.blind_margin_m);
    if (s.unsafe == 0 && avoidance::JudgeUnknown(s, o.unknown) == avoidance::UnknownVerdict::kAcceptable &&
        l.unsafe == 0) {
      *step = direct.step;
      detail_ = "avoid: the goal is in reach and the way to it clear: steering straight at it (" +
                Fixed(remaining) + " m to go)";
      return AvoidOutcome::kStep;
    }
  }
  avoidance::Choice choice;
  try {
    choice = avoidance::VoteArcs(map_->grid, {p.x, p.y, p.yaw}, goto_.target.x(), goto_.target.y(), o);
  } catch (const std::invalid_argument& e) {
    AbortWith(abort_reason::kHazardUnknown, std::string("arc voting cannot decide: ") + e.what());
    return AvoidOutcome::kAborted;
  }
  if (!choice.found) {
    AbortWith(abort_reason::kHazardMap, "hazard_map: " + choice.detail);
    return AvoidOutcome::kAborted;
  }
  const avoidance::Candidate& b = choice.best;
  if (b.kind == avoidance::Candidate::Kind::kTurn) {
    step->kind = PlannedStep::Kind::kTurn;
    step->turn_rad = b.turn_rad;
  } else {
    step->kind = PlannedStep::Kind::kArc;
    step->distance_m = b.distance_m;
    step->curvature_per_m = b.curvature_per_m;
  }
  std::string d = "avoid: ";
  d += avoidance::ToString(b.kind);
  d += ' ';
  if (b.kind == avoidance::Candidate::Kind::kTurn) {
    d += Fixed(b.turn_rad * 180.0 / M_PI);
    d += " deg";
    if (std::abs(b.planned_turn_rad - b.turn_rad) > 1e-6) d += " of " + Fixed(b.planned_turn_rad * 180.0 / M_PI);
  } else {
    d += Fixed(b.distance_m);
    d += " m k ";
    d += Fixed(b.curvature_per_m);
  }
  d += " (goodness ";
  d += Fixed(b.goodness);
  d += ", goal ";
  d += Fixed(b.goal);
  d += ", ";
  d += Fixed(remaining);
  d += " m to go)";
  detail_ = std::move(d);
  return AvoidOutcome::kStep;
}

bool SequenceExecutor::AvoidRefused(const HazardReply& reply) {
  if (!is_goto_ || !goto_.avoid || avoid_refused_) return false;
  avoid_refused_ = true;
  step_note_ += "the monitor refused the voted step (" + reply.detail + "): voting again with a wider margin; ";
  EnterPhase(Phase::kReady);
  return true;
}

bool SequenceExecutor::ImagesForMap(const HazardReply& reply) {
  if (reply.zone_name != abort_reason::kHazardMap || map_images_taken_) return false;
  map_images_taken_ = true;
  if (!is_goto_ && next_step_ > 0) --next_step_;  // the same step is asked again
  step_note_ += "map could not judge the step (" + reply.detail + "): a pair first; ";
  StartCapture("science");
  science_frame_seen_ = false;
  EnterPhase(Phase::kImages);
  return true;
}

}  // namespace rover::sequence
