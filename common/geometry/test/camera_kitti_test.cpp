#include "geometry/kitti_calib.hpp"
#include "geometry/pinhole_camera.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

using namespace rover::geometry;

namespace {

std::string WriteTemp(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::temp_directory_path() / ("rover_cam_test_" + name);
  std::ofstream(path) << text;
  return path.string();
}

std::string ErrorOf(const std::string& path) {
  try {
    LoadKittiCalib(path, 1226, 370);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

const std::string kP0 =
    "P0: 7.070912e+02 0 6.018873e+02 0 0 7.070912e+02 1.831104e+02 0 0 0 1 0\n";
const std::string kP1 =
    "P1: 7.070912e+02 0 6.018873e+02 -3.798145e+02 0 7.070912e+02 1.831104e+02 0 0 0 1 0\n";

}  // namespace

TEST(KittiCalib, RealSequence06GivesDisparityFxBOverZ) {
  const std::string path = std::string(ROVER_DATA_DIR) + "/kitti_06_0000_0050/calib.txt";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " is absent: skipped";
  const StereoRig rig = LoadKittiCalib(path, 1226, 370);
  const auto& left = dynamic_cast<const PinholeCamera&>(*rig.left);
  EXPECT_DOUBLE_EQ(left.fx(), 707.0912);
  EXPECT_DOUBLE_EQ(left.cx(), 601.8873);
  EXPECT_DOUBLE_EQ(left.cy(), 183.1104);
  EXPECT_EQ(left.width(), 1226);
  EXPECT_NEAR(rig.Baseline(), 379.8145 / 707.0912, 1e-15);
  // A point Z metres ahead: the right pixel is fx*b/Z to the left, the same row (P1 row 1).
  for (double Z : {3.0, 10.0, 40.0}) {
    const Eigen::Vector3d p(1.2, -0.4, Z);
    Eigen::Vector2d l, r;
    ASSERT_TRUE(rig.left->Project(p, &l));
    ASSERT_TRUE(rig.right->Project(p, &r));
    EXPECT_NEAR(l.x() - r.x(), 379.8145 / Z, 1e-9);
    EXPECT_NEAR(l.y(), r.y(), 1e-12);
  }
}

TEST(KittiCalib, SyntheticFileMatchesTheProjectionMatrices) {
  const std::string path = WriteTemp("ok.txt", kP0 + kP1 + "P2: 1 2 3\nTr: 1 0 0 0 0 1 0 0 0 0 1 0\n");
  const StereoRig rig = LoadKittiCalib(path, 1226, 370);
  // Right camera = P1 applied to homogeneous left-frame points.
  Eigen::Matrix<double, 3, 4> P1;
  P1 << 707.0912, 0, 601.8873, -379.8145, 0, 707.0912, 183.1104, 0, 0, 0, 1, 0;
  const Eigen::Vector3d p(-2.0, 0.7, 12.5);
  const Eigen::Vector3d h = P1 * p.homogeneous();
  Eigen::Vector2d r;
  ASSERT_TRUE(rig.right->Project(p, &r));
  EXPECT_LT((r - h.hnormalized()).norm(), 1e-9);
}

TEST(KittiCalib, MalformedTextGivesOneLineWithPathAndLine) {
  struct Case {
    std::string name, text, expected;
  };
  const std::vector<Case> cases = {
      {"short.txt", kP0 + "P1: 7.07e+02 0 6.01e+02\n", ":2: P1: has 3 numbers (expected 12"},
      {"word.txt", kP0 + "\nP1: 7.07e+02 0 6.01e+02 -3.79e+02 0 7.07e+02 1.83e+02 0 0 0 one 0\n",
       ":3: P1: entry 11 is \"one\" (expected a number)"},
      {"missing.txt", kP0, ":1: no P1: line (expected \"P1: \" and 12 numbers)"},
      {"nolabel.txt", kP0 + "7 0 6\n", ":2: \"7\" is not a label"},
      {"twice.txt", kP0 + kP0 + kP1, ":2: P0: given twice"},
      {"skew.txt", "P0: 7.07e+02 1 6.01e+02 0 0 7.07e+02 1.83e+02 0 0 0 1 0\n" + kP1,
       ":1: P0 is not a rectified projection"},
      {"baseline.txt",
       kP0 + "P1: 7.07e+02 0 6.01e+02 3.79e+02 0 7.07e+02 1.83e+02 0 0 0 1 0\n",
       ":2: baseline -P1[3]/P1[0] = -0.536"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    const std::string path = WriteTemp(c.name, c.text);
    const std::string msg = ErrorOf(path);
    EXPECT_EQ(msg.rfind(path + c.expected, 0), 0u) << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    std::filesystem::remove(path);
  }
  EXPECT_EQ(ErrorOf("/nonexistent/calib.txt").rfind("/nonexistent/calib.txt:0: cannot open", 0),
            0u);
}
