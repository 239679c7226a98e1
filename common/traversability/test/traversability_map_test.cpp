// The traversability map on synthetic data with known answers: point clouds of flat ground,
// a tilted plane, a box rock of known height, noise; and a rendered scene with a rock.
#include "traversability/dense_stereo.hpp"
#include "traversability/traversability_map.hpp"

#include "config/yaml_config.hpp"
#include "geometry/camera_io.hpp"
#include "geometry/pose.hpp"
#include "render/stereo_renderer.hpp"
#include "terrain/world.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <cstdio>
#include <functional>
#include <random>
#include <tuple>

namespace rover::traversability {
namespace {

constexpr double kDeg = M_PI / 180.0;

// A dense point cloud (10 per cell) of the elevation function over +-r around (cx, cy).
void AddSurface(TraversabilityMap* map, const std::function<double(double, double)>& elevation,
                double cx, double cy, double r, double noise = 0.0, unsigned seed = 1) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  std::vector<Eigen::Vector3d> pts;
  for (double x = cx - r; x < cx + r; x += 0.06)
    for (double y = cy - r; y < cy + r; y += 0.06)
      pts.emplace_back(x, y, -(elevation(x, y) + noise * n(rng)));
  map->AddPoints(pts, std::vector<double>(pts.size(), std::max(noise, 0.01)));
}

TEST(TraversabilityMap, FlatGroundIsSafeAndUnseenGroundUnknown) {
  TraversabilityMap map(MapOptions{});
  AddSurface(&map, [](double, double) { return 0.3; }, 2.0, 0.0, 1.5);
  const Cell c = map.At(2.0, 0.0);
  EXPECT_EQ(c.state, CellState::kSafe);
  EXPECT_NEAR(c.step_m, 0.0, 1e-4);
  EXPECT_NEAR(c.tilt_rad, 0.0, 1e-4);
  EXPECT_NEAR(c.roughness_m, 0.0, 1e-4);
  EXPECT_NEAR(c.goodness, 1.0, 1e-3);
  EXPECT_EQ(map.At(-4.0, 4.0).state, CellState::kUnknown);   // in the grid, no data
  EXPECT_EQ(map.At(100.0, 0.0).state, CellState::kUnknown);  // outside the grid
}

TEST(TraversabilityMap, TiltOfAPlaneIsMeasured) {
  MapOptions o;
  o.max_tilt_deg = 20.0;
  for (double deg : {10.0, 25.0}) {
    TraversabilityMap map(o);
    const double g = std::tan(deg * kDeg);
    // Rising toward north-east.
    AddSurface(&map, [g](double x, double y) { return g * (x + y) / std::sqrt(2.0); }, 1.0, 1.0, 1.5);
    const Cell c = map.At(1.0, 1.0);
    EXPECT_NEAR(c.tilt_rad / kDeg, deg, 0.05);
    EXPECT_NEAR(c.step_m, 0.0, 1e-3);
    EXPECT_EQ(c.state, deg < 20.0 * o.caution_fraction ? CellState::kSafe
                       : deg < 20.0                   ? CellState::kCaution
                                                      : CellState::kUnsafe)
        << deg;
  }
}

TEST(TraversabilityMap, BoxRockStepHeightAndFootprint) {
  // A 0.4 m box of 0.4 m height on a 10 deg slope: the cells within the footprint radius of
  // the box see a step of 0.4 m (the plane stays on the ground), the cells beyond do not.
  MapOptions o;
  TraversabilityMap map(o);
  const double g = std::tan(10 * kDeg);
  auto ground = [g](double x, double) { return g * x; };
  auto scene = [&](double x, double y) {
    return ground(x, y) + ((std::abs(x - 3.0) < 0.2 && std::abs(y) < 0.2) ? 0.4 : 0.0);
  };
  AddSurface(&map, scene, 3.0, 0.0, 2.5);
  const Cell on = map.At(3.0, 0.0);
  EXPECT_EQ(on.state, CellState::kUnsafe);
  EXPECT_NEAR(on.step_m, 0.4, 0.02);
  EXPECT_NEAR(on.tilt_rad / kDeg, 10.0, 0.5);  // the ground's tilt, not the rock's
  const Cell beside = map.At(3.0, 0.6);        // the box edge is 0.4 m away: in the patch
  EXPECT_EQ(beside.state, CellState::kUnsafe);
  const Cell far = map.At(3.0, 1.5);  // over 1 m from the box
  EXPECT_NE(far.state, CellState::kUnsafe);
  EXPECT_NEAR(far.step_m, 0.0, 0.01);
  // A box under the limit is not a hazard.
  TraversabilityMap low(o);
  AddSurface(&low, [&](double x, double y) {
    return ground(x, y) + ((std::abs(x - 3.0) < 0.2 && std::abs(y) < 0.2) ? 0.08 : 0.0);
  }, 3.0, 0.0, 2.5);
  EXPECT_NE(low.At(3.0, 0.0).state, CellState::kUnsafe);
  EXPECT_NEAR(low.At(3.0, 0.0).step_m, 0.08, 0.01);
}

TEST(TraversabilityMap, RoughnessFromNoiseAndTooFewPointsIsUnknown) {
  MapOptions o;
  o.min_points = 3;
  TraversabilityMap map(o);
  // Bumps of +-0.1 m in a checkerboard of cells: RMS 0.1 m, over the 0.05 m limit.
  AddSurface(&map, [](double x, double y) {
    const int i = static_cast<int>(std::floor(x / 0.2)), j = static_cast<int>(std::floor(y / 0.2));
    return ((i + j) % 2 == 0) ? 0.05 : -0.05;
  }, 2.0, 0.0, 1.5);
  const Cell c = map.At(2.1, 0.1);
  EXPECT_NEAR(c.roughness_m, 0.05, 0.01);
  // One point per cell is below min_points.
  TraversabilityMap sparse(o);
  std::vector<Eigen::Vector3d> pts;
  for (double x = 0.1; x < 3; x += 0.2)
    for (double y = -1.5; y < 1.5; y += 0.2) pts.emplace_back(x, y, 0.0);
  sparse.AddPoints(pts, std::vector<double>(pts.size(), 0.01));
  EXPECT_EQ(sparse.At(1.5, 0.0).state, CellState::kUnknown);
  EXPECT_THROW(sparse.AddPoints(pts, {0.01}), std::invalid_argument);
}

TEST(TraversabilityMap, SigmaIsTheCellsPointSigmaAndRecentreForgets) {
  TraversabilityMap map(MapOptions{});
  std::vector<Eigen::Vector3d> pts;
  std::vector<double> sig;
  for (double x = 0.5; x < 3.5; x += 0.05)
    for (double y = -1.0; y < 1.0; y += 0.05) {
      pts.emplace_back(x, y, 0.0);
      sig.push_back(0.01 + 0.02 * x);  // grows with range
    }
  map.AddPoints(pts, sig);
  EXPECT_LT(map.At(1.0, 0.0).sigma_m, map.At(3.0, 0.0).sigma_m);
  EXPECT_NEAR(map.At(3.0, 0.0).sigma_m, 0.01 + 0.02 * 3.0, 0.005);
  // The cell at (1, 0) leaves a 14 m grid re-centred 9 m away; (3, 0) stays.
  map.Recentre(-9.0, 0.0);
  EXPECT_EQ(map.At(1.0, 0.0).state, CellState::kUnknown);
  map.Recentre(-5.0, 0.0);
  EXPECT_EQ(map.At(-1.0, 0.0).state, CellState::kUnknown);
  TraversabilityMap kept(MapOptions{});
  kept.AddPoints(pts, sig);
  kept.Recentre(1.0, 0.0);  // whole cells move, nothing is resampled
  EXPECT_EQ(kept.At(2.0, 0.0).state, CellState::kSafe);
  EXPECT_NEAR(kept.At(2.0, 0.0).sigma_m, 0.01 + 0.02 * 2.1, 0.005);
}

TEST(TraversabilityMap, OptionsFromYamlAndBadInput) {
  const config::ConfigNode node = config::ConfigNode::FromString(
      "cell_size_m: 0.25\nmax_step_m: 0.15\nstereo_width_px: 256\n", "test.yaml");
  const MapOptions o = LoadMapOptions(node);
  EXPECT_DOUBLE_EQ(o.cell_size_m, 0.25);
  EXPECT_DOUBLE_EQ(o.max_step_m, 0.15);
  EXPECT_EQ(o.stereo_width_px, 256);
  EXPECT_THROW(LoadMapOptions(config::ConfigNode::FromString("max_stepp: 1\n", "t.yaml")),
               config::ConfigError);
  EXPECT_THROW(LoadMapOptions(config::ConfigNode::FromString("block_size: 4\n", "t.yaml")),
               config::ConfigError);
  try {
    LoadMapOptions(YAML::Load("cell_size_m: -1"), "rover.yaml: traversability");
    FAIL();
  } catch (const config::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("cell_size_m"), std::string::npos) << e.what();
  }
  MapOptions bad;
  bad.cell_size_m = 0;
  EXPECT_THROW(TraversabilityMap{bad}, std::invalid_argument);

  TraversabilityMap map(MapOptions{});
  const geometry::StereoRig rig = geometry::LoadStereoRigFile(
      std::string(ROVER_SOURCE_DIR) + "/configs/cameras/navcam_pinhole.yaml");
  const cv::Mat small(10, 10, CV_8UC1, cv::Scalar(0));
  const cv::Mat full(1024, 1024, CV_8UC1, cv::Scalar(0));
  const cv::Mat colour(1024, 1024, CV_8UC3, cv::Scalar(0, 0, 0));
  const geometry::Pose T = geometry::Pose::Identity();
  const geometry::Matrix6d cov = geometry::Matrix6d::Identity() * 1e-4;
  EXPECT_THROW(map.AddStereoPair(small, small, rig, T, cov), std::invalid_argument);
  EXPECT_THROW(map.AddStereoPair(colour, full, rig, T, cov), std::invalid_argument);
  EXPECT_THROW(map.AddStereoPair(cv::Mat(), full, rig, T, cov), std::invalid_argument);
  geometry::Matrix6d nan_cov = cov;
  nan_cov(0, 0) = NAN;
  EXPECT_THROW(map.AddStereoPair(full, full, rig, T, nan_cov), std::invalid_argument);
}

// The rectification of a CAHVOR rig with real distortion: a 3-D point projects (through the
// original models) to pixels whose rectified positions lie on one row, with the disparity
// f B / z of the rectified pair.
TEST(DenseStereo, RectifiesACahvorRigOntoCommonRows) {
  const geometry::StereoRig base = geometry::LoadStereoRigFile(
      std::string(ROVER_SOURCE_DIR) + "/configs/cameras/navcam_cahvor.yaml");
  std::vector<double> pl = base.left->Params(), pr = base.right->Params();
  pl[15] = pr[15] = 0.0;   // R0
  pl[16] = pr[16] = -0.02; // R1: barrel distortion of a real NAVCAM's order
  pl[17] = pr[17] = 0.01;  // R2
  geometry::StereoRig rig;
  rig.left = geometry::CameraModelFromParams("cahvor", 1024, 1024, pl);
  rig.right = geometry::CameraModelFromParams("cahvor", 1024, 1024, pr);
  const RectifiedRig r = Rectify(rig, 0.5);
  EXPECT_EQ(r.width, 512);
  EXPECT_NEAR(r.baseline_m, 0.2, 1e-9);
  for (const Eigen::Vector3d& p : {Eigen::Vector3d(3.0, 0.5, 0.0), Eigen::Vector3d(5.0, -1.0, -0.3),
                                  Eigen::Vector3d(2.0, -0.4, 0.1)}) {
    // Rectified pixel of p in each camera (pinholes along R_rover_rect).
    const Eigen::Vector3d qL = r.R_rover_rect.transpose() * (p - rig.left->Center());
    const Eigen::Vector3d qR = r.R_rover_rect.transpose() * (p - rig.right->Center());
    const Eigen::Vector2d uL(r.f * qL.x() / qL.z() + r.cx, r.f * qL.y() / qL.z() + r.cy);
    const Eigen::Vector2d uR(r.f * qR.x() / qR.z() + r.cx, r.f * qR.y() / qR.z() + r.cy);
    EXPECT_NEAR(uL.y(), uR.y(), 1e-9);
    EXPECT_NEAR(uL.x() - uR.x(), r.f * r.baseline_m / qL.z(), 1e-9);
    // The maps send those rectified pixels to where the original models project p (at
    // half size, through one pyramid level).
    Eigen::Vector2d oL;
    ASSERT_TRUE(rig.left->Project(p, &oL));
    const int u = static_cast<int>(std::lround(uL.x())), v = static_cast<int>(std::lround(uL.y()));
    ASSERT_TRUE(u >= 0 && v >= 0 && u < r.width && v < r.height);
    // Nearest rectified pixel: within a pixel of the source position.
    EXPECT_NEAR(r.map_lx.at<float>(v, u), (oL.x() + 0.5) * 0.5 - 0.5, 1.0);
    EXPECT_NEAR(r.map_ly.at<float>(v, u), (oL.y() + 0.5) * 0.5 - 0.5, 1.0);
  }
}

// A rendered scene: flat textured ground and one rock 0.35 m tall 3 m ahead. The map built
// from the stereo pair marks the rock unsafe with a step near its height and the open ground
// 1.3 m beside it safe; sigma grows with range; and the triangulated points, carried into
// the site frame, lie on the world's surface (median height error under 2 cm within 4 m).
TEST(DenseStereo, RenderedRockIsUnsafeAndGroundIsSafe) {
  const config::ConfigNode root = config::ConfigNode::FromString(R"(
name: one_rock
seed: 5
map: {center: [4, 0], size_m: [12, 10], resolution_m: 0.05}
roughness: {amplitude_m: 0.005, min_wavelength_m: 0.3, max_wavelength_m: 4.0}
soil: {default: packed_soil}
rocks:
  placed:
    - {name: R, position: [3.0, 0.3], diameter_m: 0.6, height_m: 0.35}
albedo:
  packed_soil: {mean: 0.28, contrast: 0.2}
sun: {azimuth_deg: 120, elevation_deg: 55}
)", "one_rock.yaml");
  const terrain::World world(terrain::WorldOptions::Load(root));
  const geometry::StereoRig rig = geometry::LoadStereoRigFile(
      std::string(ROVER_SOURCE_DIR) + "/configs/cameras/navcam_pinhole.yaml");
  render::RenderOptions ro;
  ro.image_scale = 0.5;
  render::StereoRenderer renderer(ro);
  const geometry::Pose T = geometry::PoseFromXyzRpy(0, 0, -world.Elevation(0, 0), 0, 0, 0);
  const render::StereoImages images = renderer.RenderPair(world, rig, T, 1);
  TraversabilityMap map(MapOptions{});
  geometry::Matrix6d cov = geometry::Matrix6d::Zero();
  cov.diagonal() << 1e-4, 1e-4, 1e-4, 1e-5, 1e-5, 1e-5;
  map.AddStereoPair(images.left, images.right, images.rig, T, cov);
  EXPECT_GT(map.last_update().points, 10000);
  const Cell rock = map.At(3.0, 0.3);
  EXPECT_EQ(rock.state, CellState::kUnsafe);
  EXPECT_NEAR(rock.step_m, 0.35, 0.08);
  const Cell open = map.At(3.0, -1.0);
  EXPECT_EQ(open.state, CellState::kSafe);
  EXPECT_LT(open.step_m, 0.1);
  EXPECT_LT(open.tilt_rad, 5 * kDeg);
  // Sigma grows with range.
  EXPECT_LT(map.At(2.0, -0.5).sigma_m, map.At(5.0, -0.5).sigma_m);

  const StereoPoints sp = DenseStereo(images.left, images.right, images.rig, MapOptions{});
  std::vector<double> err;
  for (const Eigen::Vector3d& pr : sp.points_rover) {
    const Eigen::Vector3d p = T * pr;
    if (std::hypot(p.x(), p.y()) > 4.0) continue;
    err.push_back(std::abs(-p.z() - world.ElevationDetailed(p.x(), p.y())));
  }
  ASSERT_GT(err.size(), 5000u);
  std::nth_element(err.begin(), err.begin() + err.size() / 2, err.end());
  EXPECT_LT(err[err.size() / 2], 0.02);
}

// The body's tilt over tilt_radius_m: a uniform slope under the limit with ripples a
// wheel patch reads steeper is safe; the face is how much steeper the wheel patch is than
// the body's plane, rated against max_face_deg; the options load from YAML.
TEST(TraversabilityMap, TiltOverTheRoversSizeAndAFaceUnderOneWheel) {
  MapOptions o;
  o.footprint_radius_m = 0.3;
  o.max_tilt_deg = 30.0;
  o.max_step_m = 0.25;
  o.tilt_radius_m = 0.75;
  o.max_face_deg = 25.0;
  const double g = std::tan(27.0 * kDeg);
  // 27 deg with 4 cm ripples of 1 m wavelength along the slope: up to ~41 deg locally.
  auto rippled = [g](double x, double) { return g * x + 0.04 * std::sin(2 * M_PI * x); };
  {
    TraversabilityMap wheel_only([&] { MapOptions w = o; w.tilt_radius_m = 0; w.max_face_deg = 0; return w; }());
    AddSurface(&wheel_only, rippled, 3.0, 0.0, 2.0);
    TraversabilityMap body(o);
    AddSurface(&body, rippled, 3.0, 0.0, 2.0);
    int wheel_unsafe = 0, body_unsafe = 0;
    for (double x = 2.0; x <= 4.0; x += 0.2) {
      wheel_unsafe += wheel_only.At(x, 0.0).state == CellState::kUnsafe;
      const Cell c = body.At(x, 0.0);
      body_unsafe += c.state == CellState::kUnsafe;
      EXPECT_NEAR(c.tilt_rad / kDeg, 27.0, 1.5) << x;
    }
    EXPECT_GT(wheel_unsafe, 0);  // the ripples' faces pass 30 deg in a wheel patch
    EXPECT_EQ(body_unsafe, 0);   // the body stands at 27 deg, within the rover's limit
  }
  {
    // The same ripples on level ground: the body stands level, so the face is the wheel
    // patch's own tilt, and a face limit under it refuses the cell.
    auto level = [](double x, double) { return 0.04 * std::sin(2 * M_PI * x); };
    MapOptions tight = o;
    tight.max_face_deg = 5.0;
    TraversabilityMap wheel([&] { MapOptions w = o; w.tilt_radius_m = 0; w.max_face_deg = 0; return w; }());
    TraversabilityMap face(tight);
    AddSurface(&wheel, level, 3.0, 0.0, 2.0);
    AddSurface(&face, level, 3.0, 0.0, 2.0);
    const Cell w = wheel.At(3.0, 0.0), f = face.At(3.0, 0.0);  // sin'(0): the steepest point
    EXPECT_GT(w.tilt_rad / kDeg, 5.0);
    EXPECT_NEAR(f.face_rad, w.tilt_rad - f.tilt_rad, 1e-4);
    EXPECT_LT(f.tilt_rad / kDeg, 1.0);
    EXPECT_EQ(f.state, CellState::kUnsafe);
    EXPECT_EQ(wheel.At(3.0, 0.0).state, CellState::kSafe);
  }
  const MapOptions y = LoadMapOptions(
      config::ConfigNode::FromString("tilt_radius_m: 0.75\nmax_face_deg: 25\nmin_texture: 2\n", "t.yaml"));
  EXPECT_DOUBLE_EQ(y.tilt_radius_m, 0.75);
  EXPECT_DOUBLE_EQ(y.max_face_deg, 25.0);
  EXPECT_DOUBLE_EQ(y.min_texture, 2.0);
  MapOptions bad = o;
  bad.max_face_deg = 95;
  EXPECT_THROW(TraversabilityMap{bad}, std::invalid_argument);
}

// Blank images: SGBM returns disparities from noise alone; min_texture drops them.
TEST(DenseStereo, BlankImagesGiveNoPointsWithATextureFloor) {
  const geometry::StereoRig rig = geometry::LoadStereoRigFile(
      std::string(ROVER_SOURCE_DIR) + "/configs/cameras/navcam_pinhole.yaml");
  cv::Mat left(rig.left->height(), rig.left->width(), CV_8UC1), right = left.clone();
  cv::RNG rng(3);
  rng.fill(left, cv::RNG::NORMAL, 100, 0.7);  // read noise only, independent in each camera
  rng.fill(right, cv::RNG::NORMAL, 100, 0.7);
  MapOptions o;
  o.min_texture = 2.0;
  EXPECT_EQ(DenseStereo(left, right, rig, o).points_rover.size(), 0u);
}

// Texture along the rows against the image's noise: horizontal bands (brightness that
// changes only down the image) with read noise have a standard deviation well over
// min_texture, yet nothing to match along a row; min_texture_snr drops them, and keeps a
// pattern that changes along the rows.
TEST(DenseStereo, TextureAlongTheRowsAgainstTheNoise) {
  const geometry::StereoRig rig = geometry::LoadStereoRigFile(
      std::string(ROVER_SOURCE_DIR) + "/configs/cameras/navcam_pinhole.yaml");
  const int w = rig.left->width(), h = rig.left->height();
  cv::Mat bands(h, w, CV_32F), noise_l(h, w, CV_32F), noise_r(h, w, CV_32F);
  for (int v = 0; v < h; ++v) bands.row(v).setTo(100 + 20 * std::sin(2 * M_PI * v / 24.0));
  cv::RNG rng(5);
  rng.fill(noise_l, cv::RNG::NORMAL, 0, 1.5);
  rng.fill(noise_r, cv::RNG::NORMAL, 0, 1.5);
  cv::Mat left, right;
  cv::Mat(bands + noise_l).convertTo(left, CV_8U);
  cv::Mat(bands + noise_r).convertTo(right, CV_8U);
  MapOptions o;
  o.min_texture = 2.0;
  const std::size_t with_floor = DenseStereo(left, right, rig, o).points_rover.size();
  EXPECT_GT(with_floor, 1000u);  // the bands pass the plain texture floor
  o.min_texture_snr = 2.0;
  EXPECT_LT(DenseStereo(left, right, rig, o).points_rover.size(), with_floor / 100);

  // Blobs a few pixels across, shifted 40 px between the cameras: texture along the rows.
  cv::Mat blobs(h, w, CV_32F);
  rng.fill(blobs, cv::RNG::NORMAL, 0, 40);
  cv::GaussianBlur(blobs, blobs, cv::Size(0, 0), 2.0);
  cv::Mat shifted = blobs.clone();
  blobs.colRange(40, w).copyTo(shifted.colRange(0, w - 40));
  cv::Mat l2, r2;
  cv::Mat(blobs + 100 + noise_l).convertTo(l2, CV_8U);
  cv::Mat(shifted + 100 + noise_r).convertTo(r2, CV_8U);
  MapOptions plain;
  plain.max_range_m = 50;
  MapOptions snr = plain;
  snr.min_texture_snr = 2.0;
  const std::size_t all = DenseStereo(l2, r2, rig, plain).points_rover.size();
  EXPECT_GT(DenseStereo(l2, r2, rig, snr).points_rover.size(), all * 8 / 10);
  const MapOptions y = LoadMapOptions(config::ConfigNode::FromString(
      "min_texture_snr: 2\ntilt_margin_sigmas: 2\ndrop_unseen_border: true\n", "t.yaml"));
  EXPECT_DOUBLE_EQ(y.min_texture_snr, 2.0);
  EXPECT_DOUBLE_EQ(y.tilt_margin_sigmas, 2.0);
  EXPECT_TRUE(y.drop_unseen_border);
  EXPECT_THROW(LoadMapOptions(config::ConfigNode::FromString("min_texture_snr: -1\n", "t.yaml")),
               config::ConfigError);
  EXPECT_THROW(LoadMapOptions(config::ConfigNode::FromString("tilt_margin_sigmas: 11\n", "t.yaml")),
               config::ConfigError);
}

// The left border: on bland sand under a low sun, the left image's bottom-left corner shows
// ground the right camera never saw (its disparity exceeds its column). Matched anyway
// against the padded right image, it gave points a metre below the ground, and a false
// step; drop_unseen_border drops them and keeps nearly everything else.
TEST(DenseStereo, LeftBorderPixelsTheRightCameraNeverSawAreDropped) {
  const std::string text = R"(
name: sand_two_rocks_low_sun
seed: 640325
map: {center: [5, 0], size_m: [20, 16], resolution_m: 0.05}
roughness: {amplitude_m: 0.005, min_wavelength_m: 0.4, max_wavelength_m: 8.0}
ripples: {amplitude_m: 0.008, wavelength_m: 2.5, crest_azimuth_deg: 100}
soil:
  default: sand
rocks:
  placed:
    - {name: Pebble_A, position: [3.0, -0.6], diameter_m: 0.2, height_m: 0.1}
    - {name: Pebble_B, position: [4.2, 0.8], diameter_m: 0.25, height_m: 0.12}
sun: {azimuth_deg: 180, elevation_deg: 12}
)";
  const terrain::World world(terrain::WorldOptions::Load(config::ConfigNode::FromString(text, "sand.yaml")));
  const geometry::StereoRig rig = geometry::LoadStereoRigFile(
      std::string(ROVER_SOURCE_DIR) + "/configs/cameras/navcam_pinhole.yaml");
  render::RenderOptions ro;
  ro.image_scale = 0.5;
  render::StereoRenderer renderer(ro);
  const double yaw = 2.8 * kDeg, x = 0.07 + 1.5 * std::cos(yaw), y = 0.02 + 1.5 * std::sin(yaw);
  const geometry::Pose T = geometry::PoseFromXyzRpy(x, y, -world.Elevation(x, y), 0, 0, yaw);
  const render::StereoImages images = renderer.RenderPair(world, rig, T, 4);
  MapOptions o;
  o.subsample = 3;
  o.min_texture = 2.0;
  auto below = [&](const StereoPoints& sp) {
    int n = 0;
    for (const Eigen::Vector3d& pr : sp.points_rover) {
      const Eigen::Vector3d p = T * pr;
      n += -p.z() < world.ElevationDetailed(p.x(), p.y()) - 0.3;
    }
    return n;
  };
  const StereoPoints kept = DenseStereo(images.left, images.right, images.rig, o);
  o.drop_unseen_border = true;
  const StereoPoints dropped = DenseStereo(images.left, images.right, images.rig, o);
  EXPECT_GE(below(kept), 2);
  EXPECT_EQ(below(dropped), 0);
  EXPECT_GT(dropped.points_rover.size(), kept.points_rover.size() * 9 / 10);
}

// Cells known only along a line (the edge of a shadow on blank ground) fit a plane of any
// slope across the line; with tilt_margin_sigmas the tilt is rated from what the cells
// determine, so a level line of cells is not a slope, while a dense 35 deg slope still is.
TEST(TraversabilityMap, APlaneThroughALineOfCellsRatesNoTilt) {
  MapOptions o;
  o.footprint_radius_m = 0.3;
  o.tilt_radius_m = 0.75;
  o.max_tilt_deg = 30.0;
  o.tilt_margin_sigmas = 2.0;
  MapOptions plain = o;
  plain.tilt_margin_sigmas = 0.0;
  TraversabilityMap rated(o), fitted(plain);
  // Points along y = 0.02 x (a line across the cells) with 2 cm height noise.
  std::mt19937 rng(4);
  std::normal_distribution<double> n(0.0, 0.02);
  std::vector<Eigen::Vector3d> pts;
  for (double x = 1.0; x < 5.0; x += 0.01) {
    const double y = 0.3 + 0.05 * x;
    pts.emplace_back(x, y, -n(rng));
  }
  rated.AddPoints(pts, std::vector<double>(pts.size(), 0.02));
  fitted.AddPoints(pts, std::vector<double>(pts.size(), 0.02));
  int fitted_unsafe = 0, rated_unsafe = 0;
  for (double x = 1.5; x < 4.5; x += 0.2)
    for (double y = -0.5; y <= 1.1; y += 0.2) {
      fitted_unsafe += fitted.At(x, y).state == CellState::kUnsafe;
      rated_unsafe += rated.At(x, y).state == CellState::kUnsafe;
    }
  EXPECT_EQ(rated_unsafe, 0);
  EXPECT_GT(fitted_unsafe, 0);  // the bare fit finds a steep slope across the line

  TraversabilityMap slope(o);
  AddSurface(&slope, [](double x, double) { return std::tan(35.0 * kDeg) * x; }, 3.0, 0.0, 2.0, 0.01);
  const Cell c = slope.At(3.0, 0.0);
  EXPECT_EQ(c.state, CellState::kUnsafe);
  EXPECT_NEAR(c.tilt_rad / kDeg, 35.0, 1.0);
  MapOptions bad = o;
  bad.tilt_margin_sigmas = -1;
  EXPECT_THROW(TraversabilityMap{bad}, std::invalid_argument);
}

// A wall of rocks seen from one side, as the closed end of a pocket is: 0.4 m rocks side by
// side, their far halves and the ground behind them hidden. The body-scale plane through
// the ground and the rocks leans on the wall (least squares, before any rock cell is far
// enough above it to be rejected), and a step measured from that leaning plane is short of
// the rocks' height: the wall read as caution with lone unsafe cells. The ground plane must
// stay on the ground, so the wall's top and foot are unsafe, the open ground a body-length
// away safe.
TEST(TraversabilityMap, AWallOfRocksSeenFromOneSideIsUnsafe) {
  MapOptions o;  // hazard_monitor's (configs/rover.yaml)
  o.footprint_radius_m = 0.3;
  o.max_step_m = 0.25;
  o.max_tilt_deg = 32.0;
  o.tilt_radius_m = 0.75;
  o.tilt_margin_sigmas = 1.0;
  o.max_roughness_m = 0.08;
  const double rock_r = 0.35, rock_h = 0.4, wall_y = 0.35;
  auto scene = [&](double x, double y) {
    double z = 0.0;
    for (double xc = -1.2; xc <= 6.0; xc += 0.6) {
      const double d2 = (x - xc) * (x - xc) + (y - wall_y) * (y - wall_y);
      if (d2 < rock_r * rock_r) z = std::max(z, rock_h * std::sqrt(1.0 - d2 / (rock_r * rock_r)));
    }
    return z;
  };
  TraversabilityMap map(o);
  MapOptions leaning_options = o;
  leaning_options.ground_band_fraction = 0.0;  // the least-squares plane alone
  TraversabilityMap leaning(leaning_options);
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0.0, 0.01);
  std::vector<Eigen::Vector3d> pts;
  for (double x = 0.0; x < 5.0; x += 0.06)
    for (double y = -2.5; y <= wall_y; y += 0.06) pts.emplace_back(x, y, -(scene(x, y) + n(rng)));
  map.AddPoints(pts, std::vector<double>(pts.size(), 0.01));
  leaning.AddPoints(pts, std::vector<double>(pts.size(), 0.01));
  int wall_cells = 0, wall_unsafe = 0, leaning_unsafe = 0;
  for (double x = 1.1; x < 4.0; x += 0.2)
    for (double y : {0.1, 0.3}) {  // the rocks' near flanks and tops, 0.28 to 0.4 m tall
      ++wall_cells;
      const Cell c = map.At(x, y);
      wall_unsafe += c.state == CellState::kUnsafe;
      leaning_unsafe += leaning.At(x, y).state == CellState::kUnsafe;
      EXPECT_EQ(c.state, CellState::kUnsafe) << "wall at " << x << "," << y << ": step " << c.step_m << " tilt "
                                             << c.tilt_rad / kDeg;
    }
  EXPECT_EQ(wall_unsafe, wall_cells);
  EXPECT_LT(leaning_unsafe, wall_cells) << "the leaning plane's wall: " << leaning_unsafe << " of " << wall_cells;
  std::printf("wall cells unsafe: %d of %d from the ground plane, %d from the least-squares plane alone\n", wall_unsafe,
              wall_cells, leaning_unsafe);
  // The foot of the wall, its wheel patch reaching the rocks' lower flanks (cells' mean
  // heights 0.15 to 0.2 m): not safe.
  for (double x = 1.1; x < 4.0; x += 0.2) EXPECT_NE(map.At(x, -0.1).state, CellState::kSafe) << "foot at " << x;
  // Open ground over a body length from the wall: level, safe.
  for (double x = 1.1; x < 4.0; x += 0.2)
    for (double y = -0.9; y > -2.0; y -= 0.2) {
      const Cell c = map.At(x, y);
      EXPECT_EQ(c.state, CellState::kSafe) << "ground at " << x << "," << y;
      EXPECT_LT(c.tilt_rad / kDeg, 2.0) << "ground at " << x << "," << y;
    }
}

// Rating only the cells near the ones that changed (and the edge ring after a move) must
// give the same cells, bit for bit, as rating every cell: map A is read after every step
// (each rating incremental), map B only at the end (two moves in between: every cell
// rated). Ground to the grid's edges, rocks, noise, moves of a few cells either way and a
// pair that adds points without a move (a HAZCAM pair after its NAVCAM pair's recentre).
// With the crest rule on (the view flags are read beyond a patch's moments), views
// between ratings as well: the same comparison.
int CellsRatedIncrementallyThatDiffer(bool crest_rule, int* rated_out, int* crest_unseen_out);

TEST(TraversabilityMap, IncrementalRatingEqualsRatingEveryCell) {
  int rated = 0;
  int crest = 0;
  EXPECT_EQ(CellsRatedIncrementallyThatDiffer(false, &rated, &crest), 0);
  EXPECT_GT(rated, 3600 / 2);  // the comparison covers most of the grid (60 x 60 cells)
}

TEST(TraversabilityMap, IncrementalRatingWithTheCrestRuleEqualsRatingEveryCell) {
  int rated = 0;
  int crest = 0;
  EXPECT_EQ(CellsRatedIncrementallyThatDiffer(true, &rated, &crest), 0);
  EXPECT_GT(rated, 3600 / 2);
  EXPECT_GT(crest, 0);  // the rule marked cells, so the comparison covers it
}

int CellsRatedIncrementallyThatDiffer(bool crest_rule, int* rated_out, int* crest_unseen_out) {
  MapOptions o;
  if (crest_rule) o.crest_view_range_m = 3.0;
  o.extent_m = 12.0;
  o.footprint_radius_m = 0.3;
  o.tilt_radius_m = 0.75;
  o.max_face_deg = 25.0;
  o.max_step_m = 0.25;
  o.tilt_margin_sigmas = 1;
  o.dip_margin_sigmas = 2;
  o.roughness_margin_sigmas = 2;
  const auto ground = [](double x, double y) {
    double z = 0.05 * std::sin(1.3 * x) + 0.04 * std::cos(0.9 * y) + 0.08 * x / 6.0;
    for (const auto& [rx, ry, rh] : {std::tuple{2.0, 1.0, 0.3}, {-3.0, 2.5, 0.2}, {4.5, -4.0, 0.4}, {0.5, 5.2, 0.35}})
      if (std::hypot(x - rx, y - ry) < 0.35) z += rh;
    return z;
  };
  TraversabilityMap a(o), b(o);
  int step = 0;
  auto both = [&](const std::function<void(TraversabilityMap&)>& op) {
    op(a);
    op(b);
    a.cells();  // A rates now; B waits for the end
    ++step;
  };
  both([&](TraversabilityMap& m) { AddSurface(&m, ground, 0.0, 0.0, 5.9, 0.01, 1); });
  both([&](TraversabilityMap& m) { m.Recentre(0.6, 0.2); });
  both([&](TraversabilityMap& m) { AddSurface(&m, ground, 2.5, 0.5, 2.0, 0.02, 2); });
  both([&](TraversabilityMap& m) { AddSurface(&m, ground, 1.0, -0.5, 0.8, 0.02, 3); });
  both([&](TraversabilityMap& m) { m.Recentre(-0.7, 1.3); });
  if (crest_rule) {
    both([&](TraversabilityMap& m) { m.MarkView(2.0, 1.3, 0.5, false); });  // rock at (2, 1): cut
    both([&](TraversabilityMap& m) { m.MarkView(-3.0, 2.5, 0.6, false); });
  }
  both([&](TraversabilityMap& m) { AddSurface(&m, ground, -2.0, 3.0, 2.5, 0.015, 4); });
  if (crest_rule) both([&](TraversabilityMap& m) { m.MarkView(-3.0, 2.5, 0.4, true); });
  both([&](TraversabilityMap& m) { m.Recentre(-0.7, 0.1); });
  const std::vector<Cell>& ca = a.cells();
  const std::vector<Cell>& cb = b.cells();
  if (ca.size() != cb.size() || a.origin_x() != b.origin_x() || a.origin_y() != b.origin_y()) {
    ADD_FAILURE() << "the two maps' grids differ";
    return -1;
  }
  int rated = 0, differ = 0;
  for (std::size_t k = 0; k < ca.size(); ++k) {
    rated += ca[k].state != CellState::kUnknown;
    const bool same = ca[k].state == cb[k].state && ca[k].step_m == cb[k].step_m && ca[k].tilt_rad == cb[k].tilt_rad &&
                      ca[k].face_rad == cb[k].face_rad && ca[k].roughness_m == cb[k].roughness_m &&
                      ca[k].goodness == cb[k].goodness && ca[k].sigma_m == cb[k].sigma_m &&
                      ca[k].elevation_m == cb[k].elevation_m && ca[k].height_sigma_m == cb[k].height_sigma_m &&
                      ca[k].crest_unseen == cb[k].crest_unseen;
    differ += !same;
  }
  EXPECT_EQ(ca.size(), 3600u);
  *rated_out = rated;
  *crest_unseen_out = 0;
  for (const Cell& c : ca) *crest_unseen_out += c.crest_unseen;
  return differ;
}

}  // namespace
}  // namespace rover::traversability
