#include "planner/site_map.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace rover::planner {

using avoidance::CellClass;

SiteMap::SiteMap(double max_extent_m) : max_extent_m_(max_extent_m) {
  if (!(max_extent_m > 0.0) || !std::isfinite(max_extent_m))
    throw std::invalid_argument("site map: max_extent_m " + std::to_string(max_extent_m) + " must be > 0");
}

void SiteMap::Clear() {
  cells_.clear();
  rows_ = cols_ = 0;
  cell_m_ = 0.0;
}

int SiteMap::IndexOf(double v) const { return static_cast<int>(std::floor(v / cell_m_)); }

SiteMap::Cell* SiteMap::At(int i, int j) {
  const int a = i - i0_, b = j - j0_;
  if (a < 0 || b < 0 || a >= rows_ || b >= cols_) return nullptr;
  return &cells_[static_cast<std::size_t>(a) * cols_ + b];
}

const SiteMap::Cell* SiteMap::At(int i, int j) const { return const_cast<SiteMap*>(this)->At(i, j); }

bool SiteMap::Cover(int i_lo, int j_lo, int i_hi, int j_hi) {
  if (rows_ > 0) {
    i_lo = std::min(i_lo, i0_);
    j_lo = std::min(j_lo, j0_);
    i_hi = std::max(i_hi, i0_ + rows_ - 1);
    j_hi = std::max(j_hi, j0_ + cols_ - 1);
    if (i_lo == i0_ && j_lo == j0_ && i_hi == i0_ + rows_ - 1 && j_hi == j0_ + cols_ - 1) return true;
  }
  const int max_cells = static_cast<int>(std::floor(max_extent_m_ / cell_m_));
  if (i_hi - i_lo + 1 > max_cells || j_hi - j_lo + 1 > max_cells) return false;
  const int rows = i_hi - i_lo + 1, cols = j_hi - j_lo + 1;
  std::vector<Cell> cells(static_cast<std::size_t>(rows) * cols);
  for (int a = 0; a < rows_; ++a)
    for (int b = 0; b < cols_; ++b)
      cells[static_cast<std::size_t>(a + i0_ - i_lo) * cols + (b + j0_ - j_lo)] =
          cells_[static_cast<std::size_t>(a) * cols_ + b];
  cells_.swap(cells);
  i0_ = i_lo;
  j0_ = j_lo;
  rows_ = rows;
  cols_ = cols;
  return true;
}

void SiteMap::Merge(const avoidance::Grid& local) {
  if (const std::string p = local.Problem(); !p.empty()) throw std::invalid_argument("site map: merged grid: " + p);
  if (local.rows == 0 || local.cols == 0) return;
  if (cell_m_ != 0.0 && std::abs(local.cell_m - cell_m_) > 1e-9) Clear();
  if (Empty()) cell_m_ = local.cell_m;
  const int i_lo = IndexOf(local.CellCentreX(0)), i_hi = IndexOf(local.CellCentreX(local.rows - 1));
  const int j_lo = IndexOf(local.CellCentreY(0)), j_hi = IndexOf(local.CellCentreY(local.cols - 1));
  if (!Cover(i_lo, j_lo, i_hi, j_hi)) {
    Clear();
    cell_m_ = local.cell_m;
    Cover(i_lo, j_lo, i_hi, j_hi);
  }
  for (int a = 0; a < local.rows; ++a) {
    for (int b = 0; b < local.cols; ++b) {
      const std::size_t k = static_cast<std::size_t>(a) * local.cols + b;
      if (local.state[k] == CellClass::kUnknown) continue;
      Cell* c = At(IndexOf(local.CellCentreX(a)), IndexOf(local.CellCentreY(b)));
      // A rock once rated unsafe is not made caution by a view that saw less of it
      // (set_keep_unsafe).
      if (keep_unsafe_ && c->state == CellClass::kUnsafe && !c->driven && local.state[k] == CellClass::kCaution) {
        c->step_m = std::max(c->step_m, local.step_m[k]);
        continue;
      }
      c->state = local.state[k];
      c->goodness = local.goodness[k];
      c->step_m = local.step_m[k];
    }
  }
}

void SiteMap::MarkDriven(const avoidance::Pose2& pose, const avoidance::Footprint& footprint) {
  if (Empty()) return;  // nothing to place it on until a first map gives the cell size
  const double reach = 0.5 * std::hypot(footprint.length_m, footprint.width_m) + std::abs(footprint.center_forward_m);
  const int i_lo = IndexOf(pose.x - reach), i_hi = IndexOf(pose.x + reach);
  const int j_lo = IndexOf(pose.y - reach), j_hi = IndexOf(pose.y + reach);
  if (!Cover(i_lo, j_lo, i_hi, j_hi)) return;
  for (int i = i_lo; i <= i_hi; ++i)
    for (int j = j_lo; j <= j_hi; ++j)
      if (footprint.Contains(pose, (i + 0.5) * cell_m_, (j + 0.5) * cell_m_)) At(i, j)->driven = true;
}

int SiteMap::KnownCells() const {
  return static_cast<int>(std::count_if(cells_.begin(), cells_.end(), [](const Cell& c) { return c.state != CellClass::kUnknown; }));
}

int SiteMap::DrivenCells() const {
  return static_cast<int>(std::count_if(cells_.begin(), cells_.end(), [](const Cell& c) { return c.driven; }));
}

bool SiteMap::Driven(double x, double y) const {
  if (Empty()) return false;
  const Cell* c = At(IndexOf(x), IndexOf(y));
  return c && c->driven;
}

int SiteMap::MarkDrivenOn(avoidance::Grid* grid) const {
  if (Empty()) return 0;
  int changed = 0;
  for (int i = 0; i < grid->rows; ++i)
    for (int j = 0; j < grid->cols; ++j) {
      const std::size_t k = static_cast<std::size_t>(i) * grid->cols + j;
      if (grid->state[k] != CellClass::kUnknown || !Driven(grid->CellCentreX(i), grid->CellCentreY(j))) continue;
      grid->state[k] = CellClass::kSafe;
      grid->goodness[k] = 1.0f;
      ++changed;
    }
  return changed;
}

int SiteMap::KeepUnsafeOn(avoidance::Grid* grid) const {
  if (Empty() || !keep_unsafe_) return 0;
  int changed = 0;
  for (int i = 0; i < grid->rows; ++i)
    for (int j = 0; j < grid->cols; ++j) {
      const std::size_t k = static_cast<std::size_t>(i) * grid->cols + j;
      if (grid->state[k] != CellClass::kCaution) continue;
      const Cell* c = At(IndexOf(grid->CellCentreX(i)), IndexOf(grid->CellCentreY(j)));
      if (!c || c->driven || c->state != CellClass::kUnsafe) continue;
      grid->state[k] = CellClass::kUnsafe;
      grid->goodness[k] = 0.0f;
      grid->step_m[k] = std::max(grid->step_m[k], c->step_m);
      ++changed;
    }
  return changed;
}

bool SiteMap::Bounds(double* x0, double* y0, double* x1, double* y1) const {
  if (Empty()) return false;
  *x0 = i0_ * cell_m_;
  *y0 = j0_ * cell_m_;
  *x1 = (i0_ + rows_) * cell_m_;
  *y1 = (j0_ + cols_) * cell_m_;
  return true;
}

avoidance::Grid SiteMap::Window(double x0, double y0, double x1, double y1) const {
  if (Empty()) throw std::logic_error("site map: Window of an empty map");
  const int i_lo = IndexOf(x0), i_hi = IndexOf(x1), j_lo = IndexOf(y0), j_hi = IndexOf(y1);
  avoidance::Grid g = avoidance::Grid::Filled(i_lo * cell_m_, j_lo * cell_m_, cell_m_, i_hi - i_lo + 1,
                                              j_hi - j_lo + 1, CellClass::kUnknown, 0.0f);
  for (int a = 0; a < g.rows; ++a) {
    for (int b = 0; b < g.cols; ++b) {
      const Cell* c = At(i_lo + a, j_lo + b);
      if (!c) continue;
      const std::size_t k = static_cast<std::size_t>(a) * g.cols + b;
      if (c->state != CellClass::kUnknown) {
        g.state[k] = c->state;
        g.goodness[k] = c->goodness;
        g.step_m[k] = c->step_m;
      } else if (c->driven) {
        g.state[k] = CellClass::kSafe;
        g.goodness[k] = 1.0f;
      }
    }
  }
  return g;
}

}  // namespace rover::planner
