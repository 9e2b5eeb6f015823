// The pybind11 module indoorloc._core: one submodule per subsystem. Each subsystem's bindings
// live in bind_<subsystem>.cc and are registered here. C++ exceptions map to Python as
// std::invalid_argument -> ValueError, std::out_of_range -> IndexError,
// std::runtime_error (and others) -> RuntimeError (pybind11's standard translation);
// indoorloc::Interrupted (Ctrl-C seen inside a C++ loop) -> KeyboardInterrupt.
#include <pybind11/pybind11.h>

#include "indoorloc/core/interrupt.h"
#include "indoorloc/core/version.h"

namespace py = pybind11;

namespace {

// The Python error (KeyboardInterrupt, or whatever a custom SIGINT handler raised) found by
// the interrupt hook, kept until the Interrupted exception reaches Python.
PyObject* g_pending_type = nullptr;
PyObject* g_pending_value = nullptr;
PyObject* g_pending_traceback = nullptr;

// Called by indoorloc::CheckInterrupt on the main thread, with or without the GIL.
bool PollPythonSignals() {
  py::gil_scoped_acquire gil;
  if (PyErr_CheckSignals() == 0) return false;
  if (g_pending_type == nullptr) {
    PyErr_Fetch(&g_pending_type, &g_pending_value, &g_pending_traceback);
  } else {
    PyErr_Clear();  // a second Ctrl-C while the first unwinds
  }
  return true;
}

}  // namespace

namespace indoorloc::bindings {
void BindAnalog(py::module_& m);
void BindCore(py::module_& m);
void BindFusionEstimates(py::module_& m);
void BindFusionFloorPlan(py::module_& m);
void BindFusionGrid(py::module_& m);
void BindFusionGridSession(py::module_& m);
void BindFusionLive(py::module_& m);
void BindFusionModeSequence(py::module_& m);
void BindPdrStreaming(py::module_& m);
void BindFusionTracker(py::module_& m);
void BindMapmatch(py::module_& m);
void BindNetworkScale(py::module_& m);
void BindNetwork(py::module_& m);
void BindPdr(py::module_& m);
void BindWifi(py::module_& m);
void BindWifiBaselines(py::module_& m);
void BindWifiMatcher(py::module_& m);
}  // namespace indoorloc::bindings

PYBIND11_MODULE(_core, m) {
  m.doc() = "indoorloc compiled core (C++17). Use the facades in the indoorloc package.";
  m.attr("__version__") = indoorloc::kVersion;

  // Ctrl-C during C++ loops that release the GIL: they call CheckInterrupt between runs and
  // steps, which polls PyErr_CheckSignals here and unwinds with indoorloc::Interrupted.
  indoorloc::SetInterruptHook(&PollPythonSignals);
  py::register_exception_translator([](std::exception_ptr p) {
    auto raise_pending_stop = [] {
      indoorloc::ClearInterrupt();
      if (g_pending_type != nullptr) {
        PyErr_Restore(g_pending_type, g_pending_value, g_pending_traceback);
        g_pending_type = g_pending_value = g_pending_traceback = nullptr;
      } else {
        PyErr_SetNone(PyExc_KeyboardInterrupt);
      }
    };
    try {
      if (p) std::rethrow_exception(p);
    } catch (const indoorloc::Interrupted&) {
      raise_pending_stop();
    } catch (...) {
      // Another error reached Python while a stop was pending (a parallel task failed while
      // its sibling was interrupted, and the failure was the one rethrown): the stop wins,
      // and is consumed here. Left pending, it would interrupt the next call with this one's
      // KeyboardInterrupt (found by the property suite as a stale alarm).
      if (g_pending_type == nullptr) throw;  // no stop: pybind11's own translation
      raise_pending_stop();
    }
  });

  py::module_ core = m.def_submodule("core", "Random streams, log-space weights, resampling.");
  indoorloc::bindings::BindCore(core);

  // Subsystems register their bindings below as they are implemented (see docs/architecture.md).
  py::module_ mapmatch = m.def_submodule("mapmatch", "Circular particle filter on a road network (paper 000).");
  indoorloc::bindings::BindMapmatch(mapmatch);
  py::module_ analog = m.def_submodule("analog", "Exemplar-based (analog) hidden Markov model (paper 001).");
  indoorloc::bindings::BindAnalog(analog);
  py::module_ pdr = m.def_submodule("pdr", "Pedestrian dead reckoning with a foot-mounted IMU (paper 002).");
  indoorloc::bindings::BindPdr(pdr);
  indoorloc::bindings::BindPdrStreaming(pdr);
  py::module_ network = m.def_submodule("network", "INS/GPS network adjustment (paper 003).");
  indoorloc::bindings::BindNetworkScale(network);
  indoorloc::bindings::BindNetwork(network);
  py::module_ wifi = m.def_submodule("wifi", "RSS signal maps, Delaunay interpolation, gradient tracker (paper 004).");
  indoorloc::bindings::BindWifi(wifi);
  indoorloc::bindings::BindWifiBaselines(wifi);
  indoorloc::bindings::BindWifiMatcher(wifi);
  py::module_ fusion = m.def_submodule("fusion", "Particle-filter fusion of PDR steps, WiFi and a floor plan (docs/fusion.md).");
  indoorloc::bindings::BindFusionFloorPlan(fusion);
  indoorloc::bindings::BindFusionEstimates(fusion);
  indoorloc::bindings::BindFusionTracker(fusion);
  indoorloc::bindings::BindFusionGrid(fusion);
  indoorloc::bindings::BindFusionGridSession(fusion);
  indoorloc::bindings::BindFusionLive(fusion);
  indoorloc::bindings::BindFusionModeSequence(fusion);
}
