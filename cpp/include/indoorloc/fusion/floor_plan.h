// Walkable space of a building, floor by floor, with the geometric queries a particle filter
// needs in its inner loop: is a point walkable, does a step p -> q cross a wall, how far is the
// nearest wall.
//
// A floor is given as polygons in metres (floor frame):
//  - outlines: closed rings whose union is the floor's area (a GeoJSON Polygon's exterior ring;
//    its interior rings, if any, are passed as obstacles);
//  - obstacles: closed rings removed from the area (shops, rooms, columns, holes);
//  - walls: thin walls as segments inside the area (x0, y0, x1, y1).
// Walkable(p) = p lies inside at least one outline and inside no obstacle (rings may overlap:
// union semantics, not even-odd over all rings). Every ring edge and every wall segment is a
// wall: a step crosses a wall when its segment p -> q intersects (or touches) any of them.
//
// Spatial index: a uniform grid of square cells over the floor's bounding box; each cell lists
// the edges that overlap it. A step visits the cells its segment passes through (Amanatides &
// Woo traversal), so a query costs O(edges in a few cells), not O(all edges). For IsWalkable
// each cell stores how many outlines and how many obstacles contain its anchor point (a point
// near the cell centre on no edge; the counts are computed once by exact crossing numbers along
// a chain of anchors); a query then adds the signed crossings of the ring edges that the
// segment anchor -> p crosses inside the cell. All predicates are exact (a floating-point filter
// with an exact fallback). Degenerate positions (a query exactly on an edge, a segment through
// a vertex) are resolved consistently and conservatively: touching a wall counts as crossing
// it, a point on an obstacle's boundary is not walkable.
//
// Paper link: the floor plan constraint of paper 002 §VI (PDR matched with the building's map)
// and paper 000 §IV (map matching); see docs/fusion.md.
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>
#include <Eigen/Core>

#include "indoorloc/core/random.h"

namespace indoorloc::fusion {

using RowMatrixXd = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using VectorXb = Eigen::Matrix<bool, Eigen::Dynamic, 1>;

/// The geometry of one floor, in metres in the floor frame.
struct FloorGeometry {
  /// Floor number (the same numbering as the signal map's floors).
  int floor = 0;
  /// Rings (M x 2, M >= 3; a repeated closing vertex is accepted and dropped) whose union is the
  /// floor's area. At least one per floor.
  std::vector<RowMatrixXd> outlines;
  /// Rings removed from the area (shops, rooms, columns, a polygon's holes).
  std::vector<RowMatrixXd> obstacles;
  /// Thin walls inside the area: W x 4 rows (x0, y0, x1, y1) [m]; may be empty (0 x 4).
  RowMatrixXd walls = RowMatrixXd::Zero(0, 4);
};

struct FloorPlanOptions {
  /// Side of the index grid's cells [m]; <= 0 chooses it per floor so that a cell holds about
  /// `target_edges_per_cell` edges on average over the floor's box, bounded to [0.25, 1] m (a
  /// pedestrian step then visits one to three cells), to at most `max_cells` cells, and grown
  /// further if the index (cells and edge-cell registrations) would take more than
  /// max(64 MB, 1 kB per edge). A given size whose index would take more than 4 GB
  /// (kMaxBytes) is refused, naming the bytes, before anything is allocated.
  double cell_size_m = 0.0;
  double target_edges_per_cell = 2.0;
  int max_cells = 4'000'000;
  /// Reject rings whose edges cross each other (a self-intersecting ring has no well-defined
  /// inside). Costs a sweep line over each ring's edges at construction, O(E log E).
  bool check_self_intersection = true;
  bool IsValid(std::string* error) const;
};

/// What building one floor cost: sizes and counts of work (diagnostics, and the evidence that
/// construction scales as O(E log E) plus the index size).
struct FloorBuildStatistics {
  std::int64_t edges = 0;  ///< ring edges + wall segments
  std::int64_t cells = 0;  ///< cells of the index grid
  /// Edge-cell registrations of the index (an edge is listed in every cell it overlaps).
  std::int64_t edge_cell_entries = 0;
  /// Memory of the index [bytes]: per cell and per registration, as checked before allocating.
  double index_bytes = 0.0;
  /// Exact predicate evaluations of the self-intersection sweep (ordered-set comparisons and
  /// pair tests): O(E log E).
  std::int64_t self_intersection_work = 0;
  /// Scanlines and edge visits of the walkable-area computation.
  std::int64_t area_scanlines = 0;
  std::int64_t area_edge_visits = 0;
  /// True when the exact-per-slab area rule would have visited more than 2e7 edges and the
  /// area came from fewer, evenly spaced scanlines instead (see FloorPlan::WalkableArea).
  bool area_subsampled = false;
};

/// A building's walkable space with indexed geometric queries. Immutable after construction and
/// safe to query from several threads at once.
class FloorPlan {
 public:
  /// Builds the index of every floor. Throws std::invalid_argument naming the argument
  /// ("floors[1].obstacles[3]", "floors[0].walls") for: no floors, a repeated floor number, a
  /// floor without outline, a ring with fewer than 3 distinct vertices or zero area, NaN or
  /// infinite coordinates, a self-intersecting ring, or a floor with no walkable area.
  explicit FloorPlan(std::vector<FloorGeometry> floors,
                     const FloorPlanOptions& options = FloorPlanOptions());
  ~FloorPlan();
  FloorPlan(FloorPlan&&) noexcept;
  FloorPlan& operator=(FloorPlan&&) noexcept;
  FloorPlan(const FloorPlan&) = delete;
  FloorPlan& operator=(const FloorPlan&) = delete;

  int num_floors() const;
  /// Floor numbers in the order given at construction; `floor_index` arguments index this list.
  const std::vector<int>& floors() const;
  /// Index of floor number `floor`; throws std::invalid_argument if the plan has no such floor.
  int FloorIndex(int floor) const;
  /// The geometry a floor was built from (rings in their given orientation, without repeated
  /// closing or consecutive vertices).
  const FloorGeometry& geometry(int floor_index) const;
  /// Number of wall edges (ring edges + wall segments) on a floor.
  int num_edges(int floor_index) const;
  /// All wall edges of a floor as E x 4 rows (x0, y0, x1, y1) [m] (for plots and peers):
  /// outline edges, obstacle edges (each ring counter-clockwise), then the walls.
  RowMatrixXd Edges(int floor_index) const;
  /// Bounding box of a floor's outlines: (min_x, min_y, max_x, max_y) [m].
  Eigen::Vector4d Bounds(int floor_index) const;
  /// Walkable area [m^2], computed once at construction by horizontal scanlines: exact along
  /// each line, one line per slab between consecutive vertex ordinates (slabs split to at most
  /// 1/1000 of the height), hence exact up to rounding for rings that do not overlap, and within
  /// a second-order error where rings overlap. Where that rule would visit more than 2e7 edges
  /// (tens of thousands of vertices on lines that each cross tens of thousands of edges, such as
  /// a star of 1e5 spikes), a floor of one outline (checked simple) and no obstacle takes the
  /// exact shoelace area of its ring; any other floor the midpoint rule on evenly spaced slabs,
  /// as many as that budget allows (at least 100), which is approximate: a slab line that runs
  /// along a nearly horizontal edge can over-count a thin strip (BuildStatistics().area_subsampled).
  double WalkableArea(int floor_index) const;
  /// Side of the index grid's cells on a floor [m].
  double CellSize(int floor_index) const;
  /// What building a floor's index cost.
  const FloorBuildStatistics& BuildStatistics(int floor_index) const;

  // Single queries: the inner-loop form. floor_index must be valid (checked by assert only);
  // the batch forms below check everything.

  /// True if (x, y) [m] is walkable on the floor.
  bool IsWalkable(double x_m, double y_m, int floor_index) const;
  /// True if the segment (x0, y0) -> (x1, y1) [m] intersects or touches any wall edge of the
  /// floor. Does not test whether the ends are walkable.
  bool CrossesWall(double x0_m, double y0_m, double x1_m, double y1_m, int floor_index) const;
  /// CrossesWall of `count` segments (x0[k], y0[k]) -> (x1[k], y1[k]) [m] on floor index
  /// floor_indices[k]: out[k] = CrossesWall(...). One call per block of particles (the
  /// tracker's wall test); indices must be valid and coordinates finite (not checked).
  void CrossesWallSpan(int count, const double* x0_m, const double* y0_m, const double* x1_m, const double* y1_m,
                       const int* floor_indices, bool* out) const;
  /// Euclidean distance [m] from (x, y) to the nearest wall edge of the floor.
  double DistanceToWall(double x_m, double y_m, int floor_index) const;

  // Batch queries. points_m (Q x 2) [m]; segments_m (Q x 4) rows (x0, y0, x1, y1) [m];
  // floor_indices (Q), or a single entry applied to all queries. Throw std::invalid_argument on
  // wrong shapes, NaN/inf coordinates, or a floor index out of range. Results do not depend on
  // num_threads (<= 0: all hardware threads).

  VectorXb IsWalkableBatch(const Eigen::Ref<const RowMatrixXd>& points_m,
                           const Eigen::Ref<const Eigen::VectorXi>& floor_indices,
                           int num_threads = 1) const;
  VectorXb CrossesWallBatch(const Eigen::Ref<const RowMatrixXd>& segments_m,
                            const Eigen::Ref<const Eigen::VectorXi>& floor_indices,
                            int num_threads = 1) const;
  Eigen::VectorXd DistanceToWallBatch(const Eigen::Ref<const RowMatrixXd>& points_m,
                                      const Eigen::Ref<const Eigen::VectorXi>& floor_indices,
                                      int num_threads = 1) const;

  /// Draws n points uniformly over the walkable area of a floor (rejection sampling in the
  /// bounding box). Returns n x 2 [m]. Throws std::runtime_error if the walkable fraction of the
  /// box is so small that sampling would not finish (below 1e-6).
  RowMatrixXd SampleWalkable(int n, int floor_index, RandomStream& rng) const;

  /// One line: floors, edges, cells, walkable area.
  std::string Report() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace indoorloc::fusion
