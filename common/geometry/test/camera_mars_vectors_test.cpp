// Real Spirit and Curiosity NAVCAM models against the independent test vectors in
// ROVER_DATA_DIR/mars/cahvor_test_vectors.yaml (label vectors used exactly as given).
#include "geometry/cahv_camera.hpp"
#include "geometry/test/camera_test_support.hpp"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <map>

using namespace rover::geometry;
using rover::geometry::test::AngleBetween;

namespace {

const std::string kVectors = std::string(ROVER_DATA_DIR) + "/mars/cahvor_test_vectors.yaml";

Eigen::Vector3d Vec3(const YAML::Node& n) {
  return Eigen::Vector3d(n[0].as<double>(), n[1].as<double>(), n[2].as<double>());
}

std::unique_ptr<CameraModel> ModelFrom(const YAML::Node& m) {
  const int w = m["image_size"]["width"].as<int>();
  const int h = m["image_size"]["height"].as<int>();
  const std::string type = m["model_type"].as<std::string>();
  if (type == "CAHV") {
    return std::make_unique<CahvCamera>(w, h, Vec3(m["C"]), Vec3(m["A"]), Vec3(m["H"]),
                                        Vec3(m["V"]));
  }
  if (type == "CAHVOR") {
    return std::make_unique<CahvorCamera>(w, h, Vec3(m["C"]), Vec3(m["A"]), Vec3(m["H"]),
                                          Vec3(m["V"]), Vec3(m["O"]), Vec3(m["R"]));
  }
  ADD_FAILURE() << "unexpected model_type " << type;
  return nullptr;
}

}  // namespace

TEST(MarsCameraVectors, PointsProjectAndPixelsBackProjectExactly) {
  if (!std::filesystem::exists(kVectors)) GTEST_SKIP() << kVectors << " is absent: skipped";
  const YAML::Node root = YAML::LoadFile(kVectors);
  ASSERT_TRUE(root["models"].IsSequence());
  std::map<std::string, Eigen::Vector3d> centers;
  int models = 0, points = 0, pixels = 0;
  for (const YAML::Node& m : root["models"]) {
    const std::string name = m["name"].as<std::string>();
    SCOPED_TRACE(name);
    const auto cam = ModelFrom(m);
    ASSERT_TRUE(cam);
    ++models;
    centers[name] = cam->Center();
    double worst_px = 0, worst_rad = 0;
    for (const YAML::Node& pt : m["points"]) {
      const Eigen::Vector3d X = Vec3(pt["X"]);
      const Eigen::Vector2d expected(pt["pixel"][0].as<double>(), pt["pixel"][1].as<double>());
      Eigen::Vector2d px;
      ASSERT_TRUE(cam->Project(X, &px)) << X.transpose();
      worst_px = std::max(worst_px, (px - expected).norm());
      ++points;
    }
    for (const YAML::Node& pr : m["pixels"]) {
      const Eigen::Vector2d px(pr["pixel"][0].as<double>(), pr["pixel"][1].as<double>());
      const Eigen::Vector3d expected = Vec3(pr["ray"]);
      Eigen::Vector3d origin, dir;
      cam->BackProject(px, &origin, &dir);
      EXPECT_LT((origin - Vec3(m["C"])).norm(), 1e-15);
      worst_rad = std::max(worst_rad, AngleBetween(dir, expected));
      ++pixels;
    }
    EXPECT_LT(worst_px, 1e-6);
    EXPECT_LT(worst_rad, 1e-9);
    std::cout << "  " << name << ": worst point->pixel " << worst_px << " px, worst pixel->ray "
              << worst_rad << " rad\n";
  }
  EXPECT_GE(models, 4);
  EXPECT_GE(points, 80);
  EXPECT_GE(pixels, 80);
  for (const YAML::Node& pair : root["stereo_pairs"]) {
    const Eigen::Vector3d b = centers.at(pair["right"].as<std::string>()) -
                              centers.at(pair["left"].as<std::string>());
    EXPECT_NEAR(b.norm(), pair["baseline_m"].as<double>(), 1e-9);
  }
}

TEST(MarsCameraVectors, ScaledSpiritModelKeepsThePixelCentreConvention) {
  if (!std::filesystem::exists(kVectors)) GTEST_SKIP() << kVectors << " is absent: skipped";
  const YAML::Node root = YAML::LoadFile(kVectors);
  const auto cam = ModelFrom(root["models"][0]);
  const auto half = cam->Scaled(0.5);
  EXPECT_EQ(half->width(), 512);
  for (const YAML::Node& pt : root["models"][0]["points"]) {
    const Eigen::Vector2d expected(pt["pixel"][0].as<double>(), pt["pixel"][1].as<double>());
    Eigen::Vector2d px;
    ASSERT_TRUE(half->Project(Vec3(pt["X"]), &px));
    EXPECT_LT((px - (0.5 * (expected.array() + 0.5) - 0.5).matrix()).norm(), 1e-6);
  }
}
