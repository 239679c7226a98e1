#include "render/height_levels.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace rover::render::internal {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
// Step past a cell wall so that the next cell is a different one; far below 1 mm.
constexpr double kNudge = 1e-9;
// Mip cell sizes 2^m and their reciprocals (exact), so the walk needs no division.
constexpr int kMaxMips = 40;
constexpr std::array<double, kMaxMips> kPow2 = [] {
  std::array<double, kMaxMips> a{};
  double x = 1;
  for (double& v : a) { v = x; x *= 2; }
  return a;
}();
constexpr std::array<double, kMaxMips> kInvPow2 = [] {
  std::array<double, kMaxMips> a{};
  double x = 1;
  for (double& v : a) { v = x; x *= 0.5; }
  return a;
}();
}  // namespace

void Box2::Add(double x, double y) {
  if (empty()) {
    x_min = x_max = x;
    y_min = y_max = y;
    return;
  }
  x_min = std::min(x_min, x);
  x_max = std::max(x_max, x);
  y_min = std::min(y_min, y);
  y_max = std::max(y_max, y);
}

void Box2::Add(const Box2& b) {
  if (b.empty()) return;
  Add(b.x_min, b.y_min);
  Add(b.x_max, b.y_max);
}

void HeightGrid::Build(const Ground& ground, const Box2& box, double cell_m) {
  h_ = cell_m;
  inv_h_ = 1.0 / h_;
  // Nodes sit on a site-wide lattice of multiples of h, so that the same ground is
  // sampled at the same points from frame to frame and the surface does not swim.
  x0_ = std::floor(box.x_min / h_) * h_;
  y0_ = std::floor(box.y_min / h_) * h_;
  nx_ = std::max(2, static_cast<int>(std::ceil((box.x_max - x0_) / h_)) + 1);
  ny_ = std::max(2, static_cast<int>(std::ceil((box.y_max - y0_) / h_)) + 1);
  box_ = Box2{x0_, x0_ + (nx_ - 1) * h_, y0_, y0_ + (ny_ - 1) * h_};
  z_.resize(static_cast<std::size_t>(nx_) * ny_);
  for (int j = 0; j < ny_; ++j) {
    const double y = y0_ + j * h_;
    float* row = &z_[static_cast<std::size_t>(j) * nx_];
    for (int i = 0; i < nx_; ++i) row[i] = static_cast<float>(ground.Elevation(x0_ + i * h_, y));
  }
  BuildMips();
}

void HeightGrid::Adopt(const Ground::GridView& view) {
  h_ = view.h;
  inv_h_ = 1.0 / h_;
  x0_ = view.x0;
  y0_ = view.y0;
  nx_ = view.nx;
  ny_ = view.ny;
  box_ = Box2{x0_, x0_ + (nx_ - 1) * h_, y0_, y0_ + (ny_ - 1) * h_};
  z_.resize(static_cast<std::size_t>(nx_) * ny_);
  for (int i = 0; i < nx_; ++i) {
    const float* col = view.data + static_cast<std::size_t>(i) * ny_;
    for (int j = 0; j < ny_; ++j) z_[static_cast<std::size_t>(j) * nx_ + i] = col[j];
  }
  BuildMips();
}

void HeightGrid::BuildMips() {
  // Max-mip: level 0 holds each cell's highest corner, each next level the highest of
  // (up to) four children.
  mips_.clear();
  cx_.clear();
  cy_.clear();
  int cx = nx_ - 1, cy = ny_ - 1;
  std::vector<float> m0(static_cast<std::size_t>(cx) * cy);
  for (int j = 0; j < cy; ++j) {
    for (int i = 0; i < cx; ++i) {
      m0[static_cast<std::size_t>(j) * cx + i] =
          std::max(std::max(Z(i, j), Z(i + 1, j)), std::max(Z(i, j + 1), Z(i + 1, j + 1)));
    }
  }
  mips_.push_back(std::move(m0));
  cx_.push_back(cx);
  cy_.push_back(cy);
  while (cx > 1 || cy > 1) {
    const int ncx = (cx + 1) / 2, ncy = (cy + 1) / 2;
    const std::vector<float>& prev = mips_.back();
    std::vector<float> next(static_cast<std::size_t>(ncx) * ncy);
    for (int j = 0; j < ncy; ++j) {
      for (int i = 0; i < ncx; ++i) {
        float m = -std::numeric_limits<float>::infinity();
        for (int dj = 0; dj < 2; ++dj) {
          for (int di = 0; di < 2; ++di) {
            const int ci = 2 * i + di, cj = 2 * j + dj;
            if (ci < cx && cj < cy) m = std::max(m, prev[static_cast<std::size_t>(cj) * cx + ci]);
          }
        }
        next[static_cast<std::size_t>(j) * ncx + i] = m;
      }
    }
    mips_.push_back(std::move(next));
    cx = ncx;
    cy = ncy;
    cx_.push_back(cx);
    cy_.push_back(cy);
  }
  global_max_ = mips_.back()[0];
  BuildGradients();
}

bool HeightGrid::Contains(double x, double y) const {
  return x >= box_.x_min && x <= box_.x_max && y >= box_.y_min && y <= box_.y_max;
}

double HeightGrid::HitInCell(int i, int j, double gu, double gv, double du, double dv,
                             double oe, double de, double t, double t_exit) const {
  const double a0 = gu + du * t - i, b0 = gv + dv * t - j, e0 = oe + de * t;
  const double z00 = Z(i, j), z10 = Z(i + 1, j), z01 = Z(i, j + 1), z11 = Z(i + 1, j + 1);
  const double B = z10 - z00, C = z01 - z00, D = z00 - z10 - z01 + z11;
  // Ray height minus the bilinear patch along the ray is quadratic in s = t' - t.
  const double c0 = e0 - (z00 + B * a0 + C * b0 + D * a0 * b0);
  if (c0 <= 0) return t;
  const double c1 = de - (B * du + C * dv + D * (a0 * dv + b0 * du));
  const double c2 = -D * du * dv;
  const double S = t_exit - t;
  double s = kInf;
  if (std::abs(c2) * S <= 1e-12 * (std::abs(c1) + 1e-300)) {
    if (c1 < 0) s = -c0 / c1;
  } else {
    const double disc = c1 * c1 - 4 * c2 * c0;
    if (disc >= 0) {
      const double q = -0.5 * (c1 + std::copysign(std::sqrt(disc), c1));
      const double r1 = q / c2, r2 = (q != 0) ? c0 / q : kInf;
      if (r1 >= 0) s = std::min(s, r1);
      if (r2 >= 0) s = std::min(s, r2);
    }
  }
  if (s <= S) return t + s;
  return -1;
}

inline bool HeightGrid::ClipToBox(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double rdx, double rdy, double* t0,
                           double* t1) const {
  for (int k = 0; k < 2; ++k) {
    const double lo = k == 0 ? box_.x_min : box_.y_min;
    const double hi = k == 0 ? box_.x_max : box_.y_max;
    if (d[k] == 0) {
      if (o[k] < lo || o[k] > hi) return false;
      continue;
    }
    const double r = k == 0 ? rdx : rdy;
    double ta = (lo - o[k]) * r, tb = (hi - o[k]) * r;
    if (ta > tb) std::swap(ta, tb);
    *t0 = std::max(*t0, ta);
    *t1 = std::min(*t1, tb);
  }
  return *t0 <= *t1;
}

double HeightGrid::Intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t0,
                             double t1, int start_mip) const {
  if (z_.empty()) return -1;
  // Reciprocals once per ray: neither the clip nor the walk below then divides.
  const double rdx = d.x() != 0 ? 1.0 / d.x() : 0.0, rdy = d.y() != 0 ? 1.0 / d.y() : 0.0;
  if (!ClipToBox(o, d, rdx, rdy, &t0, &t1)) return -1;
  const double oe = -o.z(), de = -d.z();
  // A ray that is above every node and not descending cannot hit.
  if (de >= 0 && oe + de * t0 > global_max_) return -1;
  if (de < 0) {
    // Nothing can be hit before the ray comes down to the highest node.
    const double t_top = (global_max_ - oe) / de;
    t0 = std::max(t0, t_top);
    if (t0 > t1) return -1;
  }
  const double gu = (o.x() - x0_) * inv_h_, gv = (o.y() - y0_) * inv_h_;
  const double du = d.x() * inv_h_, dv = d.y() * inv_h_;
  const double iu = h_ * rdx, iv = h_ * rdy;
  const int su = du > 0 ? 1 : 0, sv = dv > 0 ? 1 : 0;
  const int top = static_cast<int>(mips_.size()) - 1;
  int m = std::clamp(start_mip, 0, top);
  double t = t0;
  while (t <= t1) {
    const double u = gu + du * t, v = gv + dv * t;
    const double s = kPow2[m], inv_s = kInvPow2[m];
    // u, v >= 0 up to rounding inside the clipped box, so truncation is floor here.
    const int I = std::clamp(static_cast<int>(u * inv_s), 0, cx_[m] - 1);
    const int J = std::clamp(static_cast<int>(v * inv_s), 0, cy_[m] - 1);
    double t_exit = t1;
    if (du != 0) t_exit = std::min(t_exit, ((I + su) * s - gu) * iu);
    if (dv != 0) t_exit = std::min(t_exit, ((J + sv) * s - gv) * iv);
    t_exit = std::max(t_exit, t);
    const float cell_max = mips_[m][static_cast<std::size_t>(J) * cx_[m] + I];
    const double e_min = de < 0 ? oe + de * t_exit : oe + de * t;
    if (e_min > cell_max) {
      t = t_exit + kNudge;
      // Go coarser only when the step left the parent cell too: within the same parent
      // its bound has just failed, and would again.
      if (m < top) {
        const double un = gu + du * t, vn = gv + dv * t;
        const double inv_s2 = 0.5 * inv_s;
        if (static_cast<int>(un * inv_s2) != (I >> 1) || static_cast<int>(vn * inv_s2) != (J >> 1)) ++m;
      }
      continue;
    }
    if (m > 0) {
      --m;
      continue;
    }
    const double hit = HitInCell(I, J, gu, gv, du, dv, oe, de, t, t_exit);
    if (hit >= 0) return hit;
    t = t_exit + kNudge;
  }
  return -1;
}

double HeightGrid::IntersectNear(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t0, double t1,
                                 int max_cells) const {
  if (z_.empty()) return -1;
  const double rdx = d.x() != 0 ? 1.0 / d.x() : 0.0, rdy = d.y() != 0 ? 1.0 / d.y() : 0.0;
  if (!ClipToBox(o, d, rdx, rdy, &t0, &t1)) return -1;
  const double oe = -o.z(), de = -d.z();
  const double gu = (o.x() - x0_) * inv_h_, gv = (o.y() - y0_) * inv_h_;
  const double du = d.x() * inv_h_, dv = d.y() * inv_h_;
  const double iu = h_ * rdx, iv = h_ * rdy;
  const int su = du > 0 ? 1 : 0, sv = dv > 0 ? 1 : 0;
  const int step_i = du > 0 ? 1 : -1, step_j = dv > 0 ? 1 : -1;
  const int cx = cx_[0], cy = cy_[0];
  const std::vector<float>& cells = mips_[0];
  double t = t0;
  int I = std::clamp(static_cast<int>(gu + du * t), 0, cx - 1);
  int J = std::clamp(static_cast<int>(gv + dv * t), 0, cy - 1);
  for (int n = 0; n < max_cells; ++n) {
    // Each wall crossing is computed afresh from the cell index, so nothing accumulates.
    const double tu = du != 0 ? ((I + su) - gu) * iu : kInf;
    const double tv = dv != 0 ? ((J + sv) - gv) * iv : kInf;
    const double t_exit = std::max(t, std::min(t1, std::min(tu, tv)));
    const double e_min = de < 0 ? oe + de * t_exit : oe + de * t;
    if (e_min <= cells[static_cast<std::size_t>(J) * cx + I]) {
      const double hit = HitInCell(I, J, gu, gv, du, dv, oe, de, t, t_exit);
      if (hit >= 0) return hit;
    }
    if (t_exit >= t1) return -1;
    t = t_exit;
    if (tu <= tv) {
      I += step_i;
      if (I < 0 || I >= cx) return -1;
    } else {
      J += step_j;
      if (J < 0 || J >= cy) return -1;
    }
  }
  return Intersect(o, d, t, t1, 0);
}

double HeightGrid::MaxOver(const Box2& box) const {
  if (z_.empty() || box.empty()) return -kInf;
  const double x_lo = std::max(box.x_min, box_.x_min), x_hi = std::min(box.x_max, box_.x_max);
  const double y_lo = std::max(box.y_min, box_.y_min), y_hi = std::min(box.y_max, box_.y_max);
  if (x_lo > x_hi || y_lo > y_hi) return -kInf;
  // The level whose cells are at least half the box: at most 3 x 3 of them to visit.
  const double w = std::max(x_hi - x_lo, y_hi - y_lo) / h_;
  int m = 0;
  while (m + 1 < static_cast<int>(mips_.size()) && kPow2[m] * 2 < w) ++m;
  const double inv_s = kInvPow2[m];
  const int i0 = std::clamp(static_cast<int>((x_lo - x0_) / h_ * inv_s), 0, cx_[m] - 1);
  const int i1 = std::clamp(static_cast<int>((x_hi - x0_) / h_ * inv_s), 0, cx_[m] - 1);
  const int j0 = std::clamp(static_cast<int>((y_lo - y0_) / h_ * inv_s), 0, cy_[m] - 1);
  const int j1 = std::clamp(static_cast<int>((y_hi - y0_) / h_ * inv_s), 0, cy_[m] - 1);
  const std::vector<float>& mip = mips_[m];
  float best = -std::numeric_limits<float>::infinity();
  for (int j = j0; j <= j1; ++j) {
    for (int i = i0; i <= i1; ++i) best = std::max(best, mip[static_cast<std::size_t>(j) * cx_[m] + i]);
  }
  return best;
}

double HeightGrid::ConeFreeRange(const Eigen::Vector3d& o, const Eigen::Vector3d& c, double half_angle,
                                 double max_range, double resolution_m, double known_free) const {
  if (z_.empty() || !(half_angle >= 0) || half_angle > 0.5) return 0;
  // Lowest climb of any direction in the cone (site Z is down, so up is -z), and how far a
  // point at range r can be from the axis point o + r c.
  const double el_axis = std::asin(std::clamp(-c.z(), -1.0, 1.0));
  const double lowest_up = std::sin(std::max(el_axis - half_angle, -M_PI / 2));
  const double spread = 2 * std::sin(0.5 * half_angle);
  const double oe = -o.z();
  double r = 0, step = std::max(resolution_m, 0.25);
  // Nothing can be met before the lowest ray comes down to the highest node.
  if (lowest_up < 0 && oe > global_max_) r = std::min(max_range, (global_max_ - oe) / lowest_up);
  r = std::max(r, std::min(known_free, max_range));
  while (r < max_range && step >= resolution_m) {
    const double rb = std::min(max_range, r + step);
    const double rad = spread * rb;
    Box2 box{std::min(o.x() + r * c.x(), o.x() + rb * c.x()) - rad, std::max(o.x() + r * c.x(), o.x() + rb * c.x()) + rad,
             std::min(o.y() + r * c.y(), o.y() + rb * c.y()) - rad, std::max(o.y() + r * c.y(), o.y() + rb * c.y()) + rad};
    const double e_min = oe + std::min(r * lowest_up, rb * lowest_up);
    if (MaxOver(box) < e_min) {
      r = rb;
      step *= 2;
    } else {
      step *= 0.5;
    }
  }
  return std::min(r, max_range);
}

double HeightGrid::ElevationAt(double x, double y) const { return InterpolateNodes(z_, x, y); }

void HeightGrid::BuildGradients() {
  // Each node's central difference (one-sided at the edges): NormalUpAt interpolates
  // these bilinearly, so shading shows no cell pattern and costs one lookup per hit.
  grad_.resize(z_.size());
  for (int j = 0; j < ny_; ++j) {
    const int jl = std::max(j - 1, 0), jh = std::min(j + 1, ny_ - 1);
    for (int i = 0; i < nx_; ++i) {
      const int il = std::max(i - 1, 0), ih = std::min(i + 1, nx_ - 1);
      grad_[static_cast<std::size_t>(j) * nx_ + i] = {
          static_cast<float>((Z(ih, j) - Z(il, j)) / ((ih - il) * h_)),
          static_cast<float>((Z(i, jh) - Z(i, jl)) / ((jh - jl) * h_))};
    }
  }
}

inline void HeightGrid::Locate(double x, double y, std::size_t* k, double* a, double* b) const {
  const double u = std::clamp((x - x0_) * inv_h_, 0.0, nx_ - 1.000001);
  const double v = std::clamp((y - y0_) * inv_h_, 0.0, ny_ - 1.000001);
  const int i = static_cast<int>(u), j = static_cast<int>(v);
  *a = u - i;
  *b = v - j;
  *k = static_cast<std::size_t>(j) * nx_ + i;
}

inline Eigen::Vector3d HeightGrid::NormalAtNode(std::size_t k, double a, double b) const {
  const std::array<float, 2>* g0 = &grad_[k];
  const std::array<float, 2>* g1 = g0 + nx_;
  const double w00 = (1 - a) * (1 - b), w10 = a * (1 - b), w01 = (1 - a) * b, w11 = a * b;
  const double gx = w00 * g0[0][0] + w10 * g0[1][0] + w01 * g1[0][0] + w11 * g1[1][0];
  const double gy = w00 * g0[0][1] + w10 * g0[1][1] + w01 * g1[0][1] + w11 * g1[1][1];
  // Up is -Z in the site frame.
  return Eigen::Vector3d(-gx, -gy, -1.0).normalized();
}

Eigen::Vector3d HeightGrid::NormalUpAt(double x, double y) const {
  std::size_t k = 0;
  double a = 0, b = 0;
  Locate(x, y, &k, &a, &b);
  return NormalAtNode(k, a, b);
}

Eigen::Vector3d HeightGrid::NormalUpAt(double x, double y, const std::vector<float>& field,
                                       double* field_value) const {
  std::size_t k = 0;
  double a = 0, b = 0;
  Locate(x, y, &k, &a, &b);
  *field_value =
      (1 - b) * ((1 - a) * field[k] + a * field[k + 1]) + b * ((1 - a) * field[k + nx_] + a * field[k + nx_ + 1]);
  return NormalAtNode(k, a, b);
}

std::vector<float> HeightGrid::SunHorizon(double sx, double sy, double tan_el) const {
  std::vector<float> horizon(z_.size(), kNoHorizon);
  if (z_.empty() || !(sx * sx + sy * sy > 1e-12)) return horizon;
  // Sweep along the dominant axis of the sun's direction, from the sun side inward; the
  // upstream point of node (i, j) lies on the neighbouring grid line, `frac` nodes across.
  const bool along_x = std::abs(sx) >= std::abs(sy);
  const double main = along_x ? sx : sy, cross = along_x ? sy : sx;
  const int n_main = along_x ? nx_ : ny_, n_cross = along_x ? ny_ : nx_;
  const int step = main > 0 ? 1 : -1;
  const double frac = cross / std::abs(main);
  const double drop = h_ / std::abs(main) * tan_el;
  const int first = main > 0 ? n_main - 1 : 0;
  // The best of surface and horizon on the upstream line, per node.
  std::vector<float> up_best(static_cast<std::size_t>(n_cross));
  auto node = [&](int a, int c) -> std::size_t {
    return along_x ? static_cast<std::size_t>(c) * nx_ + a : static_cast<std::size_t>(a) * nx_ + c;
  };
  for (int c = 0; c < n_cross; ++c) up_best[c] = z_[node(first, c)];
  for (int a = first - step; a >= 0 && a < n_main; a -= step) {
    for (int c = 0; c < n_cross; ++c) {
      const double q = c + frac;
      const int c0 = static_cast<int>(std::floor(q));
      float hz = kNoHorizon;
      if (c0 >= 0 && c0 < n_cross) {
        const double w = q - c0;
        const double v0 = up_best[c0];
        const double v1 = c0 + 1 < n_cross ? up_best[c0 + 1] : (w > 1e-9 ? kNoHorizon : v0);
        if (v0 > 0.5 * kNoHorizon && v1 > 0.5 * kNoHorizon) hz = static_cast<float>((1 - w) * v0 + w * v1 - drop);
      }
      horizon[node(a, c)] = hz;
    }
    for (int c = 0; c < n_cross; ++c) {
      const std::size_t k = node(a, c);
      up_best[c] = std::max(z_[k], horizon[k]);
    }
  }
  return horizon;
}

double HeightGrid::InterpolateNodes(const std::vector<float>& field, double x, double y) const {
  std::size_t k = 0;
  double a = 0, b = 0;
  Locate(x, y, &k, &a, &b);
  return (1 - b) * ((1 - a) * field[k] + a * field[k + 1]) + b * ((1 - a) * field[k + nx_] + a * field[k + nx_ + 1]);
}

void HeightLevels::Build(const Ground& ground, const Eigen::Vector2d& centre,
                         double near_range_m, const std::vector<Box2>& boxes,
                         const std::vector<double>& cells) {
  centre_ = centre;
  near_range_ = near_range_m;
  grids_.assign(boxes.size(), HeightGrid());
  global_max_ = -kInf;
  for (std::size_t L = 0; L < boxes.size(); ++L) {
    grids_[L].Build(ground, boxes[L], cells[L]);
    global_max_ = std::max(global_max_, grids_[L].max_elevation());
  }
}

void HeightLevels::Adopt(const Ground::GridView& view) {
  grids_.assign(1, HeightGrid());
  grids_[0].Adopt(view);
  near_range_ = std::numeric_limits<double>::max();
  global_max_ = grids_[0].max_elevation();
}

std::size_t HeightLevels::nodes() const {
  std::size_t n = 0;
  for (const HeightGrid& g : grids_) n += g.nodes();
  return n;
}

int HeightLevels::LevelAt(double x, double y) const {
  if (grids_.size() <= 1) return 0;
  const double rho = std::hypot(x - centre_.x(), y - centre_.y());
  if (rho <= near_range_) return 0;
  const int L = static_cast<int>(std::ceil(std::log2(rho / near_range_)));
  return std::clamp(L, 0, levels() - 1);
}

double HeightLevels::Intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t0,
                               double t1, int* level_out) const {
  if (grids_.empty() || t0 > t1) return -1;
  if (d.z() <= 0 && -o.z() + (-d.z()) * t0 > global_max_) return -1;
  if (grids_.size() == 1) {
    // One level (a ground's own grid): no circles to split at.
    const double hit = grids_[0].Intersect(o, d, t0, t1);
    if (hit >= 0 && level_out) *level_out = 0;
    return hit;
  }
  // Split the ray where it crosses the level circles; each piece lies in one level.
  double cuts[64];
  int n = 0;
  cuts[n++] = t0;
  const double px = o.x() - centre_.x(), py = o.y() - centre_.y();
  const double a = d.x() * d.x() + d.y() * d.y();
  if (a > 1e-18) {
    const double b = 2 * (px * d.x() + py * d.y());
    for (int L = 0; L + 1 < levels() && n < 62; ++L) {
      const double R = near_range_ * std::ldexp(1.0, L);
      const double c = px * px + py * py - R * R;
      const double disc = b * b - 4 * a * c;
      if (disc <= 0) continue;
      const double sq = std::sqrt(disc);
      for (double r : {(-b - sq) / (2 * a), (-b + sq) / (2 * a)}) {
        if (r > t0 && r < t1) cuts[n++] = r;
      }
    }
  }
  std::sort(cuts + 1, cuts + n);
  cuts[n++] = t1;
  for (int k = 0; k + 1 < n; ++k) {
    const double ta = cuts[k], tb = cuts[k + 1];
    if (tb <= ta) continue;
    const double tm = 0.5 * (ta + tb);
    const int L = LevelAt(o.x() + tm * d.x(), o.y() + tm * d.y());
    const double hit = grids_[L].Intersect(o, d, ta, tb);
    if (hit >= 0) {
      if (level_out) *level_out = L;
      return hit;
    }
    // Going up above everything: nothing further can be hit.
    if (d.z() <= 0 && -o.z() + (-d.z()) * tb > global_max_) return -1;
  }
  return -1;
}

}  // namespace rover::render::internal
