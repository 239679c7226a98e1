// The site map: a persistent traversability grid in the site frame. It merges the hazard
// monitor's rover-centred maps (TRAVERSABILITY_MAP, 14 m across) as they arrive, so that
// what the rover saw stays known after it has driven on and the monitor's window has moved
// past it, and it remembers the ground the rover's body has covered. The global planner
// (global_planner.hpp) plans over it; arc voting still judges each step on the monitor's
// own latest map. Knows nothing of LCM.
#pragma once

#include "avoidance/grid.hpp"

#include <cstdint>
#include <vector>

namespace rover::planner {

class SiteMap {
 public:
  // The map covers at most max_extent_m along either axis; a merge that would take it past
  // that starts it again from that merge (a traverse that long is a new site).
  explicit SiteMap(double max_extent_m = 200.0);

  // Every known cell of `local` replaces what the site map held there (the monitor's newest
  // rating of that ground: it has seen it from closer or more often); unknown cells leave
  // the site map as it was. Cells are placed by their centre. A map whose cell size differs
  // from the site map's starts it again. Throws std::invalid_argument for a broken grid.
  // With keep_unsafe (set_keep_unsafe), a cell once rated unsafe keeps that rating when a
  // later map rates it caution: see KeepUnsafeOn.
  void Merge(const avoidance::Grid& local);
  // Whether a rock the monitor once rated unsafe stays unsafe when a later view reads it
  // lower but not low (caution). A later view can see less of a rock than an earlier one:
  // from beside it, the top out of the frame and the flank's points averaged into its
  // cells (common/traversability/README.md, "Crests out of frame"), so the newest rating
  // is not always the best. navbench (seed 7, k0.15_r15): a 0.30 m rock rated unsafe at
  // 0.25 to 0.29 m by nine maps running was read 0.22 to 0.24 m, caution, by the tenth,
  // taken from beside it, and the next two steps drove the body onto it. A safe rating
  // (a view that found the ground low) or the rover's body having driven there still
  // replaces it. Off by default (the newest rating replaces the old, as before).
  void set_keep_unsafe(bool keep) { keep_unsafe_ = keep; }
  bool keep_unsafe() const { return keep_unsafe_; }
  // With keep_unsafe: the caution cells of `grid` (any grid in the site frame, such as the
  // monitor's latest map) that the site map holds unsafe (not driven over) read unsafe, at
  // the larger of the two steps. Returns how many changed (0 without keep_unsafe).
  int KeepUnsafeOn(avoidance::Grid* grid) const;
  // The ground under `footprint` at `pose` carried the rover: it is marked driven.
  void MarkDriven(const avoidance::Pose2& pose, const avoidance::Footprint& footprint);
  void Clear();

  bool Empty() const { return rows_ == 0; }
  double cell_m() const { return cell_m_; }
  int KnownCells() const;
  int DrivenCells() const;
  bool Driven(double x, double y) const;
  // The unknown cells of `grid` (any grid in the site frame, such as the monitor's latest
  // map) whose centre lies on driven ground read safe (goodness 1): the rover has been
  // there. Returns how many changed.
  int MarkDrivenOn(avoidance::Grid* grid) const;
  // The site map over the box from (x0, y0) to (x1, y1), grown to whole cells: ground never
  // seen is unknown, and driven ground the map never rated reads safe (goodness 1).
  avoidance::Grid Window(double x0, double y0, double x1, double y1) const;
  // The box of the cells held (false when empty).
  bool Bounds(double* x0, double* y0, double* x1, double* y1) const;

 private:
  struct Cell {
    avoidance::CellClass state = avoidance::CellClass::kUnknown;
    bool driven = false;
    float goodness = 0.0f;
    float step_m = 0.0f;
  };
  int IndexOf(double v) const;  // global cell index of a coordinate
  // Grows the block to hold global cells [i_lo, i_hi] x [j_lo, j_hi]; false past max_extent_m.
  bool Cover(int i_lo, int j_lo, int i_hi, int j_hi);
  Cell* At(int i, int j);
  const Cell* At(int i, int j) const;

  double max_extent_m_;
  bool keep_unsafe_ = false;
  double cell_m_ = 0.0;
  int i0_ = 0, j0_ = 0, rows_ = 0, cols_ = 0;  // global index of cell (0, 0) and the block size
  std::vector<Cell> cells_;
};

}  // namespace rover::planner
