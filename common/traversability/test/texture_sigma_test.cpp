// A stereo point's disparity sigma grows as its block's texture falls toward the image
// noise (texture_sigma_px, the block-matching error model), with known answers: the
// texture measure on noise alone and on ramps of known slope, the sigmas of a textured and
// a bland block, the measure and the sigmas DenseStereo gives a synthetic pair of textured
// and bland ground, and what the step makes of a cell that lies under the ground with the
// sigmas of each. (The option is off in configs/rover.yaml: README, "Texture and the
// disparity sigma".)
#include "traversability/dense_stereo.hpp"
#include "traversability/traversability_map.hpp"
#include "rating_options.hpp"

#include "geometry/camera_io.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <vector>

namespace rover::traversability {
namespace {

// Sobel's gain for white noise: the sum of its squared coefficients.
constexpr double kWhiteNoiseGain = 12.0;

cv::Mat Noisy(const cv::Mat& clean, double sigma, std::uint64_t seed) {
  cv::Mat noise(clean.size(), CV_32F), out;
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, sigma);
  cv::Mat f;
  clean.convertTo(f, CV_32F);
  cv::Mat(f + noise).convertTo(out, CV_8UC1);  // rounds and saturates
  return out;
}

double MeanOver(const cv::Mat& m, const cv::Rect& r) { return cv::mean(m(r))[0]; }

// Noise alone gives a texture SNR^2 of 1: the measure's own calibration.
TEST(TextureSigma, NoiseAloneMeasuresOne) {
  const cv::Mat flat(160, 200, CV_8UC1, cv::Scalar(120));
  const cv::Mat img = Noisy(flat, 3.0, 5);
  const cv::Mat snr2 = TextureSnr2(img, kWhiteNoiseGain, 5);
  EXPECT_NEAR(MeanOver(snr2, cv::Rect(10, 10, 180, 140)), 1.0, 0.1);
}

// Horizontal ramps of slope a (grey levels per pixel) under noise sigma: the Sobel
// response of a ramp is 8a, so the SNR^2 is 1 + 64 a^2 / (12 sigma^2), the texture's
// gradient energy over the noise's being rho = 64 a^2 / (12 sigma^2). The ramps' kink
// and the image's edges are left out.
TEST(TextureSigma, RampsMeasureTheirGradientOverTheNoise) {
  const double sigma = 1.5, steep = 2.0, gentle = 0.4;
  cv::Mat clean(120, 200, CV_32F);
  for (int v = 0; v < clean.rows; ++v)
    for (int u = 0; u < clean.cols; ++u)
      clean.at<float>(v, u) = static_cast<float>(u < 80 ? 20 + steep * u : 20 + steep * 80 + gentle * (u - 80));
  const cv::Mat img = Noisy(clean, sigma, 7);
  const cv::Mat snr2 = TextureSnr2(img, kWhiteNoiseGain, 5);
  // The 8-bit rounding adds its own 1/12 to the noise variance.
  const double var = sigma * sigma + 1.0 / 12.0;
  const double rho_steep = 64 * steep * steep / (12 * var), rho_gentle = 64 * gentle * gentle / (12 * var);
  const double steep_snr2 = MeanOver(snr2, cv::Rect(10, 10, 60, 100));
  const double gentle_snr2 = MeanOver(snr2, cv::Rect(100, 10, 90, 100));
  EXPECT_NEAR(steep_snr2, 1 + rho_steep, 0.1 * (1 + rho_steep));
  EXPECT_NEAR(gentle_snr2, 1 + rho_gentle, 0.1 * (1 + rho_gentle));

  // Their disparity sigmas: sqrt(0.3^2 + 0.65^2 / rho).
  MapOptions o;
  o.disparity_sigma_px = 0.3;
  o.texture_sigma_px = 0.65;
  const double s_steep = DisparitySigmaPx(steep_snr2, o), s_gentle = DisparitySigmaPx(gentle_snr2, o);
  EXPECT_NEAR(s_steep, std::sqrt(0.09 + 0.4225 / rho_steep), 0.02);    // 0.37 px
  EXPECT_NEAR(s_gentle, std::sqrt(0.09 + 0.4225 / rho_gentle), 0.1);   // 1.1 px
  EXPECT_NEAR(s_gentle / s_steep, std::sqrt((0.09 + 0.4225 / rho_gentle) / (0.09 + 0.4225 / rho_steep)), 0.3);
  EXPECT_GT(s_gentle / s_steep, 2.5);
  // Off, every block claims disparity_sigma_px.
  o.texture_sigma_px = 0;
  EXPECT_EQ(DisparitySigmaPx(steep_snr2, o), 0.3);
  EXPECT_EQ(DisparitySigmaPx(gentle_snr2, o), 0.3);
}

// The model's own answers: rho = 1 adds texture_sigma_px in quadrature; well-textured
// blocks tend to disparity_sigma_px; a block at or under the noise is capped at
// 10 x texture_sigma_px, and a non-finite measure is treated as no texture.
TEST(TextureSigma, TheModelsKnownAnswers) {
  MapOptions o;
  o.disparity_sigma_px = 0.3;
  o.texture_sigma_px = 0.4;
  EXPECT_NEAR(DisparitySigmaPx(2.0, o), 0.5, 1e-9);
  EXPECT_NEAR(DisparitySigmaPx(1e6, o), 0.3, 1e-3);
  EXPECT_NEAR(DisparitySigmaPx(1.0, o), std::sqrt(0.09 + 16.0), 1e-9);
  EXPECT_NEAR(DisparitySigmaPx(0.2, o), std::sqrt(0.09 + 16.0), 1e-9);
  EXPECT_NEAR(DisparitySigmaPx(std::nan(""), o), std::sqrt(0.09 + 16.0), 1e-9);
}

// A synthetic rectified pair through DenseStereo: a pinhole rig looking straight ahead
// (its rectification is the identity) at a fronto-parallel surface 12 px of disparity
// away, smooth random texture of high contrast on the left half of the view and of low
// contrast on the right half (bland sand), the same read noise in both images. Every point
// of the bland half claims a larger range error than any textured point at the same
// depth, in the ratio the texture measure gives; and the texture model off, all claim
// the same.
TEST(TextureSigma, DenseStereoGivesBlandGroundLargerErrors) {
  const int w = 320, h = 160, disparity = 12;
  const std::string rig_yaml =
      "left: {type: pinhole, width: 320, height: 160, fx: 300, fy: 300, cx: 159.5, cy: 79.5,\n"
      "       position: [0, 0, 0], rpy_deg: [0, 0, 0]}\n"
      "right: {type: pinhole, width: 320, height: 160, fx: 300, fy: 300, cx: 159.5, cy: 79.5,\n"
      "        position: [0, 0.1, 0], rpy_deg: [0, 0, 0]}\n";
  geometry::StereoRig rig;
  try {
    rig = geometry::LoadStereoRig(config::ConfigNode(YAML::Load(rig_yaml), "test rig", ""));
  } catch (const std::exception& e) {
    FAIL() << e.what();
  }
  // Smooth texture, wider than the view by the disparity: a left pixel u shows what the
  // right one shows at u - disparity.
  cv::Mat raw(h, w + disparity, CV_32F), tex;
  cv::RNG rng(3);
  rng.fill(raw, cv::RNG::NORMAL, 0.0, 1.0);
  cv::GaussianBlur(raw, tex, cv::Size(0, 0), 1.2);
  cv::Mat contrast(h, w + disparity, CV_32F);
  for (int u = 0; u < w + disparity; ++u) contrast.col(u).setTo(u < w / 2 ? 40.0 : 2.0);
  cv::Mat scene = 120 + tex.mul(contrast) / cv::norm(tex, cv::NORM_L2) * std::sqrt(static_cast<double>(tex.total()));
  const cv::Mat left_clean = scene(cv::Rect(0, 0, w, h)).clone();
  const cv::Mat right_clean = scene(cv::Rect(disparity, 0, w, h)).clone();
  const cv::Mat left = Noisy(left_clean, 2.0, 11), right = Noisy(right_clean, 2.0, 12);

  MapOptions o;
  o.stereo_width_px = 0;
  o.num_disparities = 32;
  o.max_range_m = 100.0;
  o.min_range_m = 0.1;
  o.disparity_sigma_px = 0.3;
  o.texture_sigma_px = 0.65;
  const StereoPoints sp = DenseStereo(left, right, rig, o);
  o.texture_sigma_px = 0;
  const StereoPoints plain = DenseStereo(left, right, rig, o);
  ASSERT_EQ(sp.points_rover.size(), plain.points_rover.size());
  ASSERT_GT(sp.points_rover.size(), 1000u);

  // The texture measure's mean over each half's interior, and the sigma ratio it predicts.
  const auto rect = PairRectification(rig, w, o);
  const cv::Mat snr2 = TextureSnr2(left, rect->texture_noise_gain, o.block_size);
  const double textured_snr2 = MeanOver(snr2, cv::Rect(40, 20, 100, 120));
  const double bland_snr2 = MeanOver(snr2, cv::Rect(190, 20, 100, 120));
  o.texture_sigma_px = 0.65;
  const double predicted = DisparitySigmaPx(bland_snr2, o) / DisparitySigmaPx(textured_snr2, o);
  EXPECT_GT(predicted, 2.0);

  // Each point's claimed error over the plain one's: its own disparity sigma over 0.3 px.
  std::vector<double> textured, bland;
  for (std::size_t k = 0; k < sp.points_rover.size(); ++k) {
    const Eigen::Vector3d& p = sp.points_rover[k];
    const double ratio = sp.error_rover[k].norm() / plain.error_rover[k].norm();
    EXPECT_GE(ratio, 1.0 - 1e-9);
    // Rover frame: x forward, y right. Away from the halves' seam.
    const double u = 159.5 + 300.0 * p.y() / p.x();
    if (u > 30 && u < 140) textured.push_back(ratio);
    if (u > 180 && u < 300) bland.push_back(ratio);
  }
  ASSERT_GT(textured.size(), 300u);
  ASSERT_GT(bland.size(), 100u);
  std::sort(textured.begin(), textured.end());
  std::sort(bland.begin(), bland.end());
  const double textured_median = textured[textured.size() / 2], bland_median = bland[bland.size() / 2];
  EXPECT_LT(textured_median, 1.2);  // textured ground keeps about disparity_sigma_px
  EXPECT_NEAR(bland_median / textured_median, predicted, 0.35 * predicted);
  EXPECT_GT(bland[bland.size() / 10], textured[textured.size() * 9 / 10]);
}

// The map's step beside a 0.19 m cobble (under the 0.25 m limit) with a neighbouring cell
// whose 8 points lie 0.12 m under the ground and agree to 0.01 m. The points are the
// front HAZCAM's (fB 11.8 px m) at 0.75 m range, their range error 0.7 vertical: the
// height sigma of a disparity sigma s is 0.75^2 / 11.8 x 0.7 x s = 0.033 s m. On textured
// ground (the block's texture 20 times the noise's energy) the cell is a hole its points
// agree on, and the step is over the limit; on bland sand (0.3 times) the same points
// claim 4 times the error, the dip margin discounts them, and the cobble reads under the
// limit. The texture model off, both are holes.
double StepBesideACobble(double dip_cell_sigma_m) {
  const MapOptions o = test::MonitorRatingOptions();
  TraversabilityMap map(o);
  std::vector<Eigen::Vector3d> pts;
  std::vector<double> sig;
  const double ground_sigma = 0.033 * DisparitySigmaPx(21.0, [] {
    MapOptions t;
    t.texture_sigma_px = 0.65;
    return t;
  }());
  for (double x = 0.51; x < 3.5; x += 0.06)
    for (double y = -1.49; y < 1.5; y += 0.06) {
      const bool rock = x >= 2.0 && x < 2.2 && y >= 0.0 && y < 0.2;
      const bool dip = x >= 2.0 && x < 2.2 && y >= -0.2 && y < 0.0;
      if (dip) continue;
      pts.emplace_back(x, y, rock ? -0.19 : 0.0);
      sig.push_back(ground_sigma);
    }
  for (int k = 0; k < 8; ++k) {
    pts.emplace_back(2.02 + 0.02 * k, -0.1, 0.12 + (k % 2 ? 0.01 : -0.01));
    sig.push_back(dip_cell_sigma_m);
  }
  map.AddPoints(pts, sig);
  double worst = 0;
  for (int a = -2; a <= 2; ++a)
    for (int b = -2; b <= 2; ++b) worst = std::max<double>(worst, map.At(2.1 + 0.2 * a, 0.1 + 0.2 * b).step_m);
  return worst;
}

TEST(TextureSigma, AFalseDipOnBlandSandIsNoStepWhileARealHoleStillIs) {
  MapOptions o;
  o.disparity_sigma_px = 0.3;
  o.texture_sigma_px = 0.65;
  const double metres_per_px = 0.75 * 0.75 / 11.8 * 0.7;
  const double textured = StepBesideACobble(metres_per_px * DisparitySigmaPx(21.0, o));
  const double bland = StepBesideACobble(metres_per_px * DisparitySigmaPx(1.3, o));
  o.texture_sigma_px = 0;
  const double bland_plain = StepBesideACobble(metres_per_px * DisparitySigmaPx(1.3, o));
  EXPECT_GE(textured, 0.25);    // a real hole of 0.12 m beside the cobble: unsafe
  EXPECT_LT(bland, 0.25);       // the same dip on bland sand: under the limit
  EXPECT_GT(bland, 0.18);       // the cobble itself still counts
  EXPECT_GE(bland_plain, 0.25); // without the model it was a hole too
}

TEST(TextureSigma, TheOptionIsReadAndChecked) {
  const MapOptions o = LoadMapOptions(YAML::Load("{texture_sigma_px: 0.5}"), "test");
  EXPECT_EQ(o.texture_sigma_px, 0.5);
  EXPECT_THROW(LoadMapOptions(YAML::Load("{texture_sigma_px: -1}"), "test"), config::ConfigError);
  const MapOptions cam = LoadCameraOptions(config::ConfigNode(YAML::Load("{texture_sigma_px: 0.8}"), "test", ""), MapOptions{});
  EXPECT_EQ(cam.texture_sigma_px, 0.8);
  MapOptions bad;
  bad.texture_sigma_px = std::nan("");
  EXPECT_THROW(TraversabilityMap{bad}, std::invalid_argument);
}

}  // namespace
}  // namespace rover::traversability
