// Going round in a loop: arc voting is local, and with a plan whose cost-to-go at a pose
// depends on what the cameras saw from there (a rock rated caution from afar and unsafe up
// close), two poses can each vote for the step that leads to the other: forward 0.6 m,
// back 0.3 m twice, forward again, until a limit stops the goto. A tabu rule (Glover's
// tabu search) breaks it: a choice already made at this pose (within the radius and
// heading below) in this goto is not made again while another allowed candidate exists, so
// the second visit tries the next best way, and every visit after that the next one.
// Knows nothing of LCM.
#pragma once

#include "avoidance/arc_voting.hpp"

#include <vector>

namespace rover::avoidance {

struct Visit {
  Pose2 pose;
  Candidate chosen;  // kind, distance, curvature and turn are compared
};

struct LoopOptions {
  double radius_m = 0.15;                                      // the same pose: this close ...
  double heading_rad = 10.0 * 3.14159265358979323846 / 180.0;  // ... and this well aligned
};

// A cycle of positions. The tabu rule above compares moves at one pose; a rover that backs
// up, turns a few degrees and drives forward to the spot it backed from makes a different
// move at a different heading every time, and goes round A-B-A for ever. Whatever the
// moves, a rover that stands again (within radius_m) where it stood at one of the last
// window_steps steps, having been more than leave_m away from there since, is going round.
// Once, by the step that arrives there (turning in place there afterwards closes nothing);
// and unless it got there by backing up: a rover backing out along its own tracks comes back
// where it stood on purpose (the vote backs up only when the way on is refused, or lies
// behind). Nor is a pose it reached by backing up one it stood at: it passed it backing out
// along its tracks, and passes it again driving forward over them; only where the backing
// began (or where the rover turned after it) can a cycle close.
struct CycleOptions {
  double radius_m = 0.2;
  double leave_m = 0.25;
  int window_steps = 12;
};

// Whether `here` closes such a cycle of the poses in `history` (the last one is the latest).
bool BackWhereItWas(const std::vector<Visit>& history, const Pose2& here, const CycleOptions& options = {});

// Whether `a` and `b` are the same move (kind, curvature and signed distance, or turn).
bool SameMove(const Candidate& a, const Candidate& b);

// The choices made before at poses like `here`.
std::vector<Candidate> ChosenHereBefore(const std::vector<Visit>& history, const Pose2& here,
                                        const LoopOptions& options = {});

// The best allowed candidate of `choice` that repeats none of `before` (highest vote; a
// turn after which not even `one_step_m` is clear only when nothing else is left), or
// nullptr when every allowed candidate repeats one (then the loop cannot be broken here).
const Candidate* BestNotRepeating(const Choice& choice, const std::vector<Candidate>& before, double one_step_m);

}  // namespace rover::avoidance
