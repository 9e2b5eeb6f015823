// Implementation of FloorPlan: a uniform grid of edges per floor (CSR layout, edge coordinates
// stored contiguously per cell), exact orientation predicates (a floating-point filter with an
// exact expansion-arithmetic fallback, after Shewchuk 1997), Amanatides & Woo cell traversal for
// wall crossings, per-cell anchors with precomputed winding counts for point location, and
// expanding rings of cells for the distance to the nearest wall. See docs/fusion.md, "Floor plan".
#include "indoorloc/fusion/floor_plan.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <limits>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "indoorloc/core/check.h"
#include "indoorloc/core/interrupt.h"
#include "indoorloc/core/validate.h"
#include "indoorloc/core/options.h"
#include "indoorloc/core/parallel.h"
#include "floor_plan_index.h"


namespace indoorloc::fusion {

using namespace floor_plan_internal;  // NOLINT: the index types of this file's implementation

bool FloorPlanOptions::IsValid(std::string* error) const {
  // A tiny positive cell size is refused when the plan is built, against max_cells (the message
  // then gives the number of cells it would take).
  return Validator(error)
      .Finite(cell_size_m, "cell_size_m")
      .Check(cell_size_m <= 1e6, "cell_size_m",
             "must be <= 0 (automatic) or in (0, 1e+06] m, got " + FormatValue(cell_size_m))
      .InRange(target_edges_per_cell, 1e-3, 1e6, "target_edges_per_cell")
      .IntInRange(max_cells, 1, 100000000, "max_cells");
}

struct FloorPlan::Impl {
  std::vector<FloorData> floors;
  std::vector<int> floor_numbers;
  FloorPlanOptions options;
};

namespace {


void CheckFloorIndex(const std::vector<FloorData>& floors, int floor_index, const char* name) {
  if (floor_index < 0 || floor_index >= static_cast<int>(floors.size())) {
    ThrowInvalidArgument(name, "floor index " + std::to_string(floor_index) +
                                   " out of range [0, " + std::to_string(floors.size()) + ")");
  }
}

// Checks a batch's floor indices (one per query, or a single one for all) and returns a
// function of the query index.
struct FloorIndices {
  const Eigen::Ref<const Eigen::VectorXi>& v;
  int operator()(Eigen::Index q) const { return v.size() == 1 ? v[0] : v[q]; }
};

void CheckBatch(const std::vector<FloorData>& floors, Eigen::Index queries,
                const Eigen::Ref<const Eigen::VectorXi>& floor_indices) {
  if (!(floor_indices.size() == queries || floor_indices.size() == 1)) {
    ThrowInvalidArgument("floor_indices", "expected one entry per query (" +
                                              std::to_string(queries) +
                                              ") or a single entry, got " +
                                              std::to_string(floor_indices.size()));
  }
  const int n = static_cast<int>(floors.size());
  for (Eigen::Index k = 0; k < floor_indices.size(); ++k) {
    if (floor_indices[k] < 0 || floor_indices[k] >= n) {
      ThrowInvalidArgument("floor_indices", DescribeEntry(k, 0, true) + " = " +
                                                std::to_string(floor_indices[k]) +
                                                " is out of range [0, " + std::to_string(n) + ")");
    }
  }
}

// Runs fn(begin, end) over fixed blocks of queries on up to num_threads threads. Every query's
// result depends on the query only, so the output does not depend on the thread count.
template <typename Fn>
void ForBlocks(Eigen::Index queries, int num_threads, const Fn& fn) {
  constexpr Eigen::Index kBlock = 2048;
  const Eigen::Index blocks = (queries + kBlock - 1) / kBlock;
  const int threads = ResolveThreadCount(num_threads);
  if (threads <= 1 || blocks <= 1) {
    fn(Eigen::Index{0}, queries);
    return;
  }
  ParallelForRuns(static_cast<int>(blocks), threads, 0, [&](int block, RandomStream&) {
    const Eigen::Index begin = block * kBlock;
    fn(begin, std::min(queries, begin + kBlock));
  });
}

}  // namespace

FloorPlan::FloorPlan(std::vector<FloorGeometry> floors, const FloorPlanOptions& options)
    : impl_(std::make_unique<Impl>()) {
  ValidateOptions(options);
  impl_->options = options;
  CheckArgument(!floors.empty(), "floors", "a floor plan needs at least one floor");
  for (size_t f = 0; f < floors.size(); ++f) {
    for (size_t g = 0; g < f; ++g) {
      if (floors[g].floor == floors[f].floor) {
        ThrowInvalidArgument("floors[" + std::to_string(f) + "].floor",
                             "floor number " + std::to_string(floors[f].floor) +
                                 " is repeated (also floors[" + std::to_string(g) + "])");
      }
    }
  }
  for (size_t f = 0; f < floors.size(); ++f) {
    impl_->floors.push_back(BuildFloor(floors[f], static_cast<int>(f), options));
    impl_->floors.back().BuildSubcellMasks();  // the wall test's fast paths (floor_plan_index.h)
    impl_->floors.back().BuildFreeQuarterBlocks();
    impl_->floor_numbers.push_back(floors[f].floor);
  }
}

FloorPlan::~FloorPlan() = default;
FloorPlan::FloorPlan(FloorPlan&&) noexcept = default;
FloorPlan& FloorPlan::operator=(FloorPlan&&) noexcept = default;

int FloorPlan::num_floors() const { return static_cast<int>(impl_->floors.size()); }

const std::vector<int>& FloorPlan::floors() const { return impl_->floor_numbers; }

int FloorPlan::FloorIndex(int floor) const {
  for (size_t f = 0; f < impl_->floor_numbers.size(); ++f) {
    if (impl_->floor_numbers[f] == floor) return static_cast<int>(f);
  }
  ThrowInvalidArgument("floor", "the floor plan has no floor number " + std::to_string(floor));
}

const FloorGeometry& FloorPlan::geometry(int floor_index) const {
  CheckFloorIndex(impl_->floors, floor_index, "floor_index");
  return impl_->floors[static_cast<size_t>(floor_index)].geometry;
}

int FloorPlan::num_edges(int floor_index) const {
  CheckFloorIndex(impl_->floors, floor_index, "floor_index");
  return static_cast<int>(impl_->floors[static_cast<size_t>(floor_index)].edges.size());
}

RowMatrixXd FloorPlan::Edges(int floor_index) const {
  CheckFloorIndex(impl_->floors, floor_index, "floor_index");
  const FloorData& d = impl_->floors[static_cast<size_t>(floor_index)];
  RowMatrixXd out(static_cast<Eigen::Index>(d.edges.size()), 4);
  for (size_t e = 0; e < d.edges.size(); ++e) {
    const Segment& g = d.edges[e];
    out.row(static_cast<Eigen::Index>(e)) << g.x0, g.y0, g.x1, g.y1;
  }
  return out;
}

Eigen::Vector4d FloorPlan::Bounds(int floor_index) const {
  CheckFloorIndex(impl_->floors, floor_index, "floor_index");
  return impl_->floors[static_cast<size_t>(floor_index)].bounds;
}

double FloorPlan::WalkableArea(int floor_index) const {
  CheckFloorIndex(impl_->floors, floor_index, "floor_index");
  return impl_->floors[static_cast<size_t>(floor_index)].walkable_area;
}

const FloorBuildStatistics& FloorPlan::BuildStatistics(int floor_index) const {
  CheckFloorIndex(impl_->floors, floor_index, "floor_index");
  return impl_->floors[static_cast<size_t>(floor_index)].statistics;
}

double FloorPlan::CellSize(int floor_index) const {
  CheckFloorIndex(impl_->floors, floor_index, "floor_index");
  return impl_->floors[static_cast<size_t>(floor_index)].h;
}

bool FloorPlan::IsWalkable(double x_m, double y_m, int floor_index) const {
  assert(floor_index >= 0 && floor_index < num_floors());
  return impl_->floors[static_cast<size_t>(floor_index)].IsWalkable(x_m, y_m);
}

bool FloorPlan::CrossesWall(double x0_m, double y0_m, double x1_m, double y1_m,
                            int floor_index) const {
  assert(floor_index >= 0 && floor_index < num_floors());
  return impl_->floors[static_cast<size_t>(floor_index)].CrossesWall(x0_m, y0_m, x1_m, y1_m);
}

void FloorPlan::CrossesWallSpan(int count, const double* x0_m, const double* y0_m, const double* x1_m,
                                const double* y1_m, const int* floor_indices, bool* out) const {
  const FloorData* floors = impl_->floors.data();
  constexpr int kAhead = 8;  // queries between a mask's prefetch and its use
  for (int k = 0; k < std::min(count, kAhead); ++k) {
    floors[floor_indices[k]].PrefetchMask(x0_m[k], y0_m[k]);
    floors[floor_indices[k]].PrefetchMask(x1_m[k], y1_m[k]);
  }
  for (int k = 0; k < count; ++k) {
    assert(floor_indices[k] >= 0 && floor_indices[k] < num_floors());
    if (k + kAhead < count) {
      const int a = k + kAhead;
      floors[floor_indices[a]].PrefetchMask(x0_m[a], y0_m[a]);
      floors[floor_indices[a]].PrefetchMask(x1_m[a], y1_m[a]);
    }
    out[k] = floors[floor_indices[k]].CrossesWall(x0_m[k], y0_m[k], x1_m[k], y1_m[k]);
  }
}

double FloorPlan::DistanceToWall(double x_m, double y_m, int floor_index) const {
  assert(floor_index >= 0 && floor_index < num_floors());
  return impl_->floors[static_cast<size_t>(floor_index)].DistanceToWall(x_m, y_m);
}

VectorXb FloorPlan::IsWalkableBatch(const Eigen::Ref<const RowMatrixXd>& points_m,
                                    const Eigen::Ref<const Eigen::VectorXi>& floor_indices,
                                    int num_threads) const {
  CheckShape(points_m, -1, 2, "points_m");
  CheckFinite(points_m, "points_m");
  CheckBatch(impl_->floors, points_m.rows(), floor_indices);
  VectorXb out(points_m.rows());
  const FloorIndices floor_of{floor_indices};
  ForBlocks(points_m.rows(), num_threads, [&](Eigen::Index begin, Eigen::Index end) {
    for (Eigen::Index q = begin; q < end; ++q) {
      out[q] = impl_->floors[static_cast<size_t>(floor_of(q))].IsWalkable(points_m(q, 0),
                                                                           points_m(q, 1));
    }
  });
  return out;
}

VectorXb FloorPlan::CrossesWallBatch(const Eigen::Ref<const RowMatrixXd>& segments_m,
                                     const Eigen::Ref<const Eigen::VectorXi>& floor_indices,
                                     int num_threads) const {
  CheckShape(segments_m, -1, 4, "segments_m");
  CheckFinite(segments_m, "segments_m");
  CheckBatch(impl_->floors, segments_m.rows(), floor_indices);
  VectorXb out(segments_m.rows());
  const FloorIndices floor_of{floor_indices};
  ForBlocks(segments_m.rows(), num_threads, [&](Eigen::Index begin, Eigen::Index end) {
    for (Eigen::Index q = begin; q < end; ++q) {
      out[q] = impl_->floors[static_cast<size_t>(floor_of(q))].CrossesWall(
          segments_m(q, 0), segments_m(q, 1), segments_m(q, 2), segments_m(q, 3));
    }
  });
  return out;
}

Eigen::VectorXd FloorPlan::DistanceToWallBatch(const Eigen::Ref<const RowMatrixXd>& points_m,
                                               const Eigen::Ref<const Eigen::VectorXi>& floor_indices,
                                               int num_threads) const {
  CheckShape(points_m, -1, 2, "points_m");
  CheckFinite(points_m, "points_m");
  CheckBatch(impl_->floors, points_m.rows(), floor_indices);
  Eigen::VectorXd out(points_m.rows());
  const FloorIndices floor_of{floor_indices};
  ForBlocks(points_m.rows(), num_threads, [&](Eigen::Index begin, Eigen::Index end) {
    for (Eigen::Index q = begin; q < end; ++q) {
      out[q] = impl_->floors[static_cast<size_t>(floor_of(q))].DistanceToWall(points_m(q, 0),
                                                                               points_m(q, 1));
    }
  });
  return out;
}

RowMatrixXd FloorPlan::SampleWalkable(int n, int floor_index, RandomStream& rng) const {
  CheckArgument(n >= 0, "n", "must be >= 0, got " + std::to_string(n));
  RequireSizeLimit(static_cast<double>(n), 2.0 * sizeof(double), "n", "points");
  CheckFloorIndex(impl_->floors, floor_index, "floor_index");
  const FloorData& d = impl_->floors[static_cast<size_t>(floor_index)];
  const double box_area = (d.bounds[2] - d.bounds[0]) * (d.bounds[3] - d.bounds[1]);
  const double fraction = d.walkable_area / box_area;
  if (!(fraction >= 1e-6)) {
    throw std::runtime_error("indoorloc: FloorPlan::SampleWalkable: the walkable area of floor " +
                             std::to_string(d.floor) + " is only " + FormatNumber(fraction) +
                             " of its bounding box; rejection sampling would not finish");
  }
  RowMatrixXd out(n, 2);
  // Far more attempts than needed (expected n / fraction); the limit only guards against an
  // area estimate that is far too large.
  const double max_attempts = 100.0 * (static_cast<double>(n) + 10.0) / fraction;
  double attempts = 0.0;
  for (int k = 0; k < n;) {
    const double x = rng.Uniform(d.bounds[0], d.bounds[2]);
    const double y = rng.Uniform(d.bounds[1], d.bounds[3]);
    if (d.IsWalkable(x, y)) {
      out(k, 0) = x;
      out(k, 1) = y;
      ++k;
    }
    // Up to 4 GB of points is allowed work: poll Ctrl-C every 2^20 draws.
    if ((static_cast<std::uint64_t>(attempts) & 0xFFFFF) == 0xFFFFF) CheckInterrupt();
    if (++attempts > max_attempts) {
      throw std::runtime_error("indoorloc: FloorPlan::SampleWalkable: too many rejected draws on "
                               "floor " + std::to_string(d.floor));
    }
  }
  return out;
}

std::string FloorPlan::Report() const {
  std::ostringstream out;
  out.setf(std::ios::fixed);
  const Impl& s = *impl_;
  size_t edges = 0, cells = 0, entries = 0;
  double area = 0.0;
  for (const FloorData& d : s.floors) {
    edges += d.edges.size();
    cells += d.cells.size();
    entries += d.entries.size();
    area += d.walkable_area;
  }
  out << "FloorPlan: " << s.floors.size() << (s.floors.size() == 1 ? " floor" : " floors")
      << " (";
  for (size_t f = 0; f < s.floors.size(); ++f) out << (f ? ", " : "") << s.floors[f].floor;
  out << "), " << edges << " edges, " << cells << " cells (";
  out.precision(2);
  for (size_t f = 0; f < s.floors.size(); ++f) out << (f ? "/" : "") << s.floors[f].h;
  out << " m), " << static_cast<double>(entries) / static_cast<double>(std::max<size_t>(cells, 1))
      << " edges/cell, walkable area ";
  out.precision(1);
  out << area << " m^2";
  return out.str();
}

}  // namespace indoorloc::fusion
