// The pybind11 module indoorloc._core: one submodule per subsystem. Each subsystem's bindings
// live in bind_<subsystem>.cc and are registered here. C++ exceptions map to Python as
// std::invalid_argument -> ValueError, std::out_of_range -> IndexError,
// std::runtime_error (and others) -> RuntimeError (pybind11's standard translation).
#include <pybind11/pybind11.h>

#include "indoorloc/core/version.h"

namespace py = pybind11;

namespace indoorloc::bindings {
void BindAnalog(py::module_& m);
void BindCore(py::module_& m);
void BindFusionFloorPlan(py::module_& m);
void BindMapmatch(py::module_& m);
void BindNetworkScale(py::module_& m);
void BindNetwork(py::module_& m);
void BindPdr(py::module_& m);
void BindWifi(py::module_& m);
void BindWifiBaselines(py::module_& m);
}  // namespace indoorloc::bindings

PYBIND11_MODULE(_core, m) {
  m.doc() = "indoorloc compiled core (C++17). Use the facades in the indoorloc package.";
  m.attr("__version__") = indoorloc::kVersion;

  py::module_ core = m.def_submodule("core", "Random streams, log-space weights, resampling.");
  indoorloc::bindings::BindCore(core);

  // Subsystems register their bindings below as they are implemented (see docs/architecture.md).
  py::module_ mapmatch = m.def_submodule("mapmatch", "Circular particle filter on a road network (paper 000).");
  indoorloc::bindings::BindMapmatch(mapmatch);
  py::module_ analog = m.def_submodule("analog", "Exemplar-based (analog) hidden Markov model (paper 001).");
  indoorloc::bindings::BindAnalog(analog);
  py::module_ pdr = m.def_submodule("pdr", "Pedestrian dead reckoning with a foot-mounted IMU (paper 002).");
  indoorloc::bindings::BindPdr(pdr);
  py::module_ network = m.def_submodule("network", "INS/GPS network adjustment (paper 003).");
  indoorloc::bindings::BindNetworkScale(network);
  indoorloc::bindings::BindNetwork(network);
  py::module_ wifi = m.def_submodule("wifi", "RSS signal maps, Delaunay interpolation, gradient tracker (paper 004).");
  indoorloc::bindings::BindWifi(wifi);
  indoorloc::bindings::BindWifiBaselines(wifi);
  py::module_ fusion = m.def_submodule("fusion", "Particle-filter fusion of PDR, WiFi and a floor plan");
  indoorloc::bindings::BindFusionFloorPlan(fusion);
}
