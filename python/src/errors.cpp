// errors.cpp - raising vff.Error subclasses (errors.h).
#include "errors.h"

namespace py = pybind11;

namespace vff::python {

py::object offsetObject(uint64_t offset) { return offset == kNoOffset ? py::object(py::none()) : py::object(py::int_(offset)); }

py::object sectionObject(uint32_t section) { return section ? py::object(py::str(sectionTagName(section))) : py::object(py::none()); }

void raise(const Error& error) {
  py::module_ errors = py::module_::import("vff._errors");
  py::object exc = errors.attr("make_error")(uint32_t(error.code), codeName(error.code), sectionObject(error.section),
                                             offsetObject(error.offset), error.message);
  PyErr_SetObject(reinterpret_cast<PyObject*>(Py_TYPE(exc.ptr())), exc.ptr());
  throw py::error_already_set();
}

}  // namespace vff::python
