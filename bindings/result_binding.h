// One way to bind a result struct: a typed, read-only object whose fields are named once here
// (CONVENTIONS rule 13, results as typed objects instead of dicts copied by hand). The fields
// are read-only properties; each array field returns a new numpy array (a copy), as the dicts
// did. For the code written against the former dicts, the object is also a read-only mapping with
// the same keys: result["positions_m"], keys(), items(), values(), get(), `in`, len(), iteration,
// to_dict() (nested results as dicts too), and it pickles as that dict (Dask ships results).
// A result whose mapping reading is deprecated (MappingDeprecated) warns on each of those calls
// (DeprecationWarning naming the attribute to use); to_dict() and the attributes never warn.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include <pybind11/pybind11.h>

namespace indoorloc::bindings {

namespace py = pybind11;

template <typename T>
class ResultBinder {
 public:
  ResultBinder(py::module_& m, const char* name, const char* doc) : cls_(m, name, doc), name_(name) {}

  /// A read-only field `key` computed from the struct by `getter`.
  template <typename Getter>
  ResultBinder& Field(const char* key, Getter&& getter, const char* doc = "") {
    cls_.def_property_readonly(key, std::forward<Getter>(getter), doc);
    keys_.emplace_back(key);
    return *this;
  }

  /// The result used to be a dict: reading it as a mapping (result["key"], keys(), items(), ...)
  /// still works for one release and warns with `since` (e.g. "house (issue 27)").
  ResultBinder& MappingDeprecated(const char* since) {
    mapping_deprecated_since_ = since;
    return *this;
  }

  /// Adds the mapping protocol, to_dict, repr and pickling over the fields declared so far.
  py::class_<T>& Finish() {
    py::tuple keys(keys_.size());
    for (std::size_t i = 0; i < keys_.size(); ++i) keys[i] = py::str(keys_[i]);
    cls_.attr("_fields") = keys;
    const std::string name = name_;
    // Called first by every mapping method: nothing, or the DeprecationWarning of a former dict.
    const std::string since = mapping_deprecated_since_;
    const auto read_as_mapping = [name, since](const char* how) {
      if (since.empty()) return;
      const std::string message = "indoorloc: reading a " + name + " as a dict (" + how +
                                  ") is deprecated since " + since +
                                  ": use its attributes (result.key) or result.to_dict()";
      // Stack level 1: the Python line that called this method (it is C, with no frame of its own).
      if (PyErr_WarnEx(PyExc_DeprecationWarning, message.c_str(), 1) != 0) throw py::error_already_set();
    };
    cls_.def("__getitem__", [read_as_mapping](const py::object& self, const py::object& key) {
          read_as_mapping("result[key]");
          if (!py::isinstance<py::str>(key) || !self.attr("_fields").contains(key)) throw py::key_error(py::repr(key));
          return self.attr(key);
        })
        .def("keys", [read_as_mapping](const py::object& self) {
               read_as_mapping("keys()");
               return py::list(self.attr("_fields"));
             }, "The field names.")
        .def("values", [read_as_mapping](const py::object& self) {
               read_as_mapping("values()");
               py::list out;
               for (const py::handle key : self.attr("_fields")) out.append(self.attr(key));
               return out;
             })
        .def("items", [read_as_mapping](const py::object& self) {
               read_as_mapping("items()");
               py::list out;
               for (const py::handle key : self.attr("_fields")) out.append(py::make_tuple(key, self.attr(key)));
               return out;
             })
        .def("get", [read_as_mapping](const py::object& self, const py::object& key, const py::object& fallback) {
               read_as_mapping("get()");
               if (py::isinstance<py::str>(key) && self.attr("_fields").contains(key)) return py::object(self.attr(key));
               return fallback;
             }, py::arg("key"), py::arg("default") = py::none())
        .def("__contains__", [read_as_mapping](const py::object& self, const py::object& key) {
               read_as_mapping("key in result");
               return py::isinstance<py::str>(key) && self.attr("_fields").contains(key);
             })
        .def("__iter__", [read_as_mapping](const py::object& self) {
               read_as_mapping("iteration");
               return py::iter(self.attr("_fields"));
             })
        .def("__len__", [read_as_mapping](const py::object& self) {
               read_as_mapping("len()");
               return py::len(self.attr("_fields"));
             })
        .def("to_dict", [](const py::object& self) {
               py::dict out;
               for (const py::handle key : self.attr("_fields")) {
                 py::object value = self.attr(key);
                 out[key] = py::hasattr(value, "to_dict") ? value.attr("to_dict")() : value;
               }
               return out;
             }, "Every field and its value (nested results as dicts).")
        .def("__reduce__", [](const py::object& self) {
               return py::make_tuple(py::module_::import("builtins").attr("dict"), py::make_tuple(self.attr("to_dict")()));
             })
        .def("__repr__", [name](const py::object& self) {
               std::string s = name + "(";
               bool first = true;
               for (const py::handle key : self.attr("_fields")) {
                 py::object value = self.attr(key);
                 s += (first ? "" : ", ") + std::string(py::str(key)) + "=";
                 s += py::hasattr(value, "shape") ? "<array " + std::string(py::str(value.attr("shape"))) + ">"
                                                  : std::string(py::repr(value));
                 first = false;
               }
               return s + ")";
             });
    cls_.attr("__hash__") = py::none();
    py::module_::import("collections.abc").attr("Mapping").attr("register")(cls_);
    return cls_;
  }

 private:
  py::class_<T> cls_;
  std::string name_;
  std::vector<std::string> keys_;
  std::string mapping_deprecated_since_;
};

}  // namespace indoorloc::bindings
