#include "geometry/cahv_camera.hpp"
#include "geometry/camera_io.hpp"
#include "geometry/pinhole_camera.hpp"
#include "geometry/pose.hpp"

#include <gtest/gtest.h>

#include <random>

using namespace rover::geometry;

TEST(PinholeCamera, ProjectsByTheTextbookFormulaWithoutDistortion) {
  // Camera 2 m forward of the reference origin, optical axis along reference +X.
  Eigen::Isometry3d T(BodyFromOptical());
  T.translation() = Eigen::Vector3d(2, 0, 0);
  const PinholeCamera cam(640, 480, 500, 520, 320.5, 240.25, {}, T);
  // Reference (12, 1, -0.5): 10 m ahead, 1 m right, 0.5 m up -> cam (1, -0.5, 10).
  Eigen::Vector2d px;
  ASSERT_TRUE(cam.Project(Eigen::Vector3d(12, 1, -0.5), &px));
  EXPECT_NEAR(px.x(), 320.5 + 500 * 0.1, 1e-12);
  EXPECT_NEAR(px.y(), 240.25 - 520 * 0.05, 1e-12);
}

TEST(PinholeCamera, UndistortConvergesTo1e12InNormalisedCoordinates) {
  const PinholeCamera cam(1024, 768, 700, 705, 515, 380, {-0.21, 0.05, 0.0012, -0.0007, -0.005});
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> u(-0.8, 0.8);
  for (int i = 0; i < 500; ++i) {
    const Eigen::Vector2d xn(u(rng), u(rng) * 0.75);
    const Eigen::Vector2d xd = cam.Distort(xn);
    Eigen::Vector2d back;
    ASSERT_TRUE(cam.Undistort(xd, &back));
    EXPECT_LT((back - xn).norm(), 1e-12);
    // The pixel round trip through BackProject meets 1e-9 px.
    const Eigen::Vector2d px(700 * xd.x() + 515, 705 * xd.y() + 380);
    Eigen::Vector3d o, d;
    cam.BackProject(px, &o, &d);
    Eigen::Vector2d px2;
    ASSERT_TRUE(cam.Project(o + d, &px2));
    EXPECT_LT((px2 - px).norm(), 1e-9);
  }
}

TEST(PinholeCamera, DistortionJacobianMatchesCentralDifferences) {
  const PinholeCamera cam(1024, 768, 700, 705, 515, 380, {-0.21, 0.05, 0.0012, -0.0007, -0.005});
  for (const Eigen::Vector2d& xn : {Eigen::Vector2d(0.3, -0.2), Eigen::Vector2d(-0.7, 0.5),
                                   Eigen::Vector2d(0.01, 0.6)}) {
    Eigen::Matrix2d J, N;
    cam.Distort(xn, &J);
    const double h = 1e-6;
    for (int k = 0; k < 2; ++k) {
      Eigen::Vector2d dx = Eigen::Vector2d::Zero();
      dx[k] = h;
      N.col(k) = (cam.Distort(xn + dx) - cam.Distort(xn - dx)) / (2 * h);
    }
    EXPECT_LT((J - N).norm(), 1e-8 * N.norm());
  }
}

TEST(PinholeCamera, RefusesPointsBeyondTheDistortionFold) {
  // k1 = -0.3: r (1 - 0.3 r^2) peaks at r^2 = 1/0.9; beyond it far-off points would fold back.
  const PinholeCamera cam(640, 480, 300, 300, 319.5, 239.5, {-0.3, 0, 0, 0});
  Eigen::Vector2d px;
  EXPECT_TRUE(cam.Project(Eigen::Vector3d(0.5, 0.5, 1.0), &px));
  EXPECT_TRUE(cam.Project(Eigen::Vector3d(1.0, 0.0, 1.0), &px));   // r^2 = 1 < 1.11
  EXPECT_FALSE(cam.Project(Eigen::Vector3d(1.1, 0.0, 1.0), &px));  // r^2 = 1.21
  EXPECT_FALSE(cam.Project(Eigen::Vector3d(3.0, 1.0, 1.0), &px));
  // Without distortion any point in front projects.
  const PinholeCamera plain(640, 480, 300, 300, 319.5, 239.5);
  EXPECT_TRUE(plain.Project(Eigen::Vector3d(30.0, 10.0, 1.0), &px));
}

TEST(PinholeCamera, ConstructorNamesTheBadValue) {
  auto message = [](auto make) -> std::string {
    try {
      make();
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(message([] { PinholeCamera(0, 480, 500, 500, 1, 1); }).find("0x480"),
            std::string::npos);
  EXPECT_NE(message([] { PinholeCamera(640, 480, -5, 500, 1, 1); }).find("fx=-5"),
            std::string::npos);
  EXPECT_NE(message([] { PinholeCamera(640, 480, 500, 500, 1, 1, {0.1, 0.2, 0.3}); })
                .find("3 distortion coefficients"),
            std::string::npos);
  Eigen::Isometry3d not_rotation = Eigen::Isometry3d::Identity();
  not_rotation.linear() *= 2.0;
  EXPECT_NE(message([&] { PinholeCamera(640, 480, 500, 500, 1, 1, {}, not_rotation); })
                .find("not a rotation"),
            std::string::npos);
}

TEST(CahvFromPinhole, ProjectsIdenticallyToThePinhole) {
  const Eigen::Isometry3d T = PoseFromXyzRpy(0.2, 0.1, -1.5, 0.01, -0.55, -0.2) *
                              Eigen::Isometry3d(BodyFromOptical());
  const PinholeCamera pinhole(1024, 1024, 1236.08, 1230.5, 511.5, 503.2, {}, T);
  const CahvCamera cahv = CahvFromPinhole(pinhole);
  EXPECT_LT((cahv.C() - T.translation()).norm(), 1e-15);
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> px_u(-0.5, 1023.5), range(0.3, 80);
  double worst_px = 0, worst_angle = 0;
  for (int i = 0; i < 1000; ++i) {
    const Eigen::Vector2d px(px_u(rng), px_u(rng));
    Eigen::Vector3d o1, d1, o2, d2;
    pinhole.BackProject(px, &o1, &d1);
    cahv.BackProject(px, &o2, &d2);
    worst_angle = std::max(worst_angle, std::atan2(d1.cross(d2).norm(), d1.dot(d2)));
    const Eigen::Vector3d p = o1 + range(rng) * d1;
    Eigen::Vector2d a, b;
    ASSERT_TRUE(pinhole.Project(p, &a));
    ASSERT_TRUE(cahv.Project(p, &b));
    worst_px = std::max(worst_px, (a - b).norm());
  }
  EXPECT_LT(worst_px, 1e-6);
  EXPECT_LT(worst_angle, 1e-9);
  // Rescaling commutes with the conversion.
  const auto scaled_pinhole = pinhole.Scaled(0.25);
  const auto scaled_cahv = cahv.Scaled(0.25);
  const CahvCamera converted = CahvFromPinhole(dynamic_cast<const PinholeCamera&>(*scaled_pinhole));
  const auto& direct = dynamic_cast<const CahvCamera&>(*scaled_cahv);
  EXPECT_LT((converted.H() - direct.H()).norm(), 1e-9);
  EXPECT_LT((converted.V() - direct.V()).norm(), 1e-9);
}

TEST(CahvFromPinhole, RefusesADistortedPinhole) {
  const PinholeCamera cam(640, 480, 500, 500, 319.5, 239.5, {-0.1, 0, 0, 0});
  EXPECT_THROW(CahvFromPinhole(cam), std::invalid_argument);
}
