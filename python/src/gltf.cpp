// gltf.cpp - vff.read_gltf_fields: the fields a glTF asset's meshes carry (the extension
// VFF_visibility_field, spec/gltf/VFF_visibility_field/README.md), read and checked by the baker's
// reader (vff/bake/gltf_fields.h), each payload opened as a vff.File from its bytes.
#include <pybind11/stl.h>

#include "bindings.h"
#include "errors.h"
#include "vff/bake/gltf_fields.h"

namespace py = pybind11;

namespace vff::python {

namespace {

// One field as Python sees it: the reader's GltfField, its payload held once as a bytes object,
// and why it cannot be opened (empty when it can).
struct PyGltfField {
  bake::GltfField field;
  py::bytes bytes;
  py::list nodes;
  // The reason open() refuses the field: the rule and the problem (no rule when it is usable).
  int refusedRule = 0;
  std::string refusedPath, refusedMessage;
};

struct PyGltfFields {
  std::string path;
  int meshCount = 0;
  py::list fields;
  py::list problems;
  bool hasError = false;
};

py::dict problemDict(const bake::GltfFieldProblem& p) {
  py::dict d;
  d["rule"] = static_cast<int>(p.rule);
  d["name"] = bake::gltfFieldRuleName(p.rule);
  d["severity"] = bake::gltfSeverityName(p.severity);
  d["path"] = p.path;
  d["message"] = p.message;
  return d;
}

bool isMeshPath(const std::string& p, int mesh) {
  const std::string prefix = "/meshes/" + std::to_string(mesh);
  return p == prefix || p.rfind(prefix + "/", 0) == 0;
}

// Why a field that is not usable may not be opened: its mesh's first error, the mismatch, or a
// match never checked.
void refusal(const bake::GltfFieldsReport& r, PyGltfField* f) {
  const bake::GltfField& g = f->field;
  if (g.usable()) return;
  for (const bake::GltfFieldProblem& p : r.problems)
    if (isMeshPath(p.path, g.mesh) &&
        (p.severity == bake::GltfSeverity::kError || p.rule == bake::GltfFieldRule::kGeometryMismatch)) {
      f->refusedRule = static_cast<int>(p.rule), f->refusedPath = p.path, f->refusedMessage = p.message;
      return;
    }
  f->refusedPath = g.path;
  if (g.valid && g.match == bake::GltfFieldMatch::kUnchecked) {
    // Not a problem of the file: the caller asked for no match, and only a matched field is used.
    f->refusedRule = static_cast<int>(bake::GltfFieldRule::kGeometryExact);
    f->refusedMessage = "the field's geometry was not matched against its mesh (read with check_geometry=False): "
                        "read it again with check_geometry=True to use it";
  } else {
    f->refusedRule = static_cast<int>(bake::GltfFieldRule::kGeometryMismatch);
    f->refusedMessage = std::string("the field cannot be used (match ") + bake::gltfFieldMatchName(g.match) + ")";
  }
}

[[noreturn]] void raiseGltf(int rule, const std::string& path, const std::string& message) {
  py::object exc = py::module_::import("vff._errors")
                       .attr("GltfError")(rule, bake::gltfFieldRuleName(static_cast<bake::GltfFieldRule>(rule)),
                                          py::none(), py::none(), message, path);
  PyErr_SetObject(reinterpret_cast<PyObject*>(Py_TYPE(exc.ptr())), exc.ptr());
  throw py::error_already_set();
}

std::shared_ptr<PyGltfFields> readGltf(const std::string& path, bool checkGeometry) {
  bake::GltfFieldReadOptions ro;
  ro.checkGeometry = checkGeometry;
  Result<bake::GltfFieldsReport> r = [&] {
    py::gil_scoped_release unlocked;  // decoding the meshes and checking the payloads takes a while
    return bake::readGltfFields(path, ro);
  }();
  if (!r) raise(r.error());
  auto out = std::make_shared<PyGltfFields>();
  out->path = path;
  out->meshCount = r->meshCount;
  out->hasError = r->hasError();
  for (const bake::GltfFieldProblem& p : r->problems) out->problems.append(problemDict(p));
  for (bake::GltfField& g : r->fields) {
    auto f = std::make_shared<PyGltfField>();
    f->bytes = py::bytes(reinterpret_cast<const char*>(g.bytes.data()), g.bytes.size());
    for (const bake::GltfFieldNode& n : g.nodes) {
      py::dict d;
      d["node"] = n.node, d["name"] = n.name, d["answered"] = n.answered, d["reason"] = n.reason;
      f->nodes.append(d);
    }
    f->field = std::move(g);
    f->field.bytes.clear();  // (held once, by `bytes`)
    f->field.bytes.shrink_to_fit();
    refusal(*r, f.get());
    out->fields.append(py::cast(f));
  }
  return out;
}

std::shared_ptr<PyFile> openField(const PyGltfField& f, const std::string& checksums) {
  const ChecksumPolicy policy = checksumPolicy(checksums);
  if (!f.field.usable()) raiseGltf(f.refusedRule, f.refusedPath, f.refusedMessage);
  std::string_view b = f.bytes;
  std::vector<uint8_t> copy(b.begin(), b.end());
  ReadOptions ro;
  ro.checksums = policy;
  auto file = File::openBuffer(std::move(copy), ro);
  return std::make_shared<PyFile>(PyFile{"", take(std::move(file))});
}

py::object optionalString(const std::string& s) { return s.empty() ? py::object(py::none()) : py::object(py::str(s)); }

py::tuple triple(const std::array<float, 3>& v) { return py::make_tuple(v[0], v[1], v[2]); }

}  // namespace

void bindGltf(py::module_& m) {
  py::class_<PyGltfField, std::shared_ptr<PyGltfField>>(m, "GltfField", R"doc(
The field one mesh of a glTF asset carries (the extension VFF_visibility_field), as
vff.read_gltf_fields() found it: where it is, what it declares, how it matches the mesh as shipped,
the nodes it answers for, and its payload (a complete .vff file). open() gives it as a vff.File.)doc")
      .def_property_readonly("mesh", [](const PyGltfField& f) { return f.field.mesh; }, "The mesh's index.")
      .def_property_readonly("name", [](const PyGltfField& f) { return f.field.meshName; }, "The mesh's name (\"\" without one).")
      .def_property_readonly("path", [](const PyGltfField& f) { return f.field.path; },
                             "The JSON pointer of the extension object (\"/meshes/0/extensions/VFF_visibility_field\").")
      .def_property_readonly("buffer_view", [](const PyGltfField& f) {
        return f.field.bufferView >= 0 ? py::object(py::int_(f.field.bufferView)) : py::object(py::none()); },
                             "The payload's bufferView, or None.")
      .def_property_readonly("uri", [](const PyGltfField& f) { return optionalString(f.field.uri); },
                             "The payload's uri as written, or None.")
      .def_property_readonly("geometry_hash", [](const PyGltfField& f) { return f.field.geometryHash; },
                             "The geometryHash the extension declares (16 hex digits).")
      .def_property_readonly("min", [](const PyGltfField& f) { return triple(f.field.min); }, "The declared bounds' minimum (x, y, z).")
      .def_property_readonly("max", [](const PyGltfField& f) { return triple(f.field.max); }, "The declared bounds' maximum (x, y, z).")
      .def_property_readonly("mesh_geometry_hash", [](const PyGltfField& f) { return optionalString(f.field.meshGeometryHash); },
                             "The geometry hash of the mesh's triangles as shipped, or None when not computed.")
      .def_property_readonly("match", [](const PyGltfField& f) { return std::string(bake::gltfFieldMatchName(f.field.match)); },
                             "\"exact\", \"close\", \"mismatch\", or \"unchecked\" (not valid, or check_geometry=False).")
      .def_property_readonly("tolerance", [](const PyGltfField& f) { return f.field.tolerance; },
                             "tau = 2R/255, the bound difference a close match allows (0 when not matched).")
      .def_property_readonly("bounds_difference", [](const PyGltfField& f) { return f.field.boundsDifference; },
                             "The largest of the six differences between the declared and the shipped bounds.")
      .def_property_readonly("valid", [](const PyGltfField& f) { return f.field.valid; },
                             "No error (rules 14004 to 14011) on this mesh.")
      .def_property_readonly("usable", [](const PyGltfField& f) { return f.field.usable(); },
                             "Valid and matched exact or close: a reader may answer rays with it.")
      .def_property_readonly("nodes", [](const PyGltfField& f) { return f.nodes; }, R"doc(
The nodes that use the mesh, as dicts: node (index), name, answered (its world transform is a
similarity, unskinned, unmorphed), reason (why not: "non-uniform scale", "skin", ...; "" when answered).)doc")
      .def_property_readonly("bytes", [](const PyGltfField& f) { return f.bytes; },
                             "The payload: a complete .vff file (b\"\" when the field has an error).")
      .def("open", &openField, py::arg("checksums") = "all", R"doc(
The payload as a vff.File (in memory; its path is ""). checksums as vff.open(). Raises vff.GltfError
(its code the rule, its path the JSON pointer) when the field is not usable: an error on its mesh,
a geometry mismatch, or a match not checked (check_geometry=False).)doc")
      .def("__repr__", [](const PyGltfField& f) {
        return "<vff.GltfField mesh " + std::to_string(f.field.mesh) + " '" + f.field.meshName + "': " +
               bake::gltfFieldMatchName(f.field.match) + (f.field.valid ? "" : ", not valid") + ", " +
               std::to_string(py::len(f.bytes)) + " bytes>";
      });

  py::class_<PyGltfFields, std::shared_ptr<PyGltfFields>>(m, "GltfFields", R"doc(
What vff.read_gltf_fields() found in a glTF asset: its fields, one per mesh carrying the extension,
in mesh order, and every problem of the extension's rules, in check order.)doc")
      .def_property_readonly("path", [](const PyGltfFields& r) { return r.path; }, "The asset's path as given.")
      .def_property_readonly("mesh_count", [](const PyGltfFields& r) { return r.meshCount; }, "Meshes in the asset.")
      .def_property_readonly("fields", [](const PyGltfFields& r) { return r.fields; }, "The fields (a list of vff.GltfField).")
      .def_property_readonly("problems", [](const PyGltfFields& r) { return r.problems; }, R"doc(
Every problem, as dicts: rule (the ID, 14001 to 14104), name ("gltf-payload"), severity ("error",
"warning" or "note"), path (a JSON pointer; "" for the whole file), message.)doc")
      .def_property_readonly("has_error", [](const PyGltfFields& r) { return r.hasError; },
                             "Some problem is an error (a field with a warning or note is not one).")
      .def("__repr__", [](const PyGltfFields& r) {
        return "<vff.GltfFields '" + r.path + "': " + std::to_string(r.meshCount) + " meshes, " +
               std::to_string(py::len(r.fields)) + " fields, " + std::to_string(py::len(r.problems)) + " problems>";
      });

  m.def("read_gltf_fields", &readGltf, py::arg("path"), py::arg("check_geometry") = true, R"doc(
Reads the fields of a glTF asset (.gltf or .glb; a GLB by its magic) and checks them against the
extension's rules (spec/gltf/VFF_visibility_field/README.md): a vff.GltfFields. Every rule, a file
that is not glTF 2.0 included, is a problem in its report (has_error), not an exception; a file that
cannot be opened or read raises vff.IoError (an OSError). check_geometry: decode each mesh and match
its field against it (else every match is "unchecked" and no field is usable).)doc");
}

}  // namespace vff::python
