// One way to bind an Options struct: the fields are bound with def_readwrite (or def_property for
// flattened nested fields) and BindOptionsProtocol adds the rest from them, so that no default is
// restated on the Python side (CONVENTIONS rule 13):
//   - Options(**fields): the C++ defaults, the given fields set, then IsValid (ValueError naming
//     an unknown field, a value of the wrong type, or the rule broken);
//   - replace(**fields), to_dict(), __repr__, ==, pickling (Dask ships options to workers).
#pragma once

#include <string>

#include <pybind11/pybind11.h>

#include "indoorloc/core/options.h"
#include "indoorloc/core/check.h"

namespace indoorloc::bindings {

namespace py = pybind11;

/// Names of the writable properties of a bound class, sorted (its option fields).
inline py::list OptionFieldNames(const py::handle& type) {
  py::list out;
  const py::object property = py::module_::import("builtins").attr("property");
  for (const py::handle name : py::module_::import("builtins").attr("dir")(type)) {
    const std::string n = py::str(name);
    if (n.empty() || n[0] == '_') continue;
    const py::object attr = py::getattr(type, name);
    if (py::isinstance(attr, property) && !attr.attr("fset").is_none()) out.append(name);
  }
  return out;
}

/// Sets `fields` on a copy of `base` and validates it; errors name the field.
template <typename T>
T OptionsWithFields(const T& base, const py::dict& fields, const char* type_name) {
  // A new C++ copy: casting `base` itself would return the caller's Python object (pybind11 finds
  // registered instances by address, whatever the return value policy) and replace() would then
  // modify the options it was called on.
  T copy = base;
  py::object obj = py::cast(std::move(copy));
  const py::list names = OptionFieldNames(py::type::of(obj));
  for (const auto& item : fields) {
    const std::string key = py::str(item.first);
    if (!names.contains(item.first)) {
      ThrowInvalidArgument(key, std::string("is not a field of ") + type_name + " (fields: " +
                                    std::string(py::str(py::str(", ").attr("join")(names))) + ")");
    }
    try {
      py::setattr(obj, item.first, item.second);
    } catch (const py::error_already_set& e) {
      if (!e.matches(PyExc_TypeError)) throw;
      ThrowInvalidArgument(key, std::string("has the wrong type for ") + type_name + ": got " +
                                    std::string(Py_TYPE(item.second.ptr())->tp_name));
    }
  }
  T out = obj.cast<T>();
  ValidateOptions(out, type_name);
  return out;
}

/// Adds the kwargs constructor, replace, to_dict, __repr__, __eq__ and pickling to a bound
/// Options class whose fields are already bound.
template <typename T>
void BindOptionsProtocol(py::class_<T>& cls, const char* type_name) {
  cls.def(py::init([type_name](const py::kwargs& fields) { return OptionsWithFields(T(), fields, type_name); }))
      .def("replace", [type_name](const T& self, const py::kwargs& fields) {
             return OptionsWithFields(self, fields, type_name);
           },
           "A copy with the given fields changed (validated).")
      .def("to_dict", [](const py::object& self) {
             py::dict d;
             for (const py::handle name : OptionFieldNames(py::type::of(self))) d[name] = py::getattr(self, name);
             return d;
           },
           "Every field and its value.")
      .def("__repr__", [type_name](const py::object& self) {
             std::string s = std::string(type_name) + "(";
             bool first = true;
             for (const py::handle name : OptionFieldNames(py::type::of(self))) {
               s += (first ? "" : ", ") + std::string(py::str(name)) + "=" +
                    std::string(py::repr(py::getattr(self, name)));
               first = false;
             }
             return s + ")";
           })
      .def("__eq__", [](const py::object& self, const py::object& other) {
             if (!py::isinstance(other, py::type::of(self))) return false;
             return self.attr("to_dict")().equal(other.attr("to_dict")());
           })
      .def(py::pickle([](const py::object& self) { return self.attr("to_dict")(); },
                      [type_name](const py::dict& state) { return OptionsWithFields(T(), state, type_name); }));
  cls.attr("__hash__") = py::none();
}

}  // namespace indoorloc::bindings
