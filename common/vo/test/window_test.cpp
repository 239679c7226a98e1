// The sliding-window refinement (window.hpp) on synthetic 3-D points seen from known
// poses with known pixel noise, and the windowed VO's handling of a failed pair.
#include "test_rig.hpp"
#include "geometry/pose.hpp"
#include "vo/triangulation.hpp"
#include "vo/visual_odometry.hpp"
#include "vo/window.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <random>
#include <unordered_map>

namespace rover::vo {
namespace {

using Matrix6d = Eigen::Matrix<double, 6, 6>;

// A rig driving forward 0.5 m per frame through a field of points, turning slowly.
struct Scene {
  geometry::StereoRig rig = test::MakeRig(640, 480, 500.0, 319.5, 239.5, 0.3);
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Isometry3d> poses;  // T_w_frame
  // Errors carried along a track (as VO-6 makes them: each pair's template is cut at the
  // track's last left match): a track's left error is this fraction of the last one's
  // plus a fresh match error (1: a random walk), and its right error this fraction of the
  // left's plus its own (WindowOptions::track_carry, stereo_carry).
  double track_carry = 0.0, stereo_carry = 0.0;
  mutable std::unordered_map<std::int64_t, Eigen::Vector2d> walk;  // a track's left error so far

  explicit Scene(int frames, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> ux(-15, 15), uy(-3, 1.5), uz(3, 2 + 0.5 * frames + 40);
    for (int i = 0; i < 3000; ++i) points.emplace_back(ux(rng), uy(rng), uz(rng));
    for (int k = 0; k < frames; ++k) {
      poses.push_back(geometry::PoseFromXyzRpy(0.02 * k, 0.0, 0.5 * k, 0.0, 0.004 * k, 0.0));
    }
  }

  // Noisy stereo observations of the points in view from frame k; the right image's x is
  // offset by `disparity_offset_px` (a calibration error).
  std::vector<WindowObservation> Observe(int k, double sigma_px, double disparity_offset_px, std::mt19937* rng) const {
    std::normal_distribution<double> g(0.0, sigma_px);
    std::vector<WindowObservation> out;
    TriangulationLimits limits;
    limits.max_gap_rad = 1.0;
    const Eigen::Matrix2d S = std::max(1e-6, sigma_px * sigma_px) * Eigen::Matrix2d::Identity();
    for (std::size_t i = 0; i < points.size(); ++i) {
      const Eigen::Vector3d P = poses[static_cast<std::size_t>(k)].inverse() * points[i];
      if (P.z() < 2.0 || P.z() > 40.0) continue;
      Eigen::Vector2d l, r;
      if (!rig.left->Project(P, &l) || !rig.right->Project(P, &r)) continue;
      if (l.x() < 10 || l.y() < 10 || l.x() > 629 || l.y() > 469 || r.x() < 10 || r.x() > 629) continue;
      WindowObservation z;
      z.track_id = static_cast<std::int64_t>(i);
      Eigen::Vector2d left_error(g(*rng), g(*rng));
      Eigen::Vector2d right_error = Eigen::Vector2d(g(*rng) + disparity_offset_px, g(*rng));
      if (track_carry > 0 || stereo_carry > 0) {
        Eigen::Vector2d& carried = walk.try_emplace(z.track_id, Eigen::Vector2d::Zero()).first->second;
        carried = track_carry * carried + left_error;
        left_error = carried;
        right_error += stereo_carry * left_error;
      }
      z.left = l + left_error;
      z.right = r + right_error;
      z.Sigma_left = S;
      z.Sigma_right = S;
      StereoPoint sp;
      if (!TriangulateStereo(rig, z.left, S, z.right, S, limits, &sp)) continue;
      z.P = sp.P;
      z.Sigma = sp.Sigma;
      out.push_back(z);
      if (out.size() >= 250) break;
    }
    return out;
  }
};

struct DriveResult {
  double end_error_m = 0;         // |composed - true| at the last frame
  double window_end_error_m = 0;  // |the window's newest pose - true| at the last frame
  double max_delta_error_m = 0;   // largest error of one published delta
  double last_offset_px = 0;
  std::vector<double> offsets_px;  // the offset used after each refinement
  std::vector<double> window_offsets_px;  // each full window's own estimate
  double filter_offset_px = 0, filter_sigma_px = 0;  // the drive-wide filter at the end
  std::vector<double> nees;  // each published delta's error under WindowSolution::covariance
  int with_correction = 0, step_only = 0;  // deltas published either way (carries_correction)
};

// Runs a window of `size` keyframes along the scene (size 2: frame-to-frame), each new
// pose started from the truth perturbed by a few centimetres and a few tenths of a
// degree, and composes the published deltas as VO's users do.
DriveResult Drive(const Scene& scene, int size, double sigma_px, double offset_px, double offset_sigma_px,
                  unsigned seed, WindowOptions wo = {}) {
  wo.max_frames = size;
  wo.max_iterations = 15;
  wo.disparity_offset_sigma_px = offset_sigma_px;
  SlidingWindow window(wo);
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  window.AddFrame(0, Eigen::Isometry3d::Identity(), scene.Observe(0, sigma_px, offset_px, &rng));
  DriveResult out;
  Eigen::Isometry3d last = Eigen::Isometry3d::Identity();  // the newest pose, window frame
  Eigen::Isometry3d composed = Eigen::Isometry3d::Identity();  // the published deltas composed
  for (int k = 1; k < static_cast<int>(scene.poses.size()); ++k) {
    const Eigen::Isometry3d truth = scene.poses[static_cast<std::size_t>(k - 1)].inverse() * scene.poses[static_cast<std::size_t>(k)];
    const Eigen::Isometry3d guess =
        truth * geometry::PoseFromXyzRpy(0.03 * g(rng), 0.03 * g(rng), 0.03 * g(rng), 0.005 * g(rng), 0.005 * g(rng),
                                         0.005 * g(rng));
    window.AddFrame(k, window.pose(window.size() - 1) * guess, scene.Observe(k, sigma_px, offset_px, &rng));
    const WindowSolution w = window.Refine(scene.rig);
    EXPECT_TRUE(w.ok) << "frame " << k;
    if (!w.ok) return out;
    EXPECT_TRUE(w.covariance.allFinite());
    EXPECT_GT(w.covariance.diagonal().minCoeff(), 0.0);
    // Published as VisualOdometry does: the newest pose against the last one published
    // while the covariance carries that pose's correction, else the window's last step
    // (every frame here is a keyframe, so `last` is the reference pose before refining).
    EXPECT_EQ(w.carries_correction, k >= 2 && k < size) << "frame " << k;
    ++(w.carries_correction ? out.with_correction : out.step_only);
    const Eigen::Isometry3d delta =
        w.carries_correction ? last.inverse() * window.pose(window.size() - 1) : w.T_prev_last;
    last = window.pose(window.size() - 1);
    composed = composed * delta;
    out.max_delta_error_m = std::max(out.max_delta_error_m, (delta.translation() - truth.translation()).norm());
    geometry::Vector6d e = geometry::XyzRpyFromPose(delta) - geometry::XyzRpyFromPose(truth);
    for (int i = 3; i < 6; ++i) e(i) = geometry::WrapAngle(e(i));
    out.nees.push_back(e.dot(w.covariance.ldlt().solve(e)));
    out.last_offset_px = w.disparity_offset_px;
    out.offsets_px.push_back(w.disparity_offset_px);
    if (w.window_offset_sigma_px > 0) out.window_offsets_px.push_back(w.window_offset_px);
  }
  out.filter_offset_px = window.disparity_offset_px();
  out.filter_sigma_px = window.disparity_offset_sigma_px();
  out.end_error_m = ((scene.poses[0] * composed).translation() - scene.poses.back().translation()).norm();
  out.window_end_error_m = ((scene.poses[0] * last).translation() - scene.poses.back().translation()).norm();
  return out;
}

TEST(SlidingWindow, ExactObservationsGiveTheTrueMotionFromAPerturbedStart) {
  const Scene scene(8, 3);
  const DriveResult r = Drive(scene, 5, 0.0, 0.0, 0.0, 1);
  EXPECT_LT(r.max_delta_error_m, 1e-6);
  EXPECT_LT(r.end_error_m, 1e-5);
}

// The window's own estimate of the newest pose drifts less than frame-to-frame. The
// published deltas compose to it only while the window fills: once keyframes leave the
// window each delta is the window's last step alone (WindowSolution::carries_correction),
// so the composed path keeps about frame-to-frame drift here (independent noise, where
// the corrections were honest) for deltas whose covariance holds on rock fields too.
TEST(SlidingWindow, WindowOfFiveDriftsLessThanFrameToFrame) {
  // Same scene, same noise draws (same seed): only the window size differs.
  double err2 = 0, err5 = 0, composed5 = 0;
  for (unsigned seed : {11u, 12u, 13u, 14u}) {
    const Scene scene(30, seed);
    err2 += Drive(scene, 2, 0.3, 0.0, 0.0, seed).end_error_m;
    const DriveResult r5 = Drive(scene, 5, 0.3, 0.0, 0.0, seed);
    err5 += r5.window_end_error_m;
    composed5 += r5.end_error_m;
  }
  EXPECT_LT(err5, 0.8 * err2) << "window 5: " << err5 / 4 << " m, frame-to-frame: " << err2 / 4 << " m";
  EXPECT_LT(composed5, 1.3 * err2) << "window 5 composed: " << composed5 / 4 << " m, frame-to-frame: " << err2 / 4
                                   << " m";
  std::cout << "end error: window 5 " << err5 / 4 << " m (composed deltas " << composed5 / 4
            << " m), frame-to-frame " << err2 / 4 << " m\n";
}

// The covariance VO publishes with a refined delta (the window's own, with the previous
// pose's correction while the window fills, the last step's alone once keyframes leave
// it) agrees with the delta's real errors when the match covariances are
// right: the mean NEES over many deltas is near 6 (6 degrees of freedom), not far below
// (the correction double-counted) nor above (the correction left out: the delta starts
// from the previous pose as it was published, before this refinement moved it).
TEST(SlidingWindow, PublishedDeltaCovarianceMatchesItsErrors) {
  std::vector<double> nees, filling;
  for (unsigned seed : {81u, 82u, 83u, 84u}) {
    const Scene scene(25, seed);
    const DriveResult r = Drive(scene, 5, 0.3, 0.0, 0.0, seed);
    EXPECT_EQ(r.with_correction, 3);  // frames 2 to 4, while the window fills
    EXPECT_EQ(r.step_only, 21);       // frame 1 (no previous refinement), then full windows
    filling.insert(filling.end(), r.nees.begin() + 1, r.nees.begin() + 4);  // with the correction
    nees.insert(nees.end(), r.nees.begin() + 4, r.nees.end());  // full windows only
  }
  double filling_mean = 0;
  for (double v : filling) filling_mean += v / double(filling.size());
  EXPECT_GT(filling_mean, 2.5) << filling.size() << " deltas with the correction";
  EXPECT_LT(filling_mean, 11.0) << filling.size() << " deltas with the correction";
  ASSERT_GE(nees.size(), 60u);
  double mean = 0;
  for (double v : nees) mean += v / double(nees.size());
  const auto beyond = std::count_if(nees.begin(), nees.end(), [](double v) { return v > 20.06; });
  EXPECT_GT(mean, 4.0) << nees.size() << " deltas";
  EXPECT_LT(mean, 8.5) << nees.size() << " deltas";
  EXPECT_LE(beyond, 2) << "of " << nees.size() << " deltas beyond the 99.7 % bound";
  std::cout << "window 5, " << nees.size() << " deltas: NEES mean " << mean << ", " << beyond
            << " beyond 20.06\n";
}

// Tracks chained as VO-6 makes them (each template cut at the last match, so a match error
// carries into every later observation of the track): taken as independent, the window
// counts a track's early errors once per keyframe that sees them, and its published
// covariance claims more than the data give (navbench's closed loop put 4.6 % of the
// window's deltas beyond the 99.7 % bound). Weighing the random walk's steps
// (WindowOptions::track_carry = stereo_carry = 1) makes it honest again, and the estimate
// no worse.
TEST(SlidingWindow, ChainedTrackErrorsAreWeighedAsARandomWalk) {
  std::vector<double> nees_independent, nees_chained;
  double end_independent = 0, end_chained = 0;
  for (unsigned seed : {91u, 92u, 93u, 94u}) {
    for (bool chained_model : {false, true}) {
      Scene scene(25, seed);
      scene.track_carry = scene.stereo_carry = 1.0;
      WindowOptions wo;
      wo.track_carry = wo.stereo_carry = chained_model ? 1.0 : 0.0;
      const DriveResult r = Drive(scene, 5, 0.3, 0.0, 0.0, seed, wo);
      ASSERT_EQ(r.nees.size(), 24u);
      auto& nees = chained_model ? nees_chained : nees_independent;
      nees.insert(nees.end(), r.nees.begin() + 4, r.nees.end());  // full windows
      (chained_model ? end_chained : end_independent) += r.end_error_m;
    }
  }
  const auto summary = [](const std::vector<double>& v, double* mean) {
    *mean = 0;
    for (double x : v) *mean += x / double(v.size());
    return std::count_if(v.begin(), v.end(), [](double x) { return x > 20.06; });
  };
  double mean_independent = 0, mean_chained = 0;
  const auto beyond_independent = summary(nees_independent, &mean_independent);
  const auto beyond_chained = summary(nees_chained, &mean_chained);
  EXPECT_GT(mean_chained, 4.0) << nees_chained.size() << " deltas";
  EXPECT_LT(mean_chained, 8.5) << nees_chained.size() << " deltas";
  EXPECT_LE(beyond_chained, 2) << "of " << nees_chained.size() << " deltas beyond the 99.7 % bound";
  // The independent model (the window before) fails the same bounds on the same errors:
  // the overconfidence this guards against.
  EXPECT_TRUE(mean_independent > 8.5 || beyond_independent > 2)
      << "independent model: NEES mean " << mean_independent << ", " << beyond_independent << " beyond";
  EXPECT_GT(mean_independent, 1.3 * mean_chained);
  EXPECT_LT(end_chained, 1.2 * end_independent);
  std::cout << "chained track errors, " << nees_chained.size() << " deltas: NEES mean " << mean_chained << ", "
            << beyond_chained << " beyond 20.06 (taken as independent: " << mean_independent << ", "
            << beyond_independent << "); end error " << end_chained / 4 << " m (independent model "
            << end_independent / 4 << " m)\n";
}

// The closed form of a track's error covariance under the carry model, stacked as the
// window stacks observations (left x y, right x y per keyframe): with
//   l_n = rho l_n-1 + w_n (l_0 = w_0),   r_n = rho_s l_n + s_n,
// V_n = Var(l_n) = rho^2 V_n-1 + SL_n, Cov(l_i, l_j) = rho^(j-i) V_i (i <= j),
// Cov(l_i, r_j) = rho_s Cov(l_i, l_j), Cov(r_i, r_j) = rho_s^2 Cov(l_i, l_j) + [i=j] SR_i.
Eigen::MatrixXd CarriedErrorCovariance(const std::vector<Eigen::Matrix2d>& SL, const std::vector<Eigen::Matrix2d>& SR,
                                       double rho, double rho_s) {
  const int m = static_cast<int>(SL.size());
  std::vector<Eigen::Matrix2d> V(SL.size());
  for (int n = 0; n < m; ++n) V[n] = (n > 0 ? rho * rho * V[n - 1] : Eigen::Matrix2d::Zero().eval()) + SL[n];
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(4 * m, 4 * m);
  for (int i = 0; i < m; ++i) {
    for (int j = i; j < m; ++j) {
      const Eigen::Matrix2d ll = std::pow(rho, j - i) * V[i];
      C.block<2, 2>(4 * i, 4 * j) = ll;                                        // l_i, l_j
      C.block<2, 2>(4 * i, 4 * j + 2) = rho_s * ll;                            // l_i, r_j
      C.block<2, 2>(4 * i + 2, 4 * j) = rho_s * (i == j ? ll : Eigen::Matrix2d::Zero().eval());  // r_i, l_j
      C.block<2, 2>(4 * i + 2, 4 * j + 2) = rho_s * rho_s * ll + (i == j ? SR[i] : Eigen::Matrix2d::Zero().eval());
    }
  }
  // r_i against a later l_j: l_j carries l_i, and r_i = rho_s l_i + s_i (s_i independent).
  for (int i = 0; i < m; ++i) {
    for (int j = i + 1; j < m; ++j) C.block<2, 2>(4 * i + 2, 4 * j) = rho_s * std::pow(rho, j - i) * V[i];
  }
  return C.selfadjointView<Eigen::Upper>();
}

// Known answer for the weighting: the rows ToIndependentErrors makes, weighed with the
// matches' own information blockdiag(SL^-1, SR^-1), give exactly the inverse of the
// closed-form covariance (the window's information is the carry model's), for several
// carries, 0 (independent: the rows unchanged) and 1 (the random walk) included.
TEST(SlidingWindow, CarriedTrackErrorsAreWeighedByTheClosedFormCovariance) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  const int m = 5;
  std::vector<Eigen::Matrix2d> SL, SR;
  Eigen::MatrixXd W = Eigen::MatrixXd::Zero(4 * m, 4 * m);
  for (int n = 0; n < m; ++n) {
    Eigen::Matrix2d A, B;
    A << 0.3 + u(rng), u(rng), u(rng), 0.4 + u(rng);
    B << 0.2 + u(rng), u(rng), u(rng), 0.5 + u(rng);
    SL.push_back(A * A.transpose() + 0.01 * Eigen::Matrix2d::Identity());
    SR.push_back(B * B.transpose() + 0.01 * Eigen::Matrix2d::Identity());
    W.block<2, 2>(4 * n, 4 * n) = SL.back().inverse();
    W.block<2, 2>(4 * n + 2, 4 * n + 2) = SR.back().inverse();
  }
  for (const auto& [rho, rho_s] : std::vector<std::pair<double, double>>{{0.0, 0.0}, {0.5, 0.9}, {0.8, 0.3}, {1.0, 1.0}}) {
    Eigen::MatrixXd L = Eigen::MatrixXd::Identity(4 * m, 4 * m);
    ToIndependentErrors(L, m, rho, rho_s);
    const Eigen::MatrixXd C = CarriedErrorCovariance(SL, SR, rho, rho_s);
    const Eigen::MatrixXd info = L.transpose() * W * L;
    const double err = (info * C - Eigen::MatrixXd::Identity(4 * m, 4 * m)).cwiseAbs().maxCoeff();
    EXPECT_LT(err, 1e-9) << "rho " << rho << ", rho_s " << rho_s;
    // Each row block holds at most two keyframes: L is lower block-bidiagonal.
    for (int i = 0; i < m; ++i) {
      for (int j = 0; j < m; ++j) {
        if (j > i || j < i - 1) {
          const double outside = L.block<4, 4>(4 * i, 4 * j).cwiseAbs().maxCoeff();
          EXPECT_EQ(outside, 0.0) << i << "," << j;
        }
      }
    }
    if (rho == 0.0 && rho_s == 0.0) {
      EXPECT_TRUE(L.isIdentity(0.0));
    }
  }
  // A residual vector is taken the same way as the rows of a Jacobian.
  Eigen::VectorXd r = Eigen::VectorXd::LinSpaced(4 * m, 1.0, 4.0 * m);
  Eigen::MatrixXd L = Eigen::MatrixXd::Identity(4 * m, 4 * m);
  ToIndependentErrors(L, m, 0.6, 0.7);
  const Eigen::VectorXd expected = L * r;
  ToIndependentErrors(r, m, 0.6, 0.7);
  EXPECT_LT((r - expected).cwiseAbs().maxCoeff(), 1e-12);
}

// Errors carried in part (rho 0.6 along the track, 0.9 into the right match): weighed
// with the same carries the window's published deltas are honest, and taken as
// independent they claim more than the data give.
TEST(SlidingWindow, PartlyCarriedTrackErrorsGiveAnHonestWindow) {
  std::vector<double> nees_matched, nees_independent;
  for (unsigned seed : {81u, 82u, 83u}) {
    for (bool matched : {false, true}) {
      Scene scene(25, seed);
      scene.track_carry = 0.6;
      scene.stereo_carry = 0.9;
      WindowOptions wo;
      wo.track_carry = matched ? 0.6 : 0.0;
      wo.stereo_carry = matched ? 0.9 : 0.0;
      const DriveResult r = Drive(scene, 5, 0.3, 0.0, 0.0, seed, wo);
      ASSERT_EQ(r.nees.size(), 24u);
      auto& nees = matched ? nees_matched : nees_independent;
      nees.insert(nees.end(), r.nees.begin() + 4, r.nees.end());
    }
  }
  const auto mean_of = [](const std::vector<double>& v) {
    double m = 0;
    for (double x : v) m += x / double(v.size());
    return m;
  };
  const auto beyond = std::count_if(nees_matched.begin(), nees_matched.end(), [](double x) { return x > 20.06; });
  EXPECT_GT(mean_of(nees_matched), 4.0);
  EXPECT_LT(mean_of(nees_matched), 8.5);
  EXPECT_LE(beyond, 2) << "of " << nees_matched.size();
  EXPECT_GT(mean_of(nees_independent), 1.2 * mean_of(nees_matched));
  std::cout << "carry 0.6/0.9, " << nees_matched.size() << " deltas: NEES mean " << mean_of(nees_matched) << ", "
            << beyond << " beyond 20.06 (taken as independent: " << mean_of(nees_independent) << ")\n";
}

// Refines one window of `frames` keyframes of `scene` (poses started at the truth) with
// options `wo`, the noise drawn from `seed`; the scene's carried errors start afresh.
WindowSolution RefineOnce(Scene* scene, int frames, double sigma_px, unsigned seed, const WindowOptions& wo,
                          geometry::Vector6d* error = nullptr) {
  scene->walk.clear();
  std::mt19937 rng(seed);
  WindowOptions o = wo;
  o.max_frames = frames;
  o.max_iterations = 15;
  SlidingWindow window(o);
  for (int k = 0; k < frames; ++k) {
    window.AddFrame(k, scene->poses[0].inverse() * scene->poses[static_cast<std::size_t>(k)],
                    scene->Observe(k, sigma_px, 0.0, &rng));
  }
  const WindowSolution w = window.Refine(scene->rig);
  if (error) {
    const Eigen::Isometry3d truth = scene->poses[static_cast<std::size_t>(frames - 2)].inverse() *
                                    scene->poses[static_cast<std::size_t>(frames - 1)];
    *error = geometry::XyzRpyFromPose(w.T_prev_last) - geometry::XyzRpyFromPose(truth);
    for (int i = 3; i < 6; ++i) (*error)(i) = geometry::WrapAngle((*error)(i));
  }
  return w;
}

// Known answer: with the covariance's carries equal to the weights' the sandwich
// S^-1 M S^-1 is S^-1 (M = S), without Huber and with it (a down-weighted row's error is
// taken as IRLS takes it), with the disparity offset held or not; so is its variance
// factor the window's own.
TEST(SlidingWindow, SandwichUnderTheWeightsOwnModelIsTheInverseNormalMatrix) {
  for (const auto& [rho, rho_s] : std::vector<std::pair<double, double>>{{0.0, 0.0}, {0.6, 0.9}, {1.0, 1.0}}) {
    for (const double huber : {1e6, 1.0}) {
      for (const double offset_sigma : {0.0, 0.5}) {
        Scene scene(4, 31);
        scene.track_carry = 0.8;
        scene.stereo_carry = 1.0;
        WindowOptions wo;
        wo.track_carry = rho;
        wo.stereo_carry = rho_s;
        wo.huber_sigmas = huber;
        wo.disparity_offset_sigma_px = offset_sigma;
        const WindowSolution fit = RefineOnce(&scene, 4, 0.3, 5, wo);
        wo.covariance_track_carry = rho;
        wo.covariance_stereo_carry = rho_s;
        const WindowSolution sandwich = RefineOnce(&scene, 4, 0.3, 5, wo);
        ASSERT_TRUE(fit.ok && sandwich.ok);
        EXPECT_FALSE(fit.sandwich);
        EXPECT_TRUE(sandwich.sandwich);
        const std::string what = "carries " + std::to_string(rho) + "/" + std::to_string(rho_s) + ", huber " +
                                 std::to_string(huber) + ", offset sigma " + std::to_string(offset_sigma);
        // The same estimate: the weights are the same.
        EXPECT_TRUE(sandwich.T_prev_last.isApprox(fit.T_prev_last, 1e-12)) << what;
        const double scale = fit.step_covariance.diagonal().maxCoeff();
        EXPECT_LT((sandwich.step_covariance - fit.step_covariance).cwiseAbs().maxCoeff(), 1e-6 * scale) << what;
        EXPECT_LT((sandwich.fit_step_covariance - fit.step_covariance).cwiseAbs().maxCoeff(), 1e-9 * scale) << what;
        EXPECT_NEAR(sandwich.covariance_variance_factor, fit.variance_factor, 1e-6 * fit.variance_factor) << what;
        EXPECT_EQ(fit.covariance_variance_factor, fit.variance_factor) << what;
      }
    }
  }
}

// Errors truly carried (a random walk along the track, l_n = l_n-1 + w_n, repeated in
// the right match), weighed as independent (the default 0 and 0): over noise draws on
// one scene the estimate's scatter matches the sandwich under carries 1 and 1 (NEES mean
// near 6, the chi-square's), while the weights' own covariance S^-1 claims far less.
TEST(SlidingWindow, SandwichUnderTheTrueCarriesMatchesTheEstimatesScatter) {
  Scene scene(4, 41);
  scene.track_carry = 1.0;
  scene.stereo_carry = 1.0;
  WindowOptions wo;  // weights: independent errors
  wo.covariance_track_carry = 1.0;
  wo.covariance_stereo_carry = 1.0;
  const int draws = 80;
  std::vector<geometry::Vector6d> errors;
  Matrix6d sandwich = Matrix6d::Zero(), fit = Matrix6d::Zero();
  for (int d = 0; d < draws; ++d) {
    geometry::Vector6d e;
    const WindowSolution w = RefineOnce(&scene, 4, 0.3, 1000u + static_cast<unsigned>(d), wo, &e);
    ASSERT_TRUE(w.ok);
    errors.push_back(e);
    sandwich += w.step_covariance / draws;
    fit += w.fit_step_covariance / draws;
  }
  double nees_sandwich = 0, nees_fit = 0;
  for (const geometry::Vector6d& e : errors) {
    nees_sandwich += e.dot(sandwich.ldlt().solve(e)) / draws;
    nees_fit += e.dot(fit.ldlt().solve(e)) / draws;
  }
  // The mean of 80 chi-square(6) draws: 6 +- 0.4 (one sigma); the sandwich also holds the
  // linearisation and the points' start, so a wider band.
  EXPECT_GT(nees_sandwich, 4.5);
  EXPECT_LT(nees_sandwich, 7.5);
  EXPECT_GT(nees_fit, 8.5);
  EXPECT_GT(nees_fit, 1.3 * nees_sandwich);
  std::cout << draws << " draws of random-walk errors: NEES mean " << nees_sandwich << " under the sandwich (1/1), "
            << nees_fit << " under S^-1 (0/0)\n";
}

TEST(SlidingWindow, EstimatesADisparityOffsetAndRemovesItsScaleError) {
  const Scene scene(20, 21);
  const DriveResult off = Drive(scene, 5, 0.1, 0.3, 0.0, 21);    // offset not estimated
  const DriveResult on = Drive(scene, 5, 0.1, 0.3, 0.5, 21);     // estimated
  EXPECT_NEAR(on.last_offset_px, 0.3, 0.05);
  EXPECT_LT(on.end_error_m, 0.5 * off.end_error_m) << on.end_error_m << " against " << off.end_error_m;
}

// The offset is one drive-wide estimate: over a drive it converges to an injected offset,
// and to ~0 with none, instead of following each window's noise.
TEST(SlidingWindow, DriveWideOffsetConvergesToTheInjectedOffsetAndToZeroWithNone) {
  for (double injected : {0.0, 0.25}) {
    for (unsigned seed : {41u, 42u, 43u}) {
      const Scene scene(30, seed);
      const DriveResult r = Drive(scene, 5, 0.3, injected, 0.5, seed);
      ASSERT_GE(r.offsets_px.size(), 20u);
      EXPECT_NEAR(r.filter_offset_px, injected, 0.04) << "seed " << seed;
      EXPECT_LT(r.filter_sigma_px, 0.04);
      // Converged, not following the windows: over the last ten windows it moves by a
      // fraction of what their own estimates scatter.
      const auto [lo, hi] = std::minmax_element(r.offsets_px.end() - 10, r.offsets_px.end());
      const auto [wlo, whi] = std::minmax_element(r.window_offsets_px.end() - 10, r.window_offsets_px.end());
      EXPECT_LT(*hi - *lo, 0.03) << "injected " << injected << " seed " << seed;
      EXPECT_LT(*hi - *lo, 0.25 * (*whi - *wlo)) << "injected " << injected << " seed " << seed;
    }
  }
}

// Each window adds 1/window_size of its information (windows share observations): the
// filter's sigma is then of the order of the spread of its estimates over noise draws,
// not several times smaller.
TEST(SlidingWindow, OffsetFilterSigmaMatchesTheSpreadOverNoiseDraws) {
  const Scene scene(30, 51);
  std::vector<double> est;
  double sigma = 0;
  for (unsigned seed = 60; seed < 72; ++seed) {
    const DriveResult r = Drive(scene, 5, 0.3, 0.0, 0.5, seed);
    est.push_back(r.filter_offset_px);
    sigma += r.filter_sigma_px / 12;
  }
  double mean = 0, var = 0;
  for (double e : est) mean += e / double(est.size());
  for (double e : est) var += (e - mean) * (e - mean) / double(est.size() - 1);
  const double spread = std::sqrt(var);
  EXPECT_GT(sigma, 0.5 * spread) << "filter sigma " << sigma << " px, spread " << spread << " px";
  EXPECT_LT(sigma, 6.0 * spread) << "filter sigma " << sigma << " px, spread " << spread << " px";
}

// An offset the filter cannot tell from the matcher's systematic disparity error is not
// used (the window holds zero); a larger one is.
TEST(SlidingWindow, OffsetWithinTheSystematicErrorIsNotUsed) {
  WindowOptions wo;
  wo.disparity_offset_systematic_px = 0.05;
  wo.disparity_offset_min_sigmas = 2.0;
  const Scene scene(25, 31);
  const DriveResult small = Drive(scene, 5, 0.1, 0.06, 0.5, 31, wo);
  EXPECT_NEAR(small.filter_offset_px, 0.06, 0.02);  // estimated ...
  EXPECT_EQ(small.last_offset_px, 0.0);              // ... but not used
  const DriveResult large = Drive(scene, 5, 0.1, 0.3, 0.5, 31, wo);
  EXPECT_NEAR(large.last_offset_px, 0.3, 0.03);
  EXPECT_EQ(large.last_offset_px, large.filter_offset_px);
  // Used, the large offset's scale error is mostly removed.
  const DriveResult ignored = Drive(scene, 5, 0.1, 0.3, 0.0, 31);
  EXPECT_LT(large.end_error_m, 0.5 * ignored.end_error_m);
}

TEST(SlidingWindow, PopNewestRestoresThePosesAndTheOldestFrame) {
  const Scene scene(7, 5);
  WindowOptions wo;
  wo.max_frames = 3;
  SlidingWindow window(wo);
  std::mt19937 rng(5);
  for (int k = 0; k < 5; ++k) {
    window.AddFrame(k, scene.poses[static_cast<std::size_t>(k)], scene.Observe(k, 0.2, 0.0, &rng));
    if (k > 0) {
      ASSERT_TRUE(window.Refine(scene.rig).ok);
    }
  }
  ASSERT_EQ(window.size(), 3);
  std::vector<Eigen::Isometry3d> before;
  for (int i = 0; i < window.size(); ++i) before.push_back(window.pose(i));
  window.AddFrame(5, scene.poses[5] * geometry::PoseFromXyzRpy(0.5, 0, 0, 0, 0, 0.1), scene.Observe(5, 0.2, 0.0, &rng));
  ASSERT_TRUE(window.Refine(scene.rig).ok);
  EXPECT_EQ(window.frame_id(0), 3);  // frame 2 slid out
  window.PopNewest();
  ASSERT_EQ(window.size(), 3);
  EXPECT_EQ(window.frame_id(0), 2);
  EXPECT_EQ(window.frame_id(2), 4);
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(window.pose(i).isApprox(before[static_cast<std::size_t>(i)], 1e-12));
}

TEST(SlidingWindow, RelativePoseJacobianMatchesTheRetraction) {
  const Eigen::Isometry3d a = geometry::PoseFromXyzRpy(1, 2, 3, 0.1, -0.2, 0.3);
  const Eigen::Isometry3d b = geometry::PoseFromXyzRpy(1.5, 2.1, 3.2, 0.12, -0.25, 0.4);
  const Eigen::Matrix<double, 6, 12> J = RelativePoseJacobian(a, b);
  Eigen::Matrix<double, 6, 1> da, db;
  da << 1e-4, -2e-4, 1e-4, 2e-4, 1e-4, -1e-4;
  db << -1e-4, 1e-4, 2e-4, -1e-4, 2e-4, 1e-4;
  const geometry::Vector6d f0 = geometry::XyzRpyFromPose(a.inverse() * b);
  const geometry::Vector6d f1 = geometry::XyzRpyFromPose(Retract(a, da).inverse() * Retract(b, db));
  Eigen::Matrix<double, 12, 1> d;
  d << da, db;
  EXPECT_LT((f1 - f0 - J * d).norm(), 1e-6);
}

// ---- VisualOdometry in windowed mode: a failed pair leaves the window consistent ----

constexpr double kDepth = 6.0, kFocal = 400.0, kTexel = 0.006;
constexpr int kTex = 1024;

cv::Mat Texture() {
  std::mt19937 rng(7);
  std::normal_distribution<float> g(0, 1);
  cv::Mat acc = cv::Mat::zeros(kTex, kTex, CV_32F);
  for (double sigma : {1.5, 4.0}) {
    cv::Mat noise(kTex, kTex, CV_32F);
    for (int y = 0; y < kTex; ++y)
      for (int x = 0; x < kTex; ++x) noise.at<float>(y, x) = g(rng);
    cv::GaussianBlur(noise, noise, cv::Size(0, 0), sigma);
    cv::normalize(noise, noise, 0, 1, cv::NORM_MINMAX);
    acc += noise;
  }
  cv::Mat out;
  cv::normalize(acc, out, 20, 235, cv::NORM_MINMAX);
  return out;
}

// A textured wall 6 m ahead, seen with the rig moved rig_x to its right.
cv::Mat RenderWall(const cv::Mat& texture, const geometry::CameraModel& cam, double rig_x) {
  cv::Mat mx(cam.height(), cam.width(), CV_32F), my(cam.height(), cam.width(), CV_32F);
  for (int y = 0; y < cam.height(); ++y) {
    for (int x = 0; x < cam.width(); ++x) {
      Eigen::Vector3d o, d;
      cam.BackProject(Eigen::Vector2d(x, y), &o, &d);
      const Eigen::Vector3d X = o + Eigen::Vector3d(rig_x, 0, 0) + (kDepth - o.z()) / d.z() * d;
      mx.at<float>(y, x) = static_cast<float>(kTex / 2 + X.x() / kTexel);
      my.at<float>(y, x) = static_cast<float>(kTex / 2 + X.y() / kTexel);
    }
  }
  cv::Mat out, out8;
  cv::remap(texture, out, mx, my, cv::INTER_CUBIC, cv::BORDER_REFLECT);
  out.convertTo(out8, CV_8U);
  return out8;
}

TEST(WindowedVisualOdometry, FailedPairRestartsTheWindowAndMotionStaysRight) {
  const geometry::StereoRig rig = test::MakeRig(384, 288, kFocal, 191.5, 143.5, 0.25);
  const cv::Mat texture = Texture();
  auto pair = [&](double rig_x, std::int64_t id, bool blank) {
    StereoImages im;
    im.rig = rig;
    im.frame_id = id;
    im.utime = id * 100000;
    im.left = blank ? cv::Mat(rig.left->height(), rig.left->width(), CV_8UC1, cv::Scalar(128))
                    : RenderWall(texture, *rig.left, rig_x);
    im.right = blank ? im.left.clone() : RenderWall(texture, *rig.right, rig_x);
    return im;
  };
  Matrix6d prior = Matrix6d::Zero();
  prior.diagonal() << 0.01, 0.01, 0.01, 1e-4, 1e-4, 1e-4;
  VoOptions o;
  ASSERT_GE(o.window_size, 2);  // windowed by default
  VisualOdometry vo(o);
  Eigen::Isometry3d step = Eigen::Isometry3d::Identity();
  step.translation() = Eigen::Vector3d(0.12, 0, 0);
  ASSERT_EQ(vo.Process(pair(0.0, 0, false), step, prior).status, VoStatus::kBaseline);
  std::vector<VoResult> results;
  for (int k = 1; k <= 6; ++k) {
    const bool blank = k == 3;  // a pair with nothing to see
    results.push_back(vo.Process(pair(0.12 * k, k, blank), step, prior));
  }
  // Pairs 1, 2: measured, the window grows. Pair 3: fails (no features), the window
  // restarts on it. Pair 4 tracks from the blank pair: too few features, restart on 4.
  // Pairs 5, 6: measured again, from a window of 2 then 3.
  EXPECT_EQ(results[0].status, VoStatus::kOk) << results[0].reason;
  EXPECT_EQ(results[1].status, VoStatus::kOk) << results[1].reason;
  EXPECT_EQ(results[1].window_frames, 3);
  EXPECT_NE(results[2].status, VoStatus::kOk);
  EXPECT_NE(results[3].status, VoStatus::kOk);
  for (int i : {4, 5}) {
    const VoResult& r = results[static_cast<std::size_t>(i)];
    ASSERT_EQ(r.status, VoStatus::kOk) << "pair " << i + 1 << ": " << r.reason;
    EXPECT_TRUE(r.keyframe);
    EXPECT_EQ(r.window_frames, i - 2);
    EXPECT_NEAR(r.T_prev_curr.translation().x(), 0.12, 0.01);
    EXPECT_NEAR(r.T_prev_curr.translation().z(), 0.0, 0.03);
  }
  EXPECT_EQ(results[5].track_length_max, 3);  // tracks restarted on pair 4
}

TEST(WindowedVisualOdometry, StandingStillIsMeasuredAgainstTheKeyframe) {
  const geometry::StereoRig rig = test::MakeRig(384, 288, kFocal, 191.5, 143.5, 0.25);
  const cv::Mat texture = Texture();
  Matrix6d prior = Matrix6d::Zero();
  prior.diagonal() << 0.01, 0.01, 0.01, 1e-4, 1e-4, 1e-4;
  VisualOdometry vo(VoOptions{});
  StereoImages im;
  im.rig = rig;
  im.left = RenderWall(texture, *rig.left, 0.0);
  im.right = RenderWall(texture, *rig.right, 0.0);
  ASSERT_EQ(vo.Process(im, Eigen::Isometry3d::Identity(), prior).status, VoStatus::kBaseline);
  for (int k = 1; k <= 3; ++k) {
    im.frame_id = k;
    const VoResult r = vo.Process(im, Eigen::Isometry3d::Identity(), prior);
    ASSERT_EQ(r.status, VoStatus::kOk) << r.reason;
    EXPECT_FALSE(r.keyframe);
    EXPECT_EQ(r.window_frames, 1);  // nothing joined the window
    EXPECT_LT(r.T_prev_curr.translation().norm(), 0.005);
  }
}

}  // namespace
}  // namespace rover::vo
