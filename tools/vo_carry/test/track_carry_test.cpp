// The carry estimator (track_carry.hpp): known answers on synthetic tracks whose errors
// follow the carry model with chosen fractions, then one short rendered drive.
#include "vo_carry/track_carry.hpp"

#include "vo_eval/vo_evaluation.hpp"

#include <gtest/gtest.h>

#include <random>
#include <string>

namespace rover::vo_carry {
namespace {

// Tracks of `length` keyframe observations after the defining one, with
// l_n = rho A l_n-1 + w_n (l_0 = 0) and r_n = rho_s l_n + s_n, A the image map from one
// keyframe to the next (given to the accumulator).
CarryAccumulator SyntheticTracks(double rho, double rho_s, double sigma_px, int tracks, int length, unsigned seed,
                                 const Eigen::Matrix2d& A = Eigen::Matrix2d::Identity()) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, sigma_px);
  CarryAccumulator acc;
  for (int id = 1; id <= tracks; ++id) {
    Eigen::Vector2d l = Eigen::Vector2d::Zero();
    acc.Add(id, l, Eigen::Vector2d(g(rng), g(rng)), true);
    for (int n = 1; n <= length; ++n) {
      l = rho * A * l + Eigen::Vector2d(g(rng), g(rng));
      acc.Add(id, l, rho_s * l + Eigen::Vector2d(g(rng), g(rng)), false, &A);
    }
  }
  return acc;
}

TEST(TrackCarry, RecoversKnownCarriesFromSyntheticTracks) {
  for (const auto& [rho, rho_s] : std::vector<std::pair<double, double>>{{0.0, 0.0}, {0.6, 0.9}, {1.0, 1.0}}) {
    const CarryEstimate e = SyntheticTracks(rho, rho_s, 0.2, 2000, 4, 11).Estimate();
    EXPECT_EQ(e.tracks, 2000);
    EXPECT_EQ(e.track_pairs, 2000 * 3);  // (l_1, l_2) .. (l_3, l_4): the defining l_0 is no pair
    EXPECT_EQ(e.stereo_pairs, 2000 * 4);
    EXPECT_NEAR(e.track_carry, rho, 0.03) << rho;
    EXPECT_NEAR(e.track_carry_mapped, rho, 0.03) << rho;  // A = I: the same estimate
    EXPECT_EQ(e.mapped_pairs, e.track_pairs);
    EXPECT_NEAR(e.stereo_carry, rho_s, 0.03) << rho_s;
    EXPECT_NEAR(e.track_carry_xy.x(), rho, 0.05);
    EXPECT_NEAR(e.track_carry_xy.y(), rho, 0.05);
    EXPECT_NEAR(e.match_sigma_px, 0.2, 0.01);
    EXPECT_GT(e.track_carry_stderr, 0.0);
    EXPECT_LT(e.track_carry_stderr, 0.03);
  }
}

// Errors magnified by the perspective (A = 1.15 in x, 1.3 in y, as a rover closing in on
// the ground ahead sees them): the raw image carry is the magnified one, and the carry
// after the image map is the fraction that was put in.
TEST(TrackCarry, TheImageMapSeparatesPerspectiveFromCarry) {
  const Eigen::Matrix2d A = Eigen::Vector2d(1.15, 1.3).asDiagonal();
  const CarryEstimate e = SyntheticTracks(0.6, 1.0, 0.2, 3000, 4, 12, A).Estimate();
  EXPECT_NEAR(e.track_carry_mapped, 0.6, 0.03);
  EXPECT_NEAR(e.track_carry_xy.x(), 0.6 * 1.15, 0.05);
  EXPECT_NEAR(e.track_carry_xy.y(), 0.6 * 1.3, 0.05);
  EXPECT_NEAR(e.stereo_carry, 1.0, 0.03);
}

TEST(TrackCarry, ABrokenChainAddsNoPairAcrossTheGap) {
  CarryAccumulator acc;
  const Eigen::Vector2d z = Eigen::Vector2d::Zero();
  acc.Add(1, z, z, true);
  acc.Add(1, Eigen::Vector2d(1, 0), z, false);
  acc.Drop(1);
  acc.Add(1, Eigen::Vector2d(-1, 0), z, false);  // no defining observation since: ignored
  acc.Add(2, z, z, true);
  acc.Add(2, Eigen::Vector2d(1, 0), z, false);
  acc.Add(2, Eigen::Vector2d(0.5, 0), z, false);
  const CarryEstimate e = acc.Estimate();
  EXPECT_EQ(e.tracks, 2);
  EXPECT_EQ(e.track_pairs, 1);
  EXPECT_DOUBLE_EQ(e.track_carry, 0.5);
  CarryAccumulator merged;
  merged.Merge(acc);
  merged.Merge(acc);
  EXPECT_EQ(merged.Estimate().track_pairs, 2);
  EXPECT_DOUBLE_EQ(merged.Estimate().track_carry, 0.5);
}

// A short rendered drive (the renderer, a pinhole NAVCAM, exact truth): VO-6's tracks carry
// all of a match error forward, into the next keyframe's left match (after the surface's
// image map) and into the same keyframe's right match, and the raw image carry is larger
// (the rover closes in on the error). What tools/vo_carry measured over six worlds and two
// camera models (common/vo/README.md, "Carried track errors"); bounds of a few standard errors.
TEST(TrackCarry, MeasuresTheCarryOnARenderedDrive) {
  vo_eval::RenderedDriveOptions drive;
  drive.world_path = std::string(ROVER_SOURCE_DIR) + "/configs/worlds/rock_field.yaml";
  drive.rig_path = std::string(ROVER_SOURCE_DIR) + "/configs/cameras/navcam_pinhole.yaml";
  drive.frames = 10;
  drive.seed = 5;
  const vo_eval::RenderedDriveSequence seq(drive);
  vo::VoOptions vo = vo_eval::LoadVoConfig(std::string(ROVER_SOURCE_DIR) + "/configs/vo.yaml");
  CarryAccumulator acc;
  const DriveCount count = MeasureDrive(seq, vo, &acc);
  const CarryEstimate e = acc.Estimate();
  std::cout << "rock_field, " << count.keyframes << " keyframes, " << e.track_pairs << " pairs: track carry "
            << e.track_carry << " +- " << e.track_carry_stderr << " (after the image map " << e.track_carry_mapped
            << "), stereo carry " << e.stereo_carry << ", match sigma " << e.match_sigma_px << " px\n";
  EXPECT_GE(count.keyframes, 7);
  EXPECT_GT(e.track_pairs, 100);
  EXPECT_GT(e.mapped_pairs, e.track_pairs / 2);
  EXPECT_LT(e.track_carry_stderr, 0.05);
  EXPECT_GT(e.track_carry_mapped, 0.85);
  EXPECT_LT(e.track_carry_mapped, 1.2);
  EXPECT_GT(e.track_carry, e.track_carry_mapped);
  EXPECT_GT(e.stereo_carry, 0.85);
  EXPECT_LT(e.stereo_carry, 1.15);
  EXPECT_GT(e.match_sigma_px, 0.05);
  EXPECT_LT(e.match_sigma_px, 0.5);
}

}  // namespace
}  // namespace rover::vo_carry
