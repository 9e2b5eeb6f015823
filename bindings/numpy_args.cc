#include "numpy_args.h"

#include <cmath>

#include "indoorloc/core/validate.h"

namespace indoorloc::bindings {
namespace {

void CheckValues(const double* data, Eigen::Index size, Eigen::Index cols, const char* name,
                 Finiteness finiteness) {
  if (finiteness == Finiteness::kAny) return;
  for (Eigen::Index k = 0; k < size; ++k) {
    const double v = data[k];
    const bool ok = std::isfinite(v) ||
                    (finiteness == Finiteness::kAllowMinusInf && v == -INFINITY);
    if (!ok) {
      const std::string where = cols < 0 ? DescribeEntry(k, 0, true)
                                         : DescribeEntry(k / cols, k % cols, false);
      ThrowInvalidArgument(name, where + (std::isnan(v) ? " is NaN" : " is infinite"));
    }
  }
}

}  // namespace

DoubleArray ToDoubleArray(const py::handle& obj, const char* name) {
  if (obj.is_none()) ThrowInvalidArgument(name, "is None, expected an array of numbers");
  // Look at the dtype before the float64 cast: forcecast would silently drop the imaginary part
  // of complex input, and turn strings or objects into whatever numpy makes of them.
  py::array raw = py::array::ensure(obj);
  if (!raw) {
    PyErr_Clear();
    ThrowInvalidArgument(name, "cannot be converted to an array");
  }
  const char kind = raw.dtype().kind();
  const std::string dtype = py::str(raw.dtype());
  if (kind == 'c') {
    ThrowInvalidArgument(name, "is complex (dtype " + dtype +
                                   "): cannot be converted to a float64 array without dropping the imaginary part");
  }
  if (kind != 'f' && kind != 'i' && kind != 'u' && kind != 'b') {
    ThrowInvalidArgument(name, "cannot be converted to a float64 array (dtype " + dtype + ")");
  }
  DoubleArray array = DoubleArray::ensure(raw);
  if (!array) {
    PyErr_Clear();
    ThrowInvalidArgument(name, "cannot be converted to a float64 array");
  }
  return array;
}

namespace {

// ToDoubleArray of an array with `ndim` dimensions (ValueError naming the argument otherwise).
DoubleArray ToDoubleArrayOfRank(const py::handle& obj, const char* name, int ndim) {
  DoubleArray array = ToDoubleArray(obj, name);
  if (array.ndim() != ndim) {
    ThrowInvalidArgument(name, "expected a " + std::to_string(ndim) + "-D array, got " +
                                   std::to_string(array.ndim()) + "-D");
  }
  return array;
}

}  // namespace

VectorArg ToVector(const py::handle& obj, const char* name, Eigen::Index size,
                   Finiteness finiteness) {
  VectorArg arg;
  arg.array = ToDoubleArrayOfRank(obj, name, 1);
  const Eigen::Index n = static_cast<Eigen::Index>(arg.array.shape(0));
  if (size >= 0 && n != size) {
    ThrowInvalidArgument(name, "expected length " + std::to_string(size) + ", got " +
                                   std::to_string(n));
  }
  CheckValues(arg.array.data(), n, -1, name, finiteness);
  new (&arg.map) Eigen::Map<const Eigen::VectorXd>(arg.array.data(), n);
  return arg;
}

MatrixArg ToMatrix(const py::handle& obj, const char* name, Eigen::Index rows, Eigen::Index cols,
                   Finiteness finiteness) {
  MatrixArg arg;
  arg.array = ToDoubleArrayOfRank(obj, name, 2);
  const Eigen::Index r = static_cast<Eigen::Index>(arg.array.shape(0));
  const Eigen::Index c = static_cast<Eigen::Index>(arg.array.shape(1));
  if ((rows >= 0 && r != rows) || (cols >= 0 && c != cols)) {
    auto dim = [](Eigen::Index n) { return n < 0 ? std::string("any") : std::to_string(n); };
    ThrowInvalidArgument(name, "expected shape (" + dim(rows) + ", " + dim(cols) + "), got (" +
                                   std::to_string(r) + ", " + std::to_string(c) + ")");
  }
  CheckValues(arg.array.data(), r * c, c, name, finiteness);
  new (&arg.map) Eigen::Map<const RowMatrixXd>(arg.array.data(), r, c);
  return arg;
}

int ToInt(const py::handle& obj, const char* name, long long lo, long long hi) {
  if (py::isinstance<py::bool_>(obj) || !(py::isinstance<py::int_>(obj) || py::hasattr(obj, "__index__"))) {
    ThrowInvalidArgument(name, "expected an integer, got " + std::string(py::str(py::type::handle_of(obj).attr("__name__"))));
  }
  const py::int_ value = py::reinterpret_steal<py::int_>(PyNumber_Index(obj.ptr()));
  if (!value) {
    PyErr_Clear();
    ThrowInvalidArgument(name, "expected an integer");
  }
  int overflow = 0;
  const long long v = PyLong_AsLongLongAndOverflow(value.ptr(), &overflow);
  if (overflow != 0 || v < lo || v > hi) {
    ThrowInvalidArgument(name, "must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got " +
                                   std::string(py::str(value)));
  }
  return static_cast<int>(v);
}

py::array_t<double> ToNumpy(const Eigen::Ref<const Eigen::VectorXd>& v) {
  py::array_t<double> out(v.size());
  std::copy(v.data(), v.data() + v.size(), out.mutable_data());
  return out;
}

Eigen::VectorXi ToIntVector(const py::handle& obj, const char* name, Eigen::Index size) {
  VectorArg v = ToVector(obj, name, size);
  Eigen::VectorXi out(v.map.size());
  for (Eigen::Index i = 0; i < v.map.size(); ++i) {
    const double x = v.map[i];
    if (x != std::floor(x)) {
      ThrowInvalidArgument(name, DescribeEntry(i, 0, true) + " is not an integer, got " + FormatValue(x));
    }
    // Beyond 32 bits a cast would wrap (an id of 2**31 became -2147483648).
    if (x < -2147483648.0 || x > 2147483647.0) {
      ThrowInvalidArgument(name, DescribeEntry(i, 0, true) + " = " + FormatValue(x) +
                                     " does not fit in a 32-bit integer [-2147483648, 2147483647]");
    }
    out[i] = static_cast<int>(x);
  }
  return out;
}

}  // namespace indoorloc::bindings
