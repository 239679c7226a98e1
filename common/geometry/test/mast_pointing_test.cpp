// Moving camera models rigidly (CameraModel::Moved) and pointing a mast head with them
// (PointedRig): the directions of pan and tilt, the pivot, and pan 0 / tilt 0.
#include "geometry/cahv_camera.hpp"
#include "geometry/cahvore_camera.hpp"
#include "geometry/camera_io.hpp"
#include "geometry/mast_pointing.hpp"
#include "geometry/pinhole_camera.hpp"
#include "geometry/pose.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace rover::geometry;

namespace {

constexpr double kDeg = M_PI / 180.0;

// A camera 1.5 m up the mast, 31 deg down, a little rolled and yawed.
Eigen::Isometry3d MastPose() {
  return PoseFromXyzRpy(0.3, -0.1, -1.5, 0.02, -31 * kDeg, 0.1) * Eigen::Isometry3d(BodyFromOptical());
}

// One model of each type, each with its distortion terms in play.
std::vector<std::shared_ptr<const CameraModel>> OneOfEachType() {
  const PinholeCamera posed(1024, 768, 700, 705, 515, 380, {-0.21, 0.05, 0.0012, -0.0007, -0.005}, MastPose());
  const CahvCamera cahv = CahvFromPinhole(PinholeCamera(800, 600, 420, 421, 401.3, 297.8, {}, MastPose()));
  const Eigen::Vector3d O = 1.00002 * (Eigen::AngleAxisd(0.087, cahv.H().normalized()) * cahv.A()).normalized();
  return {
      std::make_shared<PinholeCamera>(posed),
      std::make_shared<CahvCamera>(cahv),
      std::make_shared<CahvorCamera>(800, 600, cahv.C(), cahv.A(), cahv.H(), cahv.V(), O,
                                     Eigen::Vector3d(0.01, -0.2, 0.05)),
      // Curiosity rear hazcam, sol 3423 (general CAHVORE, L = 0.37, a moving entrance pupil).
      std::make_shared<CahvoreCamera>(
          1024, 1024, Eigen::Vector3d(-0.975657, 0.552157, -0.780044), Eigen::Vector3d(-0.705382, 0.001497, 0.708826),
          Eigen::Vector3d(-359.39, -455.682, 359.501), Eigen::Vector3d(-40.5226, -0.430925, 687.887),
          Eigen::Vector3d(-0.706341, 0.000162, 0.707872), Eigen::Vector3d(4.0e-06, -0.014132, -0.00714),
          Eigen::Vector3d(0.002847, 0.001342, 0.00022), 0.37),
  };
}

Eigen::Isometry3d RandomMotion(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized().toRotationMatrix();
  T.translation() = Eigen::Vector3d(n(rng), n(rng), n(rng)) * 3.0;
  return T;
}

// The ray through the image centre: for these pinholes (cx, cy at the centre) the optical axis.
Eigen::Vector3d CentreRay(const CameraModel& cam) {
  Eigen::Vector3d origin, direction;
  cam.BackProject(Eigen::Vector2d(0.5 * (cam.width() - 1), 0.5 * (cam.height() - 1)), &origin, &direction);
  return direction;
}

// A NAVCAM-like head: two undistorted pinholes 0.20 m apart across the rover, 1.5 m up,
// `pitch_deg` about the rover's Y axis (negative: looking down).
StereoRig Head(double pitch_deg) {
  StereoRig rig;
  for (double y : {-0.1, 0.1}) {
    const Eigen::Isometry3d T = PoseFromXyzRpy(0.2, y, -1.5, 0, pitch_deg * kDeg, 0) * Eigen::Isometry3d(BodyFromOptical());
    (y < 0 ? rig.left : rig.right) = std::make_shared<PinholeCamera>(1024, 1024, 1236.08, 1236.08, 511.5, 511.5,
                                                                     std::vector<double>{}, T);
  }
  return rig;
}

TEST(CameraMoved, APointMovedWithTheCameraKeepsItsPixel) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (const auto& cam : OneOfEachType()) {
    SCOPED_TRACE(cam->type());
    for (int trial = 0; trial < 5; ++trial) {
      const Eigen::Isometry3d T = RandomMotion(rng);
      const std::unique_ptr<CameraModel> moved = cam->Moved(T);
      EXPECT_EQ(moved->type(), cam->type());
      EXPECT_EQ(moved->width(), cam->width());
      EXPECT_EQ(moved->height(), cam->height());
      EXPECT_LT((moved->Center() - T * cam->Center()).norm(), 1e-12);
      for (int k = 0; k < 10; ++k) {
        // A point the original sees, inside its image, 0.5 to 20 m along the ray.
        const Eigen::Vector2d u0(0.05 + 0.9 * unit(rng) * cam->width(), 0.05 + 0.9 * unit(rng) * cam->height());
        Eigen::Vector3d origin, direction;
        cam->BackProject(u0, &origin, &direction);
        const Eigen::Vector3d p = origin + (0.5 + 19.5 * unit(rng)) * direction;
        Eigen::Vector2d before, after;
        ASSERT_TRUE(cam->Project(p, &before));
        ASSERT_TRUE(moved->Project(T * p, &after));
        EXPECT_LT((after - before).norm(), 1e-6) << "pixel " << before.transpose();
      }
    }
  }
}

TEST(PointedRig, PanRightTurnsTheOpticalAxisTowardPlusY) {
  const StereoRig head = Head(0.0);  // level, looking along +X
  ASSERT_LT((CentreRay(*head.left) - Eigen::Vector3d::UnitX()).norm(), 1e-12);
  const StereoRig right = PointedRig(head, 90 * kDeg, 0.0);
  for (const auto* cam : {right.left.get(), right.right.get()}) {
    EXPECT_LT((CentreRay(*cam) - Eigen::Vector3d::UnitY()).norm(), 1e-9) << CentreRay(*cam).transpose();
  }
  // The bar turned with the head: the left camera is now ahead of the right one.
  EXPECT_GT(right.left->Center().x(), right.right->Center().x());
  EXPECT_LT(CentreRay(*PointedRig(head, -30 * kDeg, 0.0).left).y(), -0.49);  // - pans left
}

TEST(PointedRig, TiltDownPointsTheOpticalAxisFurtherDown) {
  const StereoRig head = Head(-31.0);  // as mounted: 31 deg below the horizon
  const double z0 = CentreRay(*head.left).z();
  EXPECT_NEAR(z0, std::sin(31 * kDeg), 1e-12);  // +Z is down
  const StereoRig down = PointedRig(head, 0.0, 10 * kDeg);
  EXPECT_GT(CentreRay(*down.left).z(), z0);
  EXPECT_NEAR(CentreRay(*down.left).z(), std::sin(41 * kDeg), 1e-9);
  EXPECT_NEAR(CentreRay(*down.right).z(), std::sin(41 * kDeg), 1e-9);
  EXPECT_LT(CentreRay(*PointedRig(head, 0.0, -10 * kDeg).left).z(), z0);  // - looks up
  // The tilt is about the bar as the pan leaves it: panned 60 deg right and tilted 10 deg
  // down, the axis is 41 deg down at azimuth 60 deg (tilting about the unpanned bar would
  // change the azimuth and the elevation).
  const Eigen::Vector3d axis = CentreRay(*PointedRig(head, 60 * kDeg, 10 * kDeg).left);
  EXPECT_NEAR(axis.z(), std::sin(41 * kDeg), 1e-9);
  EXPECT_NEAR(std::atan2(axis.y(), axis.x()), 60 * kDeg, 1e-9);
}

TEST(PointedRig, ThePivotBetweenTheCameraCentresStaysPut) {
  // A rig mounted with some roll and yaw: the pivot is still the midpoint of the centres.
  StereoRig head = Head(-31.0);
  const Eigen::Isometry3d skew = PoseFromXyzRpy(0.01, 0.02, -0.03, 0.05, 0.0, 0.2);
  head.left = head.left->Moved(skew);
  head.right = head.right->Moved(skew);
  const Eigen::Vector3d m = 0.5 * (head.left->Center() + head.right->Center());
  for (const auto& [pan, tilt] : {std::pair{60 * kDeg, 15 * kDeg}, std::pair{-120 * kDeg, -20 * kDeg}}) {
    const StereoRig pointed = PointedRig(head, pan, tilt);
    EXPECT_LT((0.5 * (pointed.left->Center() + pointed.right->Center()) - m).norm(), 1e-12);
    EXPECT_NEAR(pointed.Baseline(), head.Baseline(), 1e-12);
    EXPECT_LT((MastPointingMotion(head, pan, tilt) * m - m).norm(), 1e-12);
  }
}

TEST(PointedRig, PanZeroTiltZeroLeavesTheRigAsItIs) {
  const StereoRig head = Head(-31.0);
  const StereoRig same = PointedRig(head, 0.0, 0.0);
  EXPECT_EQ(same.left, head.left);
  EXPECT_EQ(same.right, head.right);
  for (const Eigen::Vector3d& p : {Eigen::Vector3d(3, 0.4, 0), Eigen::Vector3d(6, -1.5, 0.2)}) {
    Eigen::Vector2d a, b;
    ASSERT_TRUE(head.left->Project(p, &a));
    ASSERT_TRUE(same.left->Project(p, &b));
    EXPECT_EQ(a, b);
  }
}

TEST(PointedRig, RefusesWhatItCannotPoint) {
  const StereoRig head = Head(-31.0);
  EXPECT_THROW(PointedRig(head, std::nan(""), 0.0), std::invalid_argument);
  EXPECT_THROW(PointedRig(head, 0.0, INFINITY), std::invalid_argument);
  StereoRig stacked = head;  // one camera above the other: no horizontal bar to tilt about
  stacked.right = head.left->Moved(Eigen::Isometry3d(Eigen::Translation3d(0, 0, -0.2)));
  EXPECT_THROW(PointedRig(stacked, 0.0, 0.1), std::invalid_argument);
}

}  // namespace
