// `goto ... avoid on`: the executor's use of arc voting (common/avoidance) on the hazard
// monitor's traversability map, following the global planner's cost-to-go over the site
// map the executor accumulates from every map (common/planner), and the pair taken before a
// step the map cannot judge. MER drove this way under autonomous navigation: image, map,
// then drive one step, GESTALT's vote guided by Field D*'s global costs.
#include "avoidance/arc_voting.hpp"
#include "avoidance/look_aside.hpp"
#include "avoidance/loop_breaker.hpp"
#include "avoidance/tops_over_ground.hpp"
#include "hazards/hazard_assessor.hpp"
#include "planner/global_planner.hpp"
#include "sequence/executor.hpp"
#include "sequence/executor_internal.hpp"

#include <cmath>
#include <stdexcept>

namespace rover::sequence {

using internal::Fixed;

namespace {

// Keep-out zones as the executor holds them, for the planner.
std::vector<hazards::KeepOutZone> HazardZones(const std::vector<KeepOutZone>& zones) {
  std::vector<hazards::KeepOutZone> out;
  for (const KeepOutZone& z : zones) {
    hazards::KeepOutZone h;
    h.name = z.name;
    h.shape = z.shape == KeepOutZone::Shape::kCircle ? hazards::KeepOutZone::Shape::kCircle
                                                     : hazards::KeepOutZone::Shape::kPolygon;
    h.center = z.center;
    h.radius_m = z.radius_m;
    h.vertices = z.vertices;
    out.push_back(std::move(h));
  }
  return out;
}

// A footprint grown by `from_margin_m` all round, grown by `to_margin_m` instead.
avoidance::Footprint Narrowed(avoidance::Footprint f, double from_margin_m, double to_margin_m) {
  f.length_m -= 2.0 * (from_margin_m - to_margin_m);
  f.width_m -= 2.0 * (from_margin_m - to_margin_m);
  return f;
}

// The vote's options with the footprint's margin narrowed from o's to `margin_m`.
avoidance::VoteOptions Narrowed(const avoidance::VoteOptions& o, double margin_m) {
  avoidance::VoteOptions n = o;
  n.footprint = Narrowed(o.footprint, o.footprint_margin_m, margin_m);
  n.footprint_margin_m = margin_m;
  return n;
}

}  // namespace

void SequenceExecutor::OnTraversabilityMap(const TraversabilityMap& map) {
  map_ = map;
  // The monitor starts its map again in a new site frame; so does the site map.
  const int site = pose_ ? pose_->site_index : 0;
  if (site != map_site_) {
    site_map_.Clear();
    refused_ways_.Reset();
    map_site_ = site;
  }
  try {
    if (options_.avoid_top_rise_m > 0.0 && options_.avoid_top_rise_in_plan)
      site_map_.Merge(PlannedGrid(map.grid));
    else
      site_map_.Merge(map.grid);  // no copy of each map when the plan keeps the map's rating
  } catch (const std::invalid_argument& e) {
    step_note_ += std::string("map not merged (") + e.what() + "); ";
  }
  if (phase_ == Phase::kMoving && thought_ahead_ && map.last_frame_id > ahead_map_frame_) CheckStepChosenAhead();
  Advance();
}

// The monitor's map as the plan counts it with avoid_top_rise_in_plan: the cells whose
// tops stand over their ground (avoid_top_rise_m) are unsafe there as they are to the vote.
avoidance::Grid SequenceExecutor::PlannedGrid(avoidance::Grid grid) const {
  avoidance::MarkTopsOverGround(&grid, options_.avoid_top_ground_radius_m, options_.avoid_top_rise_m);
  return grid;
}

// Where the rover has been: the ground under its body carried it (site_map.hpp).
void SequenceExecutor::MarkDriven() {
  if (!pose_ || !map_ || !PoseFinite() || pose_->site_index != map_site_) return;
  const PlanePose p = CurrentPlanePose();
  site_map_.MarkDriven({p.x, p.y, p.yaw}, map_->footprint);
}

ArrivalDisc SequenceExecutor::GotoArrival() const {
  const double sigma = pose_ ? hazards::HorizontalSigma(pose_->covariance) : 0.0;
  return ArrivalRadius(goto_.tolerance_m, sigma, options_.goto_arrival_sigmas, options_.goto_min_arrival_fraction);
}

SequenceExecutor::AvoidOutcome SequenceExecutor::AvoidStep(PlannedStep* step) {
  const PlanePose p = CurrentPlanePose();
  const double remaining = (goto_.target - Eigen::Vector2d(p.x, p.y)).norm();
  const ArrivalDisc disc = GotoArrival();
  if (remaining <= disc.radius_m) {
    detail_ = arrival_note_ =
        "goto reached the disc: " + Fixed(remaining) + " m from the target by the estimate, " + disc.Describe();
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
  // 2. The map that includes it (the monitor maps a pair before it answers anything after),
  //    unless a forward step known safe on the map in hand can be driven while it is mapped.
  if (!map_ || map_->last_frame_id < pair_here_id_) {
    if (ThinkAhead(p, remaining, disc, step)) return AvoidOutcome::kStep;
    if (PhaseAge() <= options_.map_wait_s) return AvoidOutcome::kWait;
    if (!map_) {
      AbortWith(abort_reason::kHazardUnknown, "no traversability map within " + Fixed(options_.map_wait_s) +
                                                  " s (is the hazard monitor's map on: hazards.map.enabled or --map on? is a camera running?)");
      return AvoidOutcome::kAborted;
    }
    step_note_ += "map without frame " + std::to_string(pair_here_id_) + "; ";
  }
  return VoteOnMap(p, remaining, disc, step);
}

// 3. The vote on map_, following the global plan. While thinking ahead (think_ahead.cpp)
//    it only chooses: anything but a forward arc is kDeclined, and nothing is aborted,
//    looked at or refused.
SequenceExecutor::AvoidOutcome SequenceExecutor::VoteOnMap(const PlanePose& p, double remaining,
                                                           const ArrivalDisc& disc, PlannedStep* step) {
  avoid_note_.clear();
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
  const bool strict = options_.avoid_unseen_ground_strict;
  o.blind_margin_m = strict ? 0.0 : map_->blind_margin_m;
  o.unknown = map_->unknown;
  o.max_driven_step_m = map_->max_driven_step_m;
  o.good_enough = options_.avoid_good_enough > 0.0   ? options_.avoid_good_enough
                  : map_->caution_goodness > 0.0 ? map_->caution_goodness
                                                 : 1.0;
  // Strict: ground that could hide a rock is not swept at all, not even by a corner.
  o.unknown.hidden_at_any_share = strict;
  // And not swept near either: a known cell beside it may hold a hidden rock's rim.
  o.unknown.hidden_reach_m = strict ? options_.avoid_hidden_reach_m : 0.0;
  o.suspension = map_->suspension;
  o.backup_m = std::min(options_.avoid_backup_m, StepLength());
  o.previous_turn_rad = last_turn_rad_;
  o.previous_arc_m = arcs_to_retrace_.Last().length_m;
  o.previous_arc_curvature_per_m = arcs_to_retrace_.Last().curvature_per_m;
  o.footprint_margin_m = margin;
  // Keep-out zones are obstacles: their cells, grown by the position uncertainty as the
  // hazard monitor grows them (and a cell, since a cell counts when its centre is under the
  // footprint grown by half a cell), are unsafe to the vote.
  const double zone_grow = options_.avoid_zone_sigma_multiplier * hazards::HorizontalSigma(pose_->covariance);
  avoidance::Grid grid = map_->grid;
  // Ground known without the cameras: what the rover has driven over, and the ring round
  // where the goto began (avoid_start_ring_known).
  site_map_.MarkDrivenOn(&grid);
  // A rock rated unsafe before and caution now stays unsafe (avoid_keep_unsafe).
  if (const int kept = site_map_.KeepUnsafeOn(&grid); kept > 0)
    avoid_note_ += std::to_string(kept) + " cells rated unsafe before and caution now kept unsafe; ";
  if (strict && options_.avoid_start_ring_known && goto_start_pose_) {
    grid.MarkKnown(map_->footprint, *goto_start_pose_, map_->blind_margin_m);
    // And the rover can turn round where it began: the ground a whole turn in place of the
    // vote's footprint sweeps there.
    grid.MarkTurnKnown(o.footprint, *goto_start_pose_);
  }
  // A rock's flank round its unseen top reads far low: unsafe until that ground is seen.
  if (options_.avoid_hidden_flank_step_m > 0.0)
    grid.MarkFlanksOfHiddenGround(map_->unknown.hidden_patch_m, options_.avoid_hidden_flank_step_m);
  // A rock whose cells read a step under the limit while their tops stand over it.
  if (options_.avoid_top_rise_m > 0.0) {
    if (const int tops = avoidance::MarkTopsOverGround(&grid, options_.avoid_top_ground_radius_m,
                                                       options_.avoid_top_rise_m); tops > 0)
      avoid_note_ += std::to_string(tops) + " cells whose tops stand " + Fixed(options_.avoid_top_rise_m) +
                     " m or more over the ground round them unsafe; ";
  }
  if (!zones_.empty()) {
    const auto cells = planner::ZoneCells(grid, HazardZones(zones_), zone_grow + grid.cell_m);
    for (std::size_t k = 0; k < cells.size(); ++k)
      if (cells[k]) grid.state[k] = avoidance::CellClass::kUnsafe, grid.goodness[k] = 0.0f;
  }
  // The global plan from here, over everything seen so far, and round the ways refused.
  const avoidance::Pose2 here{p.x, p.y, p.yaw};
  // (After a look aside the rover stands where it voted before: that vote said so already.)
  const bool going_round = looked_here_ == 0 && avoidance::BackWhereItWas(avoid_history_, here);
  std::optional<planner::GlobalPlan> plan;
  const double vote_margin_m = o.footprint_margin_m;
  if (options_.planner_enabled) {
    switch (PlanAhead(p, disc, &o.footprint, &o.footprint_margin_m, zone_grow, going_round, &plan)) {
      case PlanVerdict::kFollow: break;
      case PlanVerdict::kAborted: return AvoidOutcome::kAborted;
      case PlanVerdict::kDeclined: return AvoidOutcome::kDeclined;
    }
    if (plan) {
      o.goal_distance = &*plan;
      o.way_heading_rad = plan->WayHeading(o.lookahead_m);
    }
  }
  // Near the goal (inside the look-ahead) with a clear line to it: steer straight at it as
  // a plain goto does, so that the vote's look-ahead, longer than the way left, cannot
  // carry the rover past the disc.
  if (remaining < o.lookahead_m) {
    const GotoDecision direct = SteerToward(p, goto_.target, disc.radius_m, StepLength(), MaxTurn(),
                                            options_.goto_turn_threshold_deg * M_PI / 180.0);
    const bool turn = direct.step.kind == PlannedStep::Kind::kTurn;
    const auto step_path = avoidance::SamplePath(here, turn ? direct.step.turn_rad : 0.0,
                                                 turn ? 0.0 : direct.step.distance_m, 0.0);
    const double bearing = std::atan2(goto_.target.y() - p.y, goto_.target.x() - p.x);
    const auto line = avoidance::SamplePath(here, geometry::WrapAngle(bearing - p.yaw), remaining, 0.0);
    const auto s =
        avoidance::SweepFootprint(grid, o.footprint, step_path, here, o.blind_margin_m, o.unknown.hidden_patch_m,
                                  o.unknown.hidden_reach_m);
    const auto l = avoidance::SweepFootprint(grid, o.footprint, line, here, o.blind_margin_m);
    const bool drivable = o.max_driven_step_m <= 0.0 || s.max_step_m < o.max_driven_step_m;
    if (s.unsafe == 0 && drivable && avoidance::JudgeUnknown(s, o.unknown) == avoidance::UnknownVerdict::kAcceptable &&
        l.unsafe == 0) {
      if (thinking_ahead_ && !KnownSafeAhead(grid, o.footprint, here, direct.step)) return AvoidOutcome::kDeclined;
      *step = direct.step;
      step_choice_ = StepChoice::kSteerAtGoal;
      detail_ = "avoid: the goal is in reach and the way to it clear: steering straight at it (" +
                Fixed(remaining) + " m to go" +
                (avoid_note_.empty() ? "" : "; " + avoid_note_.substr(0, avoid_note_.size() - 2)) + ")";
      return AvoidOutcome::kStep;
    }
  }
  avoidance::Choice choice;
  try {
    choice = avoidance::VoteArcs(grid, {p.x, p.y, p.yaw}, goto_.target.x(), goto_.target.y(), o);
  } catch (const std::invalid_argument& e) {
    if (thinking_ahead_) return AvoidOutcome::kDeclined;
    AbortWith(abort_reason::kHazardUnknown, std::string("arc voting cannot decide: ") + e.what());
    return AvoidOutcome::kAborted;
  }
  // Ahead, only a forward arc gentle enough not to swing the body round (no look aside
  // would be wanted before it) is chosen; the rest waits for the new map.
  if (thinking_ahead_ && (!choice.found || choice.best.kind != avoidance::Candidate::Kind::kArc ||
                          choice.best.distance_m <= 0.0 || choice.best.near_limit ||
                          std::abs(choice.best.curvature_per_m) >= options_.avoid_look_curvature_per_m))
    return AvoidOutcome::kDeclined;
  // 4. No step on but backing up, or none at all, or a step that swings the body round:
  //    first look aside at the ground a turn would sweep, if no view from here has framed
  //    it (behind, with no step at all), then vote again on the map with it.
  if (LookAside(grid, o.footprint, o.backup_m, here, choice)) return AvoidOutcome::kWait;
  // Boxed in with the vote's margin (and looked round): the vote again with the squeeze's.
  // The abort says when the margin was narrowed, by the plan or here.
  std::string squeezed_too = o.footprint_margin_m < vote_margin_m
                                 ? " (with the vote's margin narrowed to " + Fixed(o.footprint_margin_m) + " m)"
                                 : "";
  if (const double squeeze = SqueezeMargin(o.footprint_margin_m); !choice.found && squeeze >= 0.0) {
    const avoidance::VoteOptions narrow = Narrowed(o, squeeze);
    try {
      avoidance::Choice squeezed = avoidance::VoteArcs(grid, {p.x, p.y, p.yaw}, goto_.target.x(), goto_.target.y(), narrow);
      if (squeezed.found) {
        avoid_note_ += "no step keeps the vote's margin (" + choice.detail + "): squeezing through with " +
                       Fixed(narrow.footprint_margin_m) + " m; ";
        choice = std::move(squeezed);
        o = narrow;
      } else {
        squeezed_too = " (nor with the vote's margin narrowed to " + Fixed(narrow.footprint_margin_m) + " m)";
      }
    } catch (const std::invalid_argument& e) {
      AbortWith(abort_reason::kHazardUnknown, std::string("arc voting cannot decide: ") + e.what());
      return AvoidOutcome::kAborted;
    }
  }
  if (!choice.found) {
    AbortWith(abort_reason::kHazardMap,
              "hazard_map: " + choice.detail + squeezed_too +
                  (zones_.empty() ? "" : " (keep-out zones, grown by " + Fixed(zone_grow) + " m, count as unsafe cells)"));
    return AvoidOutcome::kAborted;
  }
  // Round in a loop (avoidance/loop_breaker.hpp): a choice made at this pose before in this
  // goto gives way to the next best one.
  const auto before = avoidance::ChosenHereBefore(avoid_history_, here);
  const avoidance::Candidate* chosen = &choice.best;
  bool loop_broken = false;
  for (const auto& c : before) {
    if (!avoidance::SameMove(c, choice.best)) continue;
    const double one_step = std::min(o.step_m, std::max(remaining, 0.05)) - 1e-6;
    if (const auto* other = avoidance::BestNotRepeating(choice, before, one_step)) {
      chosen = other;
      loop_broken = true;
    }
    break;
  }
  if (thinking_ahead_ && loop_broken) return AvoidOutcome::kDeclined;
  avoid_history_.push_back({here, *chosen});
  const avoidance::Candidate& b = *chosen;
  // Backing up while the plan's way lies ahead: the vote refused every step along it (a
  // backup is then only the last resort, arc_voting.hpp). The planner remembers it.
  if (plan && b.kind == avoidance::Candidate::Kind::kBackup && std::isfinite(o.way_heading_rad) &&
      std::abs(geometry::WrapAngle(o.way_heading_rad - p.yaw)) <= 0.5 * M_PI)
    RefuseWay(*plan, "backing up, the plan's way ahead refused");
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
  d += " m to go";
  if (plan) d += ", plan " + Fixed(plan->path_length_m()) + " m";
  if (loop_broken) d += "; the vote's first choice was made here before: the next best instead";
  if (b.near_limit) d += "; no other step allowed: " + b.near_limit_why;
  if (!avoid_note_.empty()) d += "; " + avoid_note_.substr(0, avoid_note_.size() - 2);  // less its "; "
  d += ")";
  if (thinking_ahead_ && !KnownSafeAhead(grid, o.footprint, here, *step)) return AvoidOutcome::kDeclined;
  detail_ = std::move(d);
  step_choice_ = StepChoice::kArcVote;
  return AvoidOutcome::kStep;
}

// The plan over the site map. A goal unreachable for planner_unreachable_plans plans in a
// row aborts the goto; until then the vote follows the plan's field, which is defined
// round obstacles even when the way is shut (global_planner.hpp).
SequenceExecutor::PlanVerdict SequenceExecutor::PlanAhead(const PlanePose& p, const ArrivalDisc& disc,
                                                          avoidance::Footprint* footprint, double* margin_m,
                                                          double zone_grow, bool going_round,
                                                          std::optional<planner::GlobalPlan>* plan) {
  // Keep-out zones and the ways this goto could not follow (planner/blocked_ways.hpp).
  auto plan_once = [&] {
    const auto [po, r] = PlanSetUp(p, disc, *footprint, zone_grow);
    *plan = planner::PlanOnSiteMap(site_map_, r, po);
  };
  try {
    plan_once();
    // Back where it stood a few steps ago (avoidance::BackWhereItWas): the way the plan
    // leads from here has been refused; plan round it now.
    if (going_round && (*plan)->reachable()) {
      const std::size_t n = refused_ways_.discs().size();
      RefuseWay(**plan, "back where it stood a few steps ago");
      if (refused_ways_.discs().size() > n) plan_once();
    }
    if (blocked_ways_.Update(**plan, refused_ways_.discs().size())) {
      const hazards::KeepOutZone& z = blocked_ways_.zones().back();
      avoid_note_ += "no progress along the plan in " + std::to_string(options_.planner_block_after_steps) +
                    " steps: its way at " + Fixed(z.center.x()) + "," + Fixed(z.center.y()) +
                    " blocked, planning round it; ";
      plan_once();
    }
  } catch (const std::invalid_argument& e) {
    if (thinking_ahead_) return PlanVerdict::kDeclined;
    AbortWith(abort_reason::kGoalUnreachable, std::string("the planner cannot plan: ") + e.what());
    return PlanVerdict::kAborted;
  }
  if ((*plan)->reachable()) {
    unreachable_plans_ = 0;
    return PlanVerdict::kFollow;
  }
  if (thinking_ahead_) return PlanVerdict::kDeclined;  // no way on the old map: see the new one
  avoidance::Footprint narrower;
  if (auto squeezed = SqueezeThrough(p, disc, *footprint, *margin_m, zone_grow, &narrower)) {
    avoid_note_ += "no way keeps the vote's margin (" + (*plan)->why_unreachable() + "): squeezing through with " +
                   Fixed(options_.avoid_squeeze_margin_m) + " m; ";
    *plan = std::move(squeezed);
    *footprint = narrower;
    *margin_m = options_.avoid_squeeze_margin_m;
    unreachable_plans_ = 0;
    return PlanVerdict::kFollow;
  }
  const std::string squeeze_too =
      SqueezeMargin(*margin_m) >= 0.0 ? " (nor with the vote's margin narrowed to " + Fixed(options_.avoid_squeeze_margin_m) + " m)" : "";
  if (++unreachable_plans_ >= options_.planner_unreachable_plans) {
    const std::size_t blocked = blocked_ways_.zones().size();
    AbortWith(abort_reason::kGoalUnreachable,
              "goal unreachable on " + std::to_string(unreachable_plans_) + " plans in a row: " +
                  (*plan)->why_unreachable() + squeeze_too +
                  (blocked == 0 ? ""
                                : " (" + std::to_string(blocked) +
                                      " ways blocked where the rover made no progress along the plan)"));
    return PlanVerdict::kAborted;
  }
  avoid_note_ += "plan " + std::to_string(unreachable_plans_) + " finds no way (" + (*plan)->why_unreachable() + ")" +
                 squeeze_too + "; ";
  return PlanVerdict::kFollow;
}

planner::PlannerOptions PlanOptions(const ExecutorOptions& options, const avoidance::Footprint& vote_footprint,
                                    double cell_m) {
  planner::PlannerOptions po;
  // The vote counts a cell under the body when its centre is within half a cell of it
  // (AvoidStep): the plan keeps the rover's centre as far off, or it leads into gaps no
  // step will cross.
  const bool vote_clearance = options.planner_vote_clearance && cell_m > 0.0;
  po.SetRadiiFrom(vote_footprint, vote_clearance ? 0.5 * cell_m : 0.0);
  po.unknown_cost = options.planner_unknown_cost;
  po.caution_cost = options.planner_caution_cost;
  po.near_cost = options.planner_near_cost;
  po.margin_m = options.planner_margin_m;
  return po;
}

std::pair<planner::PlannerOptions, planner::PlanRequest> SequenceExecutor::PlanSetUp(
    const PlanePose& p, const ArrivalDisc& disc, const avoidance::Footprint& footprint, double zone_grow) const {
  const double cell = site_map_.cell_m();
  const planner::PlannerOptions po = PlanOptions(options_, footprint, cell);
  // The vote also marks a zone's cells out to a cell past its grown edge: the plan's zones
  // are a cell larger with the vote's clearance.
  const bool vote_clearance = options_.planner_vote_clearance && cell > 0.0;
  planner::PlanRequest r;
  r.start_x = p.x, r.start_y = p.y;
  r.goal_x = goto_.target.x(), r.goal_y = goto_.target.y();
  r.goal_radius_m = disc.radius_m;
  r.zone_grow_m = zone_grow + (vote_clearance ? cell : 0.0);
  r.prior = prior_ ? &*prior_ : nullptr;
  r.zones = HazardZones(zones_);
  r.zones.insert(r.zones.end(), blocked_ways_.zones().begin(), blocked_ways_.zones().end());
  r.costly = refused_ways_.discs();
  return {po, r};
}

// Squeezing through: the margin to narrow the vote's `margin_m` to, or -1 for none. Not
// after the monitor refused a step (the margin is then tripled on purpose, VoteOnMap).
double SequenceExecutor::SqueezeMargin(double margin_m) const {
  const double squeeze = options_.avoid_squeeze_margin_m;
  return squeeze >= 0.0 && squeeze < margin_m && !avoid_refused_ ? squeeze : -1.0;
}

// The body's margin narrowed to the squeeze's, planned once more over the same map, zones
// and refused ways.
std::optional<planner::GlobalPlan> SequenceExecutor::SqueezeThrough(const PlanePose& p, const ArrivalDisc& disc,
                                                                    const avoidance::Footprint& footprint,
                                                                    double margin_m, double zone_grow,
                                                                    avoidance::Footprint* narrower) const {
  const double squeeze = SqueezeMargin(margin_m);
  if (squeeze < 0.0) return std::nullopt;
  *narrower = Narrowed(footprint, margin_m, squeeze);
  const auto [po, r] = PlanSetUp(p, disc, *narrower, zone_grow);
  try {
    planner::GlobalPlan plan = planner::PlanOnSiteMap(site_map_, r, po);
    if (plan.reachable()) return plan;
  } catch (const std::invalid_argument&) {
    // The same request planned with the wider footprint; the caller reports that plan.
  }
  return std::nullopt;
}

void SequenceExecutor::RefuseWay(const planner::GlobalPlan& plan, const std::string& why) {
  const auto disc = refused_ways_.Refuse(plan);
  if (!disc) return;
  avoid_note_ += why + ": the ground at " + Fixed(disc->center.x()) + "," + Fixed(disc->center.y()) +
                " costs the planner more (refusal " + std::to_string(refused_ways_.discs().size()) +
                " of this goto); ";
}

bool SequenceExecutor::AvoidRefused(const HazardReply& reply) {
  if (!is_goto_ || !goto_.avoid || avoid_refused_) return false;
  avoid_refused_ = true;
  step_note_ += "the monitor refused the voted step (" + reply.detail + "): voting again with a wider margin; ";
  EnterPhase(Phase::kReady);
  return true;
}

bool SequenceExecutor::LookAside(const avoidance::Grid& grid, const avoidance::Footprint& footprint,
                                  double backup_m, const avoidance::Pose2& here, const avoidance::Choice& choice) {
  if (options_.avoid_look_pan_deg <= 0.0 || looks_unanswered_) return false;
  // When: nothing on but backing up, or nothing at all; or the chosen step swings the body
  // round (a turn in place or a tight arc), sweeping the ground beside it.
  using Kind = avoidance::Candidate::Kind;
  const bool stuck = !choice.found || choice.best.kind == Kind::kBackup;
  const bool swings = choice.found && (choice.best.kind == Kind::kTurn ||
                                       std::abs(choice.best.curvature_per_m) >= options_.avoid_look_curvature_per_m);
  if (!stuck && !swings) return false;
  const auto unknown = avoidance::CountUnknownBeside(grid, footprint, here, backup_m);
  struct Side {
    int bit, cells;
    double pan_deg;  // + toward the right
    const char* name;
    const char* what;
  };
  const double p = options_.avoid_look_pan_deg;
  Side sides[3] = {{1, unknown.left, -p, "left", "a turn would sweep"},
                   {2, unknown.right, p, "right", "a turn would sweep"},
                   {4, unknown.behind, 180.0, "behind", "a back-up would cross"}};
  if (sides[1].cells > sides[0].cells) std::swap(sides[0], sides[1]);  // the more unknown side first
  // Behind only when even backing up is refused: a back-up on offer needs no look back.
  if (choice.found) sides[2].cells = 0;
  for (const Side& s : sides) {
    if ((looked_here_ & s.bit) != 0 || s.cells < options_.avoid_look_min_cells) continue;
    looked_here_ |= s.bit;
    ++looks_total_;
    const double pan = s.pan_deg, tilt = options_.avoid_look_tilt_deg;
    step_note_ += std::string("looked ") + s.name + " (" + std::to_string(s.cells) + " unknown cells " + s.what +
                  "; pan " + Fixed(pan, 0) + " deg, tilt " + Fixed(tilt, 0) + " deg) before voting again; ";
    detail_ = std::string("avoid: ") + (!choice.found ? "no step" : stuck ? "only backing up" : "the step swings the body") +
              " here: looking " + s.name + " at " + std::to_string(s.cells) + " unknown cells " + s.what;
    StartCapture("look", pan * M_PI / 180.0, tilt * M_PI / 180.0);
    look_frame_id_ = frame_id_;
    science_frame_seen_ = false;
    EnterPhase(Phase::kImages);
    return true;
  }
  return false;
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
