#include "vo/window.hpp"

#include "geometry/pose.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include <algorithm>
#include <cmath>

namespace rover::vo {

namespace {

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix63 = Eigen::Matrix<double, 6, 3>;

struct PointBlock {
  std::int64_t id = 0;
  Eigen::Vector3d X = Eigen::Vector3d::Zero();
  std::vector<std::pair<int, const WindowObservation*>> obs;  // (keyframe, observation)
  std::vector<Eigen::Matrix4d> W;  // each observation's information
};

// Residual (measured minus predicted, left then right) and the Jacobians of the
// prediction with respect to the pose perturbation and to the point.
bool Linearise(const geometry::StereoRig& rig, const Eigen::Isometry3d& T_w, const Eigen::Vector3d& X,
               const WindowObservation& z, Eigen::Vector4d* r, Eigen::Matrix<double, 4, 6>* Jp,
               Eigen::Matrix<double, 4, 3>* Jx) {
  const Eigen::Matrix3d Rt = T_w.linear().transpose();
  const Eigen::Vector3d P = Rt * (X - T_w.translation());
  Eigen::Vector2d ul, ur;
  Eigen::Matrix<double, 2, 3> Jl, Jr;
  if (!rig.left->Project(P, &ul, Jp ? &Jl : nullptr)) return false;
  if (!rig.right->Project(P, &ur, Jp ? &Jr : nullptr)) return false;
  r->head<2>() = z.left - ul;
  r->tail<2>() = z.right - ur;
  if (Jp) {
    Eigen::Matrix<double, 4, 3> Ju;
    Ju.topRows<2>() = Jl;
    Ju.bottomRows<2>() = Jr;
    // P = Exp(-w) (P0 - v): dP/dv = -I, dP/dw = [P]x.
    Jp->leftCols<3>() = -Ju;
    Jp->rightCols<3>() = Ju * geometry::Skew(P);
    *Jx = Ju * Rt;
  }
  return true;
}

Eigen::Matrix4d Information(const WindowObservation& z) {
  Eigen::Matrix4d W = Eigen::Matrix4d::Zero();
  W.topLeftCorner<2, 2>() = z.Sigma_left.inverse();
  W.bottomRightCorner<2, 2>() = z.Sigma_right.inverse();
  return W;
}

}  // namespace

// A track's observations in the window (keyframe order), stacked 4 rows each (left x y,
// right x y), taken to the errors that are independent (WindowOptions::track_carry, rho,
// and stereo_carry, rho_s): with l_n = rho l_n-1 + w_n and r_n = rho_s l_n + s_n, row
// block n becomes (left_n - rho left_n-1, right_n - rho_s left_n), the first (left_0,
// right_0 - rho_s left_0): each is a match's own error (w_n, s_n) with that match's
// covariance, so the observations' information stays blockdiag(Sigma_left^-1,
// Sigma_right^-1). This is the exact whitening (the inverse Cholesky factor) of the
// track's error covariance: a lower block-bidiagonal matrix, so each row block still
// holds the poses of at most two keyframes. rho = 0 and rho_s = 0 leave the rows as they
// are; rho = 1 and rho_s = 1 take the random walk to its steps.
void ToIndependentErrors(Eigen::Ref<Eigen::MatrixXd> rows, int m, double track_carry, double stereo_carry) {
  if (track_carry == 0.0 && stereo_carry == 0.0) return;
  for (int n = m - 1; n >= 0; --n) {
    rows.middleRows(4 * n + 2, 2) -= stereo_carry * rows.middleRows(4 * n, 2);
    if (n > 0) rows.middleRows(4 * n, 2) -= track_carry * rows.middleRows(4 * (n - 1), 2);
  }
}

namespace {

// Information on the offset with which a full window holds it at the drive-wide value.
constexpr double kHeldOffsetInfo = 1e8;

// The offset filter's starting information: the zero-mean prior's.
double FilterStartInfo(const WindowOptions& o) {
  return o.disparity_offset_sigma_px > 0 ? 1.0 / (o.disparity_offset_sigma_px * o.disparity_offset_sigma_px) : 0.0;
}

// The offset the window uses: the filter's estimate when it differs from zero by more than
// disparity_offset_min_sigmas of its sigma, the systematic part included; else zero.
double AppliedOffset(const WindowOptions& o, double mean, double info) {
  if (o.disparity_offset_min_sigmas <= 0 || info <= 0) return mean;
  const double sigma = std::sqrt(1.0 / info + o.disparity_offset_systematic_px * o.disparity_offset_systematic_px);
  return std::abs(mean) > o.disparity_offset_min_sigmas * sigma ? mean : 0.0;
}

// Huber: cost of a squared normalised residual e2, and the IRLS weight.
double HuberCost(double e2, double k, double* weight) {
  const double e = std::sqrt(e2);
  if (e <= k) {
    if (weight) *weight = 1.0;
    return e2;
  }
  if (weight) *weight = k / e;
  return 2 * k * e - k * k;
}

// The joint covariance of poses a and b (a = 0: the fixed pose, zero) from the reduced
// covariance of the free poses 1..M-1.
Eigen::Matrix<double, 12, 12> LastTwoPoses(const Eigen::MatrixXd& cov, int a, int b) {
  Eigen::Matrix<double, 12, 12> joint = Eigen::Matrix<double, 12, 12>::Zero();
  joint.bottomRightCorner<6, 6>() = cov.block<6, 6>(6 * (b - 1), 6 * (b - 1));
  if (a > 0) {
    joint.topLeftCorner<6, 6>() = cov.block<6, 6>(6 * (a - 1), 6 * (a - 1));
    joint.topRightCorner<6, 6>() = cov.block<6, 6>(6 * (a - 1), 6 * (b - 1));
    joint.bottomLeftCorner<6, 6>() = joint.topRightCorner<6, 6>().transpose();
  }
  return joint;
}

// The covariance of a track's rows as the estimator weighed them, when its errors follow
// the covariance's carry model (c, d) and the rows were taken to independent errors under
// the weights' (a, b): the raw errors are A_cd^-1 e (e the matches' own, blockdiag
// Sigma_obs), so the rows' are B Sigma_obs B^T with B = A_ab A_cd^-1 (B = I when the two
// models are the same).
Eigen::MatrixXd RowCovariance(const std::vector<Eigen::Matrix4d>& Sigma_obs, const WindowOptions& o) {
  const int m = static_cast<int>(Sigma_obs.size());
  const int rows = 4 * m;
  Eigen::MatrixXd A_ab = Eigen::MatrixXd::Identity(rows, rows), A_cd = A_ab;
  ToIndependentErrors(A_ab, m, o.track_carry, o.stereo_carry);
  ToIndependentErrors(A_cd, m, o.covariance_track_carry, o.covariance_stereo_carry);
  // A_cd is unit lower triangular: B^T = A_cd^-T A_ab^T.
  const Eigen::MatrixXd Bt = A_cd.transpose().triangularView<Eigen::UnitUpper>().solve(A_ab.transpose());
  Eigen::MatrixXd Sigma = Eigen::MatrixXd::Zero(rows, rows);
  for (int n = 0; n < m; ++n) Sigma.block<4, 4>(4 * n, 4 * n) = Sigma_obs[static_cast<std::size_t>(n)];
  return Bt.transpose() * Sigma * Bt;
}

// One point's share of the sandwich: its rows r move the reduced solution by G r, with
// G = (Jc^T - Hcx Hxx^-1 Jx^T) W (the point eliminated), so M_j = G Cov(r) G^T; and its
// share of the cost's expectation, E[r^T W r] - tr(Hxx^-1 Jx^T W Cov(r) W Jx) (the point's
// own fit takes that part; the reduced variables' part, tr(S^-1 M), is taken once for all).
struct PointInfluence {
  Eigen::MatrixXd M;
  double expected_cost = 0;
};
PointInfluence Influence(const Eigen::MatrixXd& Jc, const Eigen::MatrixXd& Jx, const std::vector<Eigen::Matrix4d>& W_used,
                         const std::vector<Eigen::Matrix4d>& Sigma_obs, const Eigen::MatrixXd& Hcx,
                         const Eigen::Matrix3d& Hxx_inv, const WindowOptions& o) {
  const int rows = static_cast<int>(Jc.rows());
  Eigen::MatrixXd W = Eigen::MatrixXd::Zero(rows, rows);
  for (std::size_t n = 0; n < W_used.size(); ++n) W.block<4, 4>(4 * static_cast<int>(n), 4 * static_cast<int>(n)) = W_used[n];
  const Eigen::MatrixXd C = RowCovariance(Sigma_obs, o);
  const Eigen::MatrixXd G = (Jc.transpose() - Hcx * Hxx_inv * Jx.transpose()) * W;
  PointInfluence out;
  out.M = G * C * G.transpose();
  const Eigen::MatrixXd WJx = W * Jx;
  out.expected_cost = (W * C).trace() - (Hxx_inv * WJx.transpose() * C * WJx).trace();
  return out;
}


// One observation of a point as the window linearises it: its keyframe, its index in the
// point's observations, and, taken to independent errors (ToIndependentErrors), its four
// residual rows and their Jacobians by the point (Jx), by its own keyframe's pose (Jcur)
// and, when a track's left errors carry (track_carry), by the previous observation's
// keyframe's pose (Jprev). Fixed-size blocks: a row block holds two keyframes' poses at
// most, so the normal equations are built block by block with nothing allocated (the
// dense 4m x 6m stacks of every point, rebuilt each iteration, cost more than the rest of
// the window). The offset's Jacobian is e_2 in every block (the right x; carrying
// subtracts left rows, whose offset column is zero).
struct ObsTerm {
  int frame = 0, k = 0;
  Eigen::Vector4d r;
  Eigen::Matrix<double, 4, 6> Jcur, Jprev;
  Eigen::Matrix<double, 4, 3> Jx;
};

// ToIndependentErrors on the blocks: left_n - rho left_n-1, right_n - rho_s left_n, with
// raw values on the right (block n-1 is taken after block n; top rows of Jcur never change).
void Whiten(std::vector<ObsTerm>* terms, double rho, double rho_s, bool jacobians) {
  if (rho == 0.0 && rho_s == 0.0) return;
  std::vector<ObsTerm>& t = *terms;
  for (int n = static_cast<int>(t.size()) - 1; n >= 0; --n) {
    ObsTerm& o = t[static_cast<std::size_t>(n)];
    o.r.tail<2>() -= rho_s * o.r.head<2>();
    if (jacobians) {
      o.Jx.bottomRows<2>() -= rho_s * o.Jx.topRows<2>();
      o.Jcur.bottomRows<2>() -= rho_s * o.Jcur.topRows<2>();
    }
    if (n == 0) continue;
    const ObsTerm& p = t[static_cast<std::size_t>(n - 1)];
    o.r.head<2>() -= rho * p.r.head<2>();
    if (jacobians) {
      o.Jx.topRows<2>() -= rho * p.Jx.topRows<2>();
      o.Jprev.topRows<2>() = -rho * p.Jcur.topRows<2>();
      o.Jprev.bottomRows<2>().setZero();
    }
  }
}

// A point's observations that project, linearised at (poses, X, offset d) and whitened;
// returns how many did not project (behind a camera).
int LinearisePoint(const geometry::StereoRig& rig, const PointBlock& p, const std::vector<Eigen::Isometry3d>& poses,
                   const Eigen::Vector3d& X, double d, bool jacobians, const WindowOptions& o,
                   std::vector<ObsTerm>* out) {
  out->clear();
  int failed = 0;
  for (std::size_t k = 0; k < p.obs.size(); ++k) {
    const auto& [i, z] = p.obs[k];
    ObsTerm t;
    if (!Linearise(rig, poses[static_cast<std::size_t>(i)], X, *z, &t.r, jacobians ? &t.Jcur : nullptr,
                   jacobians ? &t.Jx : nullptr)) {
      ++failed;
      continue;
    }
    t.r(2) -= d;
    t.frame = i;
    t.k = static_cast<int>(k);
    out->push_back(t);
  }
  Whiten(out, o.track_carry, o.stereo_carry, jacobians);
  return failed;
}

// The Huber cost of a point's linearised observations, with a large finite penalty per
// observation behind a camera.
double PointCost(const PointBlock& p, const std::vector<ObsTerm>& terms, int failed, double huber) {
  double cost = failed * 2 * huber * 100.0;
  for (const ObsTerm& t : terms) {
    cost += HuberCost(t.r.dot(p.W[static_cast<std::size_t>(t.k)] * t.r), huber, nullptr);
  }
  return cost;
}

// The first observation whose pose block row block n holds: n - 1 when left errors carry.
int FirstBlock(int n, double track_carry) { return track_carry != 0.0 && n > 0 ? n - 1 : n; }

// One point's part of the normal equations: its 3x3 block (inverted, damped), its gradient,
// and its coupling to the reduced variables: a 6x3 block per observation's keyframe (none
// used for keyframe 0, the fixed pose) and a row for the offset.
struct PointSystem {
  Eigen::Matrix3d Hxx_inv = Eigen::Matrix3d::Identity();
  Eigen::Vector3d bx = Eigen::Vector3d::Zero();
  std::vector<int> frames;
  std::vector<Matrix63> Hc;
  Eigen::RowVector3d Hd = Eigen::RowVector3d::Zero();

  // Hcx^T c: the coupling times a step of the reduced variables.
  Eigen::Vector3d CouplingTimes(const Eigen::VectorXd& c, bool offset, int id) const {
    Eigen::Vector3d v = Eigen::Vector3d::Zero();
    for (std::size_t a = 0; a < frames.size(); ++a) {
      if (frames[a] > 0) v += Hc[a].transpose() * c.segment<6>(6 * (frames[a] - 1));
    }
    if (offset) v += Hd.transpose() * c(id);
    return v;
  }
  // The coupling as one nc x 3 matrix (the sandwich's dense form).
  Eigen::MatrixXd DenseCoupling(int nc, bool offset) const {
    Eigen::MatrixXd H = Eigen::MatrixXd::Zero(nc, 3);
    for (std::size_t a = 0; a < frames.size(); ++a) {
      if (frames[a] > 0) H.block<6, 3>(6 * (frames[a] - 1), 0) += Hc[a];
    }
    if (offset) H.row(nc - 1) = Hd;
    return H;
  }
};

// Adds a point's observations (IRLS-weighted by Huber) to the reduced system's Hcc and bc
// and fills its PointSystem (before damping and inversion).
void AccumulatePoint(const PointBlock& p, const std::vector<ObsTerm>& terms, const WindowOptions& o, bool offset,
                     int id, Eigen::MatrixXd* Hcc, Eigen::VectorXd* bc, PointSystem* ps, Eigen::Matrix3d* Hxx) {
  const int m = static_cast<int>(terms.size());
  ps->frames.clear();
  for (const ObsTerm& t : terms) ps->frames.push_back(t.frame);
  ps->Hc.assign(static_cast<std::size_t>(m), Matrix63::Zero());
  ps->Hd.setZero();
  Hxx->setZero();
  ps->bx.setZero();
  for (int n = 0; n < m; ++n) {
    const ObsTerm& t = terms[static_cast<std::size_t>(n)];
    Eigen::Matrix4d W = p.W[static_cast<std::size_t>(t.k)];
    double w = 1;
    HuberCost(t.r.dot(W * t.r), o.huber_sigmas, &w);
    W *= w;
    const Eigen::Matrix<double, 4, 3> WJx = W * t.Jx;
    const Eigen::Vector4d Wr = W * t.r;
    const Eigen::Vector4d WJd = W.col(2);
    *Hxx += t.Jx.transpose() * WJx;
    ps->bx += t.Jx.transpose() * Wr;
    if (offset) {
      (*Hcc)(id, id) += WJd(2);
      (*bc)(id) += Wr(2);
      ps->Hd += WJx.row(2);
    }
    const int first = FirstBlock(n, o.track_carry);
    for (int a = first; a <= n; ++a) {
      const int ia = ps->frames[static_cast<std::size_t>(a)];
      if (ia == 0) continue;
      const int ka = 6 * (ia - 1);
      const Eigen::Matrix<double, 4, 6>& Ja = a == n ? t.Jcur : t.Jprev;
      bc->segment<6>(ka) += Ja.transpose() * Wr;
      ps->Hc[static_cast<std::size_t>(a)] += Ja.transpose() * WJx;
      if (offset) {
        const Vector6d Hpd = Ja.transpose() * WJd;
        Hcc->block<6, 1>(ka, id) += Hpd;
        Hcc->block<1, 6>(id, ka) += Hpd.transpose();
      }
      const Eigen::Matrix<double, 6, 4> JaW = Ja.transpose() * W;
      for (int c = first; c <= n; ++c) {
        const int ic = ps->frames[static_cast<std::size_t>(c)];
        if (ic == 0) continue;
        Hcc->block<6, 6>(ka, 6 * (ic - 1)) += JaW * (c == n ? t.Jcur : t.Jprev);
      }
    }
  }
}

// Eliminates a point: S -= Hcx Hxx^-1 Hcx^T, bs -= Hcx Hxx^-1 bx, block by block.
void EliminatePoint(const PointSystem& ps, bool offset, int id, Eigen::MatrixXd* S, Eigen::VectorXd* bs) {
  const Eigen::RowVector3d HHd = ps.Hd * ps.Hxx_inv;
  for (std::size_t a = 0; a < ps.frames.size(); ++a) {
    if (ps.frames[a] == 0) continue;
    const int ka = 6 * (ps.frames[a] - 1);
    const Matrix63 HH = ps.Hc[a] * ps.Hxx_inv;
    bs->segment<6>(ka) -= HH * ps.bx;
    for (std::size_t c = 0; c < ps.frames.size(); ++c) {
      if (ps.frames[c] == 0) continue;
      S->block<6, 6>(ka, 6 * (ps.frames[c] - 1)) -= HH * ps.Hc[c].transpose();
    }
    if (offset) {
      S->block<6, 1>(ka, id) -= HH * ps.Hd.transpose();
      S->block<1, 6>(id, ka) -= HHd * ps.Hc[a].transpose();
    }
  }
  if (offset) {
    (*bs)(id) -= HHd.dot(ps.bx);
    (*S)(id, id) -= HHd.dot(ps.Hd);
  }
}

// The dense, whitened stacks of a point's rows as the sandwich takes them: Jc (by the
// reduced variables) and Jx (by the point).
void DenseRows(const std::vector<ObsTerm>& terms, const WindowOptions& o, int nc, bool offset, Eigen::MatrixXd* Jc,
               Eigen::MatrixXd* Jx) {
  const int m = static_cast<int>(terms.size());
  Jc->setZero(4 * m, nc);
  Jx->resize(4 * m, 3);
  for (int n = 0; n < m; ++n) {
    const ObsTerm& t = terms[static_cast<std::size_t>(n)];
    Jx->middleRows<4>(4 * n) = t.Jx;
    if (offset) (*Jc)(4 * n + 2, nc - 1) = 1.0;
    for (int a = FirstBlock(n, o.track_carry); a <= n; ++a) {
      const int ia = terms[static_cast<std::size_t>(a)].frame;
      if (ia > 0) Jc->block<4, 6>(4 * n, 6 * (ia - 1)) += a == n ? t.Jcur : t.Jprev;
    }
  }
}

}  // namespace

Eigen::Isometry3d Retract(const Eigen::Isometry3d& T, const Vector6d& d) {
  Eigen::Isometry3d out = T;
  const Eigen::Vector3d w = d.tail<3>();
  const double angle = w.norm();
  const Eigen::Matrix3d dR =
      angle > 1e-15 ? Eigen::AngleAxisd(angle, w / angle).toRotationMatrix() : Eigen::Matrix3d::Identity();
  out.linear() = T.linear() * dR;
  out.translation() = T.translation() + T.linear() * d.head<3>();
  return out;
}

Eigen::Matrix<double, 6, 12> RelativePoseJacobian(const Eigen::Isometry3d& Ta, const Eigen::Isometry3d& Tb) {
  Eigen::Matrix<double, 6, 12> J;
  const double h = 1e-6;
  for (int i = 0; i < 12; ++i) {
    Vector6d d = Vector6d::Zero();
    d(i % 6) = h;
    const Eigen::Isometry3d a_plus = i < 6 ? Retract(Ta, d) : Ta;
    const Eigen::Isometry3d b_plus = i < 6 ? Tb : Retract(Tb, d);
    const Eigen::Isometry3d a_minus = i < 6 ? Retract(Ta, -d) : Ta;
    const Eigen::Isometry3d b_minus = i < 6 ? Tb : Retract(Tb, -d);
    geometry::Vector6d diff = geometry::XyzRpyFromPose(a_plus.inverse() * b_plus) -
                              geometry::XyzRpyFromPose(a_minus.inverse() * b_minus);
    for (int k = 3; k < 6; ++k) diff(k) = geometry::WrapAngle(diff(k));
    J.col(i) = diff / (2 * h);
  }
  return J;
}

double SlidingWindow::disparity_offset_sigma_px() const {
  const double info = offset_info_ > 0 ? offset_info_ : FilterStartInfo(o_);
  return info > 0 ? 1.0 / std::sqrt(info) : 0.0;
}

void SlidingWindow::Reset() {
  frames_.clear();
  saved_poses_.clear();
  has_dropped_ = false;
  has_newest_cov_ = false;
  points_.clear();
}

void SlidingWindow::AddFrame(std::int64_t frame_id, const Eigen::Isometry3d& T_w_frame,
                             std::vector<WindowObservation> observations) {
  saved_poses_.clear();
  for (const Frame& f : frames_) saved_poses_.push_back(f.T_w);
  has_dropped_ = false;
  if (static_cast<int>(frames_.size()) >= std::max(2, o_.max_frames)) {
    dropped_ = std::move(frames_.front());
    frames_.erase(frames_.begin());
    saved_poses_.erase(saved_poses_.begin());
    has_dropped_ = true;
  }
  Frame f;
  f.id = frame_id;
  f.T_w = T_w_frame;
  f.obs = std::move(observations);
  frames_.push_back(std::move(f));
}

void SlidingWindow::PopNewest() {
  has_newest_cov_ = false;
  if (frames_.empty()) return;
  frames_.pop_back();
  for (std::size_t i = 0; i < frames_.size() && i < saved_poses_.size(); ++i) frames_[i].T_w = saved_poses_[i];
  if (has_dropped_) {
    frames_.insert(frames_.begin(), std::move(dropped_));
    has_dropped_ = false;
  }
  saved_poses_.clear();
}

WindowSolution SlidingWindow::Refine(const geometry::StereoRig& rig) {
  WindowSolution sol;
  const int M = size();
  if (M < 2 || !rig.left || !rig.right) return sol;
  const int np = M - 1;  // free poses 1..M-1
  const int dim = 6 * np;

  // Points seen in at least two keyframes.
  std::unordered_map<std::int64_t, int> index;
  std::vector<PointBlock> pts;
  for (int i = 0; i < M; ++i) {
    for (const WindowObservation& z : frames_[static_cast<std::size_t>(i)].obs) {
      auto [it, fresh] = index.emplace(z.track_id, static_cast<int>(pts.size()));
      if (fresh) {
        pts.emplace_back();
        pts.back().id = z.track_id;
      }
      pts[static_cast<std::size_t>(it->second)].obs.emplace_back(i, &z);
    }
  }
  std::vector<PointBlock> used;
  used.reserve(pts.size());
  for (PointBlock& p : pts) {
    if (p.obs.size() < 2) continue;
    const auto cached = points_.find(p.id);
    if (cached != points_.end()) {
      p.X = cached->second;
    } else {
      // The best-conditioned observation starts the point.
      double best = 1e300;
      for (const auto& [i, z] : p.obs) {
        const double tr = z->Sigma.trace();
        if (tr < best) {
          best = tr;
          p.X = frames_[static_cast<std::size_t>(i)].T_w * z->P;
        }
      }
    }
    for (const auto& [i, z] : p.obs) p.W.push_back(Information(*z));
    used.push_back(std::move(p));
  }
  sol.points = static_cast<int>(used.size());
  for (const PointBlock& p : used) sol.observations += static_cast<int>(p.obs.size());
  const int redundancy = 4 * sol.observations - 3 * sol.points - dim;
  if (sol.points < 3 || redundancy <= 0) return sol;

  std::vector<ObsTerm> terms;  // one point's, reused
  auto cost_of = [&](const std::vector<Eigen::Isometry3d>& poses, const std::vector<Eigen::Vector3d>& X, double d) {
    double cost = 0;
    for (std::size_t j = 0; j < used.size(); ++j) {
      const int failed = LinearisePoint(rig, used[j], poses, X[j], d, false, o_, &terms);
      cost += PointCost(used[j], terms, failed, o_.huber_sigmas);
    }
    return cost;
  };

  std::vector<Eigen::Isometry3d> poses(static_cast<std::size_t>(M));
  for (int i = 0; i < M; ++i) poses[static_cast<std::size_t>(i)] = frames_[static_cast<std::size_t>(i)].T_w;
  std::vector<Eigen::Vector3d> X(used.size());
  for (std::size_t j = 0; j < used.size(); ++j) X[j] = used[j].X;

  // The reduced variables: the free poses, then (in a full window, where a point is seen
  // at several ranges) the disparity offset. The window does not move the offset: it is
  // held at the drive-wide value (AppliedOffset), so that one window's noise does not
  // become the next one's offset; it is a variable only so that this window's estimate
  // from its own data can be read off the reduced system and fed to the filter.
  const bool offset = o_.disparity_offset_sigma_px > 0 && M >= std::max(3, o_.max_frames);
  const double filter_mean = disparity_offset_;
  const double filter_info = offset_info_ > 0 ? offset_info_ : FilterStartInfo(o_);
  const double q = o_.disparity_offset_drift_px * o_.disparity_offset_drift_px;
  const double prior_info = 1.0 / (1.0 / filter_info + q);
  const double offset_mean = AppliedOffset(o_, filter_mean, prior_info);
  const double hold_info = kHeldOffsetInfo;
  const int nc = dim + (offset ? 1 : 0);
  const int id = dim;  // index of the offset
  double delta = offset_mean;
  Eigen::MatrixXd S(nc, nc), Hcc(nc, nc);
  Eigen::VectorXd bs(nc), bc(nc);
  std::vector<PointSystem> sys(used.size());

  // Builds the normal equations at the current estimate with damping lambda and returns
  // the Schur complement on the reduced variables in S, bs.
  auto build = [&](double lambda) {
    Hcc.setZero();
    bc.setZero();
    for (std::size_t j = 0; j < used.size(); ++j) {
      LinearisePoint(rig, used[j], poses, X[j], delta, true, o_, &terms);
      Eigen::Matrix3d Hxx;
      AccumulatePoint(used[j], terms, o_, offset, id, &Hcc, &bc, &sys[j], &Hxx);
      Hxx.diagonal() *= 1 + lambda;
      Hxx.diagonal().array() += 1e-12;
      sys[j].Hxx_inv = Hxx.inverse();
    }
    if (offset) {
      Hcc(id, id) += hold_info;
      bc(id) -= hold_info * (delta - offset_mean);
    }
    S = Hcc;
    S.diagonal() *= 1 + lambda;
    bs = bc;
    for (const PointSystem& ps : sys) EliminatePoint(ps, offset, id, &S, &bs);
  };

  auto total_cost = [&](const std::vector<Eigen::Isometry3d>& P, const std::vector<Eigen::Vector3d>& Xs, double d) {
    const double prior = offset ? hold_info * (d - offset_mean) * (d - offset_mean) : 0.0;
    return cost_of(P, Xs, d) + prior;
  };
  double cost = total_cost(poses, X, delta);
  sol.initial_cost = cost;
  double lambda = 1e-4;
  for (int it = 0; it < o_.max_iterations; ++it) {
    ++sol.iterations;
    build(lambda);
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(S);
    if (ldlt.info() != Eigen::Success) break;
    const Eigen::VectorXd dc = ldlt.solve(bs);
    if (!dc.allFinite()) break;
    std::vector<Eigen::Isometry3d> new_poses = poses;
    for (int i = 1; i < M; ++i) {
      new_poses[static_cast<std::size_t>(i)] = Retract(poses[static_cast<std::size_t>(i)], dc.segment<6>(6 * (i - 1)));
    }
    const double new_delta = offset ? delta + dc(id) : delta;
    std::vector<Eigen::Vector3d> new_X = X;
    for (std::size_t j = 0; j < used.size(); ++j) {
      new_X[j] = X[j] + sys[j].Hxx_inv * (sys[j].bx - sys[j].CouplingTimes(dc, offset, id));
    }
    const double new_cost = total_cost(new_poses, new_X, new_delta);
    if (new_cost < cost) {
      const double gain = (cost - new_cost) / std::max(cost, 1e-300);
      poses = std::move(new_poses);
      X = std::move(new_X);
      delta = new_delta;
      cost = new_cost;
      lambda = std::max(1e-7, lambda / 10);
      if (gain < o_.tolerance) break;
    } else {
      lambda *= 10;
      if (lambda > 1e4) break;
    }
  }

  // The covariance of the poses: the inverse of the undamped reduced normal matrix, under
  // the weights' own model; with a covariance model of its own (covariance_track_carry,
  // covariance_stereo_carry) the sandwich S^-1 M S^-1 (Sandwich above).
  build(0.0);
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(S);
  if (ldlt.info() != Eigen::Success) return sol;
  const Eigen::MatrixXd fit_cov = ldlt.solve(Eigen::MatrixXd::Identity(nc, nc));
  if (!fit_cov.allFinite() || fit_cov.diagonal().minCoeff() <= 0) return sol;
  sol.sandwich = o_.covariance_track_carry >= 0 && o_.covariance_stereo_carry >= 0;
  double expected_cost = redundancy;
  Eigen::MatrixXd cov = fit_cov;
  if (sol.sandwich) {
    // M: each point's residual rows, as the estimator weighed them (Huber included), move
    // the reduced solution by G_j r_j once the point is eliminated; the points' errors are
    // independent, so M is the sum of G_j Cov(r_j) G_j^T.
    Eigen::MatrixXd Mg = Eigen::MatrixXd::Zero(nc, nc);
    double point_part = 0;  // sum over points of E[r^T W r] minus the point's own share
    Eigen::MatrixXd Jc, Jx;
    for (std::size_t j = 0; j < used.size(); ++j) {
      LinearisePoint(rig, used[j], poses, X[j], delta, true, o_, &terms);
      if (terms.empty()) continue;
      std::vector<Eigen::Matrix4d> W_used, Sigma_obs;
      for (const ObsTerm& t : terms) {
        const Eigen::Matrix4d W = used[j].W[static_cast<std::size_t>(t.k)];
        double w = 1;
        HuberCost(t.r.dot(W * t.r), o_.huber_sigmas, &w);
        // A row Huber down-weights lies beyond huber_sigmas: its error is taken as the IRLS
        // weight takes it, the match's covariance over w (taken at the match's own, the
        // outliers would make the sandwich smaller than S^-1).
        W_used.push_back(w * W);
        Sigma_obs.push_back(W.inverse() / w);
      }
      DenseRows(terms, o_, nc, offset, &Jc, &Jx);
      const PointInfluence f =
          Influence(Jc, Jx, W_used, Sigma_obs, sys[j].DenseCoupling(nc, offset), sys[j].Hxx_inv, o_);
      Mg += f.M;
      point_part += f.expected_cost;
    }
    if (offset) {
      Mg(id, id) += hold_info;  // the hold: a prior whose own error has variance 1 / hold_info
      point_part += 1.0;
    }
    cov = fit_cov * Mg * fit_cov;
    cov = 0.5 * (cov + cov.transpose()).eval();
    if (!cov.allFinite() || cov.diagonal().minCoeff() <= 0) return sol;
    expected_cost = point_part - (fit_cov * Mg).trace();
  }

  const int a = M - 2, b = M - 1;
  const Eigen::Matrix<double, 6, 12> J = RelativePoseJacobian(poses[static_cast<std::size_t>(a)], poses[static_cast<std::size_t>(b)]);
  const Eigen::Matrix<double, 12, 12> joint = LastTwoPoses(cov, a, b);
  sol.covariance = J * joint * J.transpose();
  sol.step_covariance = 0.5 * (sol.covariance + sol.covariance.transpose());
  const Eigen::Matrix<double, 12, 12> fit_joint = LastTwoPoses(fit_cov, a, b);
  sol.fit_step_covariance = J * fit_joint * J.transpose();
  sol.fit_step_covariance = 0.5 * (sol.fit_step_covariance + sol.fit_step_covariance.transpose()).eval();
  // Cov(c) = Sigma_then - Sigma_now holds only when this refinement used all the data of
  // the one that published pose a, in the same gauge. Once a keyframe has left the window
  // (it was dropped, not marginalised, and the next pose was fixed in its place) neither
  // holds, and the correction is larger than that: on rendered rock fields, 4 % of the
  // deltas that carried it lay beyond the 99.7 % NEES bound (VO-13). Then the delta of the
  // last step alone is published (sol.carries_correction false).
  sol.carries_correction = a > 0 && has_newest_cov_ && newest_id_ == frames_[static_cast<std::size_t>(a)].id &&
                           !has_dropped_;
  if (sol.carries_correction) {
    const Eigen::SelfAdjointEigenSolver<Matrix6d> es(newest_cov_ - joint.topLeftCorner<6, 6>());
    const Matrix6d correction =
        es.eigenvectors() * es.eigenvalues().cwiseMax(0.0).asDiagonal() * es.eigenvectors().transpose();
    sol.covariance += J.leftCols<6>() * correction * J.leftCols<6>().transpose();
  }
  has_newest_cov_ = true;
  newest_id_ = frames_[static_cast<std::size_t>(b)].id;
  newest_cov_ = joint.bottomRightCorner<6, 6>();
  sol.covariance = 0.5 * (sol.covariance + sol.covariance.transpose()).eval();
  sol.T_prev_last = poses[static_cast<std::size_t>(a)].inverse() * poses[static_cast<std::size_t>(b)];
  sol.final_cost = cost;
  sol.variance_factor = cost / redundancy;
  sol.covariance_variance_factor = expected_cost > 0 ? cost / expected_cost : sol.variance_factor;
  if (offset) {
    // This window's offset from its data alone: one Gauss-Newton step from the solution
    // with the hold taken out of the reduced system (the poses' uncertainty included).
    // An observation stays in the window for max_frames windows, so each window adds
    // 1/max_frames of its information to the drive-wide filter, which would otherwise
    // count every observation that many times. The filter's prior is its last estimate
    // with its information grown by one window's drift.
    Eigen::MatrixXd S_data = S;
    Eigen::VectorXd b_data = bs;
    S_data(id, id) -= hold_info;
    b_data(id) += hold_info * (delta - offset_mean);
    const Eigen::LDLT<Eigen::MatrixXd> data(S_data);
    if (data.info() == Eigen::Success) {
      const Eigen::VectorXd step = data.solve(b_data);
      Eigen::VectorXd e = Eigen::VectorXd::Zero(nc);
      e(id) = 1.0;
      const double var = data.solve(e)(id);
      if (step.allFinite() && std::isfinite(var) && var > 0) {
        sol.window_offset_px = delta + step(id);
        sol.window_offset_sigma_px = std::sqrt(var);
        const double add = 1.0 / (var * std::max(1, o_.max_frames));
        disparity_offset_ = (prior_info * filter_mean + add * sol.window_offset_px) / (prior_info + add);
        offset_info_ = prior_info + add;
      }
    }
  }
  sol.disparity_offset_px = AppliedOffset(o_, disparity_offset_, offset_info_ > 0 ? offset_info_ : FilterStartInfo(o_));
  sol.ok = true;

  for (int i = 0; i < M; ++i) frames_[static_cast<std::size_t>(i)].T_w = poses[static_cast<std::size_t>(i)];
  points_.clear();
  for (std::size_t j = 0; j < used.size(); ++j) points_[used[j].id] = X[j];
  return sol;
}

}  // namespace rover::vo
