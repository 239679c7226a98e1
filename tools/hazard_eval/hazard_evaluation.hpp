// hazard-eval: how well the traversability map the rover builds from its own stereo pairs
// finds the hazards of a simulated world.
//
// Stereo pairs are rendered from the world at a list of poses (the rover's attitude from
// the ground under it); after each pair the map is compared with the world's own terrain
// in the cells and rocks both cameras see from that pose, by horizontal range from
// the rover (bands 0-2, 2-4, 4-6 m):
//   rocks     rocks taller than the rover's step limit (rock_collision.max_height_m) whose
//             top is in view; detected when the map cell under the rock's centre is unsafe;
//   traversable cells (truth): in-view cells the TRUE terrain (each cell at the highest
//             point of the exact surface in it), rated by the same plane fit and limits,
//             does not make unsafe; "false unsafe" = the map marks them unsafe;
//   unsafe cells (truth): in-view cells the true terrain makes unsafe (a slope over the
//             tilt limit, a rock's step), and how many of them the map marks unsafe;
//   unknown   in-view cells the map has no rating for (occluded, no stereo match).
// Counts are summed over the poses.
#pragma once

#include "geometry/camera_model.hpp"
#include "render/render_options.hpp"
#include "terrain/world.hpp"
#include "traversability/traversability_map.hpp"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace rover::hazard_eval {

// The true terrain on the map's grid, as points the map rates with its own rules: each
// cell holds the highest of 5x5 samples of the exact surface in it (a rock reaching into a
// cell counts at its top there, as a wheel would meet it; the map's own cells hold the mean
// of the points the cameras see, which lie on rocks' visible faces and tops). at_mean: each
// cell at the mean of the surface in it instead (EvalOptions::truth_at_cell_mean). Every
// cell of the grid takes points; the map's points before are forgotten.
void FillTruth(const terrain::World& world, bool at_mean, traversability::TraversabilityMap* truth);

struct EvalPose {
  double x = 0, y = 0, yaw_deg = 0;
  // This pair's pose error at capture (x, y, z m; roll, pitch, yaw deg), over
  // EvalOptions::pose_error.
  std::array<double, 6> error = {0, 0, 0, 0, 0, 0};
};

struct EvalOptions {
  traversability::MapOptions map;
  render::RenderOptions render;
  // The front HAZCAM pair (hazard_monitor's HAZCAM_FRAME), when hazcam_rig.left is set:
  // rendered at each pose as camera_capture renders it (the mast's shadow under the main
  // rig) at hazcam_image_size and added to the map with its own stereo options before the
  // main pair, as the monitor gets it. Its view counts in "in view" out to its
  // hazcam_map.max_range_m, in front of its hazcam_map.min_x_m.
  geometry::StereoRig hazcam_rig;
  traversability::MapOptions hazcam_map;
  int hazcam_image_size = 256;
  double rock_limit_m = 0.3;       // rocks taller than this must be found
  double pose_sigma_m = 0.02;      // the pose covariance handed to the map
  double pose_sigma_deg = 0.5;
  // The rover's roll and pitch (deg) at every pose, instead of the ground's normal's.
  bool fixed_attitude = false;
  double roll_deg = 0, pitch_deg = 0;
  std::vector<EvalPose> poses;
  int image_size = 512;            // rendered width in pixels
  // The pose handed to the map is the true one moved by these (metres, degrees): an
  // estimate's error at capture (x, y, z, roll, pitch, yaw), the same for every pose.
  std::array<double, 6> pose_error = {0, 0, 0, 0, 0, 0};
  std::int64_t first_frame_seed = 1;  // the render noise seed of the first pose's pairs
  double dump_range_m = 0;         // > 0: EvalResult::dumped gets the rated cells this near
  // The truth's height of a cell: its highest point (what the rover's body meets; the
  // default), or its mean (what the map's cells measure: the mean of their points), which
  // tells the map's reading of the surface apart from a cell's size.
  bool truth_at_cell_mean = false;
  // > 0: also count what the vote sees with executor.avoid_top_rise_m at this value
  // (avoidance::MarkTopsOverGround on the map as the monitor publishes it, traversability::
  // AsGrid): a cell whose top stands this high over the ground round it (a plane within
  // top_ground_radius_m) is unsafe to the vote.
  double top_rise_m = 0;
  double top_ground_radius_m = 1.0;
};

struct BandCounts {
  int rocks = 0, rocks_detected = 0;
  int in_view_cells = 0, unknown_cells = 0;
  int traversable_cells = 0, false_unsafe_cells = 0;
  int unsafe_cells = 0, unsafe_found_cells = 0;
  // Cells the map rates caution at its step limit for an unseen crest (crest_view_range_m),
  // and those of them that are unsafe in truth.
  int crest_cells = 0, crest_truly_unsafe = 0;
  // Cells rated by both with a true step of 0.15 m or more (rocks near the limit): the sum of
  // the map's step less the truth's, and how many read 0.08 m or more under it.
  int tall_cells = 0, tall_read_low = 0;
  double tall_step_error_sum = 0;
  // With EvalOptions::top_rise_m: what the top rule adds on the grid as the vote sees it
  // (edge cells distrusted, as the monitor publishes it): rocks the map missed that it finds,
  // and the cells it makes unsafe that are unsafe in truth and that are traversable.
  int top_rocks_detected = 0, top_false_unsafe_cells = 0, top_unsafe_found_cells = 0;
  void Add(const BandCounts& o);
};

struct RockSighting {
  std::string name;
  int pose = 0;
  double range_m = 0, height_m = 0;
  bool detected = false;
  bool detected_by_top = false;  // missed by the map, unsafe to the vote by EvalOptions::top_rise_m
  float step_m = 0;  // the map's step at the rock's centre
  std::string state;
};

// A traversable cell the map marked unsafe: what each side measured.
struct FalseUnsafe {
  int pose = 0;
  double x = 0, y = 0, range_m = 0;
  traversability::Cell map, truth;
};

struct EvalResult {
  static constexpr int kBands = 3;  // 0-2, 2-4, 4-6 m
  std::array<BandCounts, kBands> bands;
  std::vector<RockSighting> sightings;
  std::vector<FalseUnsafe> false_unsafe;
  // Every rated cell within EvalOptions::dump_range_m of the rover, after each pose.
  std::vector<FalseUnsafe> dumped;
  std::vector<double> update_seconds;  // AddStereoPair per pose
  double median_update_seconds = 0;
  // Bands 0-2 and 2-4 together.
  BandCounts Within4m() const;
};

// Renders, maps and compares. Throws std::invalid_argument / config::ConfigError with a
// one-line message on bad options.
EvalResult Evaluate(const terrain::World& world, const geometry::StereoRig& rig_full_size,
                    const EvalOptions& options);

// top_rise_m > 0: adds the vote's view with the top rule (EvalOptions::top_rise_m).
std::string FormatTable(const EvalResult& result, double rock_limit_m, double top_rise_m = 0);

}  // namespace rover::hazard_eval
