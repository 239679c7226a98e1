// The way back: the forward arcs a rover drove one after another, what is left of each to
// retrace. Arc voting may back up along the last one (VoteOptions::previous_arc_m), and a
// backup along it shortens it, so that a rover boxed in at the end of a pocket retreats arc
// by arc along the ground it came over, not only the last step's length. A turn in place,
// or a backup that is not along the last arc, ends the trail: the body no longer stands
// where the arcs would lead it back.
#pragma once

#include <cstddef>
#include <deque>

namespace rover::avoidance {

class RetraceTrail {
 public:
  struct Arc {
    double length_m = 0.0;  // > 0: left to retrace
    double curvature_per_m = 0.0;
  };
  static constexpr std::size_t kMaxArcs = 32;  // a few metres of steps; older ones are dropped

  // A commanded arc (distance_m < 0: backing up) or, with is_arc false, a turn in place.
  void Driven(bool is_arc, double distance_m, double curvature_per_m);
  void Clear() { arcs_.clear(); }
  bool empty() const { return arcs_.empty(); }
  // The arc to back up along next (length 0 when there is none).
  Arc Last() const { return arcs_.empty() ? Arc{} : arcs_.back(); }
  std::size_t size() const { return arcs_.size(); }

 private:
  std::deque<Arc> arcs_;
};

}  // namespace rover::avoidance
