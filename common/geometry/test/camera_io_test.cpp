#include "geometry/cahv_camera.hpp"
#include "geometry/camera_io.hpp"
#include "geometry/pinhole_camera.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace rover::geometry;
using rover::config::ConfigError;
using rover::config::ConfigNode;

namespace {

std::string ErrorOf(const std::string& yaml) {
  try {
    LoadStereoRig(ConfigNode::FromString(yaml, "rig.yaml"));
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

const char* kRig = R"(
left:
  type: pinhole
  width: 640
  height: 480
  fx: 500
  fy: 500
  cx: 319.5
  cy: 239.5
  distortion: [-0.1, 0.01, 0, 0]
  position: [0.5, -0.06, -1.0]
  rpy_deg: [0, -35, 0]
right:
  type: cahvor
  width: 1024
  height: 1024
  C: [0.584061, 0.00602352, -1.2389]
  A: [0.311825, -0.875514, 0.369109]
  H: [1301.08, -49.1938, 190.743]
  V: [15.1976, -38.3493, 1318.0]
  O: [0.30304, -0.87994, 0.365886]
  R: [0.0003, -0.004874, 0.018766]
)";

// Where a camera's principal ray meets the flat ground z = 0 (rover frame), metres ahead.
double GroundRangeAhead(const CameraModel& cam, const Eigen::Vector2d& px) {
  Eigen::Vector3d o, d;
  cam.BackProject(px, &o, &d);
  EXPECT_GT(d.z(), 0.0) << "ray does not reach the ground";
  return o.x() + d.x() * (-o.z() / d.z());
}

}  // namespace

TEST(CameraIo, LoadsEveryFieldOfAPinholeAndACahvor) {
  const StereoRig rig = LoadStereoRig(ConfigNode::FromString(kRig, "rig.yaml"));
  const auto& left = dynamic_cast<const PinholeCamera&>(*rig.left);
  EXPECT_EQ(left.width(), 640);
  EXPECT_EQ(left.distortion().size(), 4u);
  EXPECT_DOUBLE_EQ(left.distortion()[0], -0.1);
  EXPECT_LT((left.Center() - Eigen::Vector3d(0.5, -0.06, -1.0)).norm(), 1e-15);
  // Pitch -35 deg: the optical axis points forward and 35 deg down (+Z is down).
  Eigen::Vector3d o, d;
  left.BackProject(Eigen::Vector2d(319.5, 239.5), &o, &d);
  const double t = 35.0 * M_PI / 180.0;
  EXPECT_LT((d - Eigen::Vector3d(std::cos(t), 0, std::sin(t))).norm(), 1e-12);
  // Image right is rover right, image down is (mostly) rover down.
  Eigen::Vector3d d_right, d_down;
  left.BackProject(Eigen::Vector2d(400, 239.5), &o, &d_right);
  left.BackProject(Eigen::Vector2d(319.5, 300), &o, &d_down);
  EXPECT_GT(d_right.y(), 0.1);
  EXPECT_GT(d_down.z(), d.z());
  const auto& right = dynamic_cast<const CahvorCamera&>(*rig.right);
  EXPECT_EQ(right.O(), Eigen::Vector3d(0.30304, -0.87994, 0.365886));
  EXPECT_EQ(right.R(), Eigen::Vector3d(0.0003, -0.004874, 0.018766));
}

TEST(CameraIo, QuaternionOrientationIsTheOpticalFrame) {
  const std::string yaml = R"(
left: {type: pinhole, width: 10, height: 10, fx: 5, fy: 5, cx: 4.5, cy: 4.5, quaternion_wxyz: [0.5, 0.5, 0.5, 0.5]}
right: {type: cahv, width: 10, height: 10, C: [0, 0, 0], A: [1, 0, 0], H: [4.5, 5, 0], V: [4.5, 0, 5]}
)";
  const StereoRig rig = LoadStereoRig(ConfigNode::FromString(yaml, "q.yaml"));
  // (w, x, y, z) = (1/2)(1, 1, 1, 1) is exactly BodyFromOptical(): the two cameras agree.
  for (const Eigen::Vector3d& p : {Eigen::Vector3d(5, 1, -2), Eigen::Vector3d(3, -0.4, 0.7)}) {
    Eigen::Vector2d a, b;
    ASSERT_TRUE(rig.left->Project(p, &a));
    ASSERT_TRUE(rig.right->Project(p, &b));
    EXPECT_LT((a - b).norm(), 1e-12);
  }
}

TEST(CameraIo, BadKeyGivesTheConfigErrorLine) {
  std::string yaml = kRig;
  yaml.replace(yaml.find("  fy: 500"), 9, "  fyy: 500");
  const std::string msg = ErrorOf(yaml);
  EXPECT_EQ(msg.rfind("rig.yaml: left.fyy: unknown key (expected one of:", 0), 0u) << msg;
  EXPECT_EQ(msg.find('\n'), std::string::npos);
}

TEST(CameraIo, BadValuesNameTheKeyAndWhatWasExpected) {
  std::string wrong_type = kRig;
  wrong_type.replace(wrong_type.find("type: cahvor"), 12, "type: fisheye");
  EXPECT_NE(ErrorOf(wrong_type).find("rig.yaml: right.type: expected one of: pinhole, cahv, cahvor"),
            std::string::npos)
      << ErrorOf(wrong_type);

  std::string short_vector = kRig;
  short_vector.replace(short_vector.find("O: [0.30304, -0.87994, 0.365886]"), 32, "O: [0.3, -0.8]");
  EXPECT_NE(ErrorOf(short_vector).find("right.O: expected a list of 3 numbers"), std::string::npos)
      << ErrorOf(short_vector);

  std::string missing = kRig;
  missing.replace(missing.find("  cx: 319.5\n"), 12, "");
  EXPECT_NE(ErrorOf(missing).find("left: missing key \"cx\""), std::string::npos)
      << ErrorOf(missing);

  std::string bad_distortion = kRig;
  bad_distortion.replace(bad_distortion.find("[-0.1, 0.01, 0, 0]"), 18, "[-0.1, 0.01, 0]");
  EXPECT_NE(ErrorOf(bad_distortion).find("left.distortion: expected 4 or 5 numbers"),
            std::string::npos)
      << ErrorOf(bad_distortion);

  std::string zero_axis = kRig;
  zero_axis.replace(zero_axis.find("A: [0.311825, -0.875514, 0.369109]"), 34, "A: [0, 0, 0]");
  EXPECT_NE(ErrorOf(zero_axis).find("rig.yaml: right: CahvorCamera: vector A is zero"),
            std::string::npos)
      << ErrorOf(zero_axis);

  EXPECT_NE(ErrorOf("left: {type: cahv}\nright: {type: cahv}\n").find("missing key \"width\""), std::string::npos);
  EXPECT_NE(ErrorOf("lefty: {}\n").find("rig.yaml: lefty: unknown key"), std::string::npos);
}

TEST(NavcamConfigs, PinholeRigSeesTheGroundFromOneToTenMetres) {
  const StereoRig rig =
      LoadStereoRigFile(std::string(ROVER_SOURCE_DIR) + "/configs/cameras/navcam_pinhole.yaml");
  EXPECT_NEAR(rig.Baseline(), 0.20, 1e-12);
  for (const auto& cam : {rig.left, rig.right}) {
    EXPECT_EQ(cam->width(), 1024);
    EXPECT_EQ(cam->height(), 1024);
    EXPECT_NEAR(cam->Center().z(), -1.5, 1e-12);
    // 45 deg horizontal field of view across the image edges.
    Eigen::Vector3d o, a, b;
    cam->BackProject(Eigen::Vector2d(-0.5, 511.5), &o, &a);
    cam->BackProject(Eigen::Vector2d(1023.5, 511.5), &o, &b);
    EXPECT_NEAR(std::acos(a.dot(b)) * 180 / M_PI, 45.0, 1e-9);
    const double near = GroundRangeAhead(*cam, Eigen::Vector2d(511.5, 1023.5));
    const double far = GroundRangeAhead(*cam, Eigen::Vector2d(511.5, -0.5));
    EXPECT_GT(near, 0.8);
    EXPECT_LT(near, 1.5);
    EXPECT_GT(far, 8.0);
    EXPECT_LT(far, 12.0);
  }
  // Right camera is to the rover's right (+Y).
  EXPECT_GT(rig.right->Center().y(), rig.left->Center().y());
}

TEST(NavcamConfigs, CahvorRigProjectsLikeThePinholeRig) {
  const std::string dir = std::string(ROVER_SOURCE_DIR) + "/configs/cameras/";
  const StereoRig pinhole = LoadStereoRigFile(dir + "navcam_pinhole.yaml");
  const StereoRig cahvor = LoadStereoRigFile(dir + "navcam_cahvor.yaml");
  EXPECT_EQ(cahvor.left->type(), "cahvor");
  EXPECT_NEAR(cahvor.Baseline(), pinhole.Baseline(), 1e-12);
  // And CahvFromPinhole reproduces the file's vectors.
  const CahvCamera converted = CahvFromPinhole(dynamic_cast<const PinholeCamera&>(*pinhole.left));
  const auto& file = dynamic_cast<const CahvorCamera&>(*cahvor.left);
  EXPECT_LT((converted.H() - file.H()).norm(), 1e-9);
  EXPECT_LT((converted.V() - file.V()).norm(), 1e-9);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> x(1.0, 15.0), y(-6.0, 6.0), z(-0.5, 0.5);
  int compared = 0;
  for (int i = 0; i < 2000; ++i) {
    const Eigen::Vector3d p(x(rng), y(rng), z(rng));  // ground-level points ahead
    for (int side = 0; side < 2; ++side) {
      const CameraModel& a = side == 0 ? *pinhole.left : *pinhole.right;
      const CameraModel& b = side == 0 ? *cahvor.left : *cahvor.right;
      Eigen::Vector2d pa, pb;
      const bool ok_a = a.Project(p, &pa), ok_b = b.Project(p, &pb);
      ASSERT_EQ(ok_a, ok_b);
      if (!ok_a) continue;
      EXPECT_LT((pa - pb).norm(), 1e-6);
      ++compared;
    }
  }
  EXPECT_GT(compared, 3000);
}
