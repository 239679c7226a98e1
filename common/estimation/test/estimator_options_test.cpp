#include "estimation/estimator_options.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace rover::estimation;
using rover::config::ConfigError;
using rover::config::ConfigNode;

TEST(EstimatorOptions, ExampleFileLoadsToTheDefaults) {
  const ConfigNode root =
      ConfigNode::LoadFile(std::string(ROVER_SOURCE_DIR) + "/common/estimation/estimator_example.yaml");
  const EstimatorOptions o = LoadEstimatorOptions(root["estimator"]);
  const EstimatorOptions d;
  EXPECT_NEAR(o.along_track_sigma_fraction, d.along_track_sigma_fraction, 1e-15);
  EXPECT_NEAR(o.cross_track_sigma_fraction, d.cross_track_sigma_fraction, 1e-15);
  EXPECT_NEAR(o.vertical_sigma_fraction, d.vertical_sigma_fraction, 1e-15);
  EXPECT_NEAR(o.gyro_drift_rad_per_s, d.gyro_drift_rad_per_s, 1e-18);
  EXPECT_NEAR(o.gyro_scale_sigma_fraction, d.gyro_scale_sigma_fraction, 1e-15);
  EXPECT_NEAR(o.attitude_sigma_rad, d.attitude_sigma_rad, 1e-15);
  EXPECT_EQ(o.history_max_samples, d.history_max_samples);
  EXPECT_EQ(o.slip_memory_updates, d.slip_memory_updates);
  EXPECT_NEAR(o.slip_min_distance_m, d.slip_min_distance_m, 1e-15);
  EXPECT_EQ(o.vo_heading, VoHeadingMode::kFuse);
  EXPECT_EQ(o.vo_yaw_sigma_factor, d.vo_yaw_sigma_factor);
  EXPECT_EQ(o.vo_yaw_bias_sigma_rad_per_m, d.vo_yaw_bias_sigma_rad_per_m);
  EXPECT_EQ(o.vo_yaw_bias_length_m, d.vo_yaw_bias_length_m);
  EXPECT_NO_THROW(o.Validate());
}

TEST(EstimatorOptions, ValuesAndUnitsAreConverted) {
  const ConfigNode root = ConfigNode::FromString(
      "estimator:\n  along_track_sigma_pct: 5\n  gyro_drift_deg_per_hour: 36\n"
      "  vo_heading: replace\n  history_s: 30\n  publish_hz: 8\n  vo_yaw_sigma_factor: 2\n"
      "  vo_yaw_bias_sigma_deg_per_m: 0.01\n  vo_yaw_bias_length_m: 20\n",
      "test.yaml");
  const EstimatorOptions o = LoadEstimatorOptions(root["estimator"], {"publish_hz"});
  EXPECT_NEAR(o.along_track_sigma_fraction, 0.05, 1e-15);
  EXPECT_NEAR(o.gyro_drift_rad_per_s, 36.0 * M_PI / 180.0 / 3600.0, 1e-15);
  EXPECT_EQ(o.vo_heading, VoHeadingMode::kReplace);
  EXPECT_NEAR(o.history_s, 30.0, 1e-15);
  EXPECT_EQ(o.vo_yaw_sigma_factor, 2.0);
  EXPECT_NEAR(o.vo_yaw_bias_sigma_rad_per_m, 0.01 * M_PI / 180.0, 1e-15);
  EXPECT_EQ(o.vo_yaw_bias_length_m, 20.0);
}

TEST(EstimatorOptions, ErrorsNameFileAndKey) {
  auto message = [](const std::string& text) {
    try {
      LoadEstimatorOptions(ConfigNode::FromString(text, "rover.yaml")["estimator"]);
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string typo = message("estimator:\n  along_track_sigma: 2\n");
  EXPECT_NE(typo.find("rover.yaml"), std::string::npos) << typo;
  EXPECT_NE(typo.find("estimator.along_track_sigma"), std::string::npos) << typo;
  EXPECT_NE(typo.find("unknown key"), std::string::npos) << typo;
  const std::string mode = message("estimator:\n  vo_heading: sometimes\n");
  EXPECT_NE(mode.find("estimator.vo_heading"), std::string::npos) << mode;
  const std::string range = message("estimator:\n  cross_track_sigma_pct: -1\n");
  EXPECT_NE(range.find("estimator.cross_track_sigma_pct"), std::string::npos) << range;
  const std::string memory = message("estimator:\n  slip_memory_updates: -1\n");
  EXPECT_NE(memory.find("estimator.slip_memory_updates"), std::string::npos) << memory;
  const std::string travel = message("estimator:\n  slip_min_distance_m: 0\n");
  EXPECT_NE(travel.find("estimator.slip_min_distance_m"), std::string::npos) << travel;
  const std::string factor = message("estimator:\n  vo_yaw_sigma_factor: 0\n");
  EXPECT_NE(factor.find("estimator.vo_yaw_sigma_factor"), std::string::npos) << factor;
  const std::string bias = message("estimator:\n  vo_yaw_bias_sigma_deg_per_m: -0.01\n");
  EXPECT_NE(bias.find("estimator.vo_yaw_bias_sigma_deg_per_m"), std::string::npos) << bias;
  const std::string length = message("estimator:\n  vo_yaw_bias_length_m: -5\n");
  EXPECT_NE(length.find("estimator.vo_yaw_bias_length_m"), std::string::npos) << length;
}
