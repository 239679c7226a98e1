// A GESTALT-style traversability map (Goldberg, Maimone & Matthies 2002): the rover rates
// the ground it sees for itself, from its own NAVCAM stereo pairs.
//
// Each stereo pair is rectified through the rig's camera models, matched densely (OpenCV
// StereoSGBM) and triangulated into the rover frame, then into the site frame at the
// capture pose. The points land in a square grid in the site frame (X north, Y east, Z
// down; heights below are elevations, up) that follows the rover (Recentre). Every cell
// keeps the weighted moments of its points, so pairs accumulate. A cell is rated from a
// plane fitted (Eigen) over the rover-footprint patch around it:
//   step      the highest cell above the plane minus the lowest cell below it (m),
//   tilt      the angle between the vertical and the normal of a plane fitted over the
//             rover's own size (tilt_radius_m), the tilt it would stand at there (rad),
//   face      how much steeper the wheel patch's plane is than that one (rad): a rock's
//             flank under one wheel, where the body stays level (with tilt_radius_m),
//   roughness the RMS residual of the cells about the plane (m), each less
//             roughness_margin_sigmas of its height error,
// each against its limit. A cell is unknown when it, or its patch, has too little data.
// sigma_m is the height uncertainty of the cell's points: stereo range error (grows with
// range squared) and the pose's position and attitude uncertainty (grows with range).
//
// Knows nothing of LCM. Determinism: no randomness.
#pragma once

#include "config/yaml_config.hpp"
#include "geometry/camera_model.hpp"
#include "geometry/pose.hpp"

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <string>
#include <vector>

namespace rover::traversability {

enum class CellState : std::uint8_t { kUnknown = 0, kSafe = 1, kCaution = 2, kUnsafe = 3 };
const char* CellStateName(CellState state);  // "unknown", "safe", "caution", "unsafe"

struct Cell {
  CellState state = CellState::kUnknown;
  float step_m = 0;       // largest step height in the rover-footprint patch
  float tilt_rad = 0;     // tilt of the plane fitted over the tilt patch
  float face_rad = 0;     // the wheel patch's tilt over the tilt patch's (0 without one)
  float roughness_m = 0;  // residual of the plane fit
  float goodness = 0;     // 0 (unsafe) .. 1 (ideal); meaningful when state != kUnknown
  float sigma_m = 0;      // height uncertainty (grows with range and pose uncertainty)
  // The cell's own height, for the clearance model: its top, the weighted mean elevation
  // of its points plus one standard deviation of them (m, up: a rock's top standing in a
  // cell of ground, where the mean would lie halfway down), and the points' height sigma.
  // height_sigma_m < 0: the cell has too few points.
  float elevation_m = 0;
  float height_sigma_m = -1;
  // With crest_view_range_m: the cell would have been rated safe or caution, but its patch
  // holds ground rising toward a side no pair has framed (crest_view_range_m), so its step
  // is a lower bound only: it is caution (goodness at most 1 - caution_fraction) and its
  // step_m reads max_step_m.
  bool crest_unseen = false;
};

struct MapOptions {           // read from YAML by LoadMapOptions (key names = field names)
  double cell_size_m = 0.2;
  double extent_m = 14.0;     // square grid extent, centred on the rover, moves with it
                              // (at least 2 x max_range_m + 2 x footprint_radius_m)
  double footprint_radius_m = 0.6;  // patch over which each cell's plane is fitted
  double max_step_m = 0.2;    // limits: from the rover config (rock step limit)
  double max_tilt_deg = 20.0;
  // Patch over which the tilt is fitted; 0: the footprint_radius_m patch. The rover's body
  // tilts with the plane through all its wheels, not with the ground under one wheel: a
  // wheel-sized patch on a cobble's flank, or on a ripple of a 28 deg slope, reads 30 to
  // 36 deg where the body stays within its limits. Half the wheelbase-by-track diagonal
  // makes the cell's tilt the one the rover would have standing on it.
  double tilt_radius_m = 0.0;
  // With tilt_radius_m: how much steeper the wheel patch's plane is than the plane the body
  // stands on, the face a wheel meets (a rock's flank), which a uniform slope does not
  // steepen; 0: not rated.
  double max_face_deg = 0.0;
  // The ground plane (each patch's, and the body-scale one) is fitted by least squares
  // without the cells over half a step limit above it, and then, once that has settled,
  // without those over this fraction of the step limit above it (or two of the cell's
  // height sigmas, if more, up to half a step): a plane through the ground and a wall of
  // rocks seen from one side leans on the wall, and the rocks' lower flanks stay within
  // half a step of it, so the wall read as caution. 0: half a step only.
  double ground_band_fraction = 0.25;
  // The tilt rated (and the face) is the fitted one less this many standard errors of it,
  // from the cells' height sigmas and how the known cells spread over the patch: a plane
  // through a few cells in a line (the only texture on blank sand may be a shadow's edge)
  // can have any slope across the line, and a sparse far patch's slope is mostly stereo
  // error. Dense, well-spread patches lose a fraction of a degree. 0: the fitted tilt.
  double tilt_margin_sigmas = 0.0;
  // The step counts a cell below the ground plane only by how far it lies under it beyond
  // this many standard errors of its height (its points' sigma and the standard error of
  // their scatter): the lowest of a patch's noisy cells lies under the ground by its error
  // alone, and a sparse cell holding a mismatched streak scatters widely. The highest cell
  // (a rock) always counts in full. 0: every cell at its height.
  double dip_margin_sigmas = 0.0;
  // The step counts each cell above the ground plane at its mean height plus this many of
  // its relief: the scatter of its points' heights beyond what their own stereo sigma
  // explains. A cell on a rock's flank or top holds points from low on the flank to the
  // crest, and its mean lies well under its highest ground (a 0.32 m rock read 0.26 m from
  // 1.7 m straight on, and 0.16 to 0.20 m from the HAZCAM's edge, which saw only its near
  // flank); noise alone adds no relief, so level ground reads as before. 0: the mean.
  double relief_sigmas = 0.0;
  // The step counts each cell above the ground plane at its top: its highest point as the
  // plane through the cell's own points places it, at the cell's corner where that plane
  // is highest. A cell's mean lies under its top by half the rise across it; on a rock's
  // flank that is most of what the map reads low (hazard-eval against the cells' mean true
  // height: steps of 0.15 m or more right to 0.01 m on average; against their highest
  // points, 0.06 to 0.10 m low). The cell's gradient is shrunk by this many of its standard
  // errors (from the points' scatter about the cell's plane, at least their stereo sigma),
  // so noise and a few points in one corner add nothing; a rounded crest has no gradient
  // and reads at its mean. 0: off (the mean, or relief_sigmas).
  double cell_plane_sigmas = 0.0;
  // Crests out of frame. A rock at the edge of a camera's view shows its near flank and not
  // its top: a vertical edge leans outward toward the image's sides (the cameras look
  // down), so the top leaves the frame first, and the flank's cells read well under the
  // rock (a 0.32 m rock 59 to 67 deg off the HAZCAM's axis read 0.16 to 0.20 m, caution, and
  // was driven into). A pair *frames* a cell when the top of a column crest_view_height_m
  // over the rover's ground plane at the cell's centre lies in both of its rectified
  // images (and their source images), inside its stereo range, disparity search and
  // filters. A cell is *cut* when a pair put points in it without framing it (its foot in
  // view, its top not), and *open* while cut and not framed by any pair within
  // crest_view_range_m of the rover (a far view reads a rock low by its resolution). A cell
  // rising crest_rise_fraction of the step limit or more above the ground plane, open or
  // with an open 8-neighbour, may have a higher crest there: every cell whose patch holds
  // one, rated safe or caution, is rated caution instead, its step at the limit itself
  // (max_step_m), which a cell short of unsafe reads only so: the arc vote drives a step over
  // it only when no other step is allowed (hazards.map's driven-step limit). Never better:
  // unsafe stays unsafe; and not unknown, which a step may cross a few cells of. Ground
  // never seen, or hidden behind a rock, is unknown by its own lack of points and does not
  // count here. 0: off.
  double crest_view_range_m = 0.0;
  double crest_view_height_m = 0.3;
  double crest_rise_fraction = 0.5;
  // With crest_view_range_m: an open cell (cut by pairs, framed by none within range) is
  // unknown unless it reads unsafe (never better): its top was never in view, so its rating
  // is a guess. A rock kept beside the view (navbench seed 11 k0.15_r03: orbited 45 deg right of
  // the heading, past the NAVCAM's field and at the HAZCAM's edge) showed only its foot and
  // read 0.03 to 0.05 m for 0.30 m, under every rise rule. Unknown, the vote's unseen-ground
  // rule keeps the body off it until a pair frames it (the rover turns toward it, as it
  // must to drive there). Open cells are the bands at the sides of a view; a turn frames them.
  bool open_cells_unknown = false;
  // > 0: a cell with no points of its own, rated from its patch's, is unknown unless it
  // reads unsafe (never better) when it lies in a disc this wide (m) of cells without
  // points: a hole in the data wide enough to hold a rock (hazards.map.hidden_patch_m), its
  // rating the ground round it. Navbench seed 11 k0.20_r19: cells 0.14 and 0.24 m from a
  // 0.33 m rock's centre, never seen, read safe so. 0: off (a speck of bland sand between
  // points is rated from them, as before).
  double hole_unknown_m = 0.0;
  // With crest_view_range_m: a cell with no points of its own that no pair has framed is
  // unknown unless it reads unsafe (never better). Its patch rating came from the ground
  // beside it, and nothing ever looked at it: a rock standing wholly beside the view reads
  // as the ground round it (navbench seed 11 k0.20_r19: cells 0.14 and 0.24 m from a
  // 0.33 m rock's centre read safe so). A cell a pair framed but put no points in (the
  // ground hidden behind a rock, bland sand) keeps its patch rating: a rock's top standing
  // there would have been in view. false: rated from the patch, as before.
  bool unframed_unknown = false;
  // With crest_view_range_m: a cell's height in the step is at least what the pairs that
  // framed its top read there, not only the mean of every point. A pair that cut the cell
  // (its foot in view, its top not) put only the low flank's points there, and a far pair
  // reads a rock low by its resolution; in the mean over every pair they pulled a rock's
  // cell under what a near framing view read (issue 47: 0.23 m read for a 0.31 m rock).
  // kMean: the weighted mean of the framing pairs' points (once they are min_points);
  // kMax: the highest reading of one framing pair (its points' mean, of at least
  // min_points, less their height sigma). Never lower than the mean of every point.
  // kOff: every point alike. YAML: off, mean, max.
  enum class FramedHeight : std::uint8_t { kOff, kMean, kMax };
  FramedHeight framed_height = FramedHeight::kOff;
  double max_roughness_m = 0.05;
  // The roughness counts each cell's residual about the fitted plane only beyond this many
  // standard errors of its height (as dip_margin_sigmas does below the ground for the step):
  // a patch of sparse or mixed cells (a cobble's face and the ground behind it in one cell,
  // a mismatched streak) scatters about its plane by their errors alone, and the HAZCAM's
  // near field rated cobbles under the step limit unsafe by roughness. 0: every residual in
  // full.
  double roughness_margin_sigmas = 0.0;
  double max_range_m = 6.0;   // stereo points beyond are ignored
  int min_points = 3;         // per cell; fewer -> unknown
  // A cell is kCaution when step, tilt or roughness exceeds this fraction of its limit.
  double caution_fraction = 0.6;
  // The goodness at or under which a rated cell is caution or worse (goodness is 1 less
  // the worst fraction of a limit): what the map message carries as caution_goodness.
  double CautionGoodness() const { return 1.0 - caution_fraction; }
  // A patch needs at least this fraction of its cells known to be rated.
  double min_patch_fraction = 0.3;

  // Dense stereo. Images wider than stereo_width_px are reduced to it before matching
  // (1024 -> 512); 0 matches at the images' own size.
  int stereo_width_px = 512;
  int num_disparities = 96;     // at the matching width; rounded up to a multiple of 16
  int block_size = 5;           // SGBM block, odd
  int uniqueness_ratio = 10;
  int speckle_window = 100;     // 0 disables the speckle filter
  int speckle_range = 2;
  double disparity_sigma_px = 0.3;  // matching error, in source pixels at the matching scale
  // The matching error's share from image noise, which grows as the block's texture along
  // the rows falls toward the noise (the block-matching error model: a block's disparity
  // variance is twice the noise variance over the sum of its squared horizontal intensity
  // gradients). A point's disparity sigma is
  //   sqrt(disparity_sigma_px^2 + texture_sigma_px^2 / rho),
  // rho the block's gradient energy beyond what noise alone gives, over noise's (the
  // texture SNR^2 of min_texture_snr, less 1; at least 0.01, so a block at or under the
  // noise claims 10 x texture_sigma_px): texture_sigma_px is the noise term where the
  // texture's gradient energy equals the noise's. For white noise and a 5 px block the
  // model gives 0.65 px. Bland sand then claims honest, larger height errors (a patch's
  // dip margin discounts it), well-textured ground keeps about disparity_sigma_px.
  // 0: every point disparity_sigma_px.
  double texture_sigma_px = 0.0;
  int subsample = 1;            // triangulate every n-th pixel (row and column) of the match
  double min_range_m = 0.5;     // points nearer than this are ignored
  // Mixed pixels: a pixel whose 5x5 neighbourhood spans a disparity range over this
  // fraction of its own disparity lies on a depth edge (a rock's outline against the ground
  // behind it), where SGBM gives depths between the two that hang in the air behind the
  // rock; it is dropped. 0 (the default) keeps every pixel: on rock_field with the default
  // options 0.15 removes every false unsafe cell, but with a 0.3 m patch and every 3rd
  // pixel it also removes enough of the rocks' outlines to miss some (README).
  double max_disparity_jump = 0.0;
  // Texture: a pixel whose block_size window of the left image has a standard deviation
  // under this (grey levels, 8-bit) has nothing to match, and SGBM's disparity there is
  // noise; it is dropped. 0 keeps every pixel.
  double min_texture = 0.0;
  // Texture along the rows, against the image's noise: a pixel is matched only where the
  // RMS horizontal gradient over its block_size window is at least this many times what
  // the image's read noise alone gives (noise estimated per image). Drops pixels whose
  // only texture runs along the rows (horizontal bands) or is under the noise (blank or
  // shadowed sand), where SGBM's disparity is noise. 0 keeps every pixel.
  double min_texture_snr = 0.0;
  // The left image's border band (its first num_disparities columns) is matched against a
  // padded right image: a pixel there whose true disparity exceeds its column has no match
  // in the right image, and SGBM's disparity there is wrong, too small (a point below the
  // ground). true: such pixels are dropped, bounded by the largest disparity matched in the
  // interior of the nearby rows; so is every pixel within half a block (plus one) of the
  // image's edges, whose matching block runs off the image.
  bool drop_unseen_border = false;
  // Left-right consistency: the right image is matched against the left as well, and a
  // left pixel whose disparity disagrees with the right view's at its match by more than
  // this many pixels (at the matching width) is dropped: it is occluded in the right image
  // (the ground beside a rock's left flank) or mismatched. StereoSGBM's own disp12MaxDiff
  // does nothing in MODE_SGBM_3WAY. 0 (the default) keeps every pixel.
  double lr_max_diff_px = 0.0;
  // The rectified field across (deg): 0 rectifies onto a pinhole of the camera's centre
  // focal length at the matching width (94 deg for the 124 deg HAZCAM fish-eye, 45 deg for
  // the NAVCAM); wider keeps that focal length and adds columns (Rectify), so the fish-eye's
  // sides, the ground beside the front wheels, are matched too.
  double rectified_fov_deg = 0.0;
  // Points whose rover-frame x (forward, at capture) is under this are dropped: the
  // ground a camera on the body's front face cannot see past the body (the renderer does
  // not draw the rover's body, so a simulated HAZCAM would see under it). -100: none.
  double min_x_m = -100.0;
  // Points whose ray from the left camera points less than this far below the site's
  // horizontal plane (deg, at the capture attitude; or above it) are dropped. A camera low on the body sees the horizon band foreshortened
  // to a few rows, where SGBM's matches are noise and their points hang at the camera's
  // height (the HAZCAM's first pair on flat_rock_course: points 0.5 m over the ground at
  // 1.7 m, 12 cells unsafe). 0: none.
  double min_depression_deg = 0.0;
};

// The keys of MapOptions that belong to one camera's dense stereo, which a camera's own
// section (hazard_monitor's `hazards.map.hazcam`) may set over the map's.
const std::vector<std::string>& CameraOptionKeys();

// Per update, for the log and the benchmark.
struct UpdateStats {
  int points = 0;            // points added to the grid
  double seconds_rectify = 0;
  double seconds_match = 0;
  double seconds_grid = 0;   // triangulating, binning and rating
};

struct RectifiedRig;  // dense_stereo.hpp

class TraversabilityMap {
 public:
  // Throws std::invalid_argument with a one-line message on an option out of range.
  explicit TraversabilityMap(const MapOptions& options);

  // One stereo pair (8-bit grey, same size as the models), the rig's models in the rover
  // frame, and the rover pose in the site frame at capture with its 6x6 covariance
  // (x y z roll pitch yaw). Throws std::invalid_argument with a one-line message on bad input.
  // `camera` (optional): that camera's own options (LoadCameraOptions); its stereo and
  // range fields (CameraOptionKeys) are used for this pair, the grid and the ratings stay
  // the map's.
  void AddStereoPair(const cv::Mat& left, const cv::Mat& right,
                     const geometry::StereoRig& rig_in_rover_frame,
                     const geometry::Pose& T_site_rover, const geometry::Matrix6d& pose_cov,
                     const MapOptions* camera = nullptr);
  // Points already in the site frame (x north, y east, z down), each with its height
  // sigma (m): for tests and for other range sensors. Sizes must agree.
  void AddPoints(const std::vector<Eigen::Vector3d>& points_site,
                 const std::vector<double>& sigma_m);
  // The same points from a view that framed (framed true) or cut (false) every cell they
  // land in: marks those cells as MarkView does, and with framed_height counts framed
  // points in the cells' framed height. For tests and for other range sensors.
  void AddViewedPoints(const std::vector<Eigen::Vector3d>& points_site, const std::vector<double>& sigma_m,
                       bool framed);
  // With crest_view_range_m: marks the cells within radius_m of site point (x, y) framed
  // (a pair within crest_view_range_m saw their tops) or, with framed false, cut (a pair saw
  // their feet and not their tops), as AddStereoPair does; for tests and for other range
  // sensors, whose points AddPoints takes without a view.
  void MarkView(double x, double y, double radius_m, bool framed);
  // Whether the cell holding (x, y) has been framed; open: cut and never framed (false
  // outside the grid).
  bool Framed(double x, double y) const;
  bool Open(double x, double y) const;

  // Centres the grid at (x, y) in the site frame; cells that leave the grid are forgotten.
  void Recentre(double x, double y);
  // The cell holding site point (x, y); an unknown cell when outside the grid.
  Cell At(double x, double y) const;
  // Grid geometry for publishing/plotting: cell (i, j) covers
  // x in [origin_x + i*cell, +cell), y in [origin_y + j*cell, +cell); row-major i*cols + j.
  double origin_x() const { return origin_x_; }
  double origin_y() const { return origin_y_; }
  double cell_size() const { return options_.cell_size_m; }
  int rows() const { return n_; }
  int cols() const { return n_; }
  const std::vector<Cell>& cells() const;

  const MapOptions& options() const { return options_; }
  const UpdateStats& last_update() const { return stats_; }
  // Forgets every point.
  void Clear();

  // The moments of one cell's points (weights 1/sigma^2), kept across pairs.
  struct Accumulator {
    float n = 0;         // point count
    float sw = 0;        // sum of weights
    float sh = 0;        // weighted sum of elevation (m, up)
    float shh = 0;       // weighted sum of elevation^2
    float sx = 0, sy = 0;  // weighted sums of the offset from the cell centre (m)
    // Weighted second moments of the offset (dx, dy), and of the offset with the elevation:
    // the plane through the cell's own points (cell_plane_sigmas).
    float sxx = 0, sxy = 0, syy = 0, sxh = 0, syh = 0;
  };

 private:
  // Recomputes cells_ from acc_ when dirty: only the cells whose patches hold a cell whose
  // moments changed since the last rating (changed_), and those at the grid's edge after a
  // shift; the rest keep their ratings, which depend on nothing else.
  void Rate() const;
  // The cells without points (has_points 0) lying in a disc diameter_cells wide of such
  // cells (off the grid counts as without); empty when diameter_cells is 0 (hole_unknown_m).
  std::vector<char> CellsInHoles(const std::vector<char>& has_points, double diameter_cells) const;
  void MarkAllStale() const;
  // How far a cell's top stands over its mean (MapOptions::cell_plane_sigmas), from its
  // points' moments; 0 without a determined plane.
  static double CellPlaneRise(const Accumulator& a, double cell_m, double k_sigmas);

  MapOptions options_;
  int n_ = 0;  // cells per side
  double origin_x_ = 0, origin_y_ = 0;
  std::vector<Accumulator> acc_;
  // Per cell (crest_view_range_m): kFramed when some pair within range framed its column,
  // kCut when a pair put points in it without framing it.
  static constexpr std::uint8_t kFramed = 1, kCut = 2;
  std::vector<std::uint8_t> framed_;
  // Per cell (framed_height): the moments of the points put in it by pairs that framed it.
  struct FramedMoments {
    float n = 0, sw = 0, sh = 0;
    float best = -1e30f;  // the highest one pair's reading (kMax); -1e30: none yet
  };
  std::vector<FramedMoments> framed_acc_;
  // Adds the points that land in cells `framed_now` flags to framed_acc_.
  void AddFramedMoments(const std::vector<Eigen::Vector3d>& points_site, const std::vector<double>& sigma_m,
                        const std::vector<char>& framed_now);
  void MarkFramedBy(const RectifiedRig& rect, const geometry::Pose& T_site_rover, const MapOptions& stereo,
                    const std::vector<Eigen::Vector3d>& points_site, const std::vector<double>& sigma_m);
  std::uint8_t ViewAt(double x, double y) const;
  mutable std::vector<Cell> cells_;
  mutable bool dirty_ = true;
  // Since the last Rate: the cells whose moments changed (or entered the grid), whether the
  // grid moved once (its edge cells lost neighbours), or whether every cell must be rated.
  mutable std::vector<char> changed_;
  mutable bool shifted_ = false;
  mutable bool all_stale_ = true;
  UpdateStats stats_;
};

// Reads every MapOptions field (key names = field names); unknown keys are errors.
// Throws config::ConfigError "<where>: <key>: expected ..." on a bad value.
MapOptions LoadMapOptions(const config::ConfigNode& node);
MapOptions LoadMapOptions(const YAML::Node& node, const std::string& where);
// A camera's own options: `base` with the keys of `node` (only CameraOptionKeys; others are
// errors naming the allowed ones) set over it. Throws config::ConfigError as above.
MapOptions LoadCameraOptions(const config::ConfigNode& node, const MapOptions& base);
// Throws std::invalid_argument with a one-line message when an option is out of range.
void CheckMapOptions(const MapOptions& options);

}  // namespace rover::traversability
