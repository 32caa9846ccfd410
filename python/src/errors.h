// errors.h - libvff Errors as Python exceptions of the vff.Error hierarchy (vff/_errors.py).
#pragma once

#include <pybind11/pybind11.h>

#include "vff/error.h"

namespace vff::python {

// Raises the vff.Error subclass for error.code (vff._errors.error_class), carrying code, name,
// section, offset and message. Needs the GIL.
[[noreturn]] void raise(const Error& error);

// The value of a Result, or raise(its error).
template <class T>
T take(Result<T>&& r) {
  if (!r) raise(r.error());
  return std::move(r).value();
}
inline void check(const Status& s) {
  if (!s) raise(s.error());
}

// The Python object for an Error's offset: None for kNoOffset.
pybind11::object offsetObject(uint64_t offset);
// The section tag as text ("DIST"), or None for 0.
pybind11::object sectionObject(uint32_t section);

}  // namespace vff::python
