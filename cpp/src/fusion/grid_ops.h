// Internal to the grid tracker (not installed): the grid operators and the per-step pieces of the
// forward filter shared by the batch run (GridTracker::Run, grid_tracker.cc) and the streaming
// session (GridFilterSession, grid_filter_session.cc), so that both perform the same floating-point
// operations in the same order and the session's estimates equal the batch's filtered outputs
// bit for bit. The model is in cpp/include/indoorloc/fusion/grid_tracker.h.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include <Eigen/Core>

#include "indoorloc/core/simd_dispatch.h"
#include "indoorloc/fusion/grid_tracker.h"
#include "grid_lanes.h"
#include "grid_window.h"
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

// The passes' bodies are inlined into both their portable and their AVX2 builds (grid_ops_avx2.cc).
#if defined(__GNUC__)
#define INDOORLOC_GRID_PASS inline __attribute__((always_inline))
#else
#define INDOORLOC_GRID_PASS inline
#endif

namespace indoorloc::fusion {
namespace grid_ops {

constexpr double kTwoPi = 2.0 * M_PI;

inline double WrapAngle(double a) { return std::remainder(a, kTwoPi); }

// One floor's grid: cells of side c over the floor's bounding box, row-major from the lowest y.
struct FloorGrid {
  double x0 = 0, y0 = 0;   // corner of cell (0, 0) [m]
  int nx = 0, ny = 0;
  int floor_number = 0;
  std::vector<float> walkable_fraction;  // a(c)
  std::vector<float> wall_factor;        // m(c) = a + (1 - a) e^λ
  // Where the fixes are evaluated (GridTracker::WithSurveyPositions; empty: the cell centres):
  // per cell the bilinear interpolation between the centres of cells j, j + sx, j + sy, j + sx + sy
  // (sx 0 or 1, sy 0 or nx: 0 on a grid one cell wide) with weights wx, wy in [0, 1].
  std::vector<int> fix_cell;
  std::vector<unsigned char> fix_step_x;
  std::vector<int> fix_step_y;
  std::vector<float> fix_wx, fix_wy;
  // The survey positions on this floor [m] the anchors above were computed from (kept so that
  // GridTracker::WithOptions can anchor again for another β).
  std::vector<Eigen::Vector2d> survey_points;
  std::vector<int> survey_walks;  // the survey walk of each point (for the opened cells' walk count)
  std::size_t size() const { return static_cast<std::size_t>(nx) * ny; }
};

// Fills the fix positions of `g` (fix_cell, ...) from g->survey_points for β = `beta` on cells of
// side `cell` [m]; clears them (the cell centres) for β >= 1 or no survey point
// (grid_survey_anchors.cc).
void AnchorFixesToSurvey(double beta, double cell, FloorGrid* g);

// Fills g->wall_factor from the walkable fractions for `penalty` = e^λ (0 for λ = -inf), then sets
// it to 1 at every cell whose centre lies within `radius_m` of points of g->survey_points from at
// least `min_walks` distinct g->survey_walks (GridTrackerOptions::survey_walkable_radius_m and
// survey_walkable_min_walks; radius 0: none) on cells of side `cell` [m] (grid_survey_walkable.cc).
void ComputeWallFactors(double penalty, int n_sub, double radius_m, int min_walks, double cell, FloorGrid* g);

// e^λ of the wall factor for λ = `wall_log_penalty` (0 for λ = -inf).
inline double WallPenalty(double wall_log_penalty) {
  return std::isinf(wall_log_penalty) ? 0.0 : std::exp(wall_log_penalty);
}

// The wall factor m(c) = a + (1 - a) e^λ of a cell with `walkable` of its n_sub² subsamples
// walkable (`penalty` = e^λ, 0 for λ = -inf); a = walkable / n_sub² in double, as the grid's
// walkable fraction (stored in float) was computed.
inline float WallFactor(int walkable, int n_sub, double penalty) {
  const double a = static_cast<double>(walkable) / (n_sub * n_sub);
  return static_cast<float>(a + (1.0 - a) * penalty);
}

// What the forward pass did at one step of a layer, so that the backward pass can apply the
// transposed operators and the recomputation of a segment repeats the forward pass exactly.
struct StepOps {
  int shift_x = 0, shift_y = 0;  // whole-cell shift applied
  double blur_var_cells2 = 0;    // variance of the blur applied [cells²] (0: none)
  double pending_var_m2 = 0;     // process variance not yet applied after this step [m²]
  double rx = 0, ry = 0;         // sub-cell remainder after this step [m]
};

// Discrete Gaussian kernel of variance var [cells²], normalised, radius ceil(3 sd).
inline std::vector<float> GaussianKernel(double var_cells2) {
  const int radius = KernelRadius(var_cells2);
  std::vector<double> k(2 * radius + 1);
  double sum = 0;
  for (int j = -radius; j <= radius; ++j) sum += k[j + radius] = std::exp(-0.5 * j * j / var_cells2);
  std::vector<float> out(k.size());
  for (std::size_t j = 0; j < k.size(); ++j) out[j] = static_cast<float>(k[j] / sum);
  return out;
}

// Separable blur with zero outside the grid: a symmetric operator (its own transpose). Both
// passes add the taps in kernel order to each cell (from 0), one tap over a whole row at a time,
// so that the loops vectorise; the order of the additions per cell is that of a per-cell loop.
// Only the cells of `win` are computed, from the cells of `win`: every cell outside it must be zero
// before and after the blur (grid_window.h), so the taps skipped would add +0.0.
INDOORLOC_GRID_PASS void BlurBody(std::vector<float>& g, std::vector<float>& scratch, int nx, int ny,
                                  double var_cells2, const CellWindow& win) {
  (void)ny;
  const std::vector<float> k = GaussianKernel(var_cells2);
  const int r = static_cast<int>(k.size() / 2);
  const int x0 = win.x0, x1 = win.x1;
  scratch.resize(g.size());
  // Along y: whole rows at a time; the first tap inside the window sets the row (0 + a is a).
  for (int y = win.y0; y < win.y1; ++y) {
    float* out = scratch.data() + static_cast<std::size_t>(y) * nx;
    const int j_lo = std::max(-r, win.y0 - y), j_hi = std::min(r, win.y1 - 1 - y);
    for (int j = j_lo; j <= j_hi; ++j) {
      const float w = k[j + r];
      const float* in = g.data() + static_cast<std::size_t>(y + j) * nx;
      if (j == j_lo) {
        for (int x = x0; x < x1; ++x) out[x] = w * in[x];
      } else {
        for (int x = x0; x < x1; ++x) out[x] += w * in[x];
      }
    }
  }
  // Along x: tap j adds k_j in(x + j) to every x with x + j inside the window's row.
  for (int y = win.y0; y < win.y1; ++y) {
    const float* in = scratch.data() + static_cast<std::size_t>(y) * nx;
    float* out = g.data() + static_cast<std::size_t>(y) * nx;
    std::fill(out + x0, out + x1, 0.0f);
    for (int j = -r; j <= r; ++j) {
      const float w = k[j + r];
      const int lo = std::max(x0, x0 - j), hi = std::min(x1, x1 - j);
      const float* src = in + j;
      for (int x = lo; x < hi; ++x) out[x] += w * src[x];
    }
  }
}

// g(x, y) <- g(x - sx, y - sy), zero where the source is outside the grid; in place (rows moved
// in the order that never overwrites a row still to be read, only the vacated cells zeroed).
inline void Shift(std::vector<float>& g, int nx, int ny, int sx, int sy) {
  ShiftInWindow(g, nx, CellWindow::Full(nx, ny), sx, sy);
}

// out(x, y) = g at (x + fx, y + fy) cells by bilinear interpolation, |fx|, |fy| <= 1, edges
// clamped: the fix factor of a layer whose positions are the cell centres plus a remainder.
// Only the cells of `win` are written (the default: all); each with the same operations.
inline void ResampleAt(const std::vector<float>& g, std::vector<float>& out, std::vector<float>& scratch, int nx, int ny,
                double fx, double fy, const CellWindow* win = nullptr) {
  scratch.resize(g.size());
  out.resize(g.size());
  const CellWindow w = win ? *win : CellWindow::Full(nx, ny);
  const int dx = fx >= 0 ? 1 : -1, dy = fy >= 0 ? 1 : -1;
  const float ax = static_cast<float>(std::abs(fx)), ay = static_cast<float>(std::abs(fy));
  // The rows of the window and the row next to it that the second pass reads.
  const int ya = std::max(0, w.y0 - 1), yb = std::min(ny, w.y1 + 1);
  for (int y = ya; y < yb; ++y) {
    const float* in = g.data() + static_cast<std::size_t>(y) * nx;
    float* o = scratch.data() + static_cast<std::size_t>(y) * nx;
    // Interior cells (x + dx inside the row) in one loop that vectorises; the clamped edge cell apart.
    const int lo = std::max(w.x0, dx > 0 ? 0 : 1), hi = std::min(w.x1, dx > 0 ? nx - 1 : nx);
    const float* in2 = in + dx;
    for (int x = lo; x < hi; ++x) o[x] = (1.0f - ax) * in[x] + ax * in2[x];
    const int edge = dx > 0 ? nx - 1 : 0;
    if (edge >= w.x0 && edge < w.x1) o[edge] = (1.0f - ax) * in[edge] + ax * in[edge];
  }
  for (int y = w.y0; y < w.y1; ++y) {
    const int y2 = std::min(ny - 1, std::max(0, y + dy));
    const float* a = scratch.data() + static_cast<std::size_t>(y) * nx;
    const float* b = scratch.data() + static_cast<std::size_t>(y2) * nx;
    float* o = out.data() + static_cast<std::size_t>(y) * nx;
    for (int x = w.x0; x < w.x1; ++x) o[x] = (1.0f - ay) * a[x] + ay * b[x];
  }
}

// g *= scale (in double: the result is at most 1 and never overflows a float), and entries below
// 1e-30 set to 0: they are negligible beside the sum or maximum of 1, and float denormals would
// slow every later pass and let a normalisation overflow.
INDOORLOC_GRID_PASS void NormaliseAndFlushSpan(float* g, std::size_t n, double scale) {
  if (scale < 1e30) {  // the common case, in float (vectorises): v * scale <= 1 cannot overflow
    const float f = static_cast<float>(scale);
    for (std::size_t i = 0; i < n; ++i) {
      const float x = g[i] * f;
      g[i] = x < 1e-30f ? 0.0f : x;
    }
    return;
  }
  for (std::size_t i = 0; i < n; ++i) {
    const double x = static_cast<double>(g[i]) * scale;
    g[i] = x < 1e-30 ? 0.0f : static_cast<float>(x);
  }
}
// The same on the cells of `win` only (null: the whole grid; cells outside are zero and stay so).
INDOORLOC_GRID_PASS void NormaliseAndFlushBody(std::vector<float>& g, double scale, int nx,
                                               const CellWindow* win) {
  if (!win) return NormaliseAndFlushSpan(g.data(), g.size(), scale);
  for (int y = win->y0; y < win->y1; ++y)
    NormaliseAndFlushSpan(g.data() + static_cast<std::size_t>(y) * nx + win->x0,
                          static_cast<std::size_t>(win->x1 - win->x0), scale);
}

// g *= wall (and *= fix when given); returns the sum (float lanes per row, grid_lanes.h; double
// over rows). Only the cells of `win` (its x0 a multiple of kLanes): those outside must be zero.
INDOORLOC_GRID_PASS double MultiplyAndSumBody(std::vector<float>& g, const std::vector<float>& wall, const float* fix,
                                              int nx, const CellWindow& win) {
  double total = 0;
  for (int y = win.y0; y < win.y1; ++y) {
    float* row = g.data() + static_cast<std::size_t>(y) * nx;
    const float* w = wall.data() + static_cast<std::size_t>(y) * nx;
    const float* f = fix ? fix + static_cast<std::size_t>(y) * nx : nullptr;
    Lanes acc = LanesOf(0.0f);
    int x = win.x0;
    const int x_end = win.x1;
    if (f) {
      for (; x + kLanes <= x_end; x += kLanes) {
        const Lanes v = LoadLanes(row + x) * (LoadLanes(w + x) * LoadLanes(f + x));
        StoreLanes(row + x, v);
        acc += v;
      }
    } else {
      for (; x + kLanes <= x_end; x += kLanes) {
        const Lanes v = LoadLanes(row + x) * LoadLanes(w + x);
        StoreLanes(row + x, v);
        acc += v;
      }
    }
    for (; x < x_end; ++x) {
      row[x] *= f ? w[x] * f[x] : w[x];
      acc.Add(x % kLanes, row[x]);
    }
    total += LaneTotal(acc);
  }
  return total;
}

// g *= wall (and *= fix when given), the products of MultiplyAndSum without its sum.
INDOORLOC_GRID_PASS void MultiplyBody(std::vector<float>& g, const std::vector<float>& wall, const float* fix) {
  const std::size_t n = g.size();
  float* d = g.data();
  const float* w = wall.data();
  if (fix) {
    for (std::size_t i = 0; i < n; ++i) d[i] *= w[i] * fix[i];
  } else {
    for (std::size_t i = 0; i < n; ++i) d[i] *= w[i];
  }
}

// The largest entry of g (0 for an empty or all-zero grid), in lanes (the maximum is exact).
INDOORLOC_GRID_PASS float MaxOfBody(const std::vector<float>& g) {
  Lanes m = LanesOf(0.0f);
  const std::size_t n = g.size();
  std::size_t i = 0;
  for (; i + kLanes <= n; i += kLanes) m = MaxLanes(LoadLanes(g.data() + i), m);
  float mx = 0.0f;
  for (; i < n; ++i) mx = g[i] > mx ? g[i] : mx;
  for (int j = 0; j < kLanes; ++j) mx = m[j] > mx ? m[j] : mx;
  return mx;
}

// Mean and second moments of a grid about the cell centres (double accumulation).
struct Moments {
  double mass = 0, sx = 0, sy = 0, sxx = 0, sxy = 0, syy = 0;
};

// Adds row y's sums (mass, Σ v x, Σ v x²) to the grid's sums about cell indices.
inline void AddRowMoments(double r_mass, double r_sx, double r_sxx, int y, Moments* m) {
  m->mass += r_mass;
  m->sx += r_sx;
  m->sy += r_mass * y;
  m->sxx += r_sxx;
  m->sxy += r_sx * y;
  m->syy += r_mass * y * static_cast<double>(y);
}

// Sums about cell indices -> mean [m] (sx, sy) and covariance [m²] (sxx, sxy, syy) of the cell centres.
inline Moments MomentsInMetres(const Moments& m, const FloorGrid& fg, double cell) {
  Moments out;
  out.mass = m.mass;
  if (m.mass <= 0) return out;
  const double mx = m.sx / m.mass, my = m.sy / m.mass;
  out.sx = fg.x0 + (mx + 0.5) * cell;
  out.sy = fg.y0 + (my + 0.5) * cell;
  out.sxx = (m.sxx / m.mass - mx * mx) * cell * cell;
  out.sxy = (m.sxy / m.mass - mx * my) * cell * cell;
  out.syy = (m.syy / m.mass - my * my) * cell * cell;
  return out;
}

// Sums over a row's cells x_begin .. nx - 1 (x_begin a multiple of kLanes; the others zero) of v,
// v x and v x² (v = row, or row * weight when kWeighted), x the cell index, in float lanes
// (kLanes), totals in double.
template <bool kWeighted>
INDOORLOC_GRID_PASS void RowMomentsInFloat(const float* row, const float* weight, int nx, double* mass, double* sx,
                                           double* sxx, int x_begin = 0) {
  Lanes m = LanesOf(0.0f), s1 = m, s2 = m, fx = Iota();
  if (x_begin != 0) fx += LanesOf(static_cast<float>(x_begin));  // exact: far below 2^24
  const Lanes step = LanesOf(static_cast<float>(kLanes));
  int x = x_begin;
  for (; x + kLanes <= nx; x += kLanes) {
    const Lanes v = kWeighted ? LoadLanes(row + x) * LoadLanes(weight + x) : LoadLanes(row + x);
    m += v;
    s1 += v * fx;
    s2 += v * fx * fx;
    fx += step;  // exact: cell indices far below 2^24
  }
  for (; x < nx; ++x) {
    const float v = kWeighted ? row[x] * weight[x] : row[x], f = static_cast<float>(x);
    m.Add(x % kLanes, v);
    s1.Add(x % kLanes, v * f);
    s2.Add(x % kLanes, v * f * f);
  }
  *mass = LaneTotal(m);
  *sx = LaneTotal(s1);
  *sxx = LaneTotal(s2);
}

// Sums in double of up to kDoubleRows consecutive rows y0, y0 + 1, ... of g (or g * weight), and
// with `coarse` their block sums: each row's sums (mass, Σ v x, Σ v x², and per block of q cells
// Σ v, Σ v x) are the additions of a plain loop along the row, in the same order, so the results
// equal that loop's bit for bit; the rows only run side by side, one per lane (the serial
// additions of one row cannot vectorise, those of different rows can). Block sums are added to
// `coarse` row after row, as the plain loop does.
constexpr int kDoubleRows = 4;  // two RowPairs (grid_lanes.h)

void RowGroupMomentsInDouble(const float* g, const float* weight, const FloorGrid& fg, int y0, int rows, int q,
                             double* coarse, Moments* m);

// The same sums for up to kDoubleRowsAvx2 rows, eight side by side in two 256-bit registers, bit for
// bit those of RowGroupMomentsInDouble (call only when UseAvx2()). Both: grid_moments_double.cc.
constexpr int kDoubleRowsAvx2 = 8;
void RowGroupMomentsInDoubleAvx2(const float* g, const float* weight, const FloorGrid& fg, int y0, int rows, int q,
                                 double* coarse, Moments* m);

// Of g, or of the product g * weight (the smoother's alpha * beta, formed in double: both are
// flushed at 1e-30, so the product stays far above double's underflow).
// With `coarse` (nqx * nqy * 3 doubles, zeroed by the caller), also the mass and the mass-weighted
// cell indices of every block of q x q cells (the summary the spatial median is computed from).
// With `win` (x0 a multiple of kLanes; g zero outside it), the float sums over its cells only (the
// double sums always over the whole grid).
inline Moments GridMoments(const float* g, const float* weight, const FloorGrid& fg, double cell, int q = 1,
                    double* coarse = nullptr, bool force_double = false, const CellWindow* win = nullptr) {
  Moments m;
  const bool in_float = !coarse && (!weight || !force_double);
  if (in_float) {  // the common case: float lane accumulators along the row (vectorises)
    const CellWindow w = win ? *win : CellWindow::Full(fg.nx, fg.ny);
    for (int y = w.y0; y < w.y1; ++y) {
      const float* row = g + static_cast<std::size_t>(y) * fg.nx;
      double r_mass = 0, r_sx = 0, r_sxx = 0;
      if (weight) {
        RowMomentsInFloat<true>(row, weight + static_cast<std::size_t>(y) * fg.nx, w.x1, &r_mass, &r_sx, &r_sxx, w.x0);
      } else {
        RowMomentsInFloat<false>(row, nullptr, w.x1, &r_mass, &r_sx, &r_sxx, w.x0);
      }
      AddRowMoments(r_mass, r_sx, r_sxx, y, &m);
    }
  } else {
    // Double sums (and block sums): kDoubleRows (AVX2: kDoubleRowsAvx2) rows side by side.
    const int block = coarse ? q : std::max(1, fg.nx);
    if (UseAvx2()) {
      for (int y = 0; y < fg.ny; y += kDoubleRowsAvx2)
        RowGroupMomentsInDoubleAvx2(g, weight, fg, y, std::min(kDoubleRowsAvx2, fg.ny - y), block, coarse, &m);
    } else {
      for (int y = 0; y < fg.ny; y += kDoubleRows)
        RowGroupMomentsInDouble(g, weight, fg, y, std::min(kDoubleRows, fg.ny - y), block, coarse, &m);
    }
  }
  // The smoother's product alpha * beta in float can underflow where both are small: when its
  // total is that small, redo the sums in double.
  if (weight && !coarse && !force_double && m.mass < 1e-20) return GridMoments(g, weight, fg, cell, q, coarse, true);
  return MomentsInMetres(m, fg, cell);
}

// NormaliseAndFlush(g, scale) and then GridMoments(g) (no blocks) in one pass over the rows, each
// row also copied to `store` when given: the same operations in the same order, so the same bits.
// Only the cells of `win` (x0 a multiple of kLanes; the others zero) are normalised and summed,
// and only its rows stored (from their first cell to the row's end): with a window smaller than
// the grid, `store` must be null.
INDOORLOC_GRID_PASS Moments NormaliseMomentsAndStoreBody(std::vector<float>& g, double scale, const FloorGrid& fg,
                                                         double cell, float* store, const CellWindow& win) {
  Moments m;
  const bool in_float = scale < 1e30;  // NormaliseAndFlush's two cases
  const float f = static_cast<float>(scale);
  for (int y = win.y0; y < win.y1; ++y) {
    float* row = g.data() + static_cast<std::size_t>(y) * fg.nx;
    if (in_float) {
      for (int x = win.x0; x < win.x1; ++x) {
        const float v = row[x] * f;
        row[x] = v < 1e-30f ? 0.0f : v;
      }
    } else {
      for (int x = win.x0; x < win.x1; ++x) {
        const double v = static_cast<double>(row[x]) * scale;
        row[x] = v < 1e-30 ? 0.0f : static_cast<float>(v);
      }
    }
    double r_mass = 0, r_sx = 0, r_sxx = 0;
    RowMomentsInFloat<false>(row, nullptr, win.x1, &r_mass, &r_sx, &r_sxx, win.x0);
    AddRowMoments(r_mass, r_sx, r_sxx, y, &m);
    if (store) std::memcpy(store + static_cast<std::size_t>(y) * fg.nx, row, static_cast<std::size_t>(fg.nx) * sizeof(float));
  }
  return MomentsInMetres(m, fg, cell);
}

// The passes above in their AVX2 builds (grid_ops_avx2.cc): the same bodies compiled for 256-bit
// vectors. The bodies are element-wise float operations and reductions in fixed lanes
// (grid_lanes.h), without FMA, so both builds give the same bits (a test runs both).
void BlurAvx2(std::vector<float>& g, std::vector<float>& scratch, int nx, int ny, double var_cells2,
              const CellWindow& win);
void NormaliseAndFlushAvx2(std::vector<float>& g, double scale, int nx, const CellWindow* win);
double MultiplyAndSumAvx2(std::vector<float>& g, const std::vector<float>& wall, const float* fix, int nx,
                          const CellWindow& win);
void MultiplyAvx2(std::vector<float>& g, const std::vector<float>& wall, const float* fix);
float MaxOfAvx2(const std::vector<float>& g);
Moments NormaliseMomentsAndStoreAvx2(std::vector<float>& g, double scale, const FloorGrid& fg, double cell, float* store,
                                     const CellWindow& win);

// Separable blur with zero outside the grid (BlurBody).
// With `win`, on its cells only (every cell outside it zero before and after: grid_window.h).
inline void Blur(std::vector<float>& g, std::vector<float>& scratch, int nx, int ny, double var_cells2,
                 const CellWindow* win = nullptr) {
  const CellWindow w = win ? *win : CellWindow::Full(nx, ny);
  if (UseAvx2()) return BlurAvx2(g, scratch, nx, ny, var_cells2, w);
  BlurBody(g, scratch, nx, ny, var_cells2, w);
}
// g *= scale, entries below 1e-30 flushed to 0 (NormaliseAndFlushBody); with `win` on its cells only.
inline void NormaliseAndFlush(std::vector<float>& g, double scale, int nx = 0, const CellWindow* win = nullptr) {
  if (UseAvx2()) return NormaliseAndFlushAvx2(g, scale, nx, win);
  NormaliseAndFlushBody(g, scale, nx, win);
}
// g *= wall (and fix); the sum (MultiplyAndSumBody); with `win` on its cells only.
inline double MultiplyAndSum(std::vector<float>& g, const std::vector<float>& wall, const float* fix, int nx, int ny,
                             const CellWindow* win = nullptr) {
  const CellWindow w = win ? *win : CellWindow::Full(nx, ny);
  return UseAvx2() ? MultiplyAndSumAvx2(g, wall, fix, nx, w) : MultiplyAndSumBody(g, wall, fix, nx, w);
}
// g *= wall (and fix) (MultiplyBody).
inline void Multiply(std::vector<float>& g, const std::vector<float>& wall, const float* fix) {
  if (UseAvx2()) return MultiplyAvx2(g, wall, fix);
  MultiplyBody(g, wall, fix);
}
// The largest entry (MaxOfBody).
inline float MaxOf(const std::vector<float>& g) { return UseAvx2() ? MaxOfAvx2(g) : MaxOfBody(g); }
// Normalise, moments and the smoother's copy in one pass (NormaliseMomentsAndStoreBody).
// With `win`, on its cells only (store null unless the window is the whole grid).
inline Moments NormaliseMomentsAndStore(std::vector<float>& g, double scale, const FloorGrid& fg, double cell,
                                        float* store, const CellWindow* win = nullptr) {
  const CellWindow w = win ? *win : CellWindow::Full(fg.nx, fg.ny);
  return UseAvx2() ? NormaliseMomentsAndStoreAvx2(g, scale, fg, cell, store, w)
                   : NormaliseMomentsAndStoreBody(g, scale, fg, cell, store, w);
}

// A layer's per-step estimate: mean, covariance, cumulative log evidence.
struct LayerStep {
  double mx = 0, my = 0, cxx = 0, cxy = 0, cyy = 0;
  double log_evidence = 0;
};

// The layers of a run: floors x heading-offset bins x scale bins, with normalised log priors.
struct GridLayer {
  int floor_index, offset_bin, scale_bin;
  double log_prior;
};
struct GridLayers {
  std::vector<double> offsets;  // heading offset of each bin [rad]
  std::vector<double> scales;   // stride scale of each bin
  double bin_width = 0;         // width of the offset bins [rad] (0: one known offset)
  std::vector<GridLayer> layers;
};
/// The layers of a run from the start (known: its floor index only, its offset the prior centre).
GridLayers MakeGridLayers(const GridTrackerOptions& o, const FloorPlan& plan, int n_floors, double total_area_m2,
                          const TrackStart& start, int start_floor_index);

// Plans step `st` of a layer with offset (cos co, sin so) and scale sc: advances the sub-cell
// remainder (rx, ry) [m] and the pending process variance [m²], and returns the whole-cell shift
// and the blur to apply (the deferred blur: applied once the pending variance reaches a quarter
// of a cell², and before every fix).
inline StepOps PlanStep(const StepInput& st, double sc, double co, double so, double c, double position_noise_m,
                        double bin_width, bool has_fix, double* rx, double* ry, double* pending) {
  StepOps op;
  const Eigen::Vector2d d = st.displacement_m;
  *rx += sc * (co * d.x() - so * d.y());
  *ry += sc * (so * d.x() + co * d.y());
  const double len = sc * d.norm();
  *pending += sc * sc * 0.5 * st.covariance_m2.trace() + position_noise_m * position_noise_m +
              len * len * bin_width * bin_width / 12.0;
  op.shift_x = static_cast<int>(std::lround(*rx / c));
  op.shift_y = static_cast<int>(std::lround(*ry / c));
  *rx -= op.shift_x * c;
  *ry -= op.shift_y * c;
  op.blur_var_cells2 = 0;
  if (*pending >= 0.25 * c * c || has_fix) {
    op.blur_var_cells2 = *pending / (c * c);
    *pending = 0;
  }
  op.pending_var_m2 = *pending;
  op.rx = *rx;
  op.ry = *ry;
  return op;
}

// A layer's filtered estimate from its grid (positions: cell centres + the remainder; within-cell
// spread c²/12 and the pending process variance added).
inline LayerStep FilteredLayerEstimate(const Moments& mo, const StepOps& op, double c) {
  LayerStep e;
  e.mx = mo.sx + op.rx;
  e.my = mo.sy + op.ry;
  const double extra = op.pending_var_m2 + c * c / 12.0;
  e.cxx = mo.sxx + extra;
  e.cxy = mo.sxy;
  e.cyy = mo.syy + extra;
  return e;
}

// Weighted mean sd of a fix's components [m]: the fix's own statement of its uncertainty (for WiFi
// fingerprint fixes it grows with the best match's dissimilarity, so it is large where the scan
// resembles no surveyed fingerprint). Components of weight 0 (padding) are skipped; 0 for an
// empty fix.
inline double FixSd(const PositionFix& f) {
  double sum = 0, total = 0;
  for (Eigen::Index i = 0; i < f.means_m.rows(); ++i) {
    if (!(f.weights[i] > 0)) continue;
    sum += f.weights[i] * f.sds_m[i];
    total += f.weights[i];
  }
  return total > 0 ? sum / total : 0.0;
}

// The returned covariance (GridTrackerOptions, "Calibration of the returned covariances"):
//   Σ' = a Σ + (b² + (g d)² + (h max(0, s - s0))²) I
// Σ = posterior (xx, xy, yy) [m²], d the distance to the fix's centre [m], s the fix's sd [m].
// One definition for the batch run and the streaming session.
inline Eigen::Vector3d CalibratedCovariance(const Eigen::Vector3d& posterior, double d, double s, double a, double b,
                                            double g, double h, double s0) {
  const double excess = h * std::max(0.0, s - s0);
  const double iso = b * b + (g * d) * (g * d) + excess * excess;
  return Eigen::Vector3d(a * posterior[0] + iso, a * posterior[1], a * posterior[2] + iso);
}

// Weighted mean of a fix's components [m] (the centre the covariance calibration measures from).
inline Eigen::Vector2d FixCentre(const PositionFix& f) {
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  double total = 0;
  for (Eigen::Index i = 0; i < f.means_m.rows(); ++i) {
    centre += f.weights[i] * f.means_m.row(i).transpose();
    total += f.weights[i];
  }
  return total > 0 ? Eigen::Vector2d(centre / total) : centre;
}

// A layer's prior on its floor's grid: uniform, or a Gaussian of sd start_position_sd_m around a
// known start (unnormalised; the walls and the first step's normalisation follow).
inline void FillStartPrior(const FloorGrid& fg, const TrackStart& start, double start_position_sd_m, double cell,
                           std::vector<float>* alpha) {
  alpha->resize(fg.size());
  if (!start.known) {
    std::fill(alpha->begin(), alpha->end(), 1.0f);
    return;
  }
  const double sd = start_position_sd_m;
  for (int y = 0; y < fg.ny; ++y)
    for (int x = 0; x < fg.nx; ++x) {
      const double dx = fg.x0 + (x + 0.5) * cell - start.position_m.x();
      const double dy = fg.y0 + (y + 0.5) * cell - start.position_m.y();
      const double e = -0.5 * (dx * dx + dy * dy) / (sd * sd);
      // exp(e) < 1e-47 rounds to float 0 (below the smallest denormal): no exp needed there.
      (*alpha)[static_cast<std::size_t>(y) * fg.nx + x] = e < -108.0 ? 0.0f : static_cast<float>(std::exp(e));
    }
}

// The tracker's grids and fix factors (the body of GridTracker's pimpl, shared with
// GridFilterSession and the pieces of the batch run, grid_run.h).
struct TrackerGrids {
  const FloorPlan* plan = nullptr;
  GridTrackerOptions options;
  std::vector<FloorGrid> grids;
  double total_area_m2 = 0;

  // Per step with fixes: per floor the factor Π_j L_j(c)^τ / max and the log of that max.
  struct FixFactor {
    std::vector<float> factor;
    double log_scale = 0;
  };

  // The factor of the fixes applied at one step on one floor's grid (grid_fix_factor.cc).
  FixFactor ComputeFixFactor(const std::vector<const PositionFix*>& fixes, const FloorGrid& fg) const;
};

}  // namespace grid_ops

struct GridTracker::Impl : grid_ops::TrackerGrids {};

}  // namespace indoorloc::fusion
