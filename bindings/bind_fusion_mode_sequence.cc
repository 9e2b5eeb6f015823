// Python binding of the (cell, mode) forward-backward smoother (fusion/mode_sequence_smoother.h):
// smooth_mode_sequence, numpy in and out, the GIL released around the C++ work, and its typed
// result ModeSequenceResult. The model (stencils, mode transition) is built in Python
// (indoorloc.fusion.wifi_heading_sequence); this only runs it.
#include <cmath>
#include <string>
#include <utility>

#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include "indoorloc/core/validate.h"
#include "indoorloc/fusion/mode_sequence_smoother.h"
#include "numpy_args.h"
#include "result_binding.h"

namespace indoorloc::bindings {

using namespace indoorloc::fusion;  // NOLINT: binding file

namespace {

using IntRowMatrix = Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// A 2-D array of whole numbers that fit in 32 bits, else ValueError naming `name` and the entry.
IntRowMatrix ToIntMatrix(const py::handle& obj, const char* name, Eigen::Index cols = -1) {
  const MatrixArg a = ToMatrix(obj, name, -1, cols);
  IntRowMatrix out(a.map.rows(), a.map.cols());
  for (Eigen::Index r = 0; r < a.map.rows(); ++r) {
    for (Eigen::Index c = 0; c < a.map.cols(); ++c) {
      const double x = a.map(r, c);
      if (x != std::floor(x) || x < -2147483648.0 || x > 2147483647.0) {
        ThrowInvalidArgument(name, DescribeEntry(r, c, false) + " must be a 32-bit integer, got " + FormatValue(x));
      }
      out(r, c) = static_cast<int>(x);
    }
  }
  return out;
}

// Per mode (offsets (K, 2) (dx, dy), weights (K,)).
std::vector<LatticeStencil> ToStencils(const py::object& obj) {
  if (!py::isinstance<py::sequence>(obj) || py::isinstance<py::str>(obj)) {
    ThrowInvalidArgument("stencils", "expected a sequence of (offsets (K, 2), weights (K,)) pairs, one per mode");
  }
  std::vector<LatticeStencil> out;
  const py::sequence seq = obj.cast<py::sequence>();
  for (py::ssize_t i = 0; i < static_cast<py::ssize_t>(seq.size()); ++i) {
    const std::string name = "stencils[" + std::to_string(i) + "]";
    const py::object pair = seq[static_cast<std::size_t>(i)];
    if (!py::isinstance<py::sequence>(pair) || py::len(pair) != 2) {
      ThrowInvalidArgument(name, "expected a pair (offsets (K, 2), weights (K,))");
    }
    LatticeStencil st;
    st.offsets_cells = ToIntMatrix(pair[py::int_(0)], (name + " offsets").c_str(), 2);
    st.weights = ToVector(pair[py::int_(1)], (name + " weights").c_str()).map;
    out.push_back(std::move(st));
  }
  return out;
}

}  // namespace

void BindFusionModeSequence(py::module_& m) {
  using R = ModeSequenceResult;
  ResultBinder<R>(m, "ModeSequenceResult", "The (cell, mode) forward-backward smoother's track (smooth_mode_sequence).")
      .Field("mean_m", [](const R& r) { return RowMatrixXd(r.mean_m); }, "(T, 2) posterior mean per tick [m].")
      .Field("posterior", [](const R& r) { return RowMatrixXd(r.posterior); },
             "(T, N) posterior of the cell per tick (summed over modes) when keep_posterior, else (0, N).")
      .Field("restarts", [](const R& r) { return r.summary.restarts; },
             "Ticks at which every path was walled off and the forward pass restarted from the tick's evidence.")
      .Field("log_evidence", [](const R& r) { return r.summary.log_evidence; },
             "Σ_k log s_k, the forward pass's per-tick normalisers (the emissions as scaled by the caller).")
      .Field("seconds", [](const R& r) { return r.summary.seconds; }, "Wall time of the C++ call [s].")
      .Field("report", [](const R& r) { return r.summary.BriefReport(); }, "One-line summary.")
      .Finish();

  m.def(
      "smooth_mode_sequence",
      [](const py::object& state_index, const py::object& cells_m, const py::object& stencils,
         const py::object& mode_transition, const py::object& wall_factor, const py::object& fix_ticks,
         const py::object& fix_factors, const py::object& num_ticks, bool keep_posterior) {
        ModeSequenceModel model;
        model.state_index = ToIntMatrix(state_index, "state_index");
        model.cells_m = ToMatrix(cells_m, "cells_m", -1, 2).map;
        model.stencils = ToStencils(stencils);
        model.mode_transition = ToMatrix(mode_transition, "mode_transition").map;
        ModeSequenceEvidence ev;
        ev.num_ticks = ToInt(num_ticks, "num_ticks", 1, 100000000);
        ev.wall_factor = ToVector(wall_factor, "wall_factor").map;
        ev.fix_ticks = ToIntVector(fix_ticks, "fix_ticks");
        ev.fix_factors = ToMatrix(fix_factors, "fix_factors").map;
        return WithoutGil([&] { return SmoothModeSequence(model, ev, keep_posterior); });
      },
      py::arg("state_index"), py::arg("cells_m"), py::arg("stencils"), py::arg("mode_transition"),
      py::arg("wall_factor"), py::arg("fix_ticks"), py::arg("fix_factors"), py::arg("num_ticks"),
      py::arg("keep_posterior") = false, R"doc(
Forward-backward over T = ``num_ticks`` ticks of the hidden Markov chain whose state is (lattice
cell, motion mode) (cpp/include/indoorloc/fusion/mode_sequence_smoother.h; the engine of
``indoorloc.fusion.wifi_heading_sequence``): per tick the mode moves by ``mode_transition``, the
cell by the new mode's stencil (mass moved onto a lattice cell that is no state is lost: a wall),
then the emission wall_factor ⊙ fix factor weighs it; forward pass normalised per tick (kept in
float32), backward pass normalised by its maximum, posterior summed over modes.

Parameters
----------
state_index : (ny, nx) int, the state index of lattice cell (row y, column x) or -1; each of 0..N-1 once.
cells_m : (N, 2) float, the states' centres [m].
stencils : sequence of M pairs (offsets (K, 2) int (dx, dy) [cells], weights (K,) >= 0), one per mode.
mode_transition : (M, M) float >= 0, P(m' | m) in row m.
wall_factor : (N,) float >= 0, the emission of every tick.
fix_ticks : (F,) int, strictly increasing ticks in [0, T) that have a fix.
fix_factors : (F, N) float >= 0, the fix factor of tick fix_ticks[j] in row j (times wall_factor).
num_ticks : int >= 1.
keep_posterior : also return the (T, N) posterior.

Returns
-------
ModeSequenceResult (mean_m (T, 2) [m], posterior, restarts, log_evidence, seconds, report).
ValueError naming the argument for a wrong shape, NaN, a negative entry, a state index out of range
or repeated, or a tick whose evidence is zero on every state.)doc");
}

}  // namespace indoorloc::bindings
