// bindings.h - what the parts of the extension vff._vff share.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

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

// A checksum policy spelled "all", "lazy" or "none" (else a ValueError).
ChecksumPolicy checksumPolicy(const std::string& s);

// The open() of the module: a File from a path, with a checksum policy "all", "lazy" or "none".
std::shared_ptr<PyFile> openFile(const std::string& path, const std::string& checksums);

}  // namespace vff::python
