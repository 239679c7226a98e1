// Perseverance NAVCAM and Curiosity hazcam CAHVORE models against the independent test
// vectors in ROVER_DATA_DIR/mars/cahvore_test_vectors.yaml (O normalised, as the file says).
#include "geometry/cahvore_camera.hpp"
#include "geometry/test/camera_test_support.hpp"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <filesystem>

using namespace rover::geometry;
using rover::geometry::test::AngleBetween;

namespace {

Eigen::Vector3d Vec3(const YAML::Node& n) {
  return Eigen::Vector3d(n[0].as<double>(), n[1].as<double>(), n[2].as<double>());
}

}  // namespace

TEST(MarsCahvoreVectors, PointsProjectAndPixelsBackProjectExactly) {
  const std::string path = std::string(ROVER_DATA_DIR) + "/mars/cahvore_test_vectors.yaml";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " is absent: skipped";
  const YAML::Node root = YAML::LoadFile(path);
  int models = 0, points = 0, pixels = 0;
  for (const YAML::Node& m : root["models"]) {
    const std::string name = m["name"].as<std::string>();
    SCOPED_TRACE(name);
    ASSERT_EQ(m["model_type"].as<std::string>(), "CAHVORE");
    const double L = LinearityFromCahvoreType(m["T"].as<int>(), m["P"].as<double>());
    EXPECT_EQ(L, m["linearity"].as<double>());
    const CahvoreCamera cam(m["image_size"]["width"].as<int>(),
                            m["image_size"]["height"].as<int>(), Vec3(m["C"]), Vec3(m["A"]),
                            Vec3(m["H"]), Vec3(m["V"]), Vec3(m["O"]), Vec3(m["R"]),
                            Vec3(m["E"]), L);
    ++models;
    double worst_px = 0, worst_rad = 0, worst_origin = 0;
    for (const YAML::Node& pt : m["points"]) {
      const Eigen::Vector2d expected(pt["pixel"][0].as<double>(), pt["pixel"][1].as<double>());
      Eigen::Vector2d px;
      ASSERT_TRUE(cam.Project(Vec3(pt["X"]), &px));
      worst_px = std::max(worst_px, (px - expected).norm());
      ++points;
    }
    for (const YAML::Node& pr : m["pixels"]) {
      const Eigen::Vector2d px(pr["pixel"][0].as<double>(), pr["pixel"][1].as<double>());
      Eigen::Vector3d origin, dir;
      cam.BackProject(px, &origin, &dir);
      worst_rad = std::max(worst_rad, AngleBetween(dir, Vec3(pr["ray"])));
      worst_origin = std::max(worst_origin, (origin - Vec3(pr["origin"])).norm());
      ++pixels;
    }
    EXPECT_LT(worst_px, 1e-6);
    EXPECT_LT(worst_rad, 1e-9);
    EXPECT_LT(worst_origin, 1e-9);
    std::cout << "  " << name << ": worst point->pixel " << worst_px << " px, pixel->ray "
              << worst_rad << " rad, ray origin " << worst_origin << " m\n";
  }
  EXPECT_GE(models, 2);
  EXPECT_GE(points, 40);
  EXPECT_GE(pixels, 40);
}

TEST(CahvoreCamera, FishEyeSeesBehindItsPrincipalPlaneAndProjectsBack) {
  // Equidistant (L = 0), 250 px per radian: the image corner is ~1.6 rad off axis.
  const Eigen::Vector3d A(1, 0, 0);
  const CahvoreCamera cam(640, 480, Eigen::Vector3d(0, 0, -1), A, Eigen::Vector3d(319.5, 250, 0),
                          Eigen::Vector3d(239.5, 0, 250), A, Eigen::Vector3d::Zero(),
                          Eigen::Vector3d(0.02, 0.01, 0.003), 0.0);
  Eigen::Vector3d origin, dir;
  cam.BackProject(Eigen::Vector2d(-0.5, -0.5), &origin, &dir);
  // Equidistant: the angle off axis is the pixel radius over the focal length.
  const double radius = std::hypot(320.0, 240.0);
  EXPECT_NEAR(std::acos(dir.dot(A)), radius / 250.0, 1e-12);
  EXPECT_LT(dir.x(), 0.0);  // more than 90 deg off axis
  // The entrance pupil moved forward by (theta / sin(theta) - 1) E(theta).
  const double t = radius / 250.0;
  EXPECT_NEAR(origin.x(), (t / std::sin(t) - 1) * (0.02 + 0.01 * t * t + 0.003 * t * t * t * t),
              1e-12);
  Eigen::Vector2d px;
  ASSERT_TRUE(cam.Project(origin + 5.0 * dir, &px));
  EXPECT_LT((px - Eigen::Vector2d(-0.5, -0.5)).norm(), 1e-9);
}
