// The KITTI-layout reader: a good sequence reads back exactly; every malformed one fails
// with one line naming the path and what was expected.
#include "vo_eval/kitti_sequence.hpp"

#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

#include <filesystem>
#include <fstream>

namespace rover::vo_eval {
namespace {
namespace fs = std::filesystem;

constexpr const char* kCalib =
    "P0: 7.0e+02 0 3.1e+01 0 0 7.0e+02 1.5e+01 0 0 0 1 0\n"
    "P1: 7.0e+02 0 3.1e+01 -3.5e+02 0 7.0e+02 1.5e+01 0 0 0 1 0\n"
    "P2: 1 2 3\n";

class KittiLayout : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::path(::testing::TempDir()) /
           ("kitti_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "image_0");
    fs::create_directories(dir_ / "image_1");
    for (int k = 0; k < 3; ++k) {
      cv::Mat img(16, 64, CV_8UC1, cv::Scalar(10 * k));
      char name[32];
      std::snprintf(name, sizeof(name), "%06d.png", k);
      cv::imwrite((dir_ / "image_0" / name).string(), img);
      cv::imwrite((dir_ / "image_1" / name).string(), img);
    }
    Write("calib.txt", kCalib);
    Write("times.txt", "0.0\n0.1\n0.2\n");
    Write("poses.txt",
          "1 0 0 0 0 1 0 0 0 0 1 0\n"
          "1 0 0 0 0 1 0 0 0 0 1 1\n"
          "1 0 0 0.5 0 1 0 0 0 0 1 2\n");
  }
  void TearDown() override { fs::remove_all(dir_); }
  void Write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name) << text;
  }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  // The DatasetError message of opening the sequence ("" if it opened).
  std::string OpenError() const {
    try {
      OpenKittiSequence(dir_.string());
    } catch (const DatasetError& e) {
      return e.what();
    }
    return "";
  }
  fs::path dir_;
};

TEST_F(KittiLayout, GoodSequenceReadsBack) {
  const KittiSequence seq = OpenKittiSequence(dir_.string());
  EXPECT_EQ(seq.size(), 3);
  EXPECT_EQ(seq.width, 64);
  EXPECT_EQ(seq.height, 16);
  ASSERT_TRUE(seq.has_truth());
  EXPECT_DOUBLE_EQ(seq.truth[2].translation().x(), 0.5);
  EXPECT_DOUBLE_EQ(seq.truth[2].translation().z(), 2.0);
  EXPECT_DOUBLE_EQ(seq.times_s[1], 0.1);
  const StereoFrameImages f = LoadStereoFrame(seq, 2);
  EXPECT_EQ(f.left.type(), CV_8UC1);
  EXPECT_EQ(f.left.at<unsigned char>(3, 3), 20);

  const geometry::StereoRig& rig = seq.rig;
  EXPECT_NEAR(rig.Baseline(), 0.5, 1e-12);
  Eigen::Vector2d pl, pr;
  ASSERT_TRUE(rig.left->Project(Eigen::Vector3d(0, 0, 10), &pl));
  EXPECT_NEAR(pl.x(), 31.0, 1e-9);  // cx
  EXPECT_NEAR(pl.y(), 15.0, 1e-9);  // cy
  ASSERT_TRUE(rig.right->Project(Eigen::Vector3d(0, 0, 10), &pr));
  EXPECT_NEAR(pl.x() - pr.x(), 700.0 * 0.5 / 10.0, 1e-9);  // disparity = f B / Z
}

TEST_F(KittiLayout, PosesAreOptional) {
  fs::remove(dir_ / "poses.txt");
  const KittiSequence seq = OpenKittiSequence(dir_.string());
  EXPECT_FALSE(seq.has_truth());
}

TEST_F(KittiLayout, WrittenPosesReadBack) {
  const KittiSequence seq = OpenKittiSequence(dir_.string());
  WriteKittiPoses(Path("out.txt"), seq.truth);
  const PoseList back = ReadKittiPoses(Path("out.txt"));
  ASSERT_EQ(back.size(), 3u);
  EXPECT_TRUE(back[2].isApprox(seq.truth[2], 1e-9));
}

TEST_F(KittiLayout, MissingDirectoryNamesIt) {
  fs::remove_all(dir_);
  const std::string msg = OpenError();
  EXPECT_NE(msg.find(dir_.string()), std::string::npos) << msg;
  EXPECT_NE(msg.find("not found"), std::string::npos) << msg;
}

TEST_F(KittiLayout, MissingCalibNamesIt) {
  fs::remove(dir_ / "calib.txt");
  const std::string msg = OpenError();
  EXPECT_NE(msg.find(Path("calib.txt")), std::string::npos) << msg;
  EXPECT_NE(msg.find("cannot open"), std::string::npos) << msg;
}

TEST_F(KittiLayout, ShortCalibLineNamesTheLine) {
  Write("calib.txt", "P0: 1 0 0 0 0 1 0 0 0 0 1\nP1: 1 0 0 -1 0 1 0 0 0 0 1 0\n");
  const std::string msg = OpenError();
  EXPECT_NE(msg.find(Path("calib.txt") + ":1: P0: has 11 numbers (expected 12"), std::string::npos) << msg;
}

TEST_F(KittiLayout, CalibWithoutRightCameraFails) {
  Write("calib.txt", "P0: 7.0e+02 0 3.1e+01 0 0 7.0e+02 1.5e+01 0 0 0 1 0\n");
  const std::string msg = OpenError();
  EXPECT_NE(msg.find("no P1: line"), std::string::npos) << msg;
}

TEST_F(KittiLayout, MissingRightImageIsACountMismatch) {
  fs::remove(dir_ / "image_1" / "000002.png");
  const std::string msg = OpenError();
  EXPECT_NE(msg.find(Path("image_1") + ": expected 3 PNG images"), std::string::npos) << msg;
  EXPECT_NE(msg.find("found 2"), std::string::npos) << msg;
}

TEST_F(KittiLayout, TimesCountMustMatchImages) {
  Write("times.txt", "0.0\n0.1\n");
  const std::string msg = OpenError();
  EXPECT_NE(msg.find(Path("times.txt") + ": expected 3 timestamps"), std::string::npos) << msg;
}

TEST_F(KittiLayout, PosesCountMustMatchImages) {
  Write("poses.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n");
  const std::string msg = OpenError();
  EXPECT_NE(msg.find(Path("poses.txt") + ": expected 3 poses"), std::string::npos) << msg;
}

TEST_F(KittiLayout, MalformedPoseLineNamesTheLine) {
  Write("poses.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1 x\n1 0 0 0 0 1 0 0 0 0 1 0\n");
  const std::string msg = OpenError();
  EXPECT_NE(msg.find(Path("poses.txt") + ": line 2: expected 12 numbers"), std::string::npos) << msg;
}

TEST_F(KittiLayout, ImageOfTheWrongSizeNamesItAndTheExpectedSize) {
  cv::imwrite(Path("image_1/000001.png"), cv::Mat(16, 60, CV_8UC1, cv::Scalar(0)));
  const KittiSequence seq = OpenKittiSequence(dir_.string());
  try {
    LoadStereoFrame(seq, 1);
    FAIL() << "expected DatasetError";
  } catch (const DatasetError& e) {
    EXPECT_EQ(std::string(e.what()),
              Path("image_1/000001.png") + ": expected 64x16 like the first image, found 60x16");
  }
}

TEST_F(KittiLayout, UnreadablePngNamesIt) {
  Write("image_0/000002.png", "this is not a png");
  const KittiSequence seq = OpenKittiSequence(dir_.string());
  try {
    LoadStereoFrame(seq, 2);
    FAIL() << "expected DatasetError";
  } catch (const DatasetError& e) {
    EXPECT_EQ(std::string(e.what()), Path("image_0/000002.png") + ": expected a readable PNG image, cannot decode");
  }
}

TEST_F(KittiLayout, MismatchedNamesFail) {
  fs::rename(dir_ / "image_1" / "000002.png", dir_ / "image_1" / "000009.png");
  EXPECT_NE(OpenError().find("expected 000002.png to pair with image_0/000002.png, found 000009.png"),
            std::string::npos);
}

}  // namespace
}  // namespace rover::vo_eval
