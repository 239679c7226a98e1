// Thinking while driving (ExecutorOptions::think_while_driving), after Perseverance's ENav:
// the rover need not stand still while the pair it took here is mapped, when the map in
// hand already knows the ground of its next step.
//
// After each step the rover stands for its VO pair, as MER's did. VO answers sooner than
// the map (the compute profile charges a pair's dense stereo more than VO), so without
// this the rover waits out the rest of the mapping. With it, the vote is taken on the map
// of the pair before (with the pose VO has just corrected), and its choice is driven at
// once when it is a forward arc, gentle enough not to swing the body round, whose footprint
// (the vote's, with its margin) sweeps only cells that map knows and rates safe: no unknown
// cell, no caution cell and no unsafe one, blind ring or not. The hazard monitor judges
// that step on the same map (hazard_query_t.map_frame_id) and may still refuse it. The new
// pair is mapped while the rover drives, and the next step is chosen on it. Should that map
// come while the step is still driven and rate ground on its way unsafe, the rover stops
// (CheckStepChosenAhead).
//
// Anything else (a backup, a turn, a tight arc, a way the loop breaker or the planner
// would change, a step into ground not yet known safe, a refusal) is declined: what the
// vote changed (the planner's refusals and blocks, the vote history) is put back, and the
// rover waits for the new map and votes on it exactly as it would with this off. So the
// rover stops to think only where it must: near obstacles and unseen ground.
#include "sequence/executor.hpp"
#include "sequence/executor_internal.hpp"

#include <cmath>

namespace rover::sequence {

SequenceExecutor::AvoidState SequenceExecutor::SaveAvoidState() const {
  return {refused_ways_, blocked_ways_, avoid_history_, unreachable_plans_};
}

void SequenceExecutor::RestoreAvoidState(const AvoidState& state) {
  refused_ways_ = state.refused_ways;
  blocked_ways_ = state.blocked_ways;
  avoid_history_ = state.history;
  unreachable_plans_ = state.unreachable_plans;
}

bool SequenceExecutor::ThinkAhead(const PlanePose& pose, double remaining_m, const ArrivalDisc& disc,
                                  PlannedStep* step) {
  thought_ahead_ = false;
  // Only on an earlier pair's map of this site, and only where nothing about this stop has
  // already asked for the new map: a refusal, a look aside, a pair for the map.
  if (!options_.think_while_driving || ahead_declined_ || !map_ || map_->last_frame_id <= 0 ||
      pose_->site_index != map_site_ || avoid_refused_ || looked_here_ != 0 || map_images_taken_)
    return false;
  AvoidState saved = SaveAvoidState();
  thinking_ahead_ = true;
  const AvoidOutcome outcome = VoteOnMap(pose, remaining_m, disc, step);
  thinking_ahead_ = false;
  if (outcome != AvoidOutcome::kStep) {
    RestoreAvoidState(saved);
    ahead_declined_ = true;
    return false;
  }
  thought_ahead_ = true;
  ahead_saved_ = std::move(saved);
  ahead_map_frame_ = map_->last_frame_id;
  ahead_start_ = {pose.x, pose.y, pose.yaw};
  detail_ += " [thought ahead: on the map of pair " + std::to_string(ahead_map_frame_) + " while pair " +
             std::to_string(pair_here_id_) + " is mapped]";
  return true;
}

bool SequenceExecutor::KnownSafeAhead(const avoidance::Grid& grid, const avoidance::Footprint& footprint,
                                      const avoidance::Pose2& here, const PlannedStep& step) const {
  if (step.kind != PlannedStep::Kind::kArc || !(step.distance_m > 0.0)) return false;
  // Caution is not known safe here: such cells count as unknown, which must be none.
  avoidance::Grid known_safe = grid;
  for (auto& cell : known_safe.state)
    if (cell == avoidance::CellClass::kCaution) cell = avoidance::CellClass::kUnknown;
  const auto path = avoidance::SamplePath(here, 0.0, step.distance_m, step.curvature_per_m);
  const auto s = avoidance::SweepFootprint(known_safe, footprint, path, here, /*blind_margin_m=*/0.0);
  const bool drivable = map_->max_driven_step_m <= 0.0 || s.max_step_m < map_->max_driven_step_m;
  return s.cells > 0 && s.unsafe == 0 && s.unknown == 0 && s.blind_unknown == 0 && s.outside == 0 && drivable;
}

bool SequenceExecutor::AheadRefused(const HazardReply& reply) {
  if (!thought_ahead_) return false;
  thought_ahead_ = false;
  if (ahead_saved_) RestoreAvoidState(*ahead_saved_);
  ahead_saved_.reset();
  ahead_declined_ = true;
  ahead_note_ = "the step chosen ahead on the map of pair " + std::to_string(ahead_map_frame_) +
                " was refused there (" + reply.detail + "): chosen again on the new map; ";
  EnterPhase(Phase::kReady);
  return true;
}

// The step is committed, as ENav's are, on ground its map knew safe; the map of the pair
// taken where it began reads that ground from nearer. Should it rate any of the step's way
// unsafe, the rover stops rather than finish the step onto it.
void SequenceExecutor::CheckStepChosenAhead() {
  if (step_.kind != PlannedStep::Kind::kArc || !map_) return;
  const auto path = avoidance::SamplePath(ahead_start_, 0.0, step_.distance_m, step_.curvature_per_m);
  const auto s = avoidance::SweepFootprint(map_->grid, map_->footprint, path, ahead_start_, map_->blind_margin_m);
  if (s.unsafe == 0) return;
  AbortWith(abort_reason::kHazardMap,
            "hazard_map: the map of pair " + std::to_string(map_->last_frame_id) +
                ", which came while the step chosen ahead on the map of pair " + std::to_string(ahead_map_frame_) +
                " was driven, rates its way unsafe (step " + internal::Fixed(s.worst_step_m) + " m at " +
                internal::Fixed(s.worst_x) + "," + internal::Fixed(s.worst_y) + "); stopped");
}

}  // namespace rover::sequence
