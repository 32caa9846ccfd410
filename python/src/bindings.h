// bindings.h - what the parts of the extension vff._vff share.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstdint>
#include <memory>
#include <string>

#include "vff/vff.h"

namespace vff::python {

// A File as Python holds it: the open file (its mapping), shared by every array and query made
// from it, so that any of them keeps it alive.
struct PyFile {
  std::string path;  // as given (empty for a file in memory)
  File file;
};

// The field description, layout, header, sections and planes as a dict (vff.inspect's document).
pybind11::dict describe(const File& file);

// Each part adds its classes and functions to the module.
void bindFile(pybind11::module_& m);
void bindQuery(pybind11::module_& m);
void bindBake(pybind11::module_& m);
void bindRewrite(pybind11::module_& m);
void bindScene(pybind11::module_& m);
void bindGltf(pybind11::module_& m);

// The integer argument `name` (a Python int, or anything with __index__), checked against [lo, hi]:
// a TypeError for a non-integer and a ValueError naming the argument and its range otherwise
// ("map_size: expected an integer in [1, 4096], got 0"), never pybind11's "incompatible function
// arguments". hi < 0: no upper bound ("an integer >= 0"). `note` follows the range in the message.
inline int64_t intArg(const pybind11::handle& v, const char* name, int64_t lo, int64_t hi, const char* note = "") {
  if (!pybind11::isinstance<pybind11::int_>(v) && !pybind11::hasattr(v, "__index__"))
    throw pybind11::type_error(std::string(name) + ": expected an integer, got " +
                               std::string(pybind11::str(pybind11::type::of(v).attr("__name__"))));
  const pybind11::int_ i = pybind11::reinterpret_steal<pybind11::int_>(PyNumber_Index(v.ptr()));
  if (!i) throw pybind11::error_already_set();
  int overflow = 0;
  const long long x = PyLong_AsLongLongAndOverflow(i.ptr(), &overflow);
  if (overflow != 0 || x < lo || (hi >= lo && x > hi)) {
    const std::string range = hi >= lo ? "an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]"
                                       : "an integer >= " + std::to_string(lo);
    throw pybind11::value_error(std::string(name) + ": expected " + range + note + ", got " +
                                std::string(pybind11::str(v)));
  }
  return x;
}

// A checksum policy spelled "all", "lazy" or "none" (else a ValueError).
ChecksumPolicy checksumPolicy(const std::string& s);

// The open() of the module: a File from a path, with a checksum policy "all", "lazy" or "none".
std::shared_ptr<PyFile> openFile(const std::string& path, const std::string& checksums);

}  // namespace vff::python
