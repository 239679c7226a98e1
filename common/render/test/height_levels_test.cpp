// The renderer's short cuts must not change what a ray hits: a cone's free range never
// passes the first hit of any ray inside the cone, and the near-surface walk finds the
// same hit as the max-mip walk.
#include "render/height_levels.hpp"
#include "render_test_support.hpp"
#include "terrain/random.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace rover::render::internal {
namespace {

// Rough ground: a slope and a field of rocks, sampled on 5 cm cells like a world grid.
HeightGrid RockyGrid() {
  test::MarkedGround ground;
  ground.gx = 0.04;
  ground.gy = -0.02;
  terrain::Random rng(11);
  for (int k = 0; k < 120; ++k) {
    const double r = rng.Uniform(0.05, 0.4);
    ground.bumps.push_back({rng.Uniform(-1, 9), rng.Uniform(-5, 5), r, rng.Uniform(0.3, 0.8) * r,
                            rng.Uniform() < 0.5 ? 0.0 : 0.5 * r});
  }
  HeightGrid grid;
  grid.Build(ground, Box2{-2, 10, -6, 6}, 0.05);
  return grid;
}

// A unit direction within `angle` of `axis`.
Eigen::Vector3d Within(const Eigen::Vector3d& axis, double angle, terrain::Random& rng) {
  const Eigen::Vector3d a = axis.unitOrthogonal(), b = axis.cross(a);
  const double phi = rng.Uniform(0, 2 * M_PI), theta = angle * std::sqrt(rng.Uniform());
  return (std::cos(theta) * axis + std::sin(theta) * (std::cos(phi) * a + std::sin(phi) * b)).normalized();
}

TEST(HeightGrid, ConeFreeRangeNeverPassesAHitAndTheNearWalkAgrees) {
  const HeightGrid grid = RockyGrid();
  terrain::Random rng(5);
  int bundles = 0, rays = 0, close = 0;
  for (int n = 0; n < 400; ++n) {
    // A camera 1.5 m up looking 15 to 60 deg down, as the NAVCAMs do.
    const Eigen::Vector3d o(rng.Uniform(-1, 1), rng.Uniform(-2, 2), -1.5 - rng.Uniform(0, 0.3));
    const double az = rng.Uniform(-0.6, 0.6), el = rng.Uniform(15, 60) * M_PI / 180;
    const Eigen::Vector3d axis(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
    const double half = rng.Uniform(0.001, 0.02);
    const double free = grid.ConeFreeRange(o, axis, half, 40.0, 0.0125);
    ++bundles;
    for (int k = 0; k < 16; ++k) {
      const Eigen::Vector3d d = Within(axis, half, rng);
      const double t = grid.Intersect(o, d, 0.0, 40.0);
      ASSERT_GE(t, 0.0) << "every ray looks down onto the grid";
      EXPECT_LE(free, t) << "bundle " << n << " ray " << k;
      const double near = grid.IntersectNear(o, d, free, 40.0);
      EXPECT_NEAR(near, t, 1e-9) << "bundle " << n << " ray " << k;
      if (t - free < 0.3) ++close;
      ++rays;
    }
  }
  EXPECT_EQ(rays, 16 * bundles);
  // And the short cut is worth having: most rays start within 30 cm of their hit.
  EXPECT_GT(close, rays / 2) << close << " of " << rays;
}

}  // namespace
}  // namespace rover::render::internal
