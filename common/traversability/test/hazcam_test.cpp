// The front HAZCAM pair (configs/cameras/hazcam_front.yaml: a 124 deg equidistant fish-eye,
// 0.10 m baseline, 0.52 m up, 45 deg down) in the map, with known answers: its
// rectification onto a wide pinhole pair, and a rendered world with two 0.3 m rocks in the
// near field, one beside the front wheel and one just ahead of the body, that the mast's
// NAVCAM pair does not see. Options are hazard_monitor's own (configs/rover.yaml).
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

geometry::StereoRig HazcamRig() { return geometry::LoadStereoRigFile(kSource + "/configs/cameras/hazcam_front.yaml"); }

// hazard_monitor's map options, and its HAZCAM's own over them.
struct ShippedOptions {
  MapOptions map, hazcam;
};
ShippedOptions Shipped() {
  const config::ConfigNode map = config::ConfigNode::LoadFile(kSource + "/configs/rover.yaml")["hazards"]["map"];
  ShippedOptions o;
  o.map = LoadMapOptions(map["traversability"]);
  o.hazcam = LoadCameraOptions(map["hazcam"], o.map);
  return o;
}

// The rectified pixel of rover-frame point p in the left camera of r.
Eigen::Vector2d RectifiedPixel(const RectifiedRig& r, const Eigen::Vector3d& centre, const Eigen::Vector3d& p) {
  const Eigen::Vector3d q = r.R_rover_rect.transpose() * (p - centre);
  return {r.f * q.x() / q.z() + r.cx, r.f * q.y() / q.z() + r.cy};
}

// At 256 px the fish-eye's centre focal length is 118 px, whose pinhole spans 94 deg across
// the 256 columns; the ground beside the front wheel is 60 deg off the axis, outside it.
// With the field widened to the fish-eye's 124 deg the rectified image keeps that focal
// length over 444 columns, and its maps send every pixel to where the fish-eye sees it.
TEST(Hazcam, RectifiesTheFishEyeOntoAWidePinholePair) {
  const geometry::StereoRig rig = HazcamRig();
  const RectifiedRig narrow = Rectify(rig, 0.25);
  const RectifiedRig wide = Rectify(rig, 0.25, 124.0);
  const double f_fisheye = 512.0 / (62.0 * M_PI / 180.0) * 0.25;  // px per radian at 256 px
  EXPECT_NEAR(narrow.f, f_fisheye, 0.5);
  EXPECT_NEAR(wide.f, narrow.f, 1e-9);
  EXPECT_EQ(narrow.width, 256);
  EXPECT_NEAR(wide.width, 2 * wide.f * std::tan(62.0 * M_PI / 180.0), 1.0);
  EXPECT_EQ(wide.height, 256);
  EXPECT_NEAR(wide.baseline_m, 0.10, 1e-9);
  const Eigen::Vector3d beside_wheel(1.0, 0.9, 0.0), ahead(1.3, 0.0, 0.0), below(0.9, -0.3, 0.0);
  EXPECT_GT(RectifiedPixel(narrow, rig.left->Center(), beside_wheel).x(), narrow.width);
  for (const Eigen::Vector3d& p : {beside_wheel, ahead, below, Eigen::Vector3d(1.2, -0.9, 0.0)}) {
    const Eigen::Vector2d uL = RectifiedPixel(wide, rig.left->Center(), p);
    const Eigen::Vector2d uR = RectifiedPixel(wide, rig.right->Center(), p);
    EXPECT_NEAR(uL.y(), uR.y(), 1e-9);
    const int u = static_cast<int>(std::lround(uL.x())), v = static_cast<int>(std::lround(uL.y()));
    ASSERT_TRUE(u >= 0 && v >= 0 && u < wide.width && v < wide.height) << p.transpose() << ": " << uL.transpose();
    Eigen::Vector2d oL;
    ASSERT_TRUE(rig.left->Project(p, &oL));
    // Nearest rectified pixel, at a quarter size through two pyramid levels: within a
    // pixel of the source position (off the axis the pinhole stretches the fish-eye, so a
    // rectified pixel there spans less than a source pixel).
    EXPECT_NEAR(wide.map_lx.at<float>(v, u), (oL.x() + 0.5) * 0.25 - 0.5, 1.0) << p.transpose();
    EXPECT_NEAR(wide.map_ly.at<float>(v, u), (oL.y() + 0.5) * 0.25 - 0.5, 1.0) << p.transpose();
  }
  // The near field's disparities: a rock's top 0.2 m from the lenses along the axis is
  // f B / 0.2 px, within the shipped HAZCAM options' disparity range.
  EXPECT_LT(wide.f * wide.baseline_m / 0.2, Shipped().hazcam.num_disparities);
}

// Flat, textured ground with two 0.3 m rocks (0.4 m across) that only the HAZCAM sees: one
// ahead-left of the front wheel, beside the NAVCAM's view (1.2 m ahead, 0.8 m left), and one
// against the body's front (1.0 m ahead, its centre 0.2 m beyond the front face), under the
// NAVCAM's view. (Beside the front wheel itself, behind the front face, no camera on the
// body's front sees; nor does a rock's top 0.9 m to the side at 1.0 m, 69 deg off the
// fish-eye's axis, past its 62.) `%SUN%`: the sun.
const char* kNearRocks = R"(
name: near_rocks
seed: 21
map: {center: [4, 0], size_m: [24, 20], resolution_m: 0.02}
roughness: {amplitude_m: 0.005, min_wavelength_m: 0.2, max_wavelength_m: 3.0}
soil: {default: packed_soil}
rocks:
  placed:
    - {name: Beside, position: [1.2, -0.8], diameter_m: 0.4, height_m: 0.3}
    - {name: Ahead, position: [1.0, 0.25], diameter_m: 0.4, height_m: 0.3}
albedo:
  packed_soil: {mean: 0.28, contrast: 0.25}
sun: %SUN%
)";

struct Rock {
  const char* name;
  double x, y;
};
const Rock kRocks[] = {{"Beside", 1.2, -0.8}, {"Ahead", 1.0, 0.25}};

struct Scene {
  terrain::World world;
  geometry::Pose T;
  geometry::Matrix6d cov;
};
Scene NearRocks(const std::string& sun) {
  std::string text = kNearRocks;
  text.replace(text.find("%SUN%"), 5, sun);
  Scene s{terrain::World(terrain::WorldOptions::Load(config::ConfigNode::FromString(text, "near_rocks.yaml"))),
          geometry::Pose::Identity(), geometry::Matrix6d::Zero()};
  s.T = geometry::PoseFromXyzRpy(0, 0, -s.world.Elevation(0, 0), 0, 0, 0);
  s.cov.diagonal() << 1e-4, 1e-4, 1e-4, 1e-5, 1e-5, 1e-5;
  return s;
}

// The worst state among the cells within `reach` cells of (x, y).
CellState WorstNear(const TraversabilityMap& map, double x, double y, int reach) {
  CellState worst = CellState::kUnknown;
  for (int di = -reach; di <= reach; ++di)
    for (int dj = -reach; dj <= reach; ++dj) {
      const Cell c = map.At(x + di * map.cell_size(), y + dj * map.cell_size());
      if (c.state != CellState::kUnknown && (worst == CellState::kUnknown || c.state > worst)) worst = c.state;
    }
  return worst;
}

// Two suns: ahead of the rover, and behind it, where the body's shadow covers the ground
// in front (the renderer casts it; blank, dark ground there must not read as hazards).
TEST(Hazcam, SeesTheRocksBesideTheFrontWheelAndAheadOfTheBody) {
  // What the HAZCAM's stereo reads, not what the map may then hold back: with
  // open_cells_unknown the band at the view's sides whose tops one pair did not frame is
  // unknown until a later pair frames it (OpenCells tests); the rocks stay unsafe.
  ShippedOptions o = Shipped();
  o.map.open_cells_unknown = o.hazcam.open_cells_unknown = false;
  for (const std::string sun : {"{azimuth_deg: 30, elevation_deg: 55}", "{azimuth_deg: 190, elevation_deg: 40}"}) {
    SCOPED_TRACE(sun);
    const Scene s = NearRocks(sun);
    render::RenderOptions ro;
    ro.image_scale = 0.25;  // 1024 -> 256, as camera_capture renders it
    render::StereoRenderer renderer(ro);
    const render::StereoImages hazcam = renderer.RenderPair(s.world, HazcamRig(), s.T, 1);
    ASSERT_EQ(hazcam.left.cols, 256);

    TraversabilityMap map(o.map);
    map.AddStereoPair(hazcam.left, hazcam.right, hazcam.rig, s.T, s.cov, &o.hazcam);
    EXPECT_GT(map.last_update().points, 1500);
    // Each rock: its own cell or a neighbour unsafe.
    for (const auto& [name, x, y] : kRocks) EXPECT_EQ(WorstNear(map, x, y, 1), CellState::kUnsafe) << name;
    // Every unsafe cell is on a rock or its patch (the rock's radius, the patch's 0.3 m and
    // a cell); the open ground between and beside them is rated and safe.
    int unsafe = 0, safe = 0;
    const auto& cells = map.cells();
    for (int i = 0; i < map.rows(); ++i)
      for (int j = 0; j < map.cols(); ++j) {
        const Cell& c = cells[static_cast<std::size_t>(i) * map.cols() + j];
        const double x = map.origin_x() + (i + 0.5) * map.cell_size(), y = map.origin_y() + (j + 0.5) * map.cell_size();
        if (c.state == CellState::kSafe) ++safe;
        if (c.state != CellState::kUnsafe) continue;
        ++unsafe;
        double near = 1e9;
        for (const auto& [name, rx, ry] : kRocks) near = std::min(near, std::hypot(x - rx, y - ry));
        EXPECT_LT(near, 0.2 + 0.3 + 0.2) << "unsafe cell at " << x << ", " << y;
      }
    EXPECT_GE(unsafe, 4);
    EXPECT_GT(safe, 40);
    for (const auto& [x, y] : {std::pair{1.1, 0.9}, std::pair{1.7, -0.3}, std::pair{1.6, 0.9}, std::pair{1.5, 1.1},
                               std::pair{1.1, -0.3}})
      EXPECT_EQ(map.At(x, y).state, CellState::kSafe) << x << ", " << y;
    // Nothing behind the body's front face (min_x_m): the renderer draws no body, but a real
    // HAZCAM sees its own wheels and body there.
    for (double x = -0.8; x < 0.8; x += 0.2)
      for (double y = -1.4; y <= 1.4; y += 0.2) EXPECT_EQ(map.At(x + 0.1, y + 0.1).height_sigma_m, -1.0f) << x << ", " << y;

    // The NAVCAM pair alone, from the same pose, sees neither rock: no point in either
    // rock's cell, and nothing unsafe near them (a cell without points of its own is still
    // rated from the ground its patch saw, here the ground beyond the rock).
    render::RenderOptions rn;
    rn.image_scale = 0.5;
    render::StereoRenderer navcam_renderer(rn);
    const render::StereoImages navcam = navcam_renderer.RenderPair(
        s.world, geometry::LoadStereoRigFile(kSource + "/configs/cameras/navcam_pinhole.yaml"), s.T, 1);
    TraversabilityMap mast(o.map);
    mast.AddStereoPair(navcam.left, navcam.right, navcam.rig, s.T, s.cov);
    EXPECT_GT(mast.last_update().points, 2000);
    for (const auto& [name, x, y] : kRocks) {
      EXPECT_EQ(mast.At(x, y).height_sigma_m, -1.0f) << name;
      EXPECT_NE(WorstNear(mast, x, y, 1), CellState::kUnsafe) << name;
    }
    // With open cells unknown: never better, both rocks are still unsafe.
    ShippedOptions open = Shipped();
    open.map.open_cells_unknown = open.hazcam.open_cells_unknown = true;
    TraversabilityMap held(open.map);
    held.AddStereoPair(hazcam.left, hazcam.right, hazcam.rig, s.T, s.cov, &open.hazcam);
    for (const auto& [name, x, y] : kRocks) EXPECT_EQ(WorstNear(held, x, y, 1), CellState::kUnsafe) << name;
  }
}

// The rover's own shadow over the whole near field, its edge across the HAZCAM's view
// nearly along the rows (navbench k0.15_r04's start: the sun 64 deg up behind the rover's
// right, no rock within 1.6 m; ./rover navbench stopped there on "hazard_map: step 0.22 m").
// The edge is aliased into a staircase whose steps fall at unrelated columns in the two
// images, and SGBM matched the first rows inside the shadow to the wrong steps, 34 px off:
// an island of 3 to 4 rows by 40 columns whose points hang 0.33 m over the ground 0.8 m
// ahead. No surface of the ground or of a rock on it is such an island (a rock's face meets
// the ground its base stands on in disparities that change smoothly), and the HAZCAM's
// speckle filter (speckle_window 400: 100 at the fish-eye's scale, stretched up to 4 times
// by the rectified pinhole) drops it. Twelve frames (noise seeds) at that pose: no cell
// within 2 m unsafe; with the NAVCAM's window of 100 some are.
const char* kShadowedNearField = R"(
name: shadowed_near_field
seed: 387977
map: {center: [2, 0], size_m: [12, 10], resolution_m: 0.05}
roughness: {amplitude_m: 0.01, min_wavelength_m: 0.3, max_wavelength_m: 6.0}
soil: {default: packed_soil}
albedo:
  packed_soil: {mean: 0.28, contrast: 0.18}
sun: {azimuth_deg: 133.0, elevation_deg: 64.1}
)";

TEST(Hazcam, TheRoversShadowOverTheNearFieldIsNoHazard) {
  const ShippedOptions o = Shipped();
  const terrain::World world(terrain::WorldOptions::Load(config::ConfigNode::FromString(kShadowedNearField, "shadow.yaml")));
  const double yaw = -18.11 * M_PI / 180.0;
  const geometry::Pose T = geometry::PoseFromXyzRpy(0, 0, -world.Elevation(0, 0), 0, 0, yaw);
  geometry::Matrix6d cov = geometry::Matrix6d::Zero();
  cov.diagonal() << 4e-4, 4e-4, 4e-4, 7.6e-5, 7.6e-5, 7.6e-5;  // 0.02 m, 0.5 deg
  render::RenderOptions ro;
  ro.image_scale = 0.25;
  ro.rover_shadow = render::MastUnderRig(ro.rover_shadow, geometry::LoadStereoRigFile(kSource + "/configs/cameras/navcam_pinhole.yaml"));
  render::StereoRenderer renderer(ro);
  MapOptions small_window = o.hazcam;
  small_window.speckle_window = 100;
  int frames_unsafe_small_window = 0, rated = 0;
  // Unsafe cells within 2 m of the rover.
  auto unsafe_near = [](const TraversabilityMap& map, int* rated_cells) {
    int unsafe = 0;
    const auto& cells = map.cells();
    for (int i = 0; i < map.rows(); ++i)
      for (int j = 0; j < map.cols(); ++j) {
        const double x = map.origin_x() + (i + 0.5) * map.cell_size(), y = map.origin_y() + (j + 0.5) * map.cell_size();
        if (std::hypot(x, y) > 2.0) continue;
        const Cell& c = cells[static_cast<std::size_t>(i) * map.cols() + j];
        if (rated_cells && c.state != CellState::kUnknown) ++*rated_cells;
        unsafe += c.state == CellState::kUnsafe;
      }
    return unsafe;
  };
  for (int seed = 1; seed <= 12; ++seed) {
    const render::StereoImages hazcam = renderer.RenderPair(world, HazcamRig(), T, seed);
    TraversabilityMap map(o.map), before(o.map);
    map.AddStereoPair(hazcam.left, hazcam.right, hazcam.rig, T, cov, &o.hazcam);
    before.AddStereoPair(hazcam.left, hazcam.right, hazcam.rig, T, cov, &small_window);
    EXPECT_EQ(unsafe_near(map, &rated), 0) << "frame seed " << seed;
    frames_unsafe_small_window += unsafe_near(before, nullptr) > 0;
  }
  EXPECT_GT(rated, 12 * 30);  // the shadowed near field is seen and rated, not dropped
  EXPECT_GE(frames_unsafe_small_window, 2);
}

// The rectification cache holds both rigs: NAVCAM and HAZCAM pairs in turn build each once.
TEST(Hazcam, NavcamAndHazcamPairsInTurnRectifyEachRigOnce) {
  const ShippedOptions o = Shipped();
  const Scene s = NearRocks("{azimuth_deg: 30, elevation_deg: 55}");
  render::RenderOptions rh, rn;
  rh.image_scale = 0.25;
  rn.image_scale = 0.5;
  render::StereoRenderer hazcam_renderer(rh), navcam_renderer(rn);
  const render::StereoImages hazcam = hazcam_renderer.RenderPair(s.world, HazcamRig(), s.T, 1);
  const render::StereoImages navcam = navcam_renderer.RenderPair(
      s.world, geometry::LoadStereoRigFile(kSource + "/configs/cameras/navcam_pinhole.yaml"), s.T, 1);
  std::size_t points = 0;
  auto both = [&] {
    points += DenseStereo(navcam.left, navcam.right, navcam.rig, o.map).points_rover.size();
    points += DenseStereo(hazcam.left, hazcam.right, hazcam.rig, o.hazcam).points_rover.size();
  };
  const std::size_t before = RectificationsBuilt();
  both();  // builds both (unless an earlier test on this thread did)
  const std::size_t first = RectificationsBuilt();
  EXPECT_LE(first - before, 2u);
  both();
  both();
  EXPECT_EQ(RectificationsBuilt(), first);
  EXPECT_GT(points, 6000u);
  // A third rig (the HAZCAM's at another field) is built once more, and the first two stay.
  MapOptions narrow = o.hazcam;
  narrow.rectified_fov_deg = 0;
  DenseStereo(hazcam.left, hazcam.right, hazcam.rig, narrow);
  both();
  EXPECT_EQ(RectificationsBuilt(), first + 1);
}

// A camera's own section takes only the stereo keys, and says which when it meets another.
TEST(Hazcam, CameraOptionsTakeOnlyStereoKeys) {
  const MapOptions base;
  const MapOptions o = LoadCameraOptions(
      config::ConfigNode::FromString("{num_disparities: 64, max_range_m: 3.0, rectified_fov_deg: 124}", "h.yaml"), base);
  EXPECT_EQ(o.num_disparities, 64);
  EXPECT_EQ(o.max_range_m, 3.0);
  EXPECT_EQ(o.rectified_fov_deg, 124.0);
  EXPECT_EQ(o.cell_size_m, base.cell_size_m);
  try {
    LoadCameraOptions(config::ConfigNode::FromString("{cell_size_m: 0.1}", "h.yaml"), base);
    ADD_FAILURE() << "cell_size_m accepted in a camera's section";
  } catch (const config::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("cell_size_m"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("num_disparities"), std::string::npos) << e.what();
  }
  EXPECT_THROW(LoadCameraOptions(config::ConfigNode::FromString("{rectified_fov_deg: 175}", "h.yaml"), base),
               config::ConfigError);
  EXPECT_THROW(LoadCameraOptions(config::ConfigNode::FromString("{min_range_m: 4, max_range_m: 3}", "h.yaml"), base),
               config::ConfigError);
  MapOptions bad = base;
  bad.rectified_fov_deg = -1;
  EXPECT_THROW(CheckMapOptions(bad), std::invalid_argument);
  EXPECT_THROW(Rectify(HazcamRig(), 0.25, 180.0), std::invalid_argument);
}

}  // namespace
}  // namespace rover::traversability
