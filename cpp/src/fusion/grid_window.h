// Internal to the grid tracker (not installed): the window of a layer's grid outside which every
// cell is exactly zero. A known start's prior is a Gaussian of sd start_position_sd_m, and the
// filter flushes cells below 1e-30 of the scale to 0, so its posterior lives on a small part of
// the floor; the forward pass then runs its operators (grid_ops.h) on that window only. Skipped
// cells are zeros: their additions are of +0.0 and their products 0, so the window's results
// equal the full grid's bit for bit, provided the window's first column is a multiple of the
// lanes (kLanes) from the grid's, so that every cell keeps its lane (grid_lanes.h).
#pragma once
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "grid_lanes.h"

namespace indoorloc::fusion::grid_ops {

// Cells [x0, x1) x [y0, y1) of a grid nx cells wide (row-major).
struct CellWindow {
  int x0 = 0, x1 = 0, y0 = 0, y1 = 0;
  static CellWindow Full(int nx, int ny) { return CellWindow{0, nx, 0, ny}; }
  bool empty() const { return x1 <= x0 || y1 <= y0; }
  bool IsFull(int nx, int ny) const { return x0 == 0 && y0 == 0 && x1 == nx && y1 == ny; }
};

// Radius [cells] of the blur's kernel of variance var [cells²]: ceil(3 sd), at least 1.
inline int KernelRadius(double var_cells2) {
  return std::max(1, static_cast<int>(std::ceil(3.0 * std::sqrt(var_cells2))));
}

// w moved by (sx, sy) cells and grown by `grow` cells on every side, clipped to the grid, its
// first column rounded down to a multiple of kLanes; the full grid when nothing is left (every
// cell is then zero, and the full grid's passes say so as before).
inline CellWindow MovedWindow(const CellWindow& w, int sx, int sy, int grow, int nx, int ny) {
  CellWindow out{std::max(0, w.x0 + sx - grow), std::min(nx, w.x1 + sx + grow), std::max(0, w.y0 + sy - grow),
                 std::min(ny, w.y1 + sy + grow)};
  if (out.empty()) return CellWindow::Full(nx, ny);
  out.x0 -= out.x0 % kLanes;
  return out;
}

// The smallest window holding every nonzero cell of g inside `w` (cells outside w are zero), its
// first column rounded down to a multiple of kLanes; the full grid when every cell is zero.
inline CellWindow NonzeroExtent(const std::vector<float>& g, int nx, int ny, const CellWindow& w) {
  CellWindow out{w.x1, w.x0, w.y1, w.y0};
  for (int y = w.y0; y < w.y1; ++y) {
    const float* row = g.data() + static_cast<std::size_t>(y) * nx;
    int lo = w.x0;
    while (lo < w.x1 && row[lo] == 0.0f) ++lo;
    if (lo == w.x1) continue;
    int hi = w.x1;
    while (row[hi - 1] == 0.0f) --hi;
    out.x0 = std::min(out.x0, lo);
    out.x1 = std::max(out.x1, hi);
    out.y0 = std::min(out.y0, y);
    out.y1 = y + 1;
  }
  if (out.empty()) return CellWindow::Full(nx, ny);
  out.x0 -= out.x0 % kLanes;
  return out;
}

// g(x, y) <- g(x - sx, y - sy) inside w, zero where the source is outside w; in place (rows
// moved in the order that never overwrites a row still to be read, only the vacated cells
// zeroed). With every nonzero cell of g inside w and w holding the cells they move to as well,
// this is the whole grid's shift (zero where the source is outside the grid).
inline void ShiftInWindow(std::vector<float>& g, int nx, const CellWindow& w, int sx, int sy) {
  if (sx == 0 && sy == 0) return;
  float* d = g.data();
  const std::size_t row = static_cast<std::size_t>(nx);
  const int wx = w.x1 - w.x0, wy = w.y1 - w.y0;
  auto zero_rows = [&](int y_begin, int y_end) {
    for (int y = y_begin; y < y_end; ++y) std::fill(d + y * row + w.x0, d + y * row + w.x1, 0.0f);
  };
  if (std::abs(sx) >= wx || std::abs(sy) >= wy) {
    zero_rows(w.y0, w.y1);
    return;
  }
  const int x_lo = w.x0 + std::max(0, sx), x_hi = w.x1 + std::min(0, sx);  // destination columns
  const int width = x_hi - x_lo;
  auto move_row = [&](int y) {
    float* dst = d + y * row;
    const float* src = d + (y - sy) * row + (x_lo - sx);
    std::memmove(dst + x_lo, src, static_cast<std::size_t>(width) * sizeof(float));
    std::fill(dst + w.x0, dst + x_lo, 0.0f);
    std::fill(dst + x_hi, dst + w.x1, 0.0f);
  };
  if (sy > 0) {
    for (int y = w.y1 - 1; y >= w.y0 + sy; --y) move_row(y);
    zero_rows(w.y0, w.y0 + sy);
  } else {
    for (int y = w.y0; y < w.y1 + sy; ++y) move_row(y);
    zero_rows(w.y1 + sy, w.y1);
  }
}

}  // namespace indoorloc::fusion::grid_ops

namespace indoorloc::fusion::test_hooks {
// For the C++ tests only (not installed): with `on` false, GridTracker::Run filters a known
// start's layers on their whole floor grid, as before the forward pass was limited to the window
// of nonzero cells (same results, slower). Process-wide; default true (grid_tracker.cc).
void SetKnownStartWindow(bool on);
}  // namespace indoorloc::fusion::test_hooks

