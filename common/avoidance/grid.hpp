// A traversability grid as arc voting and the hazard checks see it, and the cells a rover
// footprint crosses along a path. Site frame plane: x north, y east, yaw 0 north and +yaw
// clockwise from above; the rover's forward axis is (cos yaw, sin yaw), its right axis
// (-sin yaw, cos yaw). Knows nothing of LCM or of how the grid was made (stereo, a test).
#pragma once

#include "clearance/clearance.hpp"

#include <cstdint>
#include <string>
#include <vector>

namespace rover::avoidance {

// Mirrors traversability::CellState and traversability_map_t.STATE_*.
enum class CellClass : std::uint8_t { kUnknown = 0, kSafe = 1, kCaution = 2, kUnsafe = 3 };

struct Footprint;

struct Pose2 {
  double x = 0.0, y = 0.0, yaw = 0.0;
};

// Cell (i, j) covers x in [origin_x + i*cell, +cell), y in [origin_y + j*cell, +cell);
// row-major, index i*cols + j.
struct Grid {
  double origin_x = 0.0, origin_y = 0.0, cell_m = 0.2;
  int rows = 0, cols = 0;
  std::vector<CellClass> state;  // rows*cols
  std::vector<float> goodness;   // 0 (unsafe) .. 1 (ideal)
  std::vector<float> step_m;     // largest step height in the cell's patch
  // Optional (empty: not known, as in a TRAVERSABILITY_MAP message): the tilt of each
  // cell's plane, so that a refusal can say a slope, not only a step, was the hazard.
  std::vector<float> tilt_deg;
  // Optional (empty: not known): each cell's elevation (m, up) and its 1-sigma uncertainty,
  // from the cell's own points; sigma_m < 0: no height for the cell. What the clearance
  // model (common/clearance) reads under the wheels and the belly.
  std::vector<float> elevation_m;
  std::vector<float> sigma_m;

  bool HasHeights() const { return !sigma_m.empty(); }
  // The heights as the clearance model reads them (a view of this grid's arrays).
  clearance::HeightMap Heights() const;
  // "" when the sizes agree and the numbers are finite; otherwise what is wrong.
  std::string Problem() const;
  // Index of the cell holding (x, y), or -1 outside the grid.
  int IndexAt(double x, double y) const;
  double CellCentreX(int i) const { return origin_x + (i + 0.5) * cell_m; }
  double CellCentreY(int j) const { return origin_y + (j + 0.5) * cell_m; }
  // A grid of `state`/`goodness` everywhere, for tests.
  static Grid Filled(double origin_x, double origin_y, double cell_m, int rows, int cols,
                     CellClass state, float goodness);
  // Cells at the edge of what the cameras saw: an unsafe or caution cell with an unknown
  // (or off-grid) 4-neighbour becomes unknown. Its rating came from a plane fitted over a
  // patch only partly seen, and stereo edges (the near limit of the view, the sides of the
  // field of view) rate falsely high there; a real rock spans several cells, so its inner
  // cells stay unsafe. Returns how many cells changed.
  int DistrustEdges();
  // Gives every cell a known elevation and sigma (for tests; Paint then keeps them).
  void SetHeights(float elevation_m, float sigma_m);
  // Ground known without the cameras: the unknown cells whose centre lies under `footprint`
  // at `pose`, grown by grow_m, read safe (goodness 1): ground the rover's body has driven
  // over carried it, and the ground round the rover where a drive begins is the operators'
  // (see arc_voting.hpp). Known cells keep their rating. Returns how many changed.
  int MarkKnown(const Footprint& footprint, const Pose2& pose, double grow_m);
  // The same for the ground a whole turn in place of `footprint` at `pose` sweeps: every
  // unknown cell SweepFootprint would count for it (its centre within half a cell of the
  // footprint at some heading) reads safe. Returns how many changed.
  int MarkTurnKnown(const Footprint& footprint, const Pose2& pose);
  // The flanks of rocks whose tops the cameras never saw: every safe or caution cell whose
  // step reads min_step_m or more and that has an 8-neighbour in unknown ground patch_m
  // across (a disc of that diameter all unknown, as SweepFootprint's hidden ground; off the
  // grid is not unknown here) becomes unsafe (goodness 0, its step kept). A rock's top that
  // took no points (out of the NAVCAM's frame, above the HAZCAM's lowest ray) leaves such
  // unknown ground inside the rock, and the cells round it, rated from patches without their
  // highest part, read its flank far low: navbench's rock_2180, 0.43 m tall and 1 m across,
  // read 0.11 to 0.20 m round its unseen top, and a body corner swept one of those cells
  // into it. Such a cell is not a cobble's flank until the ground beside it is seen: once a
  // pair fills the patch, its rating stands. Returns how many cells changed.
  int MarkFlanksOfHiddenGround(double patch_m, double min_step_m);
  // Sets the cells whose centre lies within radius_m of (x, y). With heights, a cell painted
  // unknown loses its height and any other stands step_m above the level (a rock that tall).
  void Paint(double x, double y, double radius_m, CellClass state, float goodness, float step_m);
};

// The rover body: a length x width rectangle whose centre is center_forward_m ahead of
// the rover origin (the hazard monitor's `footprint`).
struct Footprint {
  double length_m = 1.6;
  double width_m = 1.4;
  double center_forward_m = 0.0;
  // Whether site point (x, y) is inside the rectangle at pose p, grown by `grow_m`.
  bool Contains(const Pose2& p, double x, double y, double grow_m = 0.0) const;
  // The least growth at which the rectangle at p contains (x, y) (< 0: inside it).
  double Outside(const Pose2& p, double x, double y) const;
  // The radius, from the rover origin, of the disc a whole turn in place sweeps: out to the
  // rectangle's farthest corner, grown by `grow_m` (the rectangle holds the centre of
  // turning, so a point at every radius out to that corner, which the turn carries round).
  double TurnRadius(double grow_m = 0.0) const;
};

// Poses along a turn in place by turn_rad and then an arc of signed length distance_m and
// curvature k (+ right), start and end included, at most spacing_m / angle_rad apart.
std::vector<Pose2> SamplePath(const Pose2& start, double turn_rad, double distance_m,
                              double curvature_per_m, double spacing_m = 0.05,
                              double angle_rad = 0.035);

// The cells a footprint swept along a path crosses (each once, by its centre inside the
// rectangle grown by half a cell, so a cell partly under the body counts), except those
// under the footprint at `standing` (where the rover stands: it is on them). An unsafe cell
// at the standing footprint's edge (its centre within half a cell inside or outside the
// rectangle: a rock the rover is already that close to, by the last step's slip, or a
// rock's flank the map grew since) still counts at every pose that brings the body nearer
// to it than it stands now: the rover may move away from it or past it, never into it (a
// turn in place swings a corner into a rock beside the body, and that once grazed one).
// Unknown cells within blind_margin_m of the standing footprint
// are not counted as unknown: NAVCAM on the mast cannot see that ring from where the rover
// stands (see common/hazards/README.md).
struct Sweep {
  int cells = 0;          // counted cells (outside the standing footprint)
  int unknown = 0;        // unknown among them, outside the blind ring
  int blind_unknown = 0;  // unknown inside the blind ring
  int unsafe = 0;
  int outside = 0;        // swept points outside the grid (counted as unknown)
  double min_goodness = 1.0;  // over known counted cells (unsafe = 0)
  // The highest step among the counted cells that are not unsafe (safe and caution), and
  // that cell's centre: what a step limit tighter than the map's own judges
  // (VoteOptions::max_driven_step_m, hazards' MapCheckOptions::max_driven_step_m).
  double max_step_m = 0.0;
  double max_step_x = 0.0, max_step_y = 0.0;
  // The worst unsafe cell: the highest step (or the first met if steps are equal).
  double worst_step_m = 0.0;
  double worst_tilt_deg = -1.0;  // its tilt (< 0: the grid holds no tilts)
  double worst_x = 0.0, worst_y = 0.0;
  // The first path pose whose footprint meets an unsafe cell (-1: none), and what was met
  // before it: the lowest goodness of known cells and the unknown cells beyond the ring.
  int first_unsafe_pose = -1;
  double clear_min_goodness = 1.0;
  int clear_unknown = 0;
  int clear_cells = 0;  // counted cells met before it (known and unknown)
  // Counted unknown cells beyond the ring that lie in unknown ground at least
  // `hidden_patch_m` across (see SweepFootprint), and the first such cell's centre.
  int hidden = 0;
  double hidden_x = 0.0, hidden_y = 0.0;
  double UnknownFraction() const { return cells > 0 ? static_cast<double>(unknown) / cells : 0.0; }
};
//
// hidden_patch_m > 0: also finds the unknown ground that could hide a hazard. A cell is
// hidden when it lies in a disc of that diameter whose cells are all unknown (off the grid
// counts as unknown), not counting as unknown the cells under the standing footprint and
// in its blind ring: a rock there was in view from earlier stops and is wider than the
// ring. Unknown cells in thin bands or specks (bland sand between textured grains, the
// near edge of the view) cannot hold a rock that wide, whose visible flank the map would
// rate; a patch that wide could.
//
// hidden_reach_m > 0 (with hidden_patch_m): hidden ground counts this much farther out
// than the footprint (grown by half a cell) reaches, wherever the path brings the footprint
// nearer to it than where the rover stands. A known cell beside unseen ground may hold the
// rim of a rock whose rest lies in it: a cell is rated from the points it took, and those
// may all lie on its far side, so the rock's edge is known only to within a cell (navbench
// seed 11 k0.20_r19: a side swept a safe cell at a 0.33 m rock's rim, the rock itself
// unseen beside the view). Such cells add to `hidden` only, not to the unknown share.
Sweep SweepFootprint(const Grid& grid, const Footprint& footprint, const std::vector<Pose2>& path,
                     const Pose2& standing, double blind_margin_m, double hidden_patch_m = 0.0,
                     double hidden_reach_m = 0.0);

// How much unknown ground a step may cross. More than max_fraction of its counted cells
// unknown is too much when hidden_patch_m is 0, or when some of it lies in unknown ground
// hidden_patch_m across (room for a rock over the step limit). Unknown cells in specks and
// thin bands only, which cannot hide such a rock, are too much over max_scattered_fraction.
struct UnknownLimits {
  double max_fraction = 0.2;
  double hidden_patch_m = 0.0;  // 0: the fraction alone
  double max_scattered_fraction = 0.5;
  // With hidden_patch_m: a step that crosses ground that could hide a rock is refused
  // however small a share of its cells that is (a body corner swept into unseen ground
  // beside the view is a few cells of a step). false: only over max_fraction.
  bool hidden_at_any_share = false;
  // With hidden_patch_m: how much farther out than the footprint hidden ground counts
  // (SweepFootprint's hidden_reach_m). 0: only under the footprint.
  double hidden_reach_m = 0.0;
};
enum class UnknownVerdict { kAcceptable, kHidden, kTooMuch };
// `s` was swept with limits.hidden_patch_m.
UnknownVerdict JudgeUnknown(const Sweep& s, const UnknownLimits& limits);
// The fraction over which a kTooMuch sweep was judged.
double UnknownLimit(const UnknownLimits& limits);

}  // namespace rover::avoidance
