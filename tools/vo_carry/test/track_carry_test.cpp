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
// l_n = rho l_n-1 + w_n (l_0 = 0) and r_n = rho_s l_n + s_n.
CarryAccumulator SyntheticTracks(double rho, double rho_s, double sigma_px, int tracks, int length, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, sigma_px);
  CarryAccumulator acc;
  for (int id = 1; id <= tracks; ++id) {
    Eigen::Vector2d l = Eigen::Vector2d::Zero();
    acc.Add(id, l, Eigen::Vector2d(g(rng), g(rng)), true);
    for (int n = 1; n <= length; ++n) {
      l = rho * l + Eigen::Vector2d(g(rng), g(rng));
      acc.Add(id, l, rho_s * l + Eigen::Vector2d(g(rng), g(rng)), false);
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
    EXPECT_NEAR(e.stereo_carry, rho_s, 0.03) << rho_s;
    EXPECT_NEAR(e.track_carry_xy.x(), rho, 0.05);
    EXPECT_NEAR(e.track_carry_xy.y(), rho, 0.05);
    EXPECT_NEAR(e.match_sigma_px, 0.2, 0.01);
    EXPECT_GT(e.track_carry_stderr, 0.0);
    EXPECT_LT(e.track_carry_stderr, 0.03);
  }
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

// A short rendered drive: tracks are followed against truth, and the measured carries are
// fractions (the tracker neither reverses nor amplifies a match error) known to better
// than 0.1.
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
            << e.track_carry << " +- " << e.track_carry_stderr << ", stereo carry " << e.stereo_carry
            << ", match sigma " << e.match_sigma_px << " px\n";
  EXPECT_GE(count.keyframes, 7);
  EXPECT_GT(e.track_pairs, 100);
  EXPECT_LT(e.track_carry_stderr, 0.1);
  EXPECT_GT(e.track_carry, -0.1);
  EXPECT_LT(e.track_carry, 1.1);
  EXPECT_GT(e.match_sigma_px, 0.0);
  EXPECT_LT(e.match_sigma_px, 1.0);
}

}  // namespace
}  // namespace rover::vo_carry
