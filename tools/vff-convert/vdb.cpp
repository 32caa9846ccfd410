// vdb.cpp - the OpenVDB side of vff-convert (layout in vdb.h and README.md): a field's packed slices
// as sparse grids and back. The only unit of vff-convert that includes OpenVDB.
//
// The field JSON ("vff.field") has the members of the EXR export's attribute (exr.cpp) under its own
// format name; fieldJson/parseFieldJson and encodeNormalExact are interchange.cpp's, shared with exr.cpp.
#include "vdb.h"

#include <openvdb/io/Archive.h>
#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <xxhash.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <sstream>
#include <utility>
#include <vector>

#include "cli.h"
#include "vff/bake/exception_text.h"

namespace vff::convert {
namespace {

using nlohmann::json;

constexpr const char* kFormatName = "vff-convert-vdb/1";
constexpr unsigned char kVdbMagic[8] = {0x20, 0x42, 0x44, 0x56, 0, 0, 0, 0};  // int64 0x56444220, LE
// The header OpenVDB writes: magic (8), file version (4), library version (4 + 4), "has grid
// offsets" (1), then the UUID as 36 ASCII characters.
constexpr size_t kUuidOffset = 21, kUuidLength = 36;

// The provenance array: the source META's "vff.provenance" entries, then this export's entry (the
// shape of resample.h's appendProvenance, operation "to-vdb").
Result<std::string> provenanceJson(const FieldData& d, const VdbWriteOptions& o) {
  json list = json::array();
  if (!d.metadata.empty()) {
    const json meta = json::parse(d.metadata, nullptr, false);
    // The reader has checked META (rule 8001): a text nlohmann cannot hold has a number beyond binary64.
    if (meta.is_discarded())
      return makeError(Code::kUnsupported, "the source's META holds a number beyond the binary64 range");
    if (!meta.is_object()) return makeError(Code::kMetadataNotObject, "the source's META is not a JSON object");
    if (const auto it = meta.find("vff.provenance"); it != meta.end()) {
      if (!it->is_array()) return makeError(Code::kMetadataJson, "the source's META key \"vff.provenance\" is not an array");
      list = *it;
    }
  }
  list.push_back({{"tool", "vff-convert"},
                  {"version", kLibraryVersion},
                  {"operations", {"to-vdb"}},
                  {"options", json::object()},
                  {"source",
                   {{"name", o.sourceName},
                    {"format", o.sourceFormat},
                    {"xxh3", cli::hexDigits64(o.sourceXxh3)},
                    {"positionScheme", positionSchemeName(d.field.positionScheme)},
                    {"positionParam", d.field.positionParam},
                    {"mapCount", d.field.mapCount},
                    {"mapResolution", d.field.mapResolution},
                    {"distanceEncoding", distanceEncodingName(d.field.distanceEncoding)}}}});
  return list.dump();
}

// Archive::write with a seekable stream is what io::File::write does with its ofstream (grid
// offsets included, so readers can load one grid without the others); a subclass reaches it with
// a string stream, so the bytes can be fixed up and written atomically.
class MemoryArchive : public openvdb::io::Archive {
 public:
  void writeTo(std::ostream& os, const openvdb::GridCPtrVec& grids, const openvdb::MetaMap& meta) const {
    openvdb::io::Archive::write(os, grids, /*seekable=*/true, meta);
  }
};

// What an OpenVDB exception says, fit for a message (shared with the baker's level-set input).
using bake::exceptionText;

bool isUuidText(const std::string& s, size_t at) {
  if (s.size() < at + kUuidLength) return false;
  for (size_t k = 0; k < kUuidLength; ++k) {
    const char c = s[at + k];
    const bool dash = k == 8 || k == 13 || k == 18 || k == 23;
    if (dash ? c != '-' : !std::isxdigit(static_cast<unsigned char>(c))) return false;
  }
  return true;
}

// Replaces the random UUID by one made from XXH3-128 of everything after it (RFC 9562 version 8,
// "custom"), so that equal fields give equal files.
Status fixUuid(std::string* bytes) {
  if (bytes->size() < kUuidOffset + kUuidLength || std::memcmp(bytes->data(), kVdbMagic, 8) != 0 ||
      !isUuidText(*bytes, kUuidOffset))
    return makeError(Code::kUnsupported, "OpenVDB wrote a header this tool does not know (no UUID at byte 21)");
  const XXH128_hash_t h = XXH3_128bits(bytes->data() + kUuidOffset + kUuidLength,
                                       bytes->size() - kUuidOffset - kUuidLength);
  uint8_t u[16];
  for (int k = 0; k < 8; ++k) {
    u[k] = uint8_t(h.high64 >> (56 - 8 * k));
    u[8 + k] = uint8_t(h.low64 >> (56 - 8 * k));
  }
  u[6] = uint8_t((u[6] & 0x0f) | 0x80);  // version 8
  u[8] = uint8_t((u[8] & 0x3f) | 0x80);  // variant 10
  static const char* hex = "0123456789abcdef";
  std::string text;
  for (int k = 0; k < 16; ++k) {
    if (k == 4 || k == 6 || k == 8 || k == 10) text += '-';
    text += hex[u[k] >> 4];
    text += hex[u[k] & 15];
  }
  bytes->replace(kUuidOffset, kUuidLength, text);
  return {};
}

}  // namespace

bool looksLikeVdb(const std::string& path) { return startsWithBytes(path, kVdbMagic); }

Status writeVdb(const std::string& path, const FieldData& d, const VdbWriteOptions& options,
                VdbWriteReport* report) {
  const FieldDesc& f = d.field;
  const LayoutDesc& l = d.layout;
  const auto [m, g, normals, dBytes, nBytes, perSlice] = packedPlanes(d);
  const std::vector<float> cosines = texelCosines(f);
  auto provenance = provenanceJson(d, options);
  if (!provenance) return std::move(provenance).error();

  std::string bytes;
  try {
    openvdb::initialize();
    auto dist = openvdb::FloatGrid::create(std::numeric_limits<float>::infinity());
    dist->setName("distance");
    dist->setGridClass(openvdb::GRID_UNKNOWN);
    dist->setCreator(std::string("vff-convert ") + kLibraryVersion);
    dist->insertMeta("vff.plane", openvdb::StringMetadata("distance"));
    const Result<json> field = fieldJson(d, kFormatName);
    if (!field) return field.error();
    dist->insertMeta("vff.field", openvdb::StringMetadata(field->dump()));
    dist->insertMeta("vff.provenance", openvdb::StringMetadata(*provenance));
    openvdb::Vec3fGrid::Ptr norm;
    if (normals) {
      norm = openvdb::Vec3fGrid::create(openvdb::Vec3f(0.0f));
      norm->setName("normal");
      norm->setVectorType(openvdb::VEC_INVARIANT);
      norm->setCreator(std::string("vff-convert ") + kLibraryVersion);
      norm->insertMeta("vff.plane", openvdb::StringMetadata("normal"));
    }
    auto da = dist->getAccessor();
    std::optional<openvdb::Vec3fGrid::Accessor> na;
    if (norm) na.emplace(norm->getAccessor());
    // The slices as the EXR export composes them: each map at its placement with its gutter
    // (replicated edge texels); unused tiles stay background.
    for (uint32_t s = 0; s < l.sliceCount; ++s) {
      const uint32_t first = s * perSlice, last = std::min(f.mapCount, first + perSlice);
      for (uint32_t k = first; k < last; ++k) {
        const TilePlacement p = placeMap(l, k);
        const std::span<const uint8_t> dmap(d.distance.data() + k * dBytes, dBytes);
        for (int64_t ty = -g; ty < int64_t{m} + g; ++ty) {
          for (int64_t tx = -g; tx < int64_t{m} + g; ++tx) {
            const uint32_t i = clampToMap(tx, m), j = clampToMap(ty, m);
            const uint32_t code = loadCode(f.distanceEncoding, dmap, m, i, j);
            const Texel t = decodeDistance(f.distanceEncoding, code, f.sphere.radius, cosines[uint64_t{j} * m + i]);
            if (!t.hit) continue;
            const openvdb::Coord c(static_cast<int32_t>(int64_t{p.x} + tx), static_cast<int32_t>(int64_t{p.y} + ty),
                                   static_cast<int32_t>(s));
            da.setValueOn(c, t.distance);
            if (na) {
              const Vec3 n = decodeNormal(d.normals.data() + k * nBytes + 4 * (uint64_t{j} * m + i));
              na->setValueOn(c, openvdb::Vec3f(n.x, n.y, n.z));
            }
          }
        }
      }
    }
    if (report) report->activeVoxels = dist->activeVoxelCount();
    openvdb::GridCPtrVec grids{dist};
    if (norm) grids.push_back(norm);
    std::ostringstream os(std::ios_base::out | std::ios_base::binary);
    MemoryArchive().writeTo(os, grids, openvdb::MetaMap());
    bytes = std::move(os).str();
  } catch (const std::bad_alloc&) {
    return makeError(Code::kOutOfMemory, path + ": out of memory while building the grids");
  } catch (const std::exception& e) {
    return makeError(Code::kIoWrite, path + ": cannot be written as OpenVDB: " + exceptionText(e));
  }
  if (Status s = fixUuid(&bytes); !s) return s;
  return cli::writeFileAtomic(path, std::span<const uint8_t>(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size()));
}

Result<FieldData> readVdb(const std::string& path, VdbReadReport* report) {
  *report = {};
  if (std::FILE* probe = std::fopen(path.c_str(), "rb")) {
    std::fclose(probe);
  } else {
    return makeError(Code::kIoOpen, path + ": " + std::strerror(errno));
  }
  if (!looksLikeVdb(path)) return makeError(Code::kBadMagic, "not an OpenVDB file (no .vdb magic number)");
  FieldData d;
  try {
    openvdb::initialize();
    openvdb::io::File file(path);
    file.open(/*delayLoad=*/false);
    const openvdb::GridPtrVecPtr headers = file.readAllGridMetadata();
    openvdb::GridBase::ConstPtr fieldGrid;
    for (const auto& h : *headers)
      if (h->getMetadata<openvdb::StringMetadata>("vff.field")) {
        fieldGrid = h;
        break;
      }
    if (!fieldGrid)
      return makeError(Code::kMissingSection,
                       "no grid with the string metadata vff.field: the file was not written by vff-convert --to vdb");
    if (Status s = parseFieldJson(fieldGrid->getMetadata<openvdb::StringMetadata>("vff.field")->value(), kFormatName, "metadata vff.field", &d); !s)
      return s.error();

    const FieldDesc& f = d.field;
    const LayoutDesc& l = d.layout;
    const uint32_t m = f.mapResolution;
    const bool normals = f.normalEncoding != NormalEncoding::kNone;
    const uint64_t dBytes = distanceMapBytes(f.distanceEncoding, m);
    const uint64_t nBytes = normalMapBytes(f.normalEncoding, m);
    const uint32_t perSlice = l.tilesPerRow * l.tilesPerColumn;
    const std::vector<float> cosines = texelCosines(f);

    // Every grid checked before the planes are allocated.
    const auto inSlices = [&](const openvdb::GridBase& grid, const char* name) -> Status {
      const openvdb::CoordBBox box = grid.evalActiveVoxelBoundingBox();
      if (grid.activeVoxelCount() == 0) return {};
      if (box.min().x() < 0 || box.min().y() < 0 || box.min().z() < 0 || box.max().x() >= int64_t{l.sliceWidth} ||
          box.max().y() >= int64_t{l.sliceHeight} || box.max().z() >= int64_t{l.sliceCount})
        return makeError(Code::kLayoutGeometry,
                         std::string("grid \"") + name + "\" has active voxels outside the " + std::to_string(l.sliceCount) +
                             " slices of " + std::to_string(l.sliceWidth) + "x" + std::to_string(l.sliceHeight));
      return {};
    };
    if (!fieldGrid->isType<openvdb::FloatGrid>())
      return makeError(Code::kLayoutGeometry, "grid \"" + fieldGrid->getName() + "\" (vff.field) is not a float grid");
    auto dist = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid(fieldGrid->getName()));
    if (!dist) return makeError(Code::kLayoutGeometry, "cannot read grid \"" + fieldGrid->getName() + "\" as a float grid");
    if (Status s = inSlices(*dist, "distance"); !s) return s.error();
    openvdb::Vec3fGrid::Ptr norm;
    if (normals) {
      bool found = false;
      for (const auto& h : *headers) found = found || h->getName() == "normal";
      if (!found) return makeError(Code::kLayoutGeometry, "the field has normals but the file has no grid \"normal\"");
      norm = openvdb::gridPtrCast<openvdb::Vec3fGrid>(file.readGrid("normal"));
      if (!norm) return makeError(Code::kLayoutGeometry, "grid \"normal\" is not a vec3s grid");
      if (Status s = inSlices(*norm, "normal"); !s) return s.error();
    }
    file.close();
    report->activeVoxels = dist->activeVoxelCount();

    d.distance.assign(uint64_t{f.mapCount} * dBytes, 0);
    if (normals) d.normals.assign(uint64_t{f.mapCount} * nBytes, 0);
    auto da = dist->getConstAccessor();
    std::optional<openvdb::Vec3fGrid::ConstAccessor> na;
    if (norm) na.emplace(norm->getConstAccessor());
    for (uint32_t k = 0; k < f.mapCount; ++k) {
      const TilePlacement p = placeMap(l, k);
      const std::span<uint8_t> dmap(d.distance.data() + k * dBytes, dBytes);
      const auto slice = static_cast<int32_t>(k / perSlice);
      for (uint32_t j = 0; j < m; ++j) {
        for (uint32_t i = 0; i < m; ++i) {
          const openvdb::Coord c(static_cast<int32_t>(p.x + i), static_cast<int32_t>(p.y + j), slice);
          float v = 0;
          const bool hit = da.probeValue(c, v);
          const float cosAlpha = cosines[uint64_t{j} * m + i];
          const uint32_t code = encodeDistance(f.distanceEncoding, hit, v, f.sphere.radius, cosAlpha);
          storeCode(f.distanceEncoding, dmap, m, i, j, code);
          if (!hit) continue;
          if (!sameValue(decodeDistance(f.distanceEncoding, code, f.sphere.radius, cosAlpha).distance, v, /*half=*/false))
            ++report->inexactTexels;
          if (na) {
            const openvdb::Vec3f n = na->getValue(c);
            if (!encodeNormalExact({n.x(), n.y(), n.z()}, /*half=*/false, d.normals.data() + k * nBytes + 4 * (uint64_t{j} * m + i)))
              ++report->inexactNormals;
          }
        }
      }
    }
  } catch (const std::bad_alloc&) {
    return makeError(Code::kOutOfMemory, "out of memory while reading " + path);
  } catch (const std::exception& e) {
    // The file opened and has the magic number, so a failure here is a corrupt or truncated file.
    return makeError(Code::kSectionDecode, path + ": cannot be read as OpenVDB (corrupt or truncated): " + exceptionText(e));
  }
  return d;
}

}  // namespace vff::convert
