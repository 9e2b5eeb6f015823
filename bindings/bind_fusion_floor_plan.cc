// Python bindings of the fusion subsystem's floor plan: FloorGeometry, FloorPlanOptions and
// FloorPlan with batched (numpy) queries.
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include "indoorloc/core/options.h"
#include "indoorloc/core/random.h"
#include "indoorloc/core/validate.h"
#include "indoorloc/fusion/floor_plan.h"
#include "numpy_args.h"
#include "options_binding.h"

namespace indoorloc::bindings {

using fusion::FloorGeometry;
using fusion::FloorPlan;
using fusion::FloorPlanOptions;

namespace {

// A list of rings (each array-like (M, 2) [m]) -> matrices, naming "<name>[k]" on errors.
std::vector<RowMatrixXd> ToRings(const py::handle& obj, const std::string& name) {
  std::vector<RowMatrixXd> rings;
  if (obj.is_none()) return rings;
  if (!py::isinstance<py::sequence>(obj) || py::isinstance<py::str>(obj)) {
    ThrowInvalidArgument(name, "expected a list of (M, 2) arrays");
  }
  // A single (M, 2) array passed instead of a list of them is a common slip: say so.
  if (py::isinstance<py::array>(obj) && py::cast<py::array>(obj).ndim() == 2) {
    ThrowInvalidArgument(name, "expected a list of (M, 2) arrays, got one 2-D array "
                               "(wrap it in a list)");
  }
  const py::sequence seq = py::reinterpret_borrow<py::sequence>(obj);
  for (size_t k = 0; k < seq.size(); ++k) {
    const std::string item = name + "[" + std::to_string(k) + "]";
    MatrixArg m = ToMatrix(seq[k], item.c_str(), -1, 2);
    rings.emplace_back(m.map);
  }
  return rings;
}

Eigen::VectorXi ToFloorIndices(const py::handle& obj, const char* name) {
  if (py::isinstance<py::int_>(obj) && !py::isinstance<py::bool_>(obj)) {
    // ToInt names the argument (pybind11's cast said "Unable to cast ... to C++ type '?'").
    return Eigen::VectorXi::Constant(1, ToInt(obj, name, std::numeric_limits<int>::min(),
                                              std::numeric_limits<int>::max()));
  }
  return ToIntVector(obj, name);
}

// Query coordinates [m] within +-kMaxScale: beyond, squared distances overflow to inf
// (distance_to_wall of a point at 1e300 returned inf).
MatrixArg ToQueries(const py::object& obj, const char* name, Eigen::Index cols) {
  MatrixArg m = ToMatrix(obj, name, -1, cols);
  RequireAllInRange(m.map, -kMaxScale, kMaxScale, name);
  return m;
}

// One batch query of the plan: the (Q, cols) queries and their floor indices checked with the
// GIL held, then `query(queries, floor_indices, num_threads)` run without it.
template <typename Query>
auto BatchQuery(const py::object& queries, const char* name, Eigen::Index cols, const py::object& floor_indices,
                int num_threads, const Query& query) {
  MatrixArg q = ToQueries(queries, name, cols);
  const Eigen::VectorXi f = ToFloorIndices(floor_indices, "floor_indices");
  py::gil_scoped_release release;
  return query(q.map, f, num_threads);
}

py::list RingsToList(const std::vector<RowMatrixXd>& rings) {
  py::list out;
  for (const RowMatrixXd& r : rings) out.append(py::cast(r));
  return out;
}

py::array_t<bool> ToNumpyBool(const fusion::VectorXb& v) {
  py::array_t<bool> out(v.size());
  bool* data = out.mutable_data();
  for (Eigen::Index i = 0; i < v.size(); ++i) data[i] = v[i];
  return out;
}

std::string GeometryRepr(const FloorGeometry& g) {
  std::ostringstream out;
  out << "<FloorGeometry floor " << g.floor << ": " << g.outlines.size() << " outline(s), "
      << g.obstacles.size() << " obstacle(s), " << g.walls.rows() << " wall(s)>";
  return out.str();
}

const char* kBatchNote = R"doc(
floor_indices : int or (Q,) int array, default 0
    Index into ``floors`` (not the floor number; see ``floor_index``): one per query, or a
    single one for all queries.
num_threads : int, default 1
    Threads to use (<= 0: all hardware threads). Results do not depend on it.)doc";

}  // namespace

static void BindFloorPlanQueries(py::class_<FloorPlan>& floor_plan);

/// One floor's outlines, obstacles and walls as given.
static void BindFloorGeometry(py::module_& m) {
  py::class_<FloorGeometry>(m, "FloorGeometry", R"doc(
The geometry of one floor, in metres in the floor frame.

Parameters
----------
floor : int, default 0
    Floor number (the numbering of the signal map's floors).
outlines : list of (M, 2) float arrays [m]
    Closed rings (a repeated closing vertex is accepted) whose union is the floor's area.
obstacles : list of (M, 2) float arrays [m], optional
    Rings removed from the area (shops, rooms, columns, the holes of a polygon).
walls : (W, 4) float array [m], optional
    Thin walls as segments, rows (x0, y0, x1, y1).

Walkable = inside at least one outline and inside no obstacle. Every ring edge and every wall
is a wall for ``FloorPlan.crosses_wall``.)doc")
      .def(py::init([](int floor, const py::object& outlines, const py::object& obstacles,
                       const py::object& walls) {
             FloorGeometry g;
             g.floor = floor;
             g.outlines = ToRings(outlines, "outlines");
             g.obstacles = ToRings(obstacles, "obstacles");
             if (!walls.is_none() && ToDoubleArray(walls, "walls").size() > 0) {
               MatrixArg w = ToMatrix(walls, "walls", -1, -1);
               if (w.map.size() > 0) {
                 CheckArgument(w.map.cols() == 4, "walls",
                               "expected shape (W, 4) rows (x0, y0, x1, y1), got (" +
                                   std::to_string(w.map.rows()) + ", " +
                                   std::to_string(w.map.cols()) + ")");
                 g.walls = w.map;
               }
             }
             return g;
           }),
           py::arg("floor") = 0, py::arg("outlines") = py::list(),
           py::arg("obstacles") = py::list(), py::arg("walls") = py::none())
      .def_readwrite("floor", &FloorGeometry::floor, "Floor number.")
      .def_property(
          "outlines", [](const FloorGeometry& g) { return RingsToList(g.outlines); },
          [](FloorGeometry& g, const py::object& rings) { g.outlines = ToRings(rings, "outlines"); },
          "Outline rings: list of (M, 2) arrays [m] (copies).")
      .def_property(
          "obstacles", [](const FloorGeometry& g) { return RingsToList(g.obstacles); },
          [](FloorGeometry& g, const py::object& rings) { g.obstacles = ToRings(rings, "obstacles"); },
          "Obstacle rings: list of (M, 2) arrays [m] (copies).")
      .def_property(
          "walls", [](const FloorGeometry& g) { return g.walls; },
          [](FloorGeometry& g, const py::object& walls) {
            MatrixArg w = ToMatrix(walls, "walls", -1, 4);
            g.walls = w.map;
          },
          "Wall segments (W, 4) rows (x0, y0, x1, y1) [m] (a copy).")
      .def("__repr__", &GeometryRepr);
}

/// Options of the floor plan's index.
static void BindFloorPlanOptions(py::module_& m) {
  py::class_<FloorPlanOptions> floor_plan_options(m, "FloorPlanOptions", R"doc(
Options of the floor plan's index. Set fields by keyword: ``FloorPlanOptions(cell_size_m=0.5)``;
defaults from ``FloorPlanOptions().to_dict()``; ``replace``, equality and pickling as for every
Options class.)doc");
  floor_plan_options
      .def_readwrite("cell_size_m", &FloorPlanOptions::cell_size_m,
                     "Side of the grid's square cells [m]; <= 0 chooses it per floor so that a cell holds "
                     "about target_edges_per_cell edges on average, bounded to [0.25, 1] m and to max_cells.")
      .def_readwrite("target_edges_per_cell", &FloorPlanOptions::target_edges_per_cell,
                     "Mean edges per cell aimed at by the automatic cell size.")
      .def_readwrite("max_cells", &FloorPlanOptions::max_cells, "Limit of a floor's grid cells.")
      .def_readwrite("check_self_intersection", &FloorPlanOptions::check_self_intersection,
                     "Reject rings whose edges cross each other (one indexed pass at construction).");
  BindOptionsProtocol(floor_plan_options, "FloorPlanOptions",
                      {"cell_size_m", "target_edges_per_cell", "max_cells", "check_self_intersection"});
}

/// FloorPlan: construction, floors and their geometry, then its queries.
static void BindFloorPlan(py::module_& m) {
  py::class_<FloorPlan> floor_plan(m, "FloorPlan", R"doc(
A building's walkable space, floor by floor, with indexed geometric queries: is a point walkable,
does a step cross a wall, how far is the nearest wall. Immutable; queries release the GIL and
may run on several threads.

Parameters
----------
floors : FloorGeometry or list of FloorGeometry
    One entry per floor; floor numbers must be distinct. ``floor_index`` arguments index this
    list.
options : FloorPlanOptions, optional

Raises
------
ValueError
    Naming the bad argument (e.g. ``floors[1].obstacles[3]``): no floors, a repeated floor
    number, a floor without outline, a ring with fewer than 3 distinct vertices or zero area,
    NaN or infinite coordinates, a self-intersecting ring, a zero-length wall, a floor with no
    walkable area.)doc");
  floor_plan
      .def(py::init([](const py::object& floors, const FloorPlanOptions& options) {
             std::vector<FloorGeometry> list;
             if (py::isinstance<FloorGeometry>(floors)) {
               list.push_back(floors.cast<FloorGeometry>());
             } else {
               if (!py::isinstance<py::sequence>(floors)) {
                 ThrowInvalidArgument("floors", "expected a FloorGeometry or a list of them");
               }
               const py::sequence seq = py::reinterpret_borrow<py::sequence>(floors);
               for (size_t k = 0; k < seq.size(); ++k) {
                 if (!py::isinstance<FloorGeometry>(seq[k])) {
                   ThrowInvalidArgument("floors[" + std::to_string(k) + "]",
                                        "expected a FloorGeometry");
                 }
                 list.push_back(seq[k].cast<FloorGeometry>());
               }
             }
             py::gil_scoped_release release;
             return new FloorPlan(std::move(list), options);
           }),
           py::arg("floors"), py::arg("options") = FloorPlanOptions())
      .def_property_readonly("num_floors", &FloorPlan::num_floors)
      .def_property_readonly("floors", &FloorPlan::floors,
                             "Floor numbers in construction order (list of int).")
      .def("floor_index", &FloorPlan::FloorIndex, py::arg("floor"),
           "Index of floor number ``floor`` (ValueError if the plan has no such floor).")
      .def("geometry", &FloorPlan::geometry, py::arg("floor_index") = 0,
           "The FloorGeometry a floor was built from (closing vertices dropped; a copy).")
      .def("num_edges", &FloorPlan::num_edges, py::arg("floor_index") = 0,
           "Number of wall edges (ring edges + wall segments) of a floor.")
      .def("edges", &FloorPlan::Edges, py::arg("floor_index") = 0, R"doc(
All wall edges of a floor, (E, 4) rows (x0, y0, x1, y1) [m]: outline edges, obstacle edges (each
ring counter-clockwise), then the walls.)doc")
      .def("bounds", &FloorPlan::Bounds, py::arg("floor_index") = 0,
           "Bounding box of a floor's outlines (min_x, min_y, max_x, max_y) [m].")
      .def("walkable_area", &FloorPlan::WalkableArea, py::arg("floor_index") = 0,
           "Walkable area of a floor [m^2] (computed at construction by scanlines).")
      .def("build_statistics", [](const FloorPlan& plan, int floor_index) {
             const fusion::FloorBuildStatistics& b = plan.BuildStatistics(floor_index);
             py::dict d;
             d["edges"] = b.edges;
             d["cells"] = b.cells;
             d["edge_cell_entries"] = b.edge_cell_entries;
             d["index_bytes"] = b.index_bytes;
             d["self_intersection_work"] = b.self_intersection_work;
             d["area_scanlines"] = b.area_scanlines;
             d["area_edge_visits"] = b.area_edge_visits;
             d["area_subsampled"] = b.area_subsampled;
             return d;
           }, py::arg("floor_index") = 0, R"doc(
What building a floor's index cost, as a dict: edges, cells, edge_cell_entries (edge-cell
registrations), index_bytes, self_intersection_work (exact predicate evaluations of the
self-intersection sweep: O(E log E)), area_scanlines, area_edge_visits, area_subsampled.)doc")
      .def("cell_size", &FloorPlan::CellSize, py::arg("floor_index") = 0,
           "Side of a floor's index cells [m].");
  BindFloorPlanQueries(floor_plan);
}

void BindFusionFloorPlan(py::module_& m) {
  BindFloorGeometry(m);
  BindFloorPlanOptions(m);
  BindFloorPlan(m);
}

/// The indexed queries of FloorPlan (walkable, wall crossing, distance, sampling).
static void BindFloorPlanQueries(py::class_<FloorPlan>& floor_plan) {
  // pybind11 copies docstrings; these are assembled once here.
  static const std::string is_walkable_doc = std::string(R"doc(
Whether points are walkable (inside an outline and inside no obstacle).

Parameters
----------
points_m : (Q, 2) float array [m])doc") + kBatchNote + R"doc(

Returns
-------
(Q,) bool array)doc";
  static const std::string crosses_wall_doc = std::string(R"doc(
Whether steps p -> q intersect or touch any wall edge (exact predicates). The ends themselves
are not tested for walkability.

Parameters
----------
segments_m : (Q, 4) float array [m]
    Rows (x0, y0, x1, y1).)doc") + kBatchNote + R"doc(

Returns
-------
(Q,) bool array)doc";
  static const std::string distance_doc = std::string(R"doc(
Euclidean distance [m] from points to the nearest wall edge (ring edge or wall segment).

Parameters
----------
points_m : (Q, 2) float array [m])doc") + kBatchNote + R"doc(

Returns
-------
(Q,) float array [m])doc";

  floor_plan
      .def("is_walkable", [](const FloorPlan& plan, const py::object& points_m,
                             const py::object& floor_indices, int num_threads) {
             return ToNumpyBool(BatchQuery(points_m, "points_m", 2, floor_indices, num_threads,
                                           [&plan](const auto& p, const auto& f, int t) {
                                             return plan.IsWalkableBatch(p, f, t);
                                           }));
           },
           py::arg("points_m"), py::arg("floor_indices") = 0, py::arg("num_threads") = 1,
           is_walkable_doc.c_str())
      .def("crosses_wall", [](const FloorPlan& plan, const py::object& segments_m,
                              const py::object& floor_indices, int num_threads) {
             return ToNumpyBool(BatchQuery(segments_m, "segments_m", 4, floor_indices, num_threads,
                                           [&plan](const auto& s, const auto& f, int t) {
                                             return plan.CrossesWallBatch(s, f, t);
                                           }));
           },
           py::arg("segments_m"), py::arg("floor_indices") = 0, py::arg("num_threads") = 1,
           crosses_wall_doc.c_str())
      .def("distance_to_wall", [](const FloorPlan& plan, const py::object& points_m,
                                  const py::object& floor_indices, int num_threads) {
             return ToNumpy(BatchQuery(points_m, "points_m", 2, floor_indices, num_threads,
                                       [&plan](const auto& p, const auto& f, int t) {
                                         return plan.DistanceToWallBatch(p, f, t);
                                       }));
           },
           py::arg("points_m"), py::arg("floor_indices") = 0, py::arg("num_threads") = 1,
           distance_doc.c_str())
      .def("sample_walkable", [](const FloorPlan& plan, int n, int floor_index,
                                 const py::object& rng) {
             CheckArgument(n >= 0, "n", "must be >= 0, got " + std::to_string(n));
             RowMatrixXd out;
             if (py::isinstance<RandomStream>(rng)) {
               RandomStream& stream = rng.cast<RandomStream&>();
               py::gil_scoped_release release;
               out = plan.SampleWalkable(n, floor_index, stream);
             } else if (py::isinstance<py::int_>(rng) && !py::isinstance<py::bool_>(rng)) {
               const unsigned long long seed = PyLong_AsUnsignedLongLong(rng.ptr());
               if (seed == static_cast<unsigned long long>(-1) && PyErr_Occurred()) {
                 PyErr_Clear();
                 ThrowInvalidArgument("rng", "a seed must be an int in [0, 2**64), got " + std::string(py::str(rng)));
               }
               RandomStream stream(seed);
               py::gil_scoped_release release;
               out = plan.SampleWalkable(n, floor_index, stream);
             } else {
               ThrowInvalidArgument("rng", "expected an indoorloc.core.RandomStream or an int seed");
             }
             return out;
           },
           py::arg("n"), py::arg("floor_index") = 0, py::arg("rng") = 0, R"doc(
Draw points uniformly over a floor's walkable area (rejection in the outlines' bounding box).

Parameters
----------
n : int
    Number of points.
floor_index : int, default 0
rng : indoorloc.core.RandomStream or int, default 0
    A stream (advanced in place) or a seed for a fresh stream.

Returns
-------
(n, 2) float array [m]

Raises
------
RuntimeError
    If the walkable area is below 1e-6 of the bounding box.)doc")
      .def("report", &FloorPlan::Report, "One line: floors, edges, cells, walkable area.")
      .def("__repr__", [](const FloorPlan& plan) { return "<" + plan.Report() + ">"; });
}

}  // namespace indoorloc::bindings
