#include "avoidance/arc_voting.hpp"

#include "avoidance/goal_field.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <stdexcept>

namespace rover::avoidance {

namespace {

std::string Fixed(double v, int digits = 2) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}

// How much closer to the goal the path brings the rover: round the hazards when there is a
// field and the rover stands where it is defined, else in a straight line. By the nearest
// point of the path; but a path that gets no nearer than where it starts is a loss, by
// where it ends, not a draw (as a draw, a straight arc away from a goal behind the rover,
// on ground already seen and rated better than the unseen ground a turn faces, won step
// after step and drove the rover away).
double Progress(const GoalDistance* field, const Pose2& pose, const std::vector<Pose2>& path, double gx, double gy) {
  std::function<double(double, double)> to_go = [&](double x, double y) { return std::hypot(gx - x, gy - y); };
  if (field && std::isfinite(field->DistanceAt(pose.x, pose.y)))
    to_go = [&](double x, double y) { return field->DistanceAt(x, y); };
  const double d0 = to_go(pose.x, pose.y);
  double best = GoalField::kUnreachable, last = GoalField::kUnreachable;
  for (std::size_t i = 1; i < path.size(); ++i) {
    const double d = to_go(path[i].x, path[i].y);
    if (!std::isfinite(d)) continue;
    best = std::min(best, d);
    last = d;
  }
  if (!std::isfinite(best)) return 0.0;
  return best < d0 ? d0 - best : d0 - last;
}

std::vector<clearance::Pose> ToClearance(const std::vector<Pose2>& path) {
  std::vector<clearance::Pose> out;
  out.reserve(path.size());
  for (const Pose2& p : path) out.push_back({p.x, p.y, p.yaw});
  return out;
}

// How far a pose breaks the suspension's limits (Candidate::severity).
double Severity(const clearance::Suspension& s, const clearance::Bounds& b) {
  if (!b.decided) return 1.0;
  const double deg = M_PI / 180.0;
  return std::max({s.min_belly_clearance_m - b.min_clearance_m, b.max_rocker_rad - s.max_rocker_deg * deg,
                   b.max_bogie_rad - s.max_bogie_deg * deg,
                   std::max(b.max_roll_rad, b.max_pitch_rad) - s.max_tilt_deg * deg});
}

// Where a path stops being safe and what is met before that: by ACE's clearance bounds
// with a suspension, else by the cells' ratings.
struct Safety {
  std::size_t clear_end = 0;  // poses [0, clear_end) are safe
  double good = 1.0;          // the goodness of what they cross
  std::string hazard;         // what stops the path ("" when nothing does)
  double severity = 0.0;
};

Safety ClearanceSafety(const clearance::HeightMap& heights, const VoteOptions& o, const Pose2& pose,
                       const std::vector<Pose2>& path) {
  Safety out;
  {
    const clearance::Excused standing{{pose.x, pose.y, pose.yaw}, o.footprint.length_m, o.footprint.width_m,
                                      o.footprint.center_forward_m, o.blind_margin_m};
    // The pose the rover stands at is where it is (as the sweep leaves out the cells under
    // it): the poses after it are judged.
    std::vector<clearance::Pose> ahead = ToClearance(path);
    if (ahead.size() > 1) ahead.erase(ahead.begin());
    const clearance::PathBounds p = clearance::EvaluatePath(*o.suspension, heights, ahead, &standing);
    const std::size_t skipped = path.size() - ahead.size();
    out.clear_end = p.first_unsafe_pose < 0 ? path.size() : skipped + static_cast<std::size_t>(p.first_unsafe_pose);
    out.good = p.min_margin;
    if (p.first_unsafe_pose >= 0) {
      const Pose2& at = path[out.clear_end];
      out.hazard = "clearance at " + Fixed(at.x) + "," + Fixed(at.y) + ": " + p.first_unsafe.violation;
      out.severity = Severity(*o.suspension, p.first_unsafe);
    }
  }
  return out;
}

// What the clear part of a path is worth on the cells: the worst known cell, drawn toward
// unknown_goodness by the share of its cells that are unknown. Not the worst of the two:
// a look-ahead is seen before it is driven (the step itself is held to the unknown-ground
// limits), and as the worst of the two a single unseen cell at the far end of a 3 m
// look-ahead made an arc that turns toward the plan's way worth no more than one running
// wholly into unseen ground, so that the straight arc on the ground the cameras had just
// seen (ahead, inside their wedge) won step after step, and the rover drove on past the
// plan's turn: out wide round a wall and past a goal beside its way.
double LookAheadGoodness(const Sweep& s, double unknown_goodness) {
  if (s.clear_unknown <= 0) return s.clear_min_goodness;
  const double share = s.clear_cells > 0 ? std::min(1.0, static_cast<double>(s.clear_unknown) / s.clear_cells) : 1.0;
  const double known = s.clear_min_goodness;
  return (1.0 - share) * known + share * std::min(known, unknown_goodness);
}

Safety CellSafety(const Grid& grid, const VoteOptions& o, const Pose2& pose, const std::vector<Pose2>& path) {
  Safety out;
  const Sweep s = SweepFootprint(grid, o.footprint, path, pose, o.blind_margin_m);
  out.clear_end = s.first_unsafe_pose < 0 ? path.size() : static_cast<std::size_t>(s.first_unsafe_pose);
  out.good = LookAheadGoodness(s, o.unknown_goodness);
  if (s.unsafe > 0) {
    out.hazard = "step " + Fixed(s.worst_step_m) + " m at " + Fixed(s.worst_x) + "," + Fixed(s.worst_y);
    out.severity = s.worst_step_m;
  }
  return out;
}

Safety JudgeSafety(const Grid& grid, const clearance::HeightMap& heights, const VoteOptions& o, const Pose2& pose,
                   const std::vector<Pose2>& path) {
  if (!o.suspension) return CellSafety(grid, o, pose, path);
  Safety out = ClearanceSafety(heights, o, pose, path);
  if (!o.cells_too) return out;
  // The hazard monitor's check, which still judges every step by the cells: what it would
  // refuse is not safe either. The path stops at whichever test stops it first.
  const Safety cells = CellSafety(grid, o, pose, path);
  if (!cells.hazard.empty() && (out.hazard.empty() || cells.clear_end < out.clear_end)) {
    out.clear_end = cells.clear_end;
    out.hazard = cells.hazard;
    out.severity = cells.severity;
  }
  // What the clear part is worth stays the cells' goodness, as without a suspension: the
  // clearance margin is small on any ground the map is unsure of (2 sigma at every wheel
  // and under the whole underside), and as the vote's goodness it let the goal vote
  // outweigh steering round a rock early, so the rover drove at it and backed off in turn.
  out.good = cells.good;
  return out;
}

// Judges one candidate: `step` is the motion judged as the step (hazards), `look` the
// motion judged (step first), `driven` what is driven now, whose ground must be known
// (nullptr: `step`). A turn in place is judged whole for hazards, but only its first
// max_turn_rad is driven before the next pair: the ground the rest of it sweeps is seen
// from there before it is driven (MER's look before turning), so only the first part's
// unknown ground counts against it; the rest is look-ahead.
void Judge(const Grid& grid, const clearance::HeightMap& heights, const GoalDistance* field, const Pose2& pose, double gx, double gy, const VoteOptions& o,
           const std::vector<Pose2>& step, const std::vector<Pose2>& look, Candidate* c,
           const std::vector<Pose2>* driven = nullptr) {
  c->step_sweep = SweepFootprint(grid, o.footprint, driven ? *driven : step, pose, o.blind_margin_m,
                                 o.unknown.hidden_patch_m, o.unknown.hidden_reach_m);
  const UnknownVerdict unknown = JudgeUnknown(c->step_sweep, o.unknown);
  const Sweep& s = c->step_sweep;
  const Safety step_safety = JudgeSafety(grid, heights, o, pose, step);
  if (!step_safety.hazard.empty()) {
    c->vetoed = true;
    c->hazard = true;
    c->severity = step_safety.severity;
    c->why = step_safety.hazard;
  } else if (unknown == UnknownVerdict::kHidden) {
    c->vetoed = true;
    c->why = "unknown ground " + Fixed(o.unknown.hidden_patch_m) + " m across at " + Fixed(s.hidden_x) + "," +
             Fixed(s.hidden_y) + " could hide a rock";
  } else if (unknown == UnknownVerdict::kTooMuch) {
    c->vetoed = true;
    c->why = Fixed(100.0 * s.UnknownFraction(), 0) + " % of the cells crossed are unknown";
  } else if (c->kind == Candidate::Kind::kTurn && c->turn_rad * o.previous_turn_rad < 0.0) {
    c->vetoed = true;
    c->why = kUndoWhy;
    c->undoes_last_turn = true;
  }
  // Ground the map rates caution but near its step limit, which it may under-read
  // (VoteOptions::max_driven_step_m): judged on what is driven now (a turn's first part),
  // as the hazard monitor judges the step it is asked about.
  if (o.max_driven_step_m > 0.0 && s.max_step_m >= o.max_driven_step_m) {
    c->near_limit = true;
    c->near_limit_why = "step " + Fixed(s.max_step_m) + " m at " + Fixed(s.max_step_x) + "," +
                        Fixed(s.max_step_y) + " is over the " + Fixed(o.max_driven_step_m) + " m a step drives over";
  }
  // The look-ahead: how far it runs safe (a fraction of its length), and the worst met
  // before that.
  const Safety la = JudgeSafety(grid, heights, o, pose, look);
  const std::size_t clear_end = la.clear_end;
  double total = 0.0, clear = 0.0;
  for (std::size_t i = 1; i < look.size(); ++i) {
    const double d = std::hypot(look[i].x - look[i - 1].x, look[i].y - look[i - 1].y);
    total += d;
    if (i < clear_end) clear += d;
  }
  const double good = std::min(la.good, o.good_enough);
  c->goodness = total > 0.0 ? good * clear / total : (la.hazard.empty() ? good : 0.0);
  c->clear_m = clear;
  const std::vector<Pose2> reached(look.begin(), look.begin() + std::max<std::size_t>(1, clear_end));
  c->progress_m = Progress(field, pose, reached, gx, gy);
}

// The goal vote and the sum. Progress is measured in the plan's cost to go, which falls
// faster than a metre a metre through ground it prices higher (unknown, caution), so the
// scale is the look-ahead or the best progress any allowed candidate makes, whichever is
// more: divided by the look-ahead alone, every arc within 37 deg of the plan's way through
// unseen ground (1.25 x cos 37 deg = 1) reached the top goal vote, and the goodness alone
// chose among them.
void Score(const VoteOptions& o, double scale, Candidate* c) {
  c->goal = 0.5 * (1.0 + std::clamp(c->progress_m / scale, -1.0, 1.0));
  c->vote = o.goodness_weight * c->goodness + o.goal_weight * c->goal -
            (c->kind == Candidate::Kind::kTurn ? o.turn_penalty : 0.0);
}

}  // namespace

// Why each kind of step was refused, counted: the worst rock alone does not say what boxed
// the rover in (navbench seed 11 k0.20_r06 named a rock ahead; the turn and the backup that
// were left were refused for ground never seen beside and behind the start, and for undoing
// the last turn).
std::string VetoSummary(const std::vector<Candidate>& candidates) {
  std::string out;
  for (const Candidate::Kind kind : {Candidate::Kind::kArc, Candidate::Kind::kTurn, Candidate::Kind::kBackup}) {
    int total = 0, unsafe = 0, unseen = 0, undo = 0, other = 0;
    const Candidate* last = nullptr;
    for (const Candidate& c : candidates) {
      if (c.kind != kind) continue;
      ++total;
      last = &c;
      if (!c.vetoed) ++other;  // allowed, but a dead end or near the step limit
      else if (c.hazard) ++unsafe;
      else if (c.undoes_last_turn) ++undo;
      else ++unseen;
    }
    if (total == 0) continue;
    if (!out.empty()) out += "; ";
    if (kind == Candidate::Kind::kBackup && total == 1) {
      out += "backup: " + (last->vetoed ? last->why : std::string("allowed but not taken"));
      continue;
    }
    out += std::to_string(total) + ' ' + ToString(kind) + "s:";
    std::string parts;
    auto add = [&](int n, const char* what) {
      if (n > 0) parts += (parts.empty() ? " " : ", ") + std::to_string(n) + ' ' + what;
    };
    add(unsafe, "over unsafe ground");
    add(unseen, "over unknown ground");
    add(undo, "undoing the last turn");
    add(other, "dead ends or near the step limit");
    out += parts;
  }
  return out;
}

void VoteOptions::Validate() const {
  auto positive = [](double v, const char* name) {
    if (!(v > 0.0) || !std::isfinite(v))
      throw std::invalid_argument(std::string("avoidance: ") + name + " " + std::to_string(v) + " must be > 0");
  };
  positive(footprint.length_m, "footprint length_m");
  positive(footprint.width_m, "footprint width_m");
  if (!(footprint_margin_m >= 0.0) || 2.0 * footprint_margin_m >= std::min(footprint.length_m, footprint.width_m))
    throw std::invalid_argument("avoidance: footprint_margin_m " + std::to_string(footprint_margin_m) +
                                " must be >= 0 and leave the footprint a body");
  positive(max_curvature_per_m, "max_curvature_per_m");
  positive(lookahead_m, "lookahead_m");
  positive(step_m, "step_m");
  positive(max_turn_rad, "max_turn_rad");
  positive(max_point_turn_rad, "max_point_turn_rad");
  if (suspension) {
    if (const std::string p = suspension->Problem(); !p.empty()) throw std::invalid_argument("avoidance: suspension: " + p);
  }
  if (max_point_turn_rad > M_PI) throw std::invalid_argument("avoidance: max_point_turn_rad must be <= pi");
  if (!(max_driven_step_m >= 0.0) || !std::isfinite(max_driven_step_m))
    throw std::invalid_argument("avoidance: max_driven_step_m " + std::to_string(max_driven_step_m) +
                                " must be finite and >= 0 (0: off)");
  if (!(previous_arc_m >= 0.0) || !std::isfinite(previous_arc_m) || !std::isfinite(previous_arc_curvature_per_m))
    throw std::invalid_argument("avoidance: previous_arc_m must be finite and >= 0, its curvature finite");
  if (!std::isfinite(previous_turn_rad)) throw std::invalid_argument("avoidance: previous_turn_rad must be finite");
  if (num_arcs < 1 || num_arcs > 101) throw std::invalid_argument("avoidance: num_arcs must be 1 to 101");
  if (!(good_enough > 0.0) || !(good_enough <= 1.0))
    throw std::invalid_argument("avoidance: good_enough " + std::to_string(good_enough) + " must be in (0, 1] (1: off)");
  const auto fraction = [](double f) { return f >= 0.0 && f <= 1.0; };
  if (!(blind_margin_m >= 0.0) || !(backup_m >= 0.0) || !fraction(unknown.max_fraction) ||
      !fraction(unknown.max_scattered_fraction) || !(unknown.hidden_patch_m >= 0.0) ||
      !std::isfinite(unknown.hidden_patch_m) || !(unknown_goodness >= 0.0) || !(unknown_goodness <= 1.0) ||
      !(goodness_weight >= 0.0) || !(goal_weight >= 0.0) || !(turn_penalty >= 0.0))
    throw std::invalid_argument("avoidance: margins, fractions and weights must be finite and >= 0 (fractions <= 1)");
}

const char* ToString(Candidate::Kind kind) {
  switch (kind) {
    case Candidate::Kind::kArc: return "arc";
    case Candidate::Kind::kTurn: return "turn";
    case Candidate::Kind::kBackup: return "backup";
  }
  return "?";
}

Choice VoteArcs(const Grid& grid, const Pose2& pose, double gx, double gy, const VoteOptions& o) {
  o.Validate();
  if (const std::string p = grid.Problem(); !p.empty()) throw std::invalid_argument("avoidance: grid: " + p);
  if (o.suspension && !grid.HasHeights())
    throw std::invalid_argument("avoidance: the grid holds no heights for the clearance model");
  // The rock each unknown cell could hide, once for every candidate.
  clearance::HeightMap heights = grid.Heights();
  std::vector<float> hidden_rock;
  if (o.suspension) {
    hidden_rock = clearance::HiddenRockHeights(*o.suspension, heights);
    heights.hidden_rock_m = hidden_rock.data();
  }
  Choice choice;
  const double remaining = std::hypot(gx - pose.x, gy - pose.y);
  std::unique_ptr<GoalField> local_field;
  if (!o.goal_distance && o.goal_around_hazards) local_field = std::make_unique<GoalField>(grid, gx, gy, 0.5 * o.footprint.width_m);
  const GoalDistance* field = o.goal_distance ? o.goal_distance : local_field.get();
  // The global plan's way: how far round it lies, and whether it lies behind.
  const double way = std::isfinite(o.way_heading_rad) ? std::remainder(o.way_heading_rad - pose.yaw, 2.0 * M_PI) : 0.0;
  const bool way_behind = std::abs(way) > 0.5 * M_PI;
  // Arcs.
  for (int a = 0; a < o.num_arcs; ++a) {
    Candidate c;
    c.kind = Candidate::Kind::kArc;
    c.curvature_per_m = o.num_arcs == 1 ? 0.0 : o.max_curvature_per_m * (2.0 * a / (o.num_arcs - 1) - 1.0);
    if (std::abs(c.curvature_per_m) < 1e-9) c.curvature_per_m = 0.0;
    double s = std::min(o.step_m, std::max(remaining, 0.05));
    if (c.curvature_per_m != 0.0) s = std::min(s, o.max_turn_rad / std::abs(c.curvature_per_m));
    c.distance_m = s;
    const auto step = SamplePath(pose, 0.0, s, c.curvature_per_m);
    const auto look = SamplePath(pose, 0.0, std::max(s, o.lookahead_m), c.curvature_per_m);
    Judge(grid, heights, field, pose, gx, gy, o, step, look, &c);
    choice.candidates.push_back(c);
  }
  // Turns in place to headings up to max_point_turn_rad round, then straight ahead in the
  // new heading. The whole turn is judged (its sweep and the look-ahead after it); the step
  // driven is its first max_turn_rad, and the next step votes again from there.
  const double bearing = std::remainder(std::atan2(gy - pose.y, gx - pose.x) - pose.yaw, 2.0 * M_PI);
  std::vector<double> turns;
  for (double t = o.max_turn_rad; t < o.max_point_turn_rad + 1e-9; t += o.max_turn_rad) turns.insert(turns.end(), {-t, t});
  if (turns.empty() || std::abs(turns.back()) < o.max_point_turn_rad - 1e-9)
    turns.insert(turns.end(), {-o.max_point_turn_rad, o.max_point_turn_rad});
  if (std::abs(bearing) > 1e-3 && std::abs(bearing) <= o.max_point_turn_rad) turns.push_back(bearing);
  if (std::abs(way) > 1e-3) turns.push_back(way);
  for (double t : turns) {
    Candidate c;
    c.kind = Candidate::Kind::kTurn;
    c.planned_turn_rad = t;
    c.turn_rad = std::clamp(t, -o.max_turn_rad, o.max_turn_rad);
    const auto step = SamplePath(pose, t, 0.0, 0.0);
    const auto look = SamplePath(pose, t, o.lookahead_m, 0.0);
    const auto first = SamplePath(pose, c.turn_rad, 0.0, 0.0);
    Judge(grid, heights, field, pose, gx, gy, o, step, look, &c, &first);
    choice.candidates.push_back(c);
  }
  double scale = o.lookahead_m;
  for (const Candidate& c : choice.candidates)
    if (!c.vetoed) scale = std::max(scale, c.progress_m);
  for (Candidate& c : choice.candidates) Score(o, scale, &c);
  // A turn after which not even one step is clear leads nowhere (see the header).
  const double one_step = std::min(o.step_m, std::max(remaining, 0.05)) - 1e-6;
  auto leads_nowhere = [&](const Candidate& c) { return c.kind == Candidate::Kind::kTurn && c.clear_m < one_step; };
  // near_ok: whether a step over ground near the step limit may be picked (only when no
  // other is allowed: VoteOptions::max_driven_step_m).
  auto pick = [&](bool dead_ends, bool near_ok) {
    const Candidate* best = nullptr;
    for (const Candidate& c : choice.candidates) {
      if (c.vetoed || (c.kind == Candidate::Kind::kBackup && !way_behind) || leads_nowhere(c) != dead_ends ||
          (c.near_limit && !near_ok))
        continue;
      if (!best || c.vote > best->vote + 1e-9 ||
          (std::abs(c.vote - best->vote) <= 1e-9 && std::abs(c.curvature_per_m) < std::abs(best->curvature_per_m)))
        best = &c;
    }
    return best;
  };
  // A turn vetoed only because it undoes the last turn (its sweep safe and seen), the best
  // by vote; one whose step is near the step limit only when no other is left.
  auto pick_undo = [&] {
    const Candidate* best = nullptr;
    for (const bool near_ok : {false, true}) {
      for (const Candidate& c : choice.candidates) {
        if (!c.undoes_last_turn || (c.near_limit && !near_ok)) continue;
        if (!best || c.vote > best->vote + 1e-9) best = &c;
      }
      if (best) break;
    }
    return best;
  };
  // Backing up goes where the cameras, on the mast and facing ahead, have not looked since
  // the rover turned: the blind ring is no excuse behind it. Unknown ground there counts as
  // anywhere else, so the rover backs out along ground it has seen (the way it came)
  // and not into a rock beside the way it turned from.
  VoteOptions behind = o;
  behind.blind_margin_m = 0.0;
  // Back along the arc just driven the body sweeps the ground it has just covered: judged
  // on the body alone, without the margin the vote's footprint carries beyond it.
  VoteOptions retracing = behind;
  retracing.footprint.length_m -= 2.0 * o.footprint_margin_m;
  retracing.footprint.width_m -= 2.0 * o.footprint_margin_m;
  auto backup = [&](double distance_m, double curvature_per_m) {
    Candidate c;
    c.kind = Candidate::Kind::kBackup;
    c.distance_m = -distance_m;
    c.curvature_per_m = curvature_per_m;
    const auto step = SamplePath(pose, 0.0, -distance_m, curvature_per_m);
    Judge(grid, heights, field, pose, gx, gy, curvature_per_m != 0.0 ? retracing : behind, step, step, &c);
    Score(o, scale, &c);
    choice.candidates.push_back(c);
  };
  // The backups, by their index in choice.candidates: straight back, then, if that is not
  // allowed, back along the arc just driven (the body retraces its own ground).
  auto backups = [&] {
    std::vector<std::size_t> judged;
    backup(o.backup_m, 0.0);
    judged.push_back(choice.candidates.size() - 1);
    const double retrace_m = std::min(o.backup_m, o.previous_arc_m);
    const Candidate& straight = choice.candidates.back();
    if ((straight.vetoed || straight.near_limit) && retrace_m > 0.0 && o.previous_arc_curvature_per_m != 0.0) {
      backup(retrace_m, o.previous_arc_curvature_per_m);
      judged.push_back(choice.candidates.size() - 1);
    }
    return judged;
  };
  // With the plan's way behind, the backups are voted on with the rest.
  if (way_behind && o.backup_m > 0.0) backups();
  const Candidate* best = pick(false, false);
  // Otherwise they are the last resort.
  std::vector<std::size_t> last_resort;
  if (!best && o.backup_m > 0.0 && !way_behind) {
    last_resort = backups();
    for (std::size_t k : last_resort)
      if (!best && !choice.candidates[k].vetoed && !choice.candidates[k].near_limit) best = &choice.candidates[k];
  }
  if (!best) best = pick(true, false);
  // Only steps over ground near the step limit are left: taken in the same order.
  if (!best) best = pick(false, true);
  for (std::size_t k : last_resort)
    if (!best && !choice.candidates[k].vetoed) best = &choice.candidates[k];
  if (!best) best = pick(true, true);
  // Boxed in, with only the turn back left: the rule against undoing a turn keeps the rover
  // from turning to and fro while other steps are allowed; it is no safety rule, and an
  // abort would end the drive. Turned back, the rover stands at a heading it stood at, and
  // the next vote may allow a backup along its tracks or another turn (navbench seed 11
  // k0.20_r06: aborted 1.2 m from its start, completes with it).
  if (!best) best = pick_undo();
  if (best) {
    choice.found = true;
    choice.best = *best;
    return choice;
  }
  // Nothing allowed: name the worst hazard met by any step.
  const Candidate* worst = nullptr;
  for (const Candidate& c : choice.candidates)
    if (c.hazard && (!worst || c.severity > worst->severity)) worst = &c;
  choice.detail = "no safe step among " + std::to_string(choice.candidates.size()) + " candidates" +
                  (worst ? ": " + worst->why : ": " + choice.candidates.front().why) + " (" +
                  VetoSummary(choice.candidates) + ")";
  return choice;
}

}  // namespace rover::avoidance
