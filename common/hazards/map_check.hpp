// The predictive check of a step against the traversability map (common/traversability,
// built by the hazard monitor from the NAVCAM and front HAZCAM pairs): the rover footprint swept along the
// step's path must cross no unsafe cell (a step, tilt or roughness over its limit: a rock
// taller than the step limit is unsafe), and not too many unknown cells.
//
// Unknown cells: a check that cannot decide stops the rover, so a step whose new cells
// are more than max_unknown_fraction unknown is UNKNOWN, and the executor aborts with
// hazard_unknown -- after taking a pair where the rover stands, once (MER: image, map,
// then drive). Two kinds of cell are not counted: those under the rover where it stands
// (it is on them), and unknown cells in a ring of blind_margin_m round it, which the mast
// cameras cannot see from where the rover stands (the NAVCAM pair sees the ground from
// 1.3 m ahead of the rover origin; the body ends 0.8 m ahead). The front HAZCAM pair sees
// the ring's front from the body's front face on, but nothing sees it beside or behind the
// body, where a turn swings the corners: the ring stays excused all round (only its unknown
// cells: a cell the HAZCAMs rate unsafe there is refused like any other). That ring was in
// view from the previous stops, and a rock taller than the step limit is wider than the ring
// (MER-like rocks are 2.5 times as wide as they are tall), so part of it is seen.
//
// hidden_patch_m > 0 judges unknown ground by its shape as well. A step over
// max_unknown_fraction unknown is UNKNOWN when some of that ground is at least
// hidden_patch_m wide (a disc of it, beyond the ring), since a rock over the step limit
// could sit there unseen; unknown cells in specks and thin bands cannot hold one (bland
// sand between textured grains, the bottom edge of the view), and only more than
// max_scattered_unknown_fraction of them is UNKNOWN: the map knows too little.
#pragma once

#include "avoidance/grid.hpp"
#include "config/yaml_config.hpp"
#include "hazards/hazard_assessor.hpp"
#include "hazards/keepout.hpp"

#include <cstdint>
#include <string>
#include <unordered_set>
#include <vector>

namespace rover::hazards {

struct MapCheckOptions {
  bool enabled = true;
  double blind_margin_m = 0.5;
  double max_unknown_fraction = 0.2;
  double hidden_patch_m = 0.0;  // 0: the fraction alone
  double max_scattered_unknown_fraction = 0.5;  // with hidden_patch_m: specks and thin bands
  // Ground near the step limit: cells, even caution ones, whose step reads at or over this
  // fraction of the map's step limit (traversability.max_step_m). The map under-reads rocks
  // (a cell's points average a rock's flank; a rock at the edge of the view shows its near
  // side only), and navbench drove into a 0.32 m rock read 0.20 to 0.23 m under a 0.25 m
  // limit. The limit goes to the executor in the map's message, whose arc vote drives a
  // step over such ground only when no other step is allowed. 1: off, the default: on
  // navbench (seed 7, k = 0.20, with the map's relief_sigmas: 1) the preference took success
  // from 5 of 6 runs to 3 of 6 (two time limits), and the refusal below to 0 of 6.
  double driven_step_fraction = 1.0;
  // Whether this check refuses such steps outright (UNSAFE). Off: it boxed the rover in
  // among 0.2 to 0.25 m rocks (5 runs of 6 ended "hazard_map: no safe step").
  bool driven_step_refused = false;
  // The limit in metres (0: none): the caller sets it from the map's own options
  // (DrivenStepLimit), as hazard_monitor does.
  double max_driven_step_m = 0.0;
  double DrivenStepLimit(double map_max_step_m) const {
    return driven_step_fraction < 1.0 ? driven_step_fraction * map_max_step_m : 0.0;
  }
  // With a map that marks unseen crests (traversability crest_view_range_m): at a fraction
  // of 1 the map's own step limit, which only such cells reach without being unsafe (their
  // step reads the limit: a crest up to it may stand out of view), so that the vote drives
  // over them only when no other step is allowed; a fraction under 1 as above.
  double DrivenStepLimit(double map_max_step_m, bool map_marks_unseen_crests) const {
    if (driven_step_fraction < 1.0 || !map_marks_unseen_crests) return DrivenStepLimit(map_max_step_m);
    return map_max_step_m;
  }
  avoidance::UnknownLimits Unknown() const {
    return {max_unknown_fraction, hidden_patch_m, max_scattered_unknown_fraction};
  }
  // Throws std::invalid_argument naming the field.
  void Validate() const;
};

// Reads `enabled`, `blind_margin_m`, `max_unknown_fraction`, `hidden_patch_m`,
// `max_scattered_unknown_fraction`, `driven_step_fraction`, `driven_step_refused` of a
// `hazards.map` section;
// `extra_keys` are keys the caller reads itself (the grid's own options).
MapCheckOptions LoadMapCheckOptions(const config::ConfigNode& node, const std::vector<std::string>& extra_keys = {});

// The zone name a map verdict carries in hazard_reply_t, and the prefix of its detail.
inline constexpr const char* kMapZoneName = "hazard_map";

// Judges the swept path (first pose: where the rover stands) on `grid`: UNSAFE with detail
// "hazard_map: step 0.35 m at 4.10,0.30" (the worst unsafe cell), or with
// options.driven_step_refused "hazard_map: step 0.22 m at 4.10,0.30 is over the 0.20 m a
// step drives over" (the highest caution cell the step crosses), UNKNOWN with detail
// "hazard_map: unknown: 45 % of the cells the step crosses are unknown (limit 20 %)" or
// "hazard_map: unknown ground 0.60 m across at 4.10,0.30 could hide a rock (...)", otherwise
// SAFE. An empty or non-finite path, or a bad grid, is UNKNOWN.
SweptCheck CheckPathOnMap(const avoidance::Grid& grid, const avoidance::Footprint& footprint,
                          const std::vector<Pose2>& path, const MapCheckOptions& options);

// The map's tilt limit against the rover's own (the tilt check's roll and pitch limits).
// A cell's tilt is the slope of its ground plane, whatever the heading; on a plane of slope
// s the rover's pitch (heading up it) or roll (heading across it) reaches s, so the map
// stands for the tilt check in the worst heading when its limit is the smaller of the two.
// A tighter map limit refuses ground the tilt check allows (a 26 deg slope drive the rover
// makes within its 30 deg limits): returns that as a one-line note, empty when consistent.
std::string MapTiltLimitProblem(double map_max_tilt_deg, const TiltLimits& rover);

// The ground the rover's body has covered: it drove there, so that ground carries it. The
// mast cameras look ahead, and the map knows nothing behind the rover where it started;
// without this a rover could not back out along its own tracks (MER backed out of sand
// traps and dead ends that way). Only unknown cells are marked: a cell the map rates
// unsafe stays unsafe. Cells are squares of cell_m in the site frame, kept for the life
// of the process (a 1 km drive with a 1.4 m wide body covers about 35,000 cells of 20 cm).
class DrivenTrail {
 public:
  explicit DrivenTrail(double cell_m = 0.2);
  // The cells whose centre lies under `footprint` (body only, no margin) at `pose`.
  void Add(const Pose2& pose, const Footprint& footprint);
  // Marks the grid's unknown cells the trail covers as safe; returns how many changed.
  int MarkDriven(avoidance::Grid* grid) const;
  std::size_t size() const { return cells_.size(); }

 private:
  std::int64_t Key(double x, double y) const;
  double cell_m_;
  std::unordered_set<std::int64_t> cells_;
};

// The rover footprint rectangle of the keep-out checks, as arc voting sees it.
avoidance::Footprint GridFootprint(const Footprint& footprint);

}  // namespace rover::hazards
