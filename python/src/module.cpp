// module.cpp - the extension vff._vff: libvff's files and queries and the baker, for numpy.
// python/vff/__init__.py re-exports it as the package vff.
#include "bindings.h"
#include "vff/version.h"

namespace py = pybind11;

PYBIND11_MODULE(_vff, m) {
  m.doc() = "vff: precomputed 4D visibility fields (the extension behind the vff package)";
  m.attr("__version__") = vff::kLibraryVersion;
  m.attr("format_version") = py::make_tuple(vff::kVersionMajor, vff::kVersionMinor);
  m.def("batch_kernel", [] { return vff::batchKernelName(); },
        "The kernel the batch queries use on this CPU: \"avx512\", \"avx2\", \"sse2\" or \"scalar\".");
  vff::python::bindFile(m);
  vff::python::bindQuery(m);
  vff::python::bindScene(m);
  vff::python::bindBake(m);
  vff::python::bindRewrite(m);
  vff::python::bindGltf(m);
}
