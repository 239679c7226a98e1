#include "vo/motion_estimation.hpp"

#include "geometry/pose.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>

namespace rover::vo {

namespace {

double Weight(const Correspondence& c) {
  // eq. (14): the volume of the two error ellipsoids.
  const double d = c.Sigma_prev.determinant() + c.Sigma_curr.determinant();
  return d > 0 ? 1.0 / d : 0.0;
}

}  // namespace

Eigen::Isometry3d WeightedLeastSquaresMotion(const std::vector<Correspondence>& c,
                                             const std::vector<int>& indices) {
  const int n = indices.empty() ? static_cast<int>(c.size()) : static_cast<int>(indices.size());
  auto at = [&](int k) -> const Correspondence& { return indices.empty() ? c[k] : c[indices[k]]; };
  double wsum = 0;
  Eigen::Vector3d mp = Eigen::Vector3d::Zero(), mc = Eigen::Vector3d::Zero();
  for (int k = 0; k < n; ++k) {
    const double w = Weight(at(k));
    wsum += w;
    mp += w * at(k).P_prev;
    mc += w * at(k).P_curr;
  }
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  if (!(wsum > 0)) return T;
  mp /= wsum;
  mc /= wsum;
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  for (int k = 0; k < n; ++k) {
    H += Weight(at(k)) * (at(k).P_prev - mp) * (at(k).P_curr - mc).transpose();
  }
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix3d& U = svd.matrixU();
  const Eigen::Matrix3d& V = svd.matrixV();
  Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
  D(2, 2) = (V * U.transpose()).determinant() < 0 ? -1.0 : 1.0;
  const Eigen::Matrix3d R = V * D * U.transpose();
  T.linear() = R;
  T.translation() = mc - R * mp;
  return T;
}

double ReprojectionGap(const Correspondence& c, const geometry::StereoRig& rig,
                       const Eigen::Isometry3d& T_curr_prev) {
  const Eigen::Vector3d P = T_curr_prev * c.P_prev;
  Eigen::Vector2d pl, pr;
  if (!rig.left->Project(P, &pl) || !rig.right->Project(P, &pr)) {
    return std::numeric_limits<double>::infinity();
  }
  return std::max((pl - c.left).norm(), (pr - c.right).norm());
}

RansacOutcome RansacMotion(const std::vector<Correspondence>& c, const geometry::StereoRig& rig,
                           const RansacOptions& options, const std::vector<int>& subset) {
  std::vector<int> pool = subset;
  if (pool.empty()) {
    pool.resize(c.size());
    std::iota(pool.begin(), pool.end(), 0);
  }
  RansacOutcome best;
  const int n = static_cast<int>(pool.size());
  const int s = std::max(3, options.sample_size);
  if (n < s) return best;
  std::mt19937_64 rng(options.seed);
  std::vector<int> sample(s);
  std::vector<int> inliers;
  inliers.reserve(n);
  double best_error = std::numeric_limits<double>::infinity();
  auto score = [&](const Eigen::Isometry3d& T, std::vector<int>* in, double* err) {
    in->clear();
    *err = 0;
    for (int k : pool) {
      // The gap is the larger of the two images': a left gap already over the threshold
      // settles it without projecting into the right image (same inliers, same error).
      const Eigen::Vector3d P = T * c[k].P_prev;
      Eigen::Vector2d pl, pr;
      if (!rig.left->Project(P, &pl)) continue;
      const double gl = (pl - c[k].left).norm();
      if (!(gl < options.inlier_px)) continue;
      if (!rig.right->Project(P, &pr)) continue;
      const double g = std::max(gl, (pr - c[k].right).norm());
      if (g < options.inlier_px) {
        in->push_back(k);
        *err += g;
      }
    }
  };
  for (int it = 0; it < options.iterations; ++it) {
    // Partial Fisher-Yates: s distinct indices into pool.
    for (int k = 0; k < s; ++k) {
      std::uniform_int_distribution<int> pick(k, n - 1);
      const int j = pick(rng);
      std::swap(pool[k], pool[j]);
      sample[k] = pool[k];
    }
    const Eigen::Isometry3d T = WeightedLeastSquaresMotion(c, sample);
    double err;
    score(T, &inliers, &err);
    if (inliers.size() > best.inliers.size() ||
        (inliers.size() == best.inliers.size() && err < best_error)) {
      best.inliers = inliers;
      best.T_curr_prev = T;
      best_error = err;
    }
  }
  if (best.inliers.size() >= static_cast<std::size_t>(s)) {
    const Eigen::Isometry3d T = WeightedLeastSquaresMotion(c, best.inliers);
    double err;
    score(T, &inliers, &err);
    if (inliers.size() >= best.inliers.size()) {
      best.inliers = inliers;
      best.T_curr_prev = T;
    }
  }
  std::sort(best.inliers.begin(), best.inliers.end());
  return best;
}

double MahalanobisSquared(const Correspondence& c, const Eigen::Isometry3d& T_prev_curr) {
  const Eigen::Matrix3d Rcp = T_prev_curr.linear().transpose();
  const Eigen::Vector3d r = c.P_curr - Rcp * (c.P_prev - T_prev_curr.translation());
  const Eigen::Matrix3d S = c.Sigma_curr + Rcp * c.Sigma_prev * Rcp.transpose();
  return r.dot(S.ldlt().solve(r));
}

double NestedDifferenceChi2(const Eigen::Matrix<double, 6, 1>& d, const Eigen::Matrix<double, 6, 6>& Sigma_a,
                            const Eigen::Matrix<double, 6, 6>& Sigma_b, double min_fraction) {
  using Matrix6 = Eigen::Matrix<double, 6, 6>;
  constexpr double kInf = std::numeric_limits<double>::infinity();
  if (!d.allFinite() || !Sigma_a.allFinite() || !Sigma_b.allFinite()) return kInf;
  const Eigen::LLT<Matrix6> llt(0.5 * (Sigma_b + Sigma_b.transpose()));
  if (llt.info() != Eigen::Success) return kInf;
  // Whitened by Sigma_b = L L^T: b's covariance is the identity, the difference's
  // I - L^-1 Sigma_a L^-T, whose eigenvalues lie in [0, 1] when a is the better estimate.
  const Matrix6 L_inv = llt.matrixL().solve(Matrix6::Identity());
  const Matrix6 M = L_inv * (Sigma_b - Sigma_a) * L_inv.transpose();
  const Eigen::SelfAdjointEigenSolver<Matrix6> eig(0.5 * (M + M.transpose()));
  if (eig.info() != Eigen::Success) return kInf;
  const Eigen::Matrix<double, 6, 1> y = eig.eigenvectors().transpose() * (L_inv * d);
  double chi2 = 0;
  for (int i = 0; i < 6; ++i) chi2 += y(i) * y(i) / std::max(eig.eigenvalues()(i), min_fraction);
  return chi2;
}

MlOutcome MaximumLikelihoodMotion(const std::vector<Correspondence>& c,
                                  const std::vector<int>& indices,
                                  const Eigen::Isometry3d& initial_T_prev_curr,
                                  int max_iterations, double tolerance) {
  MlOutcome out;
  Eigen::Vector3d t = initial_T_prev_curr.translation();
  Eigen::Vector3d rpy = geometry::RpyFromRotation(initial_T_prev_curr.linear());
  using Matrix6d = Eigen::Matrix<double, 6, 6>;
  using Vector6d = Eigen::Matrix<double, 6, 1>;
  Matrix6d H = Matrix6d::Zero();
  Eigen::Matrix3d R, dR[3];
  auto linearise = [&](Matrix6d* Hout, Vector6d* gout, double* cost) {
    geometry::RotationFromRpyDerivatives(rpy, &R, dR);
    const Eigen::Matrix3d Rcp = R.transpose();
    Hout->setZero();
    gout->setZero();
    *cost = 0;
    for (int k : indices) {
      const Correspondence& x = c[k];
      const Eigen::Vector3d d = x.P_prev - t;
      const Eigen::Vector3d r = x.P_curr - Rcp * d;  // eq. (17)
      const Eigen::Matrix3d W = (x.Sigma_curr + Rcp * x.Sigma_prev * R).inverse();
      Eigen::Matrix<double, 3, 6> J;
      J.leftCols<3>() = Rcp;
      for (int i = 0; i < 3; ++i) J.col(3 + i) = -dR[i].transpose() * d;
      const Eigen::Matrix<double, 6, 3> JtW = J.transpose() * W;
      *Hout += JtW * J;
      *gout += JtW * r;
      *cost += r.dot(W * r);
    }
  };
  Vector6d g;
  double cost = 0;
  for (int it = 0; it < max_iterations; ++it) {
    linearise(&H, &g, &cost);
    const Vector6d delta = -H.ldlt().solve(g);
    if (!delta.allFinite()) break;
    t += delta.head<3>();
    rpy += delta.tail<3>();
    out.iterations = it + 1;
    if (delta.cwiseAbs().maxCoeff() < tolerance) {
      out.converged = true;
      break;
    }
  }
  linearise(&H, &g, &cost);
  out.cost = cost;
  out.redundancy = 3 * static_cast<int>(indices.size()) - 6;
  out.variance_factor = out.redundancy > 0 ? cost / out.redundancy : 0.0;
  out.T_prev_curr = geometry::PoseFromXyzRpy(t.x(), t.y(), t.z(), rpy[0], rpy[1], rpy[2]);
  Eigen::FullPivLU<Matrix6d> lu(H);
  if (lu.isInvertible()) {
    out.covariance = lu.inverse();
    out.covariance = 0.5 * (out.covariance + out.covariance.transpose()).eval();
  } else {
    out.converged = false;
  }
  return out;
}

MotionUncertainty EstimateMotionUncertainty(const std::vector<Correspondence>& c,
                                            const std::vector<int>& indices,
                                            const Eigen::Isometry3d& T_prev_curr,
                                            const std::vector<int>& cluster, int num_clusters,
                                            const SharedErrors& shared) {
  using Matrix6d = Eigen::Matrix<double, 6, 6>;
  using Vector6d = Eigen::Matrix<double, 6, 1>;
  constexpr int kModes = 5;  // shift x, shift y, rotation, scale, disparity
  MotionUncertainty out;
  const Eigen::Vector3d t = T_prev_curr.translation();
  Eigen::Matrix3d R, dR[3];
  geometry::RotationFromRpyDerivatives(geometry::RpyFromRotation(T_prev_curr.linear()), &R, dR);
  const Eigen::Matrix3d Rcp = R.transpose();
  const double unit = 1.0 / std::max(1e-9, shared.half_size_px);
  const bool clustered = num_clusters >= 2 && cluster.size() == c.size();
  std::vector<Matrix6d> H_g(clustered ? num_clusters : 0, Matrix6d::Zero());
  std::vector<Vector6d> s_g(clustered ? num_clusters : 0, Vector6d::Zero());
  Matrix6d H = Matrix6d::Zero();
  Eigen::Matrix<double, 6, kModes> B = Eigen::Matrix<double, 6, kModes>::Zero();
  double cost = 0;
  // Per cell: the scores of the cell errors (shift x, shift y, disparity now, before).
  std::vector<Eigen::Matrix<double, 6, 4>> Bc(clustered ? num_clusters : 1,
                                              Eigen::Matrix<double, 6, 4>::Zero());
  for (int k : indices) {
    const Correspondence& x = c[k];
    const Eigen::Vector3d d = x.P_prev - t;
    const Eigen::Vector3d r = x.P_curr - Rcp * d;
    const Eigen::Matrix3d W = (x.Sigma_curr + Rcp * x.Sigma_prev * R).inverse();
    Eigen::Matrix<double, 3, 6> J;
    J.leftCols<3>() = Rcp;
    for (int i = 0; i < 3; ++i) J.col(3 + i) = -dR[i].transpose() * d;
    const Eigen::Matrix<double, 6, 3> JtW = J.transpose() * W;
    const Matrix6d Hj = JtW * J;
    H += Hj;
    cost += r.dot(W * r);
    if (clustered) {
      H_g[cluster[k]] += Hj;
      s_g[cluster[k]] += JtW * r;
    }
    // r = P_c - R^T (P_p - t): the field moves P_c; the disparity offset moves both.
    const Eigen::Vector2d p = (x.left - shared.centre_px) * unit;  // the mode shapes
    Eigen::Matrix<double, 3, kModes> D;
    D.col(0) = x.dPcurr_dshift.col(0);
    D.col(1) = x.dPcurr_dshift.col(1);
    D.col(2) = x.dPcurr_dshift * Eigen::Vector2d(-p.y(), p.x());
    D.col(3) = x.dPcurr_dshift * p;
    D.col(4) = x.dPcurr_ddisparity - Rcp * x.dPprev_ddisparity;
    B += JtW * D;
    Eigen::Matrix<double, 3, 4> Dc;
    Dc.leftCols<2>() = x.dPcurr_dshift;
    Dc.col(2) = x.dPcurr_ddisparity;
    Dc.col(3) = -Rcp * x.dPprev_ddisparity;
    Bc[clustered ? cluster[k] : 0] += JtW * Dc;
  }
  out.redundancy = 3 * static_cast<int>(indices.size()) - 6;
  if (out.redundancy <= 0) return out;
  Eigen::FullPivLU<Matrix6d> lu(H);
  if (!lu.isInvertible()) return out;
  const Matrix6d Hinv = lu.inverse();
  out.inverse_normal = 0.5 * (Hinv + Hinv.transpose());
  out.variance_factor = cost / out.redundancy;
  if (clustered) {
    Matrix6d S = Matrix6d::Zero();
    double expected = 6.0;  // E tr(H^-1 S) / k for independent errors: 6 - sum tr((H^-1 H_g)^2)
    for (int g = 0; g < num_clusters; ++g) {
      if (H_g[g].isZero(0)) continue;
      ++out.clusters;
      S += s_g[g] * s_g[g].transpose();
      const Matrix6d A = out.inverse_normal * H_g[g];
      expected -= (A * A).trace();
    }
    // With most of the information in one cluster the estimate means nothing: keep s0^2.
    if (out.clusters >= 2 && expected > 1.0) out.cluster_factor = (out.inverse_normal * S).trace() / expected;
  }
  const Eigen::Matrix<double, 6, kModes> G = out.inverse_normal * B;
  const double f2 = shared.field_sigma_px * shared.field_sigma_px;
  Eigen::Matrix<double, kModes, 1> var;
  var << f2, f2, f2, f2, shared.disparity_sigma_px * shared.disparity_sigma_px;
  out.shared = G * var.asDiagonal() * G.transpose();
  out.disparity_sensitivity = G.col(4);
  const double cs2 = shared.cell_shift_sigma_px * shared.cell_shift_sigma_px;
  const double cd2 = shared.cell_disparity_sigma_px * shared.cell_disparity_sigma_px;
  const Eigen::Vector4d cell_var(cs2, cs2, cd2, cd2);
  for (const auto& b : Bc) {
    const Eigen::Matrix<double, 6, 4> Gc = out.inverse_normal * b;
    out.shared += Gc * cell_var.asDiagonal() * Gc.transpose();
  }
  out.shared = 0.5 * (out.shared + out.shared.transpose()).eval();
  out.covariance = out.Scaled(out.inverse_normal);
  out.ok = true;
  return out;
}

double ChiSquareLowerQuantile(int dof, double alpha) {
  if (dof < 1 || !(alpha > 0.0 && alpha < 1.0)) return 0.0;
  // The standard normal's alpha-quantile, by bisection on its CDF.
  double lo = -40.0, hi = 40.0;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    if (0.5 * std::erfc(-mid / std::sqrt(2.0)) < alpha) lo = mid; else hi = mid;
  }
  const double z = 0.5 * (lo + hi);
  const double k = dof;
  const double c = 1.0 - 2.0 / (9.0 * k) + z * std::sqrt(2.0 / (9.0 * k));
  return c > 0.0 ? k * c * c * c : 0.0;
}

double VarianceFactorUpperBound(double factor, int dof, double alpha) {
  if (alpha <= 0.0 || dof < 1) return factor;
  const double q = ChiSquareLowerQuantile(dof, alpha);
  return q > 0.0 ? factor * dof / q : factor;
}

}  // namespace rover::vo
