// Conversion of Python arguments to Eigen views, with indoorloc's argument checks.
//
// Every binding takes array arguments as py::object and converts them here, so that a wrong
// dimension, a non-numeric object, or NaN gives a ValueError naming the argument (pybind11's own
// Eigen caster would give a TypeError without the name). The converted arrays are C-contiguous
// float64 (copied only when the input is not); the user's array is never modified.
#pragma once

#include <string>

#include <Eigen/Core>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "indoorloc/core/check.h"

namespace indoorloc::bindings {

namespace py = pybind11;

using RowMatrixXd = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

/// What to accept besides finite numbers.
enum class Finiteness { kFinite, kAllowMinusInf, kAny };

/// A 1-D float64 view of a Python argument; `array` keeps the data alive.
struct VectorArg {
  DoubleArray array;
  Eigen::Map<const Eigen::VectorXd> map{nullptr, 0};
};

/// A 2-D row-major float64 view of a Python argument; `array` keeps the data alive.
struct MatrixArg {
  DoubleArray array;
  Eigen::Map<const RowMatrixXd> map{nullptr, 0, 0};
};

/// Converts `obj` to a float64 array or throws ValueError naming `name`.
DoubleArray ToDoubleArray(const py::handle& obj, const char* name);

/// 1-D argument of length `size` (-1: any). kAllowMinusInf is for log-weights.
VectorArg ToVector(const py::handle& obj, const char* name, Eigen::Index size = -1,
                   Finiteness finiteness = Finiteness::kFinite);

/// 2-D argument of shape (rows, cols) (-1: any).
MatrixArg ToMatrix(const py::handle& obj, const char* name, Eigen::Index rows = -1,
                   Eigen::Index cols = -1, Finiteness finiteness = Finiteness::kFinite);

/// 1-D integer argument of length `size` (-1: any): every entry a whole number that fits in a
/// 32-bit int, else ValueError naming `name`, the entry and its value.
Eigen::VectorXi ToIntVector(const py::handle& obj, const char* name, Eigen::Index size = -1);
/// A Python int (or integer-valued number) argument in [lo, hi], else ValueError naming `name`
/// (pybind11's own cast says "Unable to cast Python instance of type int to C++ type '?'").
int ToInt(const py::handle& obj, const char* name, long long lo, long long hi);
/// Copies an Eigen vector into a new numpy array.
py::array_t<double> ToNumpy(const Eigen::Ref<const Eigen::VectorXd>& v);

/// `work()` with the GIL released (it must touch no Python object); its C++ result is returned
/// after the GIL is taken back.
template <typename Work>
auto WithoutGil(Work&& work) {
  py::gil_scoped_release release;
  return work();
}

}  // namespace indoorloc::bindings
