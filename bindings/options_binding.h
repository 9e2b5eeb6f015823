// One way to bind an Options struct: the fields are bound with def_readwrite (or def_property for
// flattened nested fields) and BindOptionsProtocol adds the rest from them, so that no default is
// restated on the Python side (CONVENTIONS rule 13):
//   - Options(**fields): the C++ defaults, the given fields set, then IsValid (ValueError naming
//     an unknown field, a value of the wrong type, or the rule broken);
//   - replace(**fields), to_dict(), validate(), __repr__, ==, pickling (Dask ships options to
//     workers);
//   - the positional call form some classes once had (Options(500, 2.0)) still works, with a
//     DeprecationWarning, when the class lists its old positional order (docs/api_changes.md).
#pragma once

#include <string>
#include <utility>
#include <vector>

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
      // An int that does not fit an integer field is a value out of range, not a wrong type
      // (num_particles = 2**31 read "has the wrong type ...: got int").
      const py::object current = py::getattr(obj, item.first);
      if (py::isinstance<py::int_>(item.second) && !py::isinstance<py::bool_>(item.second) &&
          py::isinstance<py::int_>(current) && !py::isinstance<py::bool_>(current)) {
        ThrowInvalidArgument(key, std::string(py::str(item.second)) + " does not fit " + type_name + "." + key +
                                      " (a machine integer; see its limits in docs/errors.md)");
      }
      // pybind11's setter error names neither the field nor the type it wanted.
      throw py::type_error("indoorloc: argument '" + key + "': has the wrong type for " + type_name + "." +
                           key + ": got " + std::string(Py_TYPE(item.second.ptr())->tp_name));
    }
  }
  T out = obj.cast<T>();
  ValidateOptions(out);  // "argument 'options': <rule>", as when an algorithm validates them
  return out;
}

/// The keyword fields of a call that may still use the deprecated positional form: positional
/// values are matched to `legacy_order` with a DeprecationWarning.
inline py::dict FieldsFromCall(const py::args& args, const py::kwargs& kwargs, const char* type_name,
                               const std::vector<std::string>& legacy_order) {
  py::dict fields;
  for (const auto& item : kwargs) fields[item.first] = item.second;
  if (args.empty()) return fields;
  if (args.size() > legacy_order.size()) {
    throw py::type_error(std::string("indoorloc: ") + type_name + " takes its fields by keyword only (" +
                         std::to_string(args.size()) + " positional arguments given)");
  }
  const std::string message = std::string(type_name) +
                              "(...) with positional arguments is deprecated; pass the fields by keyword "
                              "(docs/api_changes.md)";
  if (PyErr_WarnEx(PyExc_DeprecationWarning, message.c_str(), 1) != 0) throw py::error_already_set();
  for (std::size_t i = 0; i < args.size(); ++i) {
    const py::str key(legacy_order[i]);
    if (fields.contains(key)) {
      throw py::type_error(std::string("indoorloc: argument '") + legacy_order[i] + "': given twice to " + type_name);
    }
    fields[key] = args[i];
  }
  return fields;
}

/// The `options=` argument of a bound function: None gives the C++ defaults, else an instance of the
/// bound Options class (TypeError naming the argument otherwise). `fields` are the option fields the
/// function once took as separate keywords (`zupt_ekf(..., smooth=True)`): they still work for one
/// release, with a DeprecationWarning, and change a copy of `options` (validated, errors naming the
/// field). An unknown keyword is a TypeError, as for any Python function. The algorithm validates
/// the options it is given itself.
template <typename T>
T OptionsArgument(const py::object& options, const py::kwargs& fields, const char* function) {
  const std::string type_name = py::str(py::type::of<T>().attr("__name__"));
  T base;
  if (!options.is_none()) {
    if (!py::isinstance<T>(options)) {
      throw py::type_error(std::string("indoorloc: argument 'options': ") + function + " needs a " + type_name +
                           " (or None for the defaults), got " + Py_TYPE(options.ptr())->tp_name);
    }
    base = options.cast<T>();
  }
  if (fields.empty()) return base;
  const py::list names = OptionFieldNames(py::type::of<T>());
  std::string given;
  for (const auto& item : fields) {
    if (!names.contains(item.first)) {
      throw py::type_error(std::string(function) + "() got an unexpected keyword argument '" +
                           std::string(py::str(item.first)) + "'");
    }
    given += (given.empty() ? "" : ", ") + std::string(py::str(item.first)) + "=...";
  }
  const std::string message = std::string(function) + "(..., " + given + ") is deprecated; pass options=" + type_name +
                              "(" + given + ") (docs/api_changes.md)";
  if (PyErr_WarnEx(PyExc_DeprecationWarning, message.c_str(), 1) != 0) throw py::error_already_set();
  return OptionsWithFields(base, fields, type_name.c_str());
}

/// Adds the kwargs constructor, replace, to_dict, validate, __repr__, __eq__ and pickling to a
/// bound Options class whose fields are already bound. `legacy_order`: the field order of a former
/// positional constructor, kept working with a DeprecationWarning (empty: keywords only).
template <typename T>
void BindOptionsProtocol(py::class_<T>& cls, const char* type_name, std::vector<std::string> legacy_order = {}) {
  cls.def(py::init([type_name, legacy_order](const py::args& args, const py::kwargs& kwargs) {
        return OptionsWithFields(T(), FieldsFromCall(args, kwargs, type_name, legacy_order), type_name);
      }))
      .def("validate", [](const T& self) { ValidateOptions(self); },
           "Raises ValueError naming the field and the rule broken, if any.")
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
