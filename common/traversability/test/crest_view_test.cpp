// Crests out of frame (MapOptions::crest_view_range_m), with known answers: a rock over the
// rover's step limit at the edge of the front HAZCAM's view shows its near flank and not
// its top, and the flank's cells read under the limit; with the option they are caution
// with their step at the limit (which the arc vote drives over only when nothing else is
// allowed). Seen whole, the same rock reads as before.
#include "traversability/dense_stereo.hpp"
#include "traversability/traversability_map.hpp"

#include "config/yaml_config.hpp"
#include "geometry/camera_io.hpp"
#include "geometry/pose.hpp"
#include "render/stereo_renderer.hpp"
#include "terrain/world.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace rover::traversability {
namespace {

const std::string kSource = ROVER_SOURCE_DIR;

struct ShippedOptions {
  MapOptions map, hazcam;
};
// hazard_monitor's options (configs/rover.yaml), with the crest rule as `range_m` sets it.
ShippedOptions Shipped(double range_m) {
  const config::ConfigNode map = config::ConfigNode::LoadFile(kSource + "/configs/rover.yaml")["hazards"]["map"];
  ShippedOptions o;
  o.map = LoadMapOptions(map["traversability"]);
  o.map.crest_view_range_m = range_m;
  o.map.open_cells_unknown = false;  // its own tests below
  o.map.unframed_unknown = false;    // likewise (UnframedCells): it needs the crest rule's range
  o.hazcam = LoadCameraOptions(map["hazcam"], o.map);
  return o;
}

// One rock of navbench k0.20_r03's size (0.316 m tall, 0.60 m across) on flat, textured
// ground at `%X%, %Y%`.
const char* kOneRock = R"(
name: one_rock
seed: 5
map: {center: [2, 0], size_m: [12, 10], resolution_m: 0.02}
roughness: {amplitude_m: 0.005, min_wavelength_m: 0.2, max_wavelength_m: 3.0}
soil: {default: packed_soil}
rocks:
  placed:
    - {name: Rock, position: [%X%, %Y%], diameter_m: 0.6, height_m: 0.316}
albedo:
  packed_soil: {mean: 0.28, contrast: 0.25}
sun: {azimuth_deg: 30, elevation_deg: 55}
)";

terrain::World OneRock(double x, double y) {
  std::string text = kOneRock;
  text.replace(text.find("%X%"), 3, std::to_string(x));
  text.replace(text.find("%Y%"), 3, std::to_string(y));
  return terrain::World(terrain::WorldOptions::Load(config::ConfigNode::FromString(text, "one_rock.yaml")));
}

// The HAZCAM pair and then the NAVCAM pair from each pose (x, y, yaw deg), into `map`.
void MapFrom(TraversabilityMap& map, const ShippedOptions& o, const terrain::World& world,
             const std::vector<Eigen::Vector3d>& poses) {
  render::RenderOptions rh;
  rh.image_scale = 0.25;
  render::StereoRenderer hazcam(rh);
  render::RenderOptions rn;
  rn.image_scale = 0.5;
  render::StereoRenderer navcam(rn);
  const geometry::StereoRig hrig = geometry::LoadStereoRigFile(kSource + "/configs/cameras/hazcam_front.yaml");
  const geometry::StereoRig nrig = geometry::LoadStereoRigFile(kSource + "/configs/cameras/navcam_pinhole.yaml");
  geometry::Matrix6d cov = geometry::Matrix6d::Zero();
  cov.diagonal() << 1e-4, 1e-4, 1e-4, 1e-5, 1e-5, 1e-5;
  int seed = 1;
  for (const Eigen::Vector3d& p : poses) {
    const geometry::Pose T =
        geometry::PoseFromXyzRpy(p.x(), p.y(), -world.Elevation(p.x(), p.y()), 0, 0, p.z() * M_PI / 180.0);
    map.Recentre(p.x(), p.y());
    const render::StereoImages h = hazcam.RenderPair(world, hrig, T, seed++);
    map.AddStereoPair(h.left, h.right, h.rig, T, cov, &o.hazcam);
    const render::StereoImages n = navcam.RenderPair(world, nrig, T, seed++);
    map.AddStereoPair(n.left, n.right, n.rig, T, cov);
  }
}

// The states of the cells within `radius` of (x, y): counts per state.
struct Census {
  int unknown = 0, safe = 0, caution = 0, unsafe = 0, crest_unseen = 0, with_points = 0;
  int good_caution = 0;  // caution cells whose step reads under the limit (0.25 m)
  double highest_step = 0;  // among the rated (known) cells
};
Census CellsNear(const TraversabilityMap& map, double x, double y, double radius) {
  Census c;
  const auto& cells = map.cells();
  for (int i = 0; i < map.rows(); ++i)
    for (int j = 0; j < map.cols(); ++j) {
      const double cx = map.origin_x() + (i + 0.5) * map.cell_size(), cy = map.origin_y() + (j + 0.5) * map.cell_size();
      if (std::hypot(cx - x, cy - y) > radius) continue;
      const Cell& cell = cells[static_cast<std::size_t>(i) * map.cols() + j];
      c.with_points += cell.height_sigma_m >= 0;
      c.crest_unseen += cell.crest_unseen;
      switch (cell.state) {
        case CellState::kUnknown: ++c.unknown; break;
        case CellState::kSafe: ++c.safe; break;
        case CellState::kCaution: ++c.caution, c.good_caution += cell.step_m < 0.25f; break;
        case CellState::kUnsafe: ++c.unsafe; break;
      }
      if (cell.state != CellState::kUnknown) c.highest_step = std::max<double>(c.highest_step, cell.step_m);
    }
  return c;
}

// The synthetic maps' options: 0.2 m cells over 6 m, a 0.3 m patch, the 0.25 m step limit.
MapOptions SyntheticOptions() {
  MapOptions o;
  o.cell_size_m = 0.2;
  o.extent_m = 6.0;
  o.footprint_radius_m = 0.3;
  o.max_step_m = 0.25;
  return o;
}

// Synthetic: level ground of known cells (x, y in [0, 2) m) and one cell at (1.1, 0.1)
// standing `rise_m` over it. Every cell is framed except, when `flank_open`, that one,
// which a pair saw without its top (cut).
TraversabilityMap Flank(double rise_m, bool flank_open, double range_m, bool open_unknown = false,
                        bool gap_beside = false) {
  MapOptions o = SyntheticOptions();
  o.open_cells_unknown = open_unknown;
  o.max_roughness_m = 0.2;  // the step alone rates these patches
  o.crest_view_range_m = range_m;
  TraversabilityMap map(o);
  std::vector<Eigen::Vector3d> pts;
  for (double x = 0.1; x < 2.0; x += 0.2)
    for (double y = -0.9; y < 1.0; y += 0.2) {
      // gap_beside: the cell next to the flank cell (1.3, 0.1) holds no points of its own.
      if (gap_beside && std::hypot(x - 1.3, y - 0.1) < 0.05) continue;
      const double h = std::hypot(x - 1.1, y - 0.1) < 0.05 ? rise_m : 0.0;
      for (int k = 0; k < 4; ++k) pts.emplace_back(x + 0.02 * (k % 2), y + 0.02 * (k / 2), -h);
    }
  map.AddPoints(pts, std::vector<double>(pts.size(), 0.01));
  for (double x = -1.9; x < 4.0; x += 0.2)
    for (double y = -2.9; y < 3.0; y += 0.2) {
      const bool flank = std::hypot(x - 1.1, y - 0.1) < 0.05;
      map.MarkView(x, y, 0.01, !(flank && flank_open));
    }
  return map;
}

// A 0.20 m flank cell (caution under the 0.25 m limit, goodness 0.2) that a pair saw
// without its top and none has framed: the cells whose patch holds it are caution with
// their step at the limit with the rule; framed (its top seen), they are as before.
TEST(CrestView, AFlankCellCutByTheFrameReadsTheStepLimit) {
  for (const bool on : {false, true}) {
    const TraversabilityMap map = Flank(0.20, true, on ? 3.0 : 0.0);
    EXPECT_TRUE(map.Open(1.1, 0.1));
    EXPECT_FALSE(map.Open(1.3, 0.1));
    EXPECT_TRUE(map.Framed(1.3, 0.1));
    for (const auto& [x, y] : {std::pair{1.1, 0.1}, std::pair{0.9, 0.1}, std::pair{1.1, 0.3}, std::pair{1.3, 0.1}}) {
      const Cell c = map.At(x, y);
      EXPECT_EQ(c.state, CellState::kCaution) << x << ", " << y << " on " << on;
      EXPECT_EQ(c.crest_unseen, on) << x << ", " << y;
      EXPECT_NEAR(c.goodness, 0.2, 0.03) << x << ", " << y;
      if (on)
        EXPECT_EQ(c.step_m, 0.25f) << x << ", " << y;
      else
        EXPECT_NEAR(c.step_m, 0.20, 0.01) << x << ", " << y;
    }
    // Beyond the patch (0.3 m) of the flank cell: level ground, safe either way.
    EXPECT_EQ(map.At(0.5, 0.1).state, CellState::kSafe);
    EXPECT_EQ(map.At(1.1, 0.7).state, CellState::kSafe);
  }
  const TraversabilityMap framed = Flank(0.20, false, 3.0);
  EXPECT_FALSE(framed.Open(1.1, 0.1));
  EXPECT_EQ(framed.At(1.1, 0.1).state, CellState::kCaution);
  EXPECT_NEAR(framed.At(1.1, 0.1).goodness, 0.2, 0.03);
  EXPECT_FALSE(framed.At(1.1, 0.1).crest_unseen);
}

// Never better than without the rule: an unsafe step stays unsafe, and a cell rising under
// crest_rise_fraction of the limit (0.10 m, a cobble) beside unframed ground reads as before.
TEST(CrestView, UnsafeStaysUnsafeAndLowGroundIsUnchanged) {
  EXPECT_EQ(Flank(0.30, true, 3.0).At(1.1, 0.1).state, CellState::kUnsafe);
  const TraversabilityMap low = Flank(0.10, true, 3.0), off = Flank(0.10, true, 0.0);
  for (const auto& [x, y] : {std::pair{1.1, 0.1}, std::pair{0.9, 0.1}, std::pair{1.1, 0.3}}) {
    EXPECT_EQ(low.At(x, y).state, off.At(x, y).state) << x << ", " << y;
    EXPECT_EQ(low.At(x, y).goodness, off.At(x, y).goodness) << x << ", " << y;
    EXPECT_EQ(low.At(x, y).step_m, off.At(x, y).step_m) << x << ", " << y;
    EXPECT_FALSE(low.At(x, y).crest_unseen) << x << ", " << y;
  }
  // Options out of range are refused.
  MapOptions bad;
  bad.crest_rise_fraction = 0.0;
  EXPECT_THROW(TraversabilityMap{bad}, std::invalid_argument);
}

// The rock 1.6 m ahead and 1.4 m to the left (and 1.5 m ahead, 1.3 m to the right), seen
// from the start by the HAZCAM at the edge of its view (its top out of the frame) and not
// by the NAVCAM: without the rule its cells read 0.17 to 0.20 m, caution, none unsafe (the
// collision's class); with it every caution cell within 0.5 m of the rock reads its step
// at the limit, and the rock's crest's cells too. Turned toward it, both pairs frame it, and it reads
// unsafe with the rule as without.
TEST(CrestView, ARockAtTheHazcamsEdgeReadsTheStepLimitUntilFramed) {
  for (const auto& [x, y] : {std::pair{1.6, 1.4}, std::pair{1.5, -1.3}}) {
    SCOPED_TRACE(std::to_string(x) + ", " + std::to_string(y));
    const terrain::World world = OneRock(x, y);
    TraversabilityMap off(Shipped(0.0).map), on(Shipped(3.0).map);
    MapFrom(off, Shipped(0.0), world, {{0, 0, 0}});
    MapFrom(on, Shipped(3.0), world, {{0, 0, 0}});
    const Census before = CellsNear(off, x, y, 0.5), after = CellsNear(on, x, y, 0.5);
    EXPECT_GE(before.caution, 3);
    EXPECT_EQ(before.unsafe, 0);
    EXPECT_GE(before.with_points, 4);  // its flank was seen
    EXPECT_GE(before.good_caution, 3);
    EXPECT_EQ(after.good_caution, 0);
    EXPECT_EQ(after.unsafe, 0);
    EXPECT_GE(after.crest_unseen, before.caution);
    const Census crest = CellsNear(on, x, y, 0.15);
    EXPECT_EQ(crest.safe + crest.good_caution, 0);
    // Turned toward it: framed, unsafe.
    TraversabilityMap looked(Shipped(3.0).map);
    MapFrom(looked, Shipped(3.0), world, {{0, 0, std::atan2(y, x) * 180.0 / M_PI}});
    const Census seen = CellsNear(looked, x, y, 0.5);
    EXPECT_GE(seen.unsafe, 4);
    EXPECT_EQ(seen.crest_unseen, 0);
  }
}

// Seen whole, straight ahead at 1.7 m: every cell of the map as without the rule.
TEST(CrestView, ARockSeenWholeReadsAsBefore) {
  const terrain::World world = OneRock(1.7, 0.0);
  TraversabilityMap off(Shipped(0.0).map), on(Shipped(3.0).map);
  MapFrom(off, Shipped(0.0), world, {{0, 0, 0}});
  MapFrom(on, Shipped(3.0), world, {{0, 0, 0}});
  ASSERT_EQ(off.cells().size(), on.cells().size());
  int rated = 0;
  for (std::size_t k = 0; k < off.cells().size(); ++k) {
    EXPECT_EQ(off.cells()[k].state, on.cells()[k].state) << k;
    rated += off.cells()[k].state != CellState::kUnknown;
  }
  EXPECT_GT(rated, 200);
  EXPECT_GE(CellsNear(on, 1.7, 0.0, 0.5).unsafe, 8);
}

// open_cells_unknown: an open cell is unknown however low it reads (a rock's foot seen
// without its top read 0.03 to 0.05 m), and keeps its own height for the clearance model;
// a cell with no points of its own beside it is still rated from its patch (most such are
// the ground behind a rock); every other cell reads as without the option, and once framed
// the open cell is rated again. An unsafe open cell stays unsafe.
TEST(OpenCells, AnOpenCellIsUnknownUntilFramed) {
  const TraversabilityMap off = Flank(0.05, true, 3.0, false, true);
  const TraversabilityMap on = Flank(0.05, true, 3.0, true, true);
  EXPECT_EQ(off.At(1.1, 0.1).state, CellState::kSafe);  // the foot of a rock reads low
  EXPECT_EQ(on.At(1.1, 0.1).state, CellState::kUnknown);
  EXPECT_EQ(on.At(1.1, 0.1).elevation_m, off.At(1.1, 0.1).elevation_m);
  EXPECT_GE(on.At(1.1, 0.1).height_sigma_m, 0.0f);
  EXPECT_LT(off.At(1.3, 0.1).height_sigma_m, 0.0f);      // no points of its own
  EXPECT_EQ(on.At(1.3, 0.1).state, CellState::kSafe);    // rated from its patch, as before
  int same = 0, changed = 0;
  for (std::size_t k = 0; k < off.cells().size(); ++k) {
    const bool eq = off.cells()[k].state == on.cells()[k].state && off.cells()[k].step_m == on.cells()[k].step_m;
    (eq ? same : changed) += 1;
  }
  EXPECT_EQ(changed, 1);
  EXPECT_GT(same, 80);
  EXPECT_EQ(Flank(0.30, true, 3.0, true).At(1.1, 0.1).state, CellState::kUnsafe);
  // Framed, the cell is rated as without the option.
  const TraversabilityMap framed = Flank(0.05, false, 3.0, true, true);
  EXPECT_EQ(framed.At(1.1, 0.1).state, CellState::kSafe);
  // Without the crest view (range 0) there are no open cells: the option does nothing.
  EXPECT_EQ(Flank(0.05, true, 0.0, true, true).At(1.1, 0.1).state, CellState::kSafe);
}

// A rendered rock seen whole, straight ahead at 1.7 m: its cells are framed, so the option
// changes none of them (it holds back only what no pair framed), and the rock is unsafe.
// The orbit that showed a rock only its foot (navbench seed 11 k0.15_r03) is measured in
// common/traversability/README.md ("A rock kept beside the view"): a one-rock scene from
// a few poses did not reproduce it, the crest rule already rating such a rock's cells.
TEST(OpenCells, ARockSeenWholeReadsAsBefore) {
  const terrain::World world = OneRock(1.7, 0.0);
  ShippedOptions with = Shipped(6.0);
  with.map.open_cells_unknown = with.hazcam.open_cells_unknown = true;
  TraversabilityMap off(Shipped(6.0).map), on(with.map);
  MapFrom(off, Shipped(6.0), world, {{0, 0, 0}});
  MapFrom(on, with, world, {{0, 0, 0}});
  int compared = 0;
  for (double x = 1.1; x <= 2.3; x += 0.2)
    for (double y = -0.6; y <= 0.6; y += 0.2) {
      EXPECT_EQ(off.At(x, y).state, on.At(x, y).state) << x << ", " << y;
      EXPECT_EQ(off.At(x, y).step_m, on.At(x, y).step_m) << x << ", " << y;
      ++compared;
    }
  EXPECT_GE(compared, 30);
  EXPECT_GE(CellsNear(on, 1.7, 0.0, 0.5).unsafe, 8);
  // The view's sides, cut by its frame, are held back: some cells there are unknown.
  EXPECT_GT(CellsNear(on, 0.0, 0.0, 6.0).unknown, CellsNear(off, 0.0, 0.0, 6.0).unknown);
}

// Level ground with points in every 0.2 m cell but a hole: the 3 x 3 cells round (1.1, 0.1)
// (`hole` true) or that one cell alone (a speck of bland sand).
// `framed` (unframed_unknown on, with the crest rule): every cell within 3 m of the origin
// framed (a pair looked at it), or none.
enum class View { kNone, kUnframed, kFramed };
TraversabilityMap Holed(bool hole, double hole_unknown_m, View view = View::kNone) {
  MapOptions o = SyntheticOptions();
  o.hole_unknown_m = hole_unknown_m;
  if (view != View::kNone) {
    o.crest_view_range_m = 6.0;
    o.unframed_unknown = true;
  }
  TraversabilityMap map(o);
  if (view == View::kFramed) map.MarkView(0.0, 0.0, 3.0, true);
  std::vector<Eigen::Vector3d> pts;
  for (double x = 0.1; x < 2.6; x += 0.2)
    for (double y = -1.1; y < 1.4; y += 0.2) {
      const double d = std::max(std::abs(x - 1.1), std::abs(y - 0.1));
      if (d < (hole ? 0.25 : 0.05)) continue;
      for (int k = 0; k < 4; ++k) pts.emplace_back(x + 0.02 * (k % 2), y + 0.02 * (k / 2), 0.0);
    }
  map.AddPoints(pts, std::vector<double>(pts.size(), 0.01));
  return map;
}

TEST(HoleCells, ACellWithoutPointsInAHoleWideEnoughForARockIsUnknown) {
  const TraversabilityMap off = Holed(true, 0.0), on = Holed(true, 0.6);
  // Without the option the hole's edge cells are rated from the ground round them.
  int rated_off = 0, rated_on = 0, hole_cells = 0;
  for (double x = 0.9; x < 1.4; x += 0.2)
    for (double y = -0.1; y < 0.4; y += 0.2) {
      ++hole_cells;
      EXPECT_LT(off.At(x, y).height_sigma_m, 0.0f) << x << ", " << y;  // no points of its own
      rated_off += off.At(x, y).state != CellState::kUnknown;
      rated_on += on.At(x, y).state != CellState::kUnknown;
    }
  EXPECT_EQ(hole_cells, 9);
  EXPECT_GE(rated_off, 8);  // all but the centre, whose patch holds no points at all
  EXPECT_EQ(rated_on, 0);
  // The ground round it, with points, reads as before.
  for (double x = 0.5; x < 1.8; x += 0.2)
    for (double y = -0.5; y < 0.8; y += 0.2) {
      if (std::max(std::abs(x - 1.1), std::abs(y - 0.1)) < 0.25) continue;
      EXPECT_EQ(on.At(x, y).state, off.At(x, y).state) << x << ", " << y;
      EXPECT_EQ(on.At(x, y).state, CellState::kSafe) << x << ", " << y;
    }
  // A speck (one cell without points) is no hole: rated from its patch, with or without.
  EXPECT_EQ(Holed(false, 0.6).At(1.1, 0.1).state, CellState::kSafe);
  EXPECT_LT(Holed(false, 0.6).At(1.1, 0.1).height_sigma_m, 0.0f);
}


// unframed_unknown: the same hole, never framed, is unknown; framed (a pair looked at it and
// found no points: the ground hidden behind a rock, bland sand), it keeps its patch rating.
TEST(UnframedCells, ACellWithoutPointsThatNoPairFramedIsUnknown) {
  const TraversabilityMap off = Holed(true, 0.0), unframed = Holed(true, 0.0, View::kUnframed),
                          framed = Holed(true, 0.0, View::kFramed);
  int rated_off = 0, rated_unframed = 0, rated_framed = 0;
  for (double x = 0.9; x < 1.4; x += 0.2)
    for (double y = -0.1; y < 0.4; y += 0.2) {
      ASSERT_LT(off.At(x, y).height_sigma_m, 0.0f) << x << ", " << y;  // no points of its own
      rated_off += off.At(x, y).state != CellState::kUnknown;
      rated_unframed += unframed.At(x, y).state != CellState::kUnknown;
      rated_framed += framed.At(x, y).state != CellState::kUnknown;
      EXPECT_EQ(framed.At(x, y).state, off.At(x, y).state) << x << ", " << y;
    }
  EXPECT_GE(rated_off, 8);
  EXPECT_EQ(rated_framed, rated_off);
  EXPECT_EQ(rated_unframed, 0);
  // Cells with points of their own read as before, framed or not; so does a lone speck
  // without points once framed, and unframed it is unknown too (nothing looked at it).
  for (double x = 0.5; x < 1.8; x += 0.2)
    for (double y = -0.5; y < 0.8; y += 0.2) {
      if (std::max(std::abs(x - 1.1), std::abs(y - 0.1)) < 0.25) continue;
      EXPECT_EQ(unframed.At(x, y).state, CellState::kSafe) << x << ", " << y;
    }
  EXPECT_EQ(Holed(false, 0.0, View::kFramed).At(1.1, 0.1).state, CellState::kSafe);
  EXPECT_EQ(Holed(false, 0.0, View::kUnframed).At(1.1, 0.1).state, CellState::kUnknown);
}

}  // namespace
}  // namespace rover::traversability
