// GESTALT-style arc voting (MER's Grid-based Estimation of Surface Traversability Applied to
// Local Terrain; Goldberg, Maimone and Matthies 2002): candidate motions are each judged by
// the worst cell its swept footprint crosses on the traversability grid (the goodness
// vote) and by how much closer it brings the rover to the goal (the goal vote); the best
// weighted sum becomes the next step. Candidates: arcs of about 20 curvatures from hard left
// to hard right (straight included), judged over a look-ahead longer than the step but
// driven one step at a time; turns in place left and right to headings up to 90 deg round
// (then straight ahead), driven max_turn_rad a step; and,
// when nothing else is allowed, backing up (over ground the map knows: unknown ground in
// the blind ring behind the rover counts, since the mast cameras face ahead).
//
// A candidate is vetoed when the step itself (not the look-ahead) crosses an unsafe cell
// (with a suspension: reaches a pose whose clearance bounds break its limits),
// or when the unknown cells it crosses (outside the blind ring round the rover) are too
// many by `unknown` (JudgeUnknown in grid.hpp: their share, and whether they could hide a
// rock). A look-ahead that meets an unsafe cell (or pose)
// leaves the candidate allowed, but its goodness is the worst cell met before that times
// the fraction of the look-ahead that is clear, and its goal vote counts only the clear
// part: arcs that run further through open ground win before the rover is close to an
// obstacle.
//
// Backing up is the last resort (or a candidate like the others when the global plan's
// way lies behind): straight back by backup_m, or, when that is not allowed, back along the
// arc the previous step drove (VoteOptions::previous_arc_m), in either case.
//
// A turn in place after which the rover could not drive even one step straight ahead
// leads nowhere: it is chosen only when neither an arc, another turn nor backing up is
// allowed, so that a rover whose nose is at a rock backs away from it rather than turning
// to and fro. A turn that undoes the previous step's turn is vetoed (VoteOptions::
// previous_turn_rad), unless nothing else is allowed: then the best such turn is taken
// rather than no step (Candidate::undoes_last_turn).
#pragma once

#include "avoidance/goal_field.hpp"
#include "avoidance/grid.hpp"

#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace rover::avoidance {

struct VoteOptions {
  Footprint footprint;
  int num_arcs = 21;                   // curvatures evenly from -max to +max (odd: straight included)
  double max_curvature_per_m = 1.0;    // tightest arc (1 m radius)
  double lookahead_m = 3.0;            // arcs are judged over this length ...
  double step_m = 0.6;                 // ... and driven this far (less at the goal)
  double max_turn_rad = 18.0 * 3.14159265358979323846 / 180.0;  // per step, arcs and turns
  // Turns in place are judged to headings up to this far round (in max_turn_rad steps,
  // and the goal's bearing), each as the whole turn and the look-ahead after it; the step
  // driven is its first max_turn_rad. A rover whose way on lies 40 deg off sees it.
  double max_point_turn_rad = 90.0 * 3.14159265358979323846 / 180.0;
  double blind_margin_m = 0.5;
  // A candidate whose step itself (not the look-ahead) crosses a cell whose step reads this
  // high or higher, even one the map rates caution, is chosen only when no other is allowed
  // (Candidate::near_limit): the map reads a rock lower than it is (a cell's points average
  // its flank; a rock at the edge of the view shows only its near side), and navbench drove
  // a body corner into a 0.32 m rock read 0.20 to 0.23 m under a 0.25 m limit when a step
  // clear of it was allowed. Not a veto: refusing such steps outright boxed the rover in
  // among the 0.2 to 0.25 m rocks of a k = 0.20 field (common/avoidance/README.md). Such
  // ground may lie in the look-ahead and be planned past. 0: off. The executor takes it
  // from the map's message (hazards.map.driven_step_fraction of the map's step limit).
  double max_driven_step_m = 0.0;
  UnknownLimits unknown;               // the step's new cells beyond the blind ring (grid.hpp)
  // What an unknown cell in the look-ahead is worth: the look-ahead's goodness (its worst
  // known cell) is drawn toward this by the share of its cells that are unknown.
  double unknown_goodness = 0.5;
  double goodness_weight = 1.0;
  double goal_weight = 1.0;
  // Ground good enough to drive ranks no higher for being better still: a candidate's
  // goodness counts up to this (1: every difference counts, GESTALT's vote). At the map's
  // caution level (1 - its caution_fraction) the vote stops weaving among safe cobbles for
  // the best worst cell over 3 m and holds to the plan's way, as ENav ranks its safe paths by
  // their cost to the goal; caution ground, and the clear fraction before an unsafe cell,
  // still weigh as before.
  double good_enough = 1.0;
  double turn_penalty = 0.05;          // a turn in place makes no progress by itself
  double backup_m = 0.3;               // 0: never back up
  // The arc the previous step drove forward: its length (0: the previous step drove no arc
  // forward) and curvature. The cameras face ahead, so backing up straight can sweep a body
  // corner over ground beside the way that they never saw; backing up along this arc
  // retraces the ground just driven. When the straight backup is not allowed, that one is
  // judged next (up to backup_m, and no further than the arc ran).
  double previous_arc_m = 0.0;
  double previous_arc_curvature_per_m = 0.0;
  // How much `footprint` is grown beyond the body all round (the executor's avoid_margin_m).
  // Backing up along the previous arc is judged on the body alone: it sweeps the ground the
  // body has just driven over, and the margin's ring beside it may have been rated unsafe
  // since (navbench seed 7 k0.30_r01 stopped "no safe step" so, in a pocket).
  double footprint_margin_m = 0.0;
  // The goal vote counts progress along the path round the hazards the map knows
  // (goal_field.hpp), not in a straight line; the rover's centre keeps half the footprint's
  // width from an unsafe cell's centre there. false: straight-line progress only.
  bool goal_around_hazards = true;
  // The goal vote's distance to go, when given (not owned): the global planner's cost-to-go
  // over the accumulated site map (common/planner), so that each candidate scores its
  // progress along the best way to the goal. nullptr: the local field above, or the line.
  const GoalDistance* goal_distance = nullptr;
  // The site heading of the way the global plan leaves the rover on (NaN: none). A turn in
  // place toward it is a candidate however far round it lies; when it lies more than 90 deg
  // off the rover's heading, backing up is a candidate like the others (not only the last
  // resort), so that a rover in a cul-de-sac turns or backs out of it.
  double way_heading_rad = std::numeric_limits<double>::quiet_NaN();
  // The turn in place the previous step made (0: it was no turn). A turn the other way
  // would only undo it: it is vetoed, so that two turns cannot take turns for ever in
  // front of an obstacle that blocks both headings (taken only when no other step is
  // allowed: Candidate::undoes_last_turn).
  double previous_turn_rad = 0.0;
  // The rover's suspension (common/clearance): when set, a path is safe when ACE's bounds
  // on its belly clearance, rocker and bogie angles and tilt, from the grid's heights, stay
  // within the suspension's limits at every pose, in place of the cells' step and tilt
  // ratings; the grid must then hold heights. Unset: the cells' ratings (unsafe cells).
  std::optional<clearance::Suspension> suspension;
  // With a suspension: whether a path must also cross no unsafe cell. The hazard monitor
  // still judges every step by the cells' ratings (hazards/map_check.hpp), which are
  // dilated by the wheel patch and refuse ground the clearance bounds allow (a low rock
  // between the wheels); a step it refuses twice aborts the goto. true keeps the vote
  // within what the monitor allows, and rates the clear part of a path by the cells'
  // goodness; false: the clearance bounds alone, the clear part rated by the smallest
  // margin they leave to a limit.
  bool cells_too = true;

  // Throws std::invalid_argument naming the field.
  void Validate() const;
};

struct Candidate {
  enum class Kind { kArc, kTurn, kBackup };
  Kind kind = Kind::kArc;
  double turn_rad = 0.0;         // kTurn: the turn driven this step (at most max_turn_rad)
  double planned_turn_rad = 0.0; // kTurn: the whole turn judged (turn_rad is its first part)
  double distance_m = 0.0;       // kArc, kBackup (signed)
  double curvature_per_m = 0.0;  // kArc (+ right)
  bool vetoed = false;
  std::string why;               // veto reason
  double goodness = 0.0;         // 0..1: worst cell before an unsafe one x clear fraction
  double goal = 0.0;             // 0..1: (1 + progress / scale) / 2 (VoteArcs: the scale)
  double progress_m = 0.0;       // the fall of the distance to go along the clear part
  double vote = 0.0;
  double clear_m = 0.0;          // how far the look-ahead runs before an unsafe cell (or pose)
  Sweep step_sweep;              // the step alone
  // Vetoed by the terrain itself (an unsafe cell, or a pose outside the suspension's
  // limits), and how badly: the worst step (m), or the worst excess over a clearance limit
  // (m of belly clearance, or rad of angle; 1 when undecided).
  bool hazard = false;
  double severity = 0.0;
  // Allowed, but its step crosses a cell whose step reads VoteOptions::max_driven_step_m or
  // more: chosen only when no other candidate is allowed. `near_limit_why` names the cell.
  bool near_limit = false;
  std::string near_limit_why;
  // Vetoed for undoing the previous step's turn alone (its sweep safe and seen): taken
  // only when no other candidate is allowed, in place of finding no step.
  bool undoes_last_turn = false;
};

// The veto reason of a turn that would undo the previous step's turn.
inline constexpr const char* kUndoWhy = "it would undo the last turn";

// When nothing is allowed: how many of each kind of step (arcs, turns, the backup) were
// refused over unsafe ground, over unknown ground, for undoing the last turn, or allowed but
// left (dead ends, near the step limit), e.g. "21 arcs: 21 over unsafe ground; 12 turns: 10
// over unsafe ground, 1 over unknown ground, 1 undoing the last turn; backup: unknown ground
// 0.60 m across at 1.30,-0.30 could hide a rock". Choice::detail ends with it in brackets.
std::string VetoSummary(const std::vector<Candidate>& candidates);

struct Choice {
  bool found = false;
  Candidate best;
  std::vector<Candidate> candidates;
  std::string detail;  // when !found: why nothing is allowed (the worst unsafe cell met, then VetoSummary)
};

// The next step from `pose` toward (goal_x, goal_y). The caller checks arrival first.
Choice VoteArcs(const Grid& grid, const Pose2& pose, double goal_x, double goal_y, const VoteOptions& options);

const char* ToString(Candidate::Kind kind);

}  // namespace rover::avoidance
