// How honest the map is about its heights, with known answers on synthetic data: which
// stereo points it takes and with what height sigma (PlaceStereoPoints: rays grazing the
// ground the rover stands on, the stereo error turned into the site's vertical), how much
// larger the matching error is in the fish-eye's stretched periphery (SourceStretch), and
// how the step treats a cell under the ground whose height is uncertain (dip_margin_sigmas)
// and pairs that disagree by a plausible pose error.
#include "traversability/dense_stereo.hpp"
#include "traversability/traversability_map.hpp"
#include "rating_options.hpp"

#include "geometry/camera_io.hpp"
#include "geometry/pose.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace rover::traversability {
namespace {

constexpr double kDeg = M_PI / 180.0;

// The HAZCAM's left lens in the rover frame (configs/cameras/hazcam_front.yaml): 0.52 m up.
const Eigen::Vector3d kLens(0.75, -0.05, -0.52);

// A point on the ray from kLens at `azimuth_deg` (from the rover's x towards its y) and
// `depression_deg` below the rover's own x-y plane, at horizontal distance `reach_m`.
Eigen::Vector3d AlongRay(double azimuth_deg, double depression_deg, double reach_m) {
  const Eigen::Vector3d horizontal(std::cos(azimuth_deg * kDeg), std::sin(azimuth_deg * kDeg), 0.0);
  return kLens + reach_m * horizontal + Eigen::Vector3d(0, 0, reach_m * std::tan(depression_deg * kDeg));
}

StereoPoints OnePoint(const Eigen::Vector3d& p, const Eigen::Vector3d& error = Eigen::Vector3d(0, 0, 0.01)) {
  StereoPoints sp;
  sp.points_rover.push_back(p);
  sp.error_rover.push_back(error);
  return sp;
}

std::size_t Kept(const StereoPoints& sp, const geometry::Pose& T_site_rover, const MapOptions& o) {
  std::vector<Eigen::Vector3d> pts;
  std::vector<double> sig;
  PlaceStereoPoints(sp, kLens, T_site_rover, geometry::Matrix6d::Zero(), o, &pts, &sig);
  return pts.size();
}

// Rolled 20 deg across a hillside (right side down, sol188_191's attitude), a ray 3.8 deg
// below the rover's plane to the downhill side runs 20 deg below the site's horizontal: it
// meets the hillside 7.8 m away, where SGBM matched foreshortened rows and put points 0.46 m
// over the ground 1.7 m away. It is dropped as grazing the ground the rover stands on; a ray
// to the ground 1.5 m ahead is kept; on level ground the site's horizon still drops rays.
TEST(HeightUncertainty, RaysGrazingTheGroundTheRoverStandsOnAreDropped) {
  MapOptions o;
  o.max_range_m = 2.0;
  o.min_depression_deg = 5.0;
  const geometry::Pose rolled = geometry::PoseFromXyzRpy(0, 0, 0, 20 * kDeg, 0, 0);
  const Eigen::Vector3d grazing = AlongRay(55.0, 3.8, 1.2);
  const Eigen::Vector3d ray_site = rolled.linear() * (grazing - kLens);
  ASSERT_GT(std::asin(ray_site.z() / ray_site.norm()) / kDeg, 15.0);  // far below the site's horizontal
  EXPECT_EQ(Kept(OnePoint(grazing), rolled, o), 0u);
  const Eigen::Vector3d ground_ahead(1.5, 0.0, 0.0);  // on the rover's plane
  EXPECT_EQ(Kept(OnePoint(ground_ahead), rolled, o), 1u);
  // Without the horizon filter both are kept: the test above is the filter's doing.
  MapOptions none = o;
  none.min_depression_deg = 0.0;
  EXPECT_EQ(Kept(OnePoint(grazing), rolled, none), 1u);
  // Level: a ray 3 deg below the horizontal is dropped, one 10 deg below is kept.
  const geometry::Pose level = geometry::Pose::Identity();
  EXPECT_EQ(Kept(OnePoint(AlongRay(0.0, 3.0, 1.5)), level, o), 0u);
  EXPECT_EQ(Kept(OnePoint(AlongRay(0.0, 10.0, 1.0)), level, o), 1u);
  // Beyond max_range_m (horizontal, rover frame): dropped.
  EXPECT_EQ(Kept(OnePoint(AlongRay(0.0, 20.0, 2.5)), level, o), 0u);
}

// The map holds site heights, so a point's stereo error (along its ray) counts by its
// vertical component in the site frame at the capture attitude: a ray level in the rover's
// frame, rolled 20 deg, has sin(20 deg) of its range error vertical (the rover frame's
// vertical alone gave it none: such a point counted as the sharpest of its cell).
// The pose adds its z variance and roll/pitch variance times the horizontal range^2.
TEST(HeightUncertainty, StereoErrorCountsByItsVerticalInTheSiteFrame) {
  MapOptions o;
  o.max_range_m = 10.0;
  const Eigen::Vector3d p = AlongRay(90.0, 0.0, 1.0);  // level in the rover frame, to the right
  const StereoPoints sp = OnePoint(p, Eigen::Vector3d(0.0, 0.1, 0.0));
  std::vector<Eigen::Vector3d> pts;
  std::vector<double> sig;
  PlaceStereoPoints(sp, kLens, geometry::Pose::Identity(), geometry::Matrix6d::Zero(), o, &pts, &sig);
  ASSERT_EQ(sig.size(), 1u);
  EXPECT_NEAR(sig[0], 0.0, 1e-12);
  const geometry::Pose rolled = geometry::PoseFromXyzRpy(1, 2, 0, 20 * kDeg, 0, 0);
  PlaceStereoPoints(sp, kLens, rolled, geometry::Matrix6d::Zero(), o, &pts, &sig);
  ASSERT_EQ(sig.size(), 1u);
  EXPECT_NEAR(sig[0], 0.1 * std::sin(20 * kDeg), 1e-9);
  EXPECT_TRUE(pts[0].isApprox(rolled * p));
  geometry::Matrix6d cov = geometry::Matrix6d::Zero();
  cov(2, 2) = 0.02 * 0.02;
  cov(3, 3) = std::pow(0.01, 2);  // roll
  cov(4, 4) = std::pow(0.02, 2);  // pitch: the larger counts in every direction
  PlaceStereoPoints(sp, kLens, rolled, cov, o, &pts, &sig);
  const double d2 = p.x() * p.x() + p.y() * p.y();
  EXPECT_NEAR(sig[0], std::sqrt(std::pow(0.1 * std::sin(20 * kDeg), 2) + 0.02 * 0.02 + d2 * 0.02 * 0.02), 1e-9);
}

// The HAZCAM's rectified pinhole keeps the fish-eye's centre focal length f: along the
// centre row a column theta off the axis lies at f tan(theta), where the equidistant
// fish-eye has f theta, so one fish-eye pixel spans 1 / cos^2(theta) rectified pixels, and
// a matching error of a fraction of a fish-eye pixel that many more pixels of disparity.
TEST(HeightUncertainty, TheFishEyesStretchedPeripheryHasALargerDisparityError) {
  const geometry::StereoRig rig = geometry::LoadStereoRigFile(std::string(ROVER_SOURCE_DIR) + "/configs/cameras/hazcam_front.yaml");
  const RectifiedRig r = Rectify(rig, 0.25, 124.0);
  const int v = static_cast<int>(std::lround(r.cy));
  EXPECT_NEAR(SourceStretch(r, static_cast<int>(std::lround(r.cx)), v), 1.0, 0.02);
  for (double theta_deg : {30.0, 45.0, 55.0}) {
    const int u = static_cast<int>(std::lround(r.cx + r.f * std::tan(theta_deg * kDeg)));
    EXPECT_NEAR(SourceStretch(r, u, v), 1.0 / std::pow(std::cos(theta_deg * kDeg), 2), 0.05 / std::pow(std::cos(theta_deg * kDeg), 2))
        << theta_deg;
  }
  // A pinhole rectified onto a pinhole of the same focal length is not stretched.
  const geometry::StereoRig navcam = geometry::LoadStereoRigFile(std::string(ROVER_SOURCE_DIR) + "/configs/cameras/navcam_pinhole.yaml");
  const RectifiedRig n = Rectify(navcam, 0.5);
  EXPECT_NEAR(SourceStretch(n, n.width - 10, n.height - 10), 1.0, 0.02);
}

// Flat ground at 0 (10 points per 0.2 m cell, sigma 0.01) with one cell raised to `top_m` at
// (2.1, 0.1), and the cell beside it, (2.1, -0.1), holding only 7 points: 4 on the ground and
// a mismatched streak of 3 at -0.25 m (flat_rock_course's first HAZCAM pair: a cell of 7
// points 0.08 m under the ground, beside a 0.19 m cobble).
TraversabilityMap RockBesideASparseCell(double top_m, const MapOptions& o, bool with_outlier_cell = true) {
  TraversabilityMap map(o);
  std::vector<Eigen::Vector3d> pts;
  for (double x = 0.51; x < 3.5; x += 0.06)
    for (double y = -1.49; y < 1.5; y += 0.06) {
      const bool rock = x >= 2.0 && x < 2.2 && y >= 0.0 && y < 0.2;
      const bool sparse = x >= 2.0 && x < 2.2 && y >= -0.2 && y < 0.0;
      if (sparse) continue;
      pts.emplace_back(x, y, rock ? -top_m : 0.0);
    }
  if (with_outlier_cell) {
    for (double y : {-0.17, -0.13, -0.09, -0.05}) pts.emplace_back(2.1, y, 0.0);
    for (double y : {-0.15, -0.11, -0.07}) pts.emplace_back(2.05, y, 0.25);
  }
  map.AddPoints(pts, std::vector<double>(pts.size(), 0.01));
  return map;
}

// The monitor's rating with one relief counted (relief_sigmas, off in configs/rover.yaml).
MapOptions HazardMonitorRating() {
  MapOptions o = test::MonitorRatingOptions();
  o.relief_sigmas = 1.0;
  return o;
}

// The worst step over the cells around (x, y) within `reach` cells.
double WorstStep(const TraversabilityMap& map, double x, double y, int reach = 2) {
  double worst = 0;
  for (int a = -reach; a <= reach; ++a)
    for (int b = -reach; b <= reach; ++b) worst = std::max<double>(worst, map.At(x + 0.2 * a, y + 0.2 * b).step_m);
  return worst;
}

// A 0.19 m cobble is under the 0.25 m step limit; the sparse cell's streak 0.25 m low pulls
// its mean 0.11 m under the ground, and counted at that height it took the step to 0.30 m.
// Its height's uncertainty, from its points' scatter (0.12 m over 7 points: 0.05 m), tells
// the step it is no evidence of a hole. (The roughness: next test.)
TEST(HeightUncertainty, ASparseCellsOutlierDoesNotRaiseACobblesStepOverTheLimit) {
  const MapOptions o = HazardMonitorRating();
  const TraversabilityMap map = RockBesideASparseCell(0.19, o);
  const double worst = WorstStep(map, 2.1, 0.1);
  EXPECT_GT(worst, 0.18);  // the cobble is seen
  EXPECT_LT(worst, 0.22);
  EXPECT_LT(map.At(2.1, -0.1).step_m, 0.22);  // the sparse cell's own rating
  // Counting every cell at its height (the margin off), the same cloud reads a false step.
  MapOptions plain = o;
  plain.dip_margin_sigmas = 0.0;
  EXPECT_GT(WorstStep(RockBesideASparseCell(0.19, plain), 2.1, 0.1), 0.27);
}

// The same cobble and sparse cell roughen their patches: the cobble 0.19 m over the plane
// and the streaked cell 0.11 m under it give residuals over the 0.08 m roughness limit
// (flat_rock_course: "hazard_map: step 0.18 m, tilt 2.6 deg" refused a straight drive
// beside a 0.15-0.19 m cobble, unsafe by roughness alone). Each cell counts only beyond two
// of its height errors: the streaked cell's 0.05 m explain its dip, the cobble's own 0.01 m
// leave it nearly whole, and no cell of the patch is unsafe; with the margin off the same
// cloud makes unsafe cells whose step is under the limit.
TEST(HeightUncertainty, ACobbleBesideASparseCellIsNotUnsafeByRoughness) {
  const MapOptions o = HazardMonitorRating();
  MapOptions plain = o;
  plain.roughness_margin_sigmas = 0.0;
  const TraversabilityMap map = RockBesideASparseCell(0.19, o);
  const TraversabilityMap before = RockBesideASparseCell(0.19, plain);
  int rough_before = 0;
  double worst_roughness = 0;
  for (double x = 1.5; x < 2.8; x += 0.2)
    for (double y = -0.7; y < 0.8; y += 0.2) {
      const Cell c = map.At(x, y), b = before.At(x, y);
      ASSERT_NE(c.state, CellState::kUnknown) << x << " " << y;
      EXPECT_NE(c.state, CellState::kUnsafe) << x << " " << y << ": step " << c.step_m << " roughness " << c.roughness_m;
      worst_roughness = std::max<double>(worst_roughness, c.roughness_m);
      if (b.state == CellState::kUnsafe && b.step_m < o.max_step_m && b.roughness_m >= o.max_roughness_m) ++rough_before;
    }
  EXPECT_LT(worst_roughness, o.max_roughness_m);
  EXPECT_GT(worst_roughness, 0.03);  // the cobble still roughens its patch
  EXPECT_GE(rough_before, 1);
}

// A patch roughened by rocks its points agree on is still rough: dense cells (0.01 m errors)
// alternating 0.12 m over and under the plane, as on a field of cobbles and holes, read a
// roughness of 0.12 m less 2 of their errors, over the limit.
TEST(HeightUncertainty, RoughnessItsCellsAgreeOnStillCounts) {
  const MapOptions o = HazardMonitorRating();
  TraversabilityMap map(o);
  std::vector<Eigen::Vector3d> pts;
  for (double x = 0.51; x < 3.5; x += 0.06)
    for (double y = -1.49; y < 1.5; y += 0.06) {
      const int i = static_cast<int>(std::floor(x / 0.2)), j = static_cast<int>(std::floor(y / 0.2));
      pts.emplace_back(x, y, ((i + j) % 2 == 0) ? -0.12 : 0.12);
    }
  map.AddPoints(pts, std::vector<double>(pts.size(), 0.01));
  const Cell c = map.At(2.1, 0.1);
  EXPECT_NEAR(c.roughness_m, 0.12 - 2 * 0.01, 0.02);
  EXPECT_EQ(c.state, CellState::kUnsafe);
}

// A real 0.30 m rock beside the same sparse cell is still a step over the limit: the
// highest cell always counts in full.
TEST(HeightUncertainty, ARealRockBesideTheSparseCellIsStillAStep) {
  const MapOptions o = HazardMonitorRating();
  const TraversabilityMap map = RockBesideASparseCell(0.30, o);
  EXPECT_EQ(map.At(2.1, 0.1).state, CellState::kUnsafe);
  EXPECT_NEAR(map.At(2.1, 0.1).step_m, 0.30, 0.02);
  const TraversabilityMap clean = RockBesideASparseCell(0.30, o, false);
  EXPECT_EQ(clean.At(2.1, 0.1).state, CellState::kUnsafe);
  EXPECT_NEAR(clean.At(2.1, 0.1).step_m, 0.30, 0.02);
}

// A hole that its points agree on (a dense cell 0.12 m under the ground) is no noise: beside
// a 0.19 m rock it still makes a step over the limit, less only 2 of its 0.01 m errors.
TEST(HeightUncertainty, AHoleDeeperThanItsErrorStillCounts) {
  const MapOptions o = HazardMonitorRating();
  TraversabilityMap map(o);
  std::vector<Eigen::Vector3d> pts;
  for (double x = 0.51; x < 3.5; x += 0.06)
    for (double y = -1.49; y < 1.5; y += 0.06) {
      const bool rock = x >= 2.0 && x < 2.2 && y >= 0.0 && y < 0.2;
      const bool hole = x >= 2.0 && x < 2.2 && y >= -0.2 && y < 0.0;
      pts.emplace_back(x, y, rock ? -0.19 : hole ? 0.12 : 0.0);
    }
  map.AddPoints(pts, std::vector<double>(pts.size(), 0.01));
  EXPECT_NEAR(map.At(2.1, 0.1).step_m, 0.19 + 0.12 - 2 * 0.01, 0.015);
  EXPECT_EQ(map.At(2.1, 0.1).state, CellState::kUnsafe);
}

// Two pairs whose poses disagree by 0.08 m in height (sol188_191's pose at capture was 0.07
// m off in z before VO's update), each covering part of a flat patch and overlapping in the
// middle, with a 0.19 m cobble: the disagreement is no step, the cobble stays under the limit.
TEST(HeightUncertainty, TwoPairsThatDisagreeByAPlausiblePoseErrorMakeNoFalseStep) {
  const MapOptions o = HazardMonitorRating();
  TraversabilityMap map(o);
  auto pair = [&](double x0, double x1, double dz) {
    std::vector<Eigen::Vector3d> pts;
    for (double x = x0; x < x1; x += 0.06)
      for (double y = -1.49; y < 1.5; y += 0.06) {
        const bool cobble = x >= 2.0 && x < 2.2 && y >= 0.0 && y < 0.2;
        pts.emplace_back(x, y, -(cobble ? 0.19 : 0.0) - dz);
      }
    map.AddPoints(pts, std::vector<double>(pts.size(), 0.015));
  };
  pair(0.51, 2.6, 0.0);
  pair(1.6, 3.5, 0.08);
  int rated = 0;
  for (double x = 0.7; x < 3.3; x += 0.2)
    for (double y = -1.3; y < 1.3; y += 0.2) {
      const Cell c = map.At(x, y);
      if (c.state == CellState::kUnknown) continue;
      ++rated;
      EXPECT_NE(c.state, CellState::kUnsafe) << x << " " << y;
      EXPECT_LT(c.step_m, 0.25) << x << " " << y;
    }
  EXPECT_GT(rated, 100);
  EXPECT_GT(WorstStep(map, 2.1, 0.1), 0.15);  // the cobble is seen
}

// Level ground (points +-0.02 m, sigma 0.02 m) round one cell, [2.0, 2.2) x [0.0, 0.2),
// whose points (sigma 0.01 m) stand at height(x, y) m: seven rows of them across the cell,
// or one (y = 0.1) when one_row.
TraversabilityMap GroundWithOneCell(const MapOptions& o, const std::function<double(double, double)>& height,
                                    bool one_row = false) {
  TraversabilityMap map(o);
  std::vector<Eigen::Vector3d> pts;
  std::vector<double> sig;
  int n = 0;
  for (double x = 0.51; x < 3.5; x += 0.06)
    for (double y = -1.49; y < 1.5; y += 0.06) {
      if (x >= 2.0 && x < 2.2 && y >= 0.0 && y < 0.2) continue;
      pts.emplace_back(x, y, (n++ % 2 == 0) ? 0.02 : -0.02);
      sig.push_back(0.02);
    }
  for (double x = 2.005; x < 2.2; x += 0.01)
    for (double y = one_row ? 0.1 : 0.01; y < 0.2; y += one_row ? 1.0 : 0.03) {
      pts.emplace_back(x, y, -height(x, y));
      sig.push_back(0.01);
    }
  map.AddPoints(pts, sig);
  return map;
}

// A rock's near flank, seen without its crest (a rock at the edge of the HAZCAM's view):
// one cell whose points rise evenly from 0.10 to 0.30 m across it, on flat ground. Its mean
// is 0.20 m, under the 0.25 m limit (caution); its points scatter 0.2 / sqrt(12) = 0.058 m
// against their 0.01 m sigma, a relief of sqrt(0.058^2 - 0.01^2) = 0.057 m, and counted
// with one relief the step reads 0.257 m: unsafe. Ground whose points scatter by their own
// sigma alone (+-0.02 m, sigma 0.02 m) has no relief and reads as before.
TEST(HeightUncertainty, ACellOnARocksFlankCountsItsRelief) {
  auto flank = [](double relief_sigmas) {
    MapOptions o = HazardMonitorRating();
    o.relief_sigmas = relief_sigmas;
    // 0.10 m at the near edge, 0.30 m at the far.
    return GroundWithOneCell(o, [](double x, double) { return 0.10 + (x - 2.0); });
  };
  const TraversabilityMap mean = flank(0.0), relief = flank(1.0);
  EXPECT_NEAR(WorstStep(mean, 2.1, 0.1, 1), 0.20, 0.015);
  EXPECT_NE(mean.At(2.1, 0.1).state, CellState::kUnsafe);
  EXPECT_NEAR(WorstStep(relief, 2.1, 0.1, 1), 0.257, 0.015);
  EXPECT_EQ(relief.At(2.1, 0.1).state, CellState::kUnsafe);
  // Level ground two patches away: noise is no relief.
  for (double x : {0.9, 3.1}) {
    EXPECT_LT(relief.At(x, -1.0).step_m, 0.02) << x;
    EXPECT_NEAR(relief.At(x, -1.0).step_m, mean.At(x, -1.0).step_m, 1e-3) << x;
  }
}

// The same flank read at its top (cell_plane_sigmas): the plane through the cell's points
// rises 1 m per metre, so at the cell's far edge it stands at 0.30 m; its gradient's
// standard error (0.01 m points, 140 of them across 0.19 m) is about 0.015, so two of them
// leave 0.97 of it and the step reads 0.297 m: unsafe. A rounded crest (a cap 0.19 m high at
// the cell's centre, 0.11 m at its corners: a cobble's top) has no gradient and reads at its
// mean, never over its 0.19 m; level ground's noise adds nothing.
TEST(HeightUncertainty, ACellOnARocksFlankReadsAtItsTopAndACrestAtItsMean) {
  auto cell = [](double k_sigmas, bool crest) {
    MapOptions o = HazardMonitorRating();
    o.relief_sigmas = 0;  // the mean, and the cell's plane alone
    o.cell_plane_sigmas = k_sigmas;
    return GroundWithOneCell(o, [crest](double x, double y) {
      const double dx = x - 2.1, dy = y - 0.1;
      return crest ? 0.19 - 4.0 * (dx * dx + dy * dy) : 0.10 + (x - 2.0);
    });
  };
  const TraversabilityMap mean = cell(0.0, false), top = cell(2.0, false);
  EXPECT_NEAR(WorstStep(mean, 2.1, 0.1, 1), 0.20, 0.015);
  EXPECT_NEAR(WorstStep(top, 2.1, 0.1, 1), 0.297, 0.01);
  EXPECT_EQ(top.At(2.1, 0.1).state, CellState::kUnsafe);
  const TraversabilityMap crest_mean = cell(0.0, true), crest_top = cell(2.0, true);
  EXPECT_LE(WorstStep(crest_top, 2.1, 0.1, 1), 0.19);
  EXPECT_NEAR(WorstStep(crest_top, 2.1, 0.1, 1), WorstStep(crest_mean, 2.1, 0.1, 1), 0.005);
  for (double x : {0.9, 3.1}) {
    EXPECT_LT(top.At(x, -1.0).step_m, 0.02) << x;
    EXPECT_NEAR(top.At(x, -1.0).step_m, mean.At(x, -1.0).step_m, 1e-3) << x;
  }
}

// A cell whose points lie on one line across it (a single image row's worth) determines no
// plane: it reads at its mean, however its points rise along the line.
TEST(HeightUncertainty, ACellWhosePointsLieOnALineReadsAtItsMean) {
  auto with = [](double k_sigmas) {
    MapOptions o = HazardMonitorRating();
    o.relief_sigmas = 0;
    o.cell_plane_sigmas = k_sigmas;
    const TraversabilityMap map =
        GroundWithOneCell(o, [](double x, double) { return 0.10 + (x - 2.0); }, /*one_row=*/true);
    return WorstStep(map, 2.1, 0.1, 1);
  };
  EXPECT_NEAR(with(2.0), with(0.0), 1e-4);
  EXPECT_NEAR(with(0.0), 0.20, 0.015);
}

// The two margins of a cell's height error, each read, range-checked, and refused in a
// camera's own section: they rate the map, not one camera's stereo.
TEST(HeightUncertainty, MarginsAreReadAndChecked) {
  for (const auto& [key, member] : {std::pair{"dip_margin_sigmas", &MapOptions::dip_margin_sigmas},
                                    std::pair{"roughness_margin_sigmas", &MapOptions::roughness_margin_sigmas},
                                    std::pair{"relief_sigmas", &MapOptions::relief_sigmas},
                                    std::pair{"cell_plane_sigmas", &MapOptions::cell_plane_sigmas}}) {
    SCOPED_TRACE(key);
    const std::string k(key);
    EXPECT_DOUBLE_EQ(LoadMapOptions(YAML::Load(k + ": 2"), "test").*member, 2.0);
    EXPECT_THROW(LoadMapOptions(YAML::Load(k + ": -1"), "test"), config::ConfigError);
    MapOptions bad;
    bad.*member = 11;
    EXPECT_THROW(TraversabilityMap{bad}, std::invalid_argument);
    EXPECT_THROW(LoadCameraOptions(config::ConfigNode(YAML::Load(k + ": 2"), "test", ""), MapOptions{}),
                 config::ConfigError);
  }
}

}  // namespace
}  // namespace rover::traversability
