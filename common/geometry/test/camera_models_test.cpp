// Properties every camera model must have: round trips, Jacobians, rescaling, serialisation.
#include "geometry/cahv_camera.hpp"
#include "geometry/cahvore_camera.hpp"
#include "geometry/camera_io.hpp"
#include "geometry/pinhole_camera.hpp"
#include "geometry/pose.hpp"
#include "geometry/test/camera_test_support.hpp"

#include <gtest/gtest.h>

#include <random>

using namespace rover::geometry;
using rover::geometry::test::AngleBetween;
using rover::geometry::test::NumericProjectJacobian;
using rover::geometry::test::NumericRayJacobian;
using rover::geometry::test::RelativeError;

namespace {

struct NamedModel {
  std::string name;
  std::shared_ptr<const CameraModel> model;
};

Eigen::Isometry3d MastPose() {
  // A camera 1.5 m up (rover Z down), tilted 30 deg down, slightly rolled and yawed.
  return PoseFromXyzRpy(0.3, -0.1, -1.5, 0.02, -0.52, 0.1) *
         Eigen::Isometry3d(BodyFromOptical());
}

std::vector<NamedModel> AllModels() {
  std::vector<NamedModel> models;
  models.push_back({"pinhole", std::make_shared<PinholeCamera>(640, 480, 500, 510, 319.5, 239.5)});
  models.push_back({"pinhole_distorted_k3_posed",
                    std::make_shared<PinholeCamera>(
                        1024, 768, 700, 705, 515, 380,
                        std::vector<double>{-0.21, 0.05, 0.0012, -0.0007, -0.005}, MastPose())});
  models.push_back({"pinhole_distorted_4", std::make_shared<PinholeCamera>(
                                                 752, 480, 460, 458, 370.2, 241.9,
                                                 std::vector<double>{-0.28, 0.07, -0.0003, 0.0009})});
  const PinholeCamera posed(1024, 1024, 1236.08, 1236.08, 511.5, 511.5, {}, MastPose());
  models.push_back({"cahv_from_pinhole", std::make_shared<CahvCamera>(CahvFromPinhole(posed))});
  // Spirit NAVCAM left, sol 767 (label vectors; inputs only, the pixels are not used here).
  models.push_back({"cahvor_spirit",
                    std::make_shared<CahvorCamera>(
                        1024, 1024, Eigen::Vector3d(0.394318, -0.0582843, -1.23826),
                        Eigen::Vector3d(0.276192, -0.889336, 0.364419),
                        Eigen::Vector3d(1262.81, -60.1316, 185.71),
                        Eigen::Vector3d(0.196974, -50.5533, 1294.91),
                        Eigen::Vector3d(0.156295, -0.929704, 0.3335),
                        Eigen::Vector3d(0.019876, -0.014281, 0.020876))});
  // A strongly distorted CAHVOR whose O is 5 deg off A and not unit length.
  const CahvCamera base = CahvFromPinhole(PinholeCamera(800, 600, 420, 421, 401.3, 297.8, {}, MastPose()));
  const Eigen::Vector3d O =
      1.00002 * (Eigen::AngleAxisd(0.087, base.H().normalized()) * base.A()).normalized();
  models.push_back({"cahvor_strong", std::make_shared<CahvorCamera>(
                                         800, 600, base.C(), base.A(), base.H(), base.V(), O,
                                         Eigen::Vector3d(0.01, -0.2, 0.05))});
  // Curiosity rear hazcam, sol 3423 (CAHVORE, general, L = 0.37; label vectors).
  models.push_back({"cahvore_msl_hazcam",
                    std::make_shared<CahvoreCamera>(
                        1024, 1024, Eigen::Vector3d(-0.975657, 0.552157, -0.780044),
                        Eigen::Vector3d(-0.705382, 0.001497, 0.708826),
                        Eigen::Vector3d(-359.39, -455.682, 359.501),
                        Eigen::Vector3d(-40.5226, -0.430925, 687.887),
                        Eigen::Vector3d(-0.706341, 0.000162, 0.707872),
                        Eigen::Vector3d(4.0e-06, -0.014132, -0.00714),
                        Eigen::Vector3d(0.002847, 0.001342, 0.00022), 0.37)});
  // A synthetic equidistant fish-eye (L = 0) whose corners see 100 deg off axis, with a
  // strong entrance-pupil shift.
  const Eigen::Vector3d fA(1, 0, 0);
  models.push_back(
      {"cahvore_fisheye",
       std::make_shared<CahvoreCamera>(
           640, 480, Eigen::Vector3d(0.1, 0.2, -1.0), fA,
           Eigen::Vector3d(319.5, 250, 0), Eigen::Vector3d(239.5, 0, 250),
           Eigen::AngleAxisd(0.035, Eigen::Vector3d::UnitZ()) * fA,
           Eigen::Vector3d(0.0, -0.05, 0.002), Eigen::Vector3d(0.02, 0.01, 0.003), 0.0)});
  // A general CAHVORE with negative linearity.
  models.push_back(
      {"cahvore_negative_linearity",
       std::make_shared<CahvoreCamera>(
           640, 480, Eigen::Vector3d(0.1, 0.2, -1.0), fA,
           Eigen::Vector3d(319.5, 400, 0), Eigen::Vector3d(239.5, 0, 400),
           Eigen::AngleAxisd(-0.02, Eigen::Vector3d::UnitY()) * fA,
           Eigen::Vector3d(0.001, 0.03, -0.004), Eigen::Vector3d(0.005, -0.002, 0.001), -0.3)});
  return models;
}

// Pixels on a grid that spans the whole image, edges included.
std::vector<Eigen::Vector2d> PixelGrid(const CameraModel& cam, int n) {
  std::vector<Eigen::Vector2d> pixels;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      pixels.emplace_back(-0.5 + cam.width() * double(i) / (n - 1),
                          -0.5 + cam.height() * double(j) / (n - 1));
    }
  }
  return pixels;
}

// 3-D points seen by the camera, drawn independently of BackProject: around the optical
// axis (CAHV A, or the pinhole z axis) at random ranges.
std::vector<Eigen::Vector3d> VisiblePoints(const CameraModel& cam, int count, unsigned seed) {
  Eigen::Vector3d axis;
  if (auto* p = dynamic_cast<const PinholeCamera*>(&cam)) {
    axis = p->T_ref_cam().linear().col(2);
  } else if (auto* c = dynamic_cast<const CahvCamera*>(&cam)) {
    axis = c->A().normalized();
  } else if (auto* r = dynamic_cast<const CahvorCamera*>(&cam)) {
    axis = r->A().normalized();
  } else {
    axis = dynamic_cast<const CahvoreCamera&>(cam).A().normalized();
  }
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> lateral(-0.5, 0.5), range(0.4, 60.0);
  std::vector<Eigen::Vector3d> points;
  while (static_cast<int>(points.size()) < count) {
    const Eigen::Vector3d dir =
        (axis + Eigen::Vector3d(lateral(rng), lateral(rng), lateral(rng))).normalized();
    const Eigen::Vector3d p = cam.Center() + range(rng) * dir;
    Eigen::Vector2d px;
    if (!cam.Project(p, &px)) continue;
    if (px.x() < -0.5 || px.y() < -0.5 || px.x() > cam.width() - 0.5 ||
        px.y() > cam.height() - 0.5) {
      continue;
    }
    points.push_back(p);
  }
  return points;
}

}  // namespace

TEST(CameraModels, PixelRayPixelRoundTripUnder1e6Px) {
  for (const auto& [name, cam] : AllModels()) {
    SCOPED_TRACE(name);
    double worst = 0;
    for (const auto& px : PixelGrid(*cam, 21)) {
      Eigen::Vector3d origin, dir;
      cam->BackProject(px, &origin, &dir);
      EXPECT_NEAR(dir.norm(), 1.0, 1e-12);
      for (double range : {0.5, 3.0, 40.0}) {
        Eigen::Vector2d back;
        ASSERT_TRUE(cam->Project(origin + range * dir, &back)) << px.transpose();
        worst = std::max(worst, (back - px).norm());
      }
    }
    EXPECT_LT(worst, 1e-6);
    // Distorted pinhole back-projection converges far below the requirement.
    EXPECT_LT(worst, 1e-8);
  }
}

TEST(CameraModels, PointPixelRayRoundTrip) {
  for (const auto& [name, cam] : AllModels()) {
    SCOPED_TRACE(name);
    for (const auto& p : VisiblePoints(*cam, 200, 7)) {
      Eigen::Vector2d px;
      ASSERT_TRUE(cam->Project(p, &px));
      Eigen::Vector3d origin, dir;
      cam->BackProject(px, &origin, &dir);
      EXPECT_LT(AngleBetween(dir, p - origin), 1e-9);
      EXPECT_GT(dir.dot(p - origin), 0.0);
    }
  }
}

TEST(CameraModels, BehindTheCameraNeverLandsInTheImage) {
  for (const auto& [name, cam] : AllModels()) {
    SCOPED_TRACE(name);
    Eigen::Vector3d origin, dir;
    cam->BackProject(Eigen::Vector2d(cam->width() / 2.0, cam->height() / 2.0), &origin, &dir);
    Eigen::Vector2d px;
    EXPECT_TRUE(cam->Project(origin + 2.0 * dir, &px));
    const bool projects = cam->Project(origin - 2.0 * dir, &px);
    if (projects) {
      EXPECT_TRUE(px.x() < -0.5 || px.y() < -0.5 || px.x() > cam->width() - 0.5 ||
                  px.y() > cam->height() - 0.5)
          << px.transpose();
    }
    // The models with a half-space limit refuse outright.
    if (cam->type() != "cahvore") {
      EXPECT_FALSE(projects);
    }
  }
}

TEST(CameraModels, ProjectJacobianMatchesCentralDifferences) {
  for (const auto& [name, cam] : AllModels()) {
    SCOPED_TRACE(name);
    for (const auto& p : VisiblePoints(*cam, 50, 11)) {
      Eigen::Vector2d px;
      Eigen::Matrix<double, 2, 3> J;
      ASSERT_TRUE(cam->Project(p, &px, &J));
      Eigen::Vector2d px_plain;
      cam->Project(p, &px_plain);
      EXPECT_EQ(px, px_plain);
      EXPECT_LT(RelativeError(J, NumericProjectJacobian(*cam, p)), 1e-6) << p.transpose();
    }
  }
}

TEST(CameraModels, RayJacobianMatchesCentralDifferences) {
  for (const auto& [name, cam] : AllModels()) {
    SCOPED_TRACE(name);
    for (const auto& px : PixelGrid(*cam, 7)) {
      Eigen::Vector3d origin, dir, dir_plain;
      Eigen::Matrix<double, 3, 2> J;
      cam->BackProject(px, &origin, &dir, &J);
      cam->BackProject(px, &origin, &dir_plain);
      EXPECT_LT((dir - dir_plain).norm(), 1e-15);
      EXPECT_LT(RelativeError(J, NumericRayJacobian(*cam, px)), 1e-6) << px.transpose();
      // The direction stays unit: its derivative is orthogonal to it.
      EXPECT_LT((dir.transpose() * J).norm(), 1e-12 * J.norm());
    }
  }
}

TEST(CameraModels, ScaledKeepsPixelCentresOnPixelCentres) {
  for (const auto& [name, cam] : AllModels()) {
    SCOPED_TRACE(name);
    for (double factor : {0.5, 0.25, 1.0 / 3.0, 2.0}) {
      SCOPED_TRACE(factor);
      const auto scaled = cam->Scaled(factor);
      EXPECT_EQ(scaled->type(), cam->type());
      EXPECT_EQ(scaled->width(), static_cast<int>(std::lround(cam->width() * factor)));
      EXPECT_EQ(scaled->height(), static_cast<int>(std::lround(cam->height() * factor)));
      EXPECT_LT((scaled->Center() - cam->Center()).norm(), 1e-15);
      for (const auto& p : VisiblePoints(*cam, 50, 3)) {
        Eigen::Vector2d px, spx;
        ASSERT_TRUE(cam->Project(p, &px));
        ASSERT_TRUE(scaled->Project(p, &spx));
        const Eigen::Vector2d expected = factor * (px.array() + 0.5) - 0.5;
        EXPECT_LT((spx - expected).norm(), 1e-9) << p.transpose();
      }
    }
  }
}

TEST(CameraModels, ScaledRejectsNonPositiveFactor) {
  for (const auto& [name, cam] : AllModels()) {
    SCOPED_TRACE(name);
    EXPECT_THROW(cam->Scaled(0.0), std::invalid_argument);
    EXPECT_THROW(cam->Scaled(-0.5), std::invalid_argument);
  }
}

TEST(CameraModels, ParamsRoundTripRebuildsTheSameModel) {
  for (const auto& [name, cam] : AllModels()) {
    SCOPED_TRACE(name);
    const std::vector<double> params = cam->Params();
    const auto rebuilt = CameraModelFromParams(cam->type(), cam->width(), cam->height(), params);
    ASSERT_EQ(rebuilt->type(), cam->type());
    EXPECT_EQ(rebuilt->width(), cam->width());
    EXPECT_EQ(rebuilt->height(), cam->height());
    const std::vector<double> again = rebuilt->Params();
    ASSERT_EQ(again.size(), params.size());
    for (std::size_t i = 0; i < params.size(); ++i) {
      EXPECT_NEAR(again[i], params[i], 1e-15 * std::max(1.0, std::abs(params[i]))) << i;
    }
    const auto clone = cam->Clone();
    for (const auto& p : VisiblePoints(*cam, 30, 5)) {
      Eigen::Vector2d a, b, c;
      ASSERT_TRUE(cam->Project(p, &a));
      ASSERT_TRUE(rebuilt->Project(p, &b));
      ASSERT_TRUE(clone->Project(p, &c));
      EXPECT_LT((a - b).norm(), 1e-9);
      EXPECT_EQ(a, c);
    }
  }
}

TEST(CameraModels, WrongParamCountsAreRejectedWithTheExpectedCount) {
  auto message = [](const std::string& type, std::size_t n) -> std::string {
    try {
      CameraModelFromParams(type, 100, 100, std::vector<double>(n, 1.0));
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(message("pinhole", 10).find("11, 15 or 16"), std::string::npos);
  EXPECT_NE(message("pinhole", 10).find("got 10"), std::string::npos);
  EXPECT_NE(message("pinhole", 13).find("\"pinhole\""), std::string::npos);
  EXPECT_NE(message("cahv", 18).find("12 parameters"), std::string::npos);
  EXPECT_NE(message("cahvor", 12).find("18 parameters"), std::string::npos);
  EXPECT_NE(message("cahvor", 12).find("got 12"), std::string::npos);
  EXPECT_NE(message("cahvore", 21).find("22 parameters"), std::string::npos);
  EXPECT_NE(message("fisheye", 12).find("unknown type \"fisheye\""), std::string::npos);
  // Counts that fit build a model.
  EXPECT_NO_THROW(CameraModelFromParams("cahv", 100, 100,
                                        {0, 0, 0, 1, 0, 0, 50, 100, 0, 50, 0, 100}));
}
