// Python bindings of the fusion floor plan: walkable space with batch geometric queries.
#include <string>
#include <vector>

#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include "indoorloc/core/options.h"
#include "indoorloc/core/random.h"
#include "indoorloc/fusion/floor_plan.h"
#include "numpy_args.h"

namespace indoorloc::bindings {

using namespace indoorloc::fusion;  // NOLINT: binding file

namespace {

RowMatrixXd RingArg(const py::handle& obj, const std::string& name) {
  MatrixArg m = ToMatrix(obj, name.c_str(), -1, 2);
  return m.map;
}

Eigen::VectorXi FloorIndicesArg(const py::object& obj, Eigen::Index count) {
  // A scalar applies to every query.
  const py::object arr = py::module_::import("numpy").attr("atleast_1d")(obj);
  VectorArg v = ToVector(arr, "floor_indices");
  CheckArgument(v.map.size() == 1 || v.map.size() == count, "floor_indices",
                "must have one entry or one per query (" + std::to_string(count) + "), got " + std::to_string(v.map.size()));
  Eigen::VectorXi out(v.map.size());
  for (Eigen::Index i = 0; i < v.map.size(); ++i) {
    CheckArgument(v.map[i] == std::floor(v.map[i]), "floor_indices", DescribeEntry(i, 0, true) + " is not an integer");
    out[i] = static_cast<int>(v.map[i]);
  }
  return out;
}

}  // namespace

void BindFusionFloorPlan(py::module_& m) {
  py::class_<FloorGeometry>(m, "FloorGeometry", R"doc(
One floor's geometry in metres: outlines (list of (M, 2) rings whose union is the floor area),
obstacles (list of rings removed from it: shops, rooms, columns, holes) and walls ((W, 4) thin
wall segments x0, y0, x1, y1).)doc")
      .def(py::init([](int floor, const py::list& outlines, const py::list& obstacles, const py::object& walls) {
             FloorGeometry g;
             g.floor = floor;
             for (size_t i = 0; i < outlines.size(); ++i) g.outlines.push_back(RingArg(outlines[i], "outlines[" + std::to_string(i) + "]"));
             for (size_t i = 0; i < obstacles.size(); ++i) g.obstacles.push_back(RingArg(obstacles[i], "obstacles[" + std::to_string(i) + "]"));
             if (!walls.is_none()) {
               MatrixArg w = ToMatrix(walls, "walls", -1, 4);
               g.walls = w.map;
             }
             return g;
           }),
           py::arg("floor") = 0, py::arg("outlines") = py::list(), py::arg("obstacles") = py::list(),
           py::arg("walls") = py::none())
      .def_readonly("floor", &FloorGeometry::floor)
      .def_readonly("outlines", &FloorGeometry::outlines)
      .def_readonly("obstacles", &FloorGeometry::obstacles)
      .def_readonly("walls", &FloorGeometry::walls)
      .def("__repr__", [](const FloorGeometry& g) {
        return "<FloorGeometry floor " + std::to_string(g.floor) + ": " + std::to_string(g.outlines.size()) + " outline(s), " +
               std::to_string(g.obstacles.size()) + " obstacle(s), " + std::to_string(g.walls.rows()) + " wall(s)>";
      });

  py::class_<FloorPlanOptions>(m, "FloorPlanOptions", "Index grid of the floor plan.")
      .def(py::init([](double cell_size_m, double target_edges_per_cell, int max_cells, bool check_self_intersection) {
             FloorPlanOptions o;
             o.cell_size_m = cell_size_m;
             o.target_edges_per_cell = target_edges_per_cell;
             o.max_cells = max_cells;
             o.check_self_intersection = check_self_intersection;
             ValidateOptions(o);
             return o;
           }),
           py::arg("cell_size_m") = 0.0, py::arg("target_edges_per_cell") = 2.0, py::arg("max_cells") = 4'000'000,
           py::arg("check_self_intersection") = true)
      .def_readwrite("cell_size_m", &FloorPlanOptions::cell_size_m)
      .def_readwrite("target_edges_per_cell", &FloorPlanOptions::target_edges_per_cell)
      .def_readwrite("max_cells", &FloorPlanOptions::max_cells)
      .def_readwrite("check_self_intersection", &FloorPlanOptions::check_self_intersection);

  py::class_<FloorPlan, std::shared_ptr<FloorPlan>>(m, "FloorPlan", R"doc(
A building's walkable space, floor by floor, with indexed queries (walkable point, wall crossing of
a step, distance to the nearest wall). Walkable = inside an outline and inside no obstacle.

Parameters
----------
floors : list of FloorGeometry
options : FloorPlanOptions)doc")
      .def(py::init([](const std::vector<FloorGeometry>& floors, const FloorPlanOptions& options) {
             py::gil_scoped_release release;
             return std::make_shared<FloorPlan>(floors, options);
           }),
           py::arg("floors"), py::arg("options") = FloorPlanOptions())
      .def_property_readonly("num_floors", &FloorPlan::num_floors)
      .def_property_readonly("floors", &FloorPlan::floors, "Floor numbers; floor_index arguments index this list.")
      .def("floor_index", &FloorPlan::FloorIndex, py::arg("floor"))
      .def("geometry", [](const FloorPlan& p, int f) {
             CheckArgument(f >= 0 && f < p.num_floors(), "floor_index", "out of range");
             return p.geometry(f);
           }, py::arg("floor_index"))
      .def("num_edges", [](const FloorPlan& p, int f) {
             CheckArgument(f >= 0 && f < p.num_floors(), "floor_index", "out of range");
             return p.num_edges(f);
           }, py::arg("floor_index") = 0)
      .def("edges", [](const FloorPlan& p, int f) {
             CheckArgument(f >= 0 && f < p.num_floors(), "floor_index", "out of range");
             return p.Edges(f);
           }, py::arg("floor_index") = 0, "Wall edges (E, 4) x0, y0, x1, y1 [m].")
      .def("bounds", [](const FloorPlan& p, int f) {
             CheckArgument(f >= 0 && f < p.num_floors(), "floor_index", "out of range");
             return Eigen::Vector4d(p.Bounds(f));
           }, py::arg("floor_index") = 0, "(min_x, min_y, max_x, max_y) [m].")
      .def("walkable_area", [](const FloorPlan& p, int f) {
             CheckArgument(f >= 0 && f < p.num_floors(), "floor_index", "out of range");
             return p.WalkableArea(f);
           }, py::arg("floor_index") = 0, "Walkable area [m²] (estimated on a fine grid).")
      .def("cell_size", [](const FloorPlan& p, int f) {
             CheckArgument(f >= 0 && f < p.num_floors(), "floor_index", "out of range");
             return p.CellSize(f);
           }, py::arg("floor_index") = 0)
      .def("is_walkable", [](const FloorPlan& p, const py::object& points_m, const py::object& floor_indices, int num_threads) {
             MatrixArg q = ToMatrix(points_m, "points_m", -1, 2);
             const Eigen::VectorXi f = FloorIndicesArg(floor_indices, q.map.rows());
             py::gil_scoped_release release;
             return Eigen::Matrix<bool, Eigen::Dynamic, 1>(p.IsWalkableBatch(q.map, f, num_threads));
           },
           py::arg("points_m"), py::arg("floor_indices") = 0, py::arg("num_threads") = 1,
           "Walkable flags (Q,) of points (Q, 2) [m] on floor indices (Q,) or one for all.")
      .def("crosses_wall", [](const FloorPlan& p, const py::object& segments_m, const py::object& floor_indices, int num_threads) {
             MatrixArg q = ToMatrix(segments_m, "segments_m", -1, 4);
             const Eigen::VectorXi f = FloorIndicesArg(floor_indices, q.map.rows());
             py::gil_scoped_release release;
             return Eigen::Matrix<bool, Eigen::Dynamic, 1>(p.CrossesWallBatch(q.map, f, num_threads));
           },
           py::arg("segments_m"), py::arg("floor_indices") = 0, py::arg("num_threads") = 1,
           "True where the segment (Q, 4) x0, y0, x1, y1 [m] intersects or touches a wall edge.")
      .def("distance_to_wall", [](const FloorPlan& p, const py::object& points_m, const py::object& floor_indices, int num_threads) {
             MatrixArg q = ToMatrix(points_m, "points_m", -1, 2);
             const Eigen::VectorXi f = FloorIndicesArg(floor_indices, q.map.rows());
             py::gil_scoped_release release;
             return Eigen::VectorXd(p.DistanceToWallBatch(q.map, f, num_threads));
           },
           py::arg("points_m"), py::arg("floor_indices") = 0, py::arg("num_threads") = 1,
           "Distance [m] (Q,) from each point (Q, 2) to the nearest wall edge.")
      .def("sample_walkable", [](const FloorPlan& p, int n, int floor_index, RandomStream& rng) {
             CheckArgument(n >= 0, "n", "must be >= 0");
             CheckArgument(floor_index >= 0 && floor_index < p.num_floors(), "floor_index", "out of range");
             py::gil_scoped_release release;
             return p.SampleWalkable(n, floor_index, rng);
           },
           py::arg("n"), py::arg("floor_index"), py::arg("stream"), "n points (n, 2) [m] uniform over the walkable area.")
      .def("report", &FloorPlan::Report)
      .def("__repr__", [](const FloorPlan& p) { return "<" + p.Report() + ">"; });
}

}  // namespace indoorloc::bindings
