#include "avoidance/loop_breaker.hpp"

#include <cmath>

namespace rover::avoidance {

bool SameMove(const Candidate& a, const Candidate& b) {
  if (a.kind != b.kind) return false;
  if (a.kind == Candidate::Kind::kTurn) return std::abs(a.turn_rad - b.turn_rad) < 1e-3;
  return std::abs(a.curvature_per_m - b.curvature_per_m) < 1e-6 && (a.distance_m > 0) == (b.distance_m > 0);
}

std::vector<Candidate> ChosenHereBefore(const std::vector<Visit>& history, const Pose2& here,
                                        const LoopOptions& options) {
  std::vector<Candidate> out;
  for (const Visit& v : history) {
    const double d = std::hypot(v.pose.x - here.x, v.pose.y - here.y);
    const double dyaw = std::abs(std::remainder(v.pose.yaw - here.yaw, 2.0 * M_PI));
    if (d <= options.radius_m && dyaw <= options.heading_rad) out.push_back(v.chosen);
  }
  return out;
}

bool BackWhereItWas(const std::vector<Visit>& history, const Pose2& here, const CycleOptions& options) {
  const std::size_t n = history.size();
  if (n == 0 || history.back().chosen.kind == Candidate::Kind::kBackup) return false;
  auto from_here = [&](const Visit& v) { return std::hypot(v.pose.x - here.x, v.pose.y - here.y); };
  // Only the step that arrives closes the cycle: turning in place there afterwards does not
  // close it again.
  if (from_here(history.back()) <= options.radius_m) return false;
  const std::size_t first = n > static_cast<std::size_t>(options.window_steps) ? n - options.window_steps : 0;
  // Back to the end: has the rover been beyond leave_m since visit i, and was visit i here?
  // Not a pose it reached by backing up: backing out along its tracks it passes those
  // poses, and driving forward again over the same tracks passes them once more; each of
  // them counted as a cycle, and so as a refused way (navbench seed 11 k0.20_r01: three of
  // its five refusals, and the plan went 6 m round). Where the retreat began (reached
  // forward, or by a turn) still closes a cycle.
  bool left = false;
  for (std::size_t i = n; i-- > first;) {
    const bool reached_backing = i > 0 && history[i - 1].chosen.kind == Candidate::Kind::kBackup;
    if (left && !reached_backing && from_here(history[i]) <= options.radius_m) return true;
    left = left || from_here(history[i]) > options.leave_m;
  }
  return false;
}

const Candidate* BestNotRepeating(const Choice& choice, const std::vector<Candidate>& before, double one_step_m) {
  auto repeats = [&](const Candidate& c) {
    for (const Candidate& b : before)
      if (SameMove(c, b)) return true;
    return false;
  };
  auto leads_nowhere = [&](const Candidate& c) { return c.kind == Candidate::Kind::kTurn && c.clear_m < one_step_m; };
  // As VoteArcs picks: ground near the step limit only when nothing else is left.
  for (const bool near_ok : {false, true}) {
    for (const bool dead_ends : {false, true}) {
      const Candidate* best = nullptr;
      for (const Candidate& c : choice.candidates) {
        if (c.vetoed || repeats(c) || leads_nowhere(c) != dead_ends || (c.near_limit && !near_ok)) continue;
        if (!best || c.vote > best->vote + 1e-9) best = &c;
      }
      if (best) return best;
    }
  }
  return nullptr;
}

}  // namespace rover::avoidance
