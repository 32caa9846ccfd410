// file.cpp - vff.open and vff.File: the description as attributes, metadata, validation, and the
// maps as numpy arrays that view the file's memory and keep the File alive.
#include <pybind11/stl.h>

#include <nlohmann/json.hpp>

#include "bindings.h"
#include "errors.h"

namespace py = pybind11;

namespace vff::python {

ChecksumPolicy checksumPolicy(const std::string& s) {
  if (s == "all") return ChecksumPolicy::kVerifyAll;
  if (s == "lazy") return ChecksumPolicy::kLazy;
  if (s == "none") return ChecksumPolicy::kNone;
  throw py::value_error("checksums: expected \"all\", \"lazy\" or \"none\", got \"" + s + "\"");
}

namespace {

Plane planeOf(const std::string& s) {
  if (s == "distance") return Plane::kDistance;
  if (s == "normal") return Plane::kNormal;
  throw py::value_error("plane: expected \"distance\" or \"normal\", got \"" + s + "\"");
}

// The numpy dtype and per-map shape of a plane's maps:
//   unorm8-*: (M, M) uint8; unorm16-diameter: (M, M) '<u2'; bit1: (M*M/8,) uint8 (LSB first);
//   bc4-diameter: (M/4, M/4, 8) uint8 (one BC4 block per 8 bytes); normals: (M, M, 2) '<i2'.
struct MapShape {
  py::dtype dtype;
  std::vector<py::ssize_t> shape;
};
MapShape mapShape(const File& f, Plane p) {
  const py::ssize_t m = f.field().mapResolution;
  if (p == Plane::kNormal) return {py::dtype("<i2"), {m, m, 2}};
  switch (f.field().distanceEncoding) {
    case DistanceEncoding::kUnorm16Diameter: return {py::dtype("<u2"), {m, m}};
    case DistanceEncoding::kBit1: return {py::dtype("u1"), {m * m / 8}};
    case DistanceEncoding::kBc4Diameter: return {py::dtype("u1"), {m / 4, m / 4, 8}};
    default: return {py::dtype("u1"), {m, m}};
  }
}

std::vector<py::ssize_t> cStrides(const std::vector<py::ssize_t>& shape, py::ssize_t item) {
  std::vector<py::ssize_t> s(shape.size());
  py::ssize_t acc = item;
  for (size_t i = shape.size(); i-- > 0;) s[i] = acc, acc *= shape[i];
  return s;
}

// A read-only array over `bytes` (memory of the File) whose base is the Python File object.
py::array viewOf(py::object owner, const MapShape& ms, const uint8_t* data, std::vector<py::ssize_t> shape) {
  const auto strides = cStrides(shape, ms.dtype.itemsize());
  py::array a(ms.dtype, shape, strides, data, owner);
  py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return a;
}

// A map index given from Python (any integer, so that -1 is this error rather than pybind11's
// "incompatible function arguments"), or an IndexError naming the range.
uint32_t mapIndex(const File& f, int64_t map) {
  const uint32_t n = f.field().mapCount;
  if (map < 0 || map >= int64_t(n))
    throw py::index_error("index: map " + std::to_string(map) + " out of range [0, " + std::to_string(int64_t(n) - 1) +
                          "]: the field has " + std::to_string(n) + " map" + (n == 1 ? "" : "s"));
  return uint32_t(map);
}

py::array mapArray(const std::shared_ptr<PyFile>& self, int64_t index, const std::string& plane) {
  const Plane p = planeOf(plane);
  const uint32_t map = mapIndex(self->file, index);
  const auto bytes = take(self->file.mapData(p, map));
  const MapShape ms = mapShape(self->file, p);
  return viewOf(py::cast(self), ms, bytes.data(), ms.shape);
}

// All maps of a plane: a view when they lie one after the other in memory (stored blocks without
// padding between them), else a copy.
py::array mapsArray(const std::shared_ptr<PyFile>& self, const std::string& plane) {
  const Plane p = planeOf(plane);
  const File& f = self->file;
  const uint32_t n = f.field().mapCount;
  const uint64_t mapBytes = f.plane(p).mapBytes;
  if (!f.plane(p).present) raise(makeError(Code::kPlanePresence, "the field has no " + plane + " plane"));
  const MapShape ms = mapShape(f, p);
  std::vector<py::ssize_t> shape{py::ssize_t(n)};
  shape.insert(shape.end(), ms.shape.begin(), ms.shape.end());
  const uint8_t* first = take(f.mapData(p, 0)).data();
  bool contiguous = true;
  for (uint32_t i = 1; i < n && contiguous; ++i) contiguous = take(f.mapData(p, i)).data() == first + i * mapBytes;
  if (contiguous) return viewOf(py::cast(self), ms, first, shape);
  py::array out(ms.dtype, shape);
  auto* dst = static_cast<uint8_t*>(out.mutable_data());
  for (uint32_t i = 0; i < n; ++i) {
    const auto src = take(f.mapData(p, i));
    std::memcpy(dst + i * mapBytes, src.data(), mapBytes);
  }
  return out;
}

py::array sliceArray(const PyFile& self, uint32_t slice, const std::string& plane) {
  const Plane p = planeOf(plane);
  const File& f = self.file;
  if (slice >= f.layout().sliceCount)
    throw py::index_error("slice " + std::to_string(slice) + " out of range: the layout has " +
                          std::to_string(f.layout().sliceCount) + " slices");
  py::array_t<uint8_t> out(py::ssize_t(f.sliceBytes(p)));
  std::span<uint8_t> dst(out.mutable_data(), size_t(out.size()));
  check(f.readSlice(p, slice, dst));
  return out;
}

// The decoded distances of one map, [j, i] for texel (i, j): NaN for a miss; bit1: 1 hit, 0 miss.
py::array_t<float> distancesArray(const PyFile& self, int64_t index) {
  const File& f = self.file;
  const FieldDesc& d = f.field();
  const uint32_t map = mapIndex(f, index);
  const auto bytes = take(f.mapData(Plane::kDistance, map));
  const uint32_t m = d.mapResolution;
  py::array_t<float> out({py::ssize_t(m), py::ssize_t(m)});
  float* dst = out.mutable_data();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (uint32_t j = 0; j < m; ++j)
    for (uint32_t i = 0; i < m; ++i) {
      const Vec3 dir = texelDirection(d.directionScheme, m, i, j);
      const Texel t = decodeDistance(d.distanceEncoding, loadCode(d.distanceEncoding, bytes, m, i, j), d.sphere.radius, dir.z);
      dst[j * m + i] = d.distanceEncoding == DistanceEncoding::kBit1 ? (t.hit ? 1.0f : 0.0f) : (t.hit ? t.distance : nan);
    }
  return out;
}

// The decoded normals of one map, [j, i, xyz]: NaN where the distance is a miss.
py::array_t<float> normalsArray(const PyFile& self, int64_t index) {
  const File& f = self.file;
  const FieldDesc& d = f.field();
  const uint32_t map = mapIndex(f, index);
  if (!f.hasNormals()) raise(makeError(Code::kPlanePresence, "the field has no normal plane"));
  const auto dist = take(f.mapData(Plane::kDistance, map));
  const auto norm = take(f.mapData(Plane::kNormal, map));
  const uint32_t m = d.mapResolution;
  py::array_t<float> out({py::ssize_t(m), py::ssize_t(m), py::ssize_t(3)});
  float* dst = out.mutable_data();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (uint32_t t = 0; t < m * m; ++t) {
    const bool hit = loadCode(d.distanceEncoding, dist, m, t % m, t / m) != missCode(d.distanceEncoding);
    const Vec3 n = decodeNormal(norm.data() + 4 * size_t(t));
    dst[3 * t] = hit ? n.x : nan, dst[3 * t + 1] = hit ? n.y : nan, dst[3 * t + 2] = hit ? n.z : nan;
  }
  return out;
}

py::list validateFile(const PyFile& self, bool decodeBlocks) {
  ValidateOptions vo;
  vo.decodeBlocks = decodeBlocks;
  const Report report = validate(self.file.bytes(), vo);
  py::module_ types = py::module_::import("vff");
  py::object problem = types.attr("Problem");
  py::list out;
  for (const Issue& i : report.issues)
    out.append(problem(uint32_t(i.code), codeName(i.code), severityName(i.severity), sectionObject(i.section),
                       offsetObject(i.offset), i.message));
  return out;
}

py::object metadataDict(const PyFile& self) {
  const std::string_view text = self.file.metadata();
  if (text.empty()) return py::dict();
  return py::module_::import("json").attr("loads")(py::str(text.data(), text.size()));
}

// A partial result (spec/partial.md: META has "vff.partial"): None for a whole field, else the tuple
// (mapBegin, mapEnd), both None when "vff.partial" gives no range mapBegin < mapEnd <= mapCount =
// FDSC mapCount.
py::object partialRange(const PyFile& self) {
  const std::string_view text = self.file.metadata();
  const nlohmann::json meta = nlohmann::json::parse(text.begin(), text.end(), nullptr, /*allow_exceptions=*/false);
  if (!meta.is_object() || !meta.contains("vff.partial")) return py::none();
  const nlohmann::json& p = meta["vff.partial"];
  auto u32 = [&](const char* k) { return p.contains(k) && p[k].is_number_unsigned() && p[k].get<uint64_t>() <= UINT32_MAX; };
  if (p.is_object() && u32("mapBegin") && u32("mapEnd") && u32("mapCount")) {
    const uint64_t begin = p["mapBegin"], end = p["mapEnd"], count = p["mapCount"];
    if (begin < end && end <= count && count == self.file.field().mapCount) return py::make_tuple(begin, end);
  }
  return py::make_tuple(py::none(), py::none());
}

}  // namespace

std::shared_ptr<PyFile> openFile(const std::string& path, const std::string& checksums) {
  ReadOptions ro;
  ro.checksums = checksumPolicy(checksums);
  Result<File> f = [&] {
    py::gil_scoped_release unlocked;  // checksumming a large file takes a while
    return File::open(path, ro);
  }();
  return std::make_shared<PyFile>(PyFile{path, take(std::move(f))});
}

py::dict describe(const File& f) {
  const FieldDesc& d = f.field();
  const LayoutDesc& l = f.layout();
  const FileInfo& info = f.info();
  py::dict doc;
  doc["version"] = py::make_tuple(info.versionMajor, info.versionMinor);
  doc["file_size"] = info.fileSize;
  doc["incompat_features"] = info.incompatFeatures;
  doc["ro_compat_features"] = info.roCompatFeatures;
  py::list sections;
  for (const SectionInfo& s : info.sections) {
    py::dict e;
    e["tag"] = sectionTagName(s.tag), e["flags"] = s.flags, e["offset"] = s.offset, e["stored_size"] = s.storedSize;
    e["raw_size"] = s.rawSize, e["codec"] = codecName(s.codec), e["known"] = s.known;
    sections.append(e);
  }
  doc["sections"] = sections;
  py::dict field;
  field["center"] = py::make_tuple(d.sphere.center[0], d.sphere.center[1], d.sphere.center[2]);
  field["radius"] = d.sphere.radius;
  field["position_scheme"] = positionSchemeName(d.positionScheme);
  field["position_param"] = d.positionParam;
  field["map_count"] = d.mapCount;
  field["direction_scheme"] = directionSchemeName(d.directionScheme);
  field["map_resolution"] = d.mapResolution;
  field["frame"] = frameConventionName(d.frame);
  field["distance_encoding"] = distanceEncodingName(d.distanceEncoding);
  field["miss_code"] = missCode(d.distanceEncoding);
  field["normal_encoding"] = normalEncodingName(d.normalEncoding);
  doc["field"] = field;
  py::dict layout;
  layout["target"] = layoutTargetName(l.target), layout["gutter"] = l.gutter, layout["tile_size"] = l.tileSize;
  layout["tiles_per_row"] = l.tilesPerRow, layout["tiles_per_column"] = l.tilesPerColumn;
  layout["slice_width"] = l.sliceWidth, layout["slice_height"] = l.sliceHeight, layout["slice_count"] = l.sliceCount;
  layout["max_texture_size"] = l.maxTextureSize, layout["max_layers"] = l.maxLayers;
  doc["layout"] = layout;
  py::dict planes;
  for (Plane p : {Plane::kDistance, Plane::kNormal}) {
    const PlaneInfo& pi = f.plane(p);
    if (!pi.present) continue;
    py::dict e;
    e["map_bytes"] = pi.mapBytes, e["maps_per_block"] = pi.mapsPerBlock, e["raw_bytes"] = pi.rawBytes;
    e["stored_bytes"] = pi.storedBytes;
    py::list codecs, filters;
    for (const BlockInfo& b : pi.blocks) codecs.append(codecName(b.codec)), filters.append(filterName(b.filter));
    e["block_codecs"] = codecs, e["block_filters"] = filters;
    planes[planeName(p)] = e;
  }
  doc["planes"] = planes;
  return doc;
}

void bindFile(py::module_& m) {
  py::class_<PyFile, std::shared_ptr<PyFile>>(m, "File", R"doc(
An open .vff file (memory-mapped, read-only). Made by vff.open(). Every array and query made from it
keeps it alive, so `del f` never invalidates them.)doc")
      .def_property_readonly("path", [](const PyFile& f) { return f.path; }, "The path it was opened from.")
      .def_property_readonly("version", [](const PyFile& f) { return py::make_tuple(f.file.info().versionMajor, f.file.info().versionMinor); },
                             "The format version (major, minor).")
      .def_property_readonly("file_size", [](const PyFile& f) { return f.file.info().fileSize; }, "Bytes in the file.")
      .def_property_readonly("center", [](const PyFile& f) { const auto& c = f.file.field().sphere.center; return py::make_tuple(c[0], c[1], c[2]); },
                             "The bounding sphere's centre (x, y, z), object space.")
      .def_property_readonly("radius", [](const PyFile& f) { return f.file.field().sphere.radius; }, "The bounding sphere's radius R.")
      .def_property_readonly("position_scheme", [](const PyFile& f) { return positionSchemeName(f.file.field().positionScheme); },
                             "The positional-sample scheme (\"octa-hemi2\", \"ea-octa-grid\", \"fibonacci\").")
      .def_property_readonly("position_param", [](const PyFile& f) { return f.file.field().positionParam; }, "The scheme's parameter n.")
      .def_property_readonly("map_count", [](const PyFile& f) { return f.file.field().mapCount; }, "Positional samples (maps).")
      .def_property_readonly("direction_scheme", [](const PyFile& f) { return directionSchemeName(f.file.field().directionScheme); },
                             "The hemisphere-to-square map.")
      .def_property_readonly("map_resolution", [](const PyFile& f) { return f.file.field().mapResolution; }, "M: each map is M x M texels.")
      .def_property_readonly("frame", [](const PyFile& f) { return frameConventionName(f.file.field().frame); }, "The tangent-frame convention.")
      .def_property_readonly("distance_encoding", [](const PyFile& f) { return distanceEncodingName(f.file.field().distanceEncoding); },
                             "How a texel stores its distance (\"unorm8-diameter\", ...).")
      .def_property_readonly("miss_code", [](const PyFile& f) { return missCode(f.file.field().distanceEncoding); }, "The code of a miss.")
      .def_property_readonly("normal_encoding", [](const PyFile& f) { return normalEncodingName(f.file.field().normalEncoding); },
                             "\"none\" or \"oct-snorm16\".")
      .def_property_readonly("has_normals", [](const PyFile& f) { return f.file.hasNormals(); }, "The file has a normal plane.")
      .def_property_readonly("layout", [](const PyFile& f) { return py::object(describe(f.file)["layout"]); }, "The packed slice layout, as a dict.")
      .def_property_readonly("sections", [](const PyFile& f) { return py::object(describe(f.file)["sections"]); }, "The section table, as a list of dicts.")
      .def_property_readonly("metadata", &metadataDict, "The META JSON object as a dict ({} without META).")
      .def_property_readonly("metadata_text", [](const PyFile& f) { return std::string(f.file.metadata()); },
                             "The META JSON text exactly as stored (empty without META).")
      .def_property_readonly("partial", &partialRange, R"doc(
None, or for a partial result of vff-bake --map-range (spec/partial.md) the range (map_begin,
map_end) of the field's maps it holds, both None when its "vff.partial" gives no valid range. Its
other maps are fillers: vff.FieldQuery refuses such a file (vff.UnsupportedError).)doc")
      .def("describe", [](const PyFile& f) { return describe(f.file); }, "Everything vff.inspect() reports, as a dict.")
      .def("validate", &validateFile, py::arg("decode_blocks") = true, R"doc(
Runs the full validator over the file's bytes. Returns a list of vff.Problem (id, name, severity,
section, offset, message); empty when the file is valid. decode_blocks: also decode every
compressed block and check every value.)doc")
      .def("map", &mapArray, py::arg("index"), py::arg("plane") = "distance", R"doc(
The raw texels of one map as a read-only numpy array viewing the file's memory (zero-copy; for a
compressed block, its decoded copy cached by the File). Shapes: unorm8-*: (M, M) uint8;
unorm16-diameter: (M, M) '<u2'; bit1: (M*M/8,) uint8, LSB first; bc4-diameter: (M/4, M/4, 8) uint8;
plane="normal": (M, M, 2) '<i2' (octahedral snorm16). The array keeps the File alive.)doc")
      .def("maps", &mapsArray, py::arg("plane") = "distance", R"doc(
Every map of a plane, shape (map_count,) + map(0).shape: a zero-copy view when the maps lie one
after another in memory (stored blocks), else a copy.)doc")
      .def("distances", &distancesArray, py::arg("index"), R"doc(
The decoded distances of one map as a (M, M) float32 array (a copy), [j, i] for texel (i, j):
object-space distance from the sphere entry to the surface, NaN for a miss; for bit1, 1 for a hit
and 0 for a miss.)doc")
      .def("normals", &normalsArray, py::arg("index"), R"doc(
The decoded unit normals of one map as a (M, M, 3) float32 array (a copy), NaN where the ray
missed. Raises vff.InvalidFileError (plane-presence) without a normal plane.)doc")
      .def("slice", &sliceArray, py::arg("index"), py::arg("plane") = "distance", R"doc(
One packed slice of the layout (a copy): File::readSlice's bytes as a flat uint8 array.)doc")
      .def("__repr__", [](const PyFile& f) {
        const FieldDesc& d = f.file.field();
        return "<vff.File '" + f.path + "': " + std::to_string(d.mapCount) + " maps of " + std::to_string(d.mapResolution) +
               "x" + std::to_string(d.mapResolution) + ", " + distanceEncodingName(d.distanceEncoding) + ">";
      });
  m.def("open", &openFile, py::arg("path"), py::arg("checksums") = "all", R"doc(
Opens a .vff file (memory-mapped). checksums: "all" (every checksum at open), "lazy" (the blocks'
when first decoded) or "none". Raises vff.IoError or vff.InvalidFileError (with the validation ID,
section and offset) when it cannot be read.)doc");
  m.def("inspect", [](const std::string& path) {
    auto f = openFile(path, "all");
    py::dict d = describe(f->file);
    d["path"] = path;
    d["metadata"] = metadataDict(*f);
    d["problems"] = validateFile(*f, true);
    return d;
  }, py::arg("path"), R"doc(
What vff-inspect reports about a file, as a dict: version, sections, field, layout, planes,
metadata, and the validator's problems (a list of vff.Problem).)doc");
}

}  // namespace vff::python
