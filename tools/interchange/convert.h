// convert.h - what vff-convert's parts share: a whole field held in memory, and the EXR side.
#pragma once

#include <nlohmann/json.hpp>

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "vff/vff.h"

namespace vff::convert {

// A field with its raw planes, plus what is needed to write it again as it was.
struct FieldData {
  FieldDesc field;
  LayoutDesc layout;              // the source's packed layout (maps are placed by it in the EXR)
  std::string metadata;           // META JSON text, empty for none
  Codec codec = Codec::kStored;   // the source's block codec (of its first distance block)
  uint32_t mapsPerBlock = 0;      // the source's G as a WriteOptions value (0: the writer's automatic G)
  std::vector<uint8_t> distance;  // mapCount * distanceMapBytes
  std::vector<uint8_t> normals;   // mapCount * normalMapBytes, empty without a normal field
  Refinement refinement;          // the source's REFN (vff/refine.h), empty for none
};

// What the EXR and OpenVDB writers read of a field's packed layout: the map size, the gutter,
// whether there is a normal plane, the bytes of a map of each plane and the maps of a slice.
struct PackedPlanes {
  uint32_t mapResolution;
  int64_t gutter;
  bool normals;
  uint64_t distanceMapBytes, normalMapBytes;
  uint32_t mapsPerSlice;
};
inline PackedPlanes packedPlanes(const FieldData& d) {
  const FieldDesc& f = d.field;
  return {f.mapResolution, d.layout.gutter, f.normalEncoding != NormalEncoding::kNone,
          distanceMapBytes(f.distanceEncoding, f.mapResolution), normalMapBytes(f.normalEncoding, f.mapResolution),
          d.layout.tilesPerRow * d.layout.tilesPerColumn};
}

enum class ExrCompression { kNone, kZip, kPiz, kDwaa };  // DWAA is lossy

struct ExrWriteOptions {
  bool half = false;  // HALF instead of FLOAT for Y and the normal's RGB
  ExrCompression compression = ExrCompression::kZip;
};

// Writes `data` as a multi-part OpenEXR file through a temporary file in the same folder and a
// rename: parts "slice.S" (channels Y, miss) and, with normals, "normal.S" (channels R, G, B), each
// sliceWidth x sliceHeight with the slice's gutters and unused tiles, and the string attribute
// "vff.field" (JSON) in the first part. Fails with kIoWrite naming the file.
Status writeExr(const std::string& path, const FieldData& data, const ExrWriteOptions& options);

struct ExrReadReport {
  bool half = false;             // Y is stored as HALF
  uint64_t inexactTexels = 0;    // hits whose Y is not what the exporter writes for any code
  uint64_t ambiguousTexels = 0;  // HALF hits whose Y the exporter writes for more than one code
  uint64_t inexactNormals = 0;   // normals whose RGB is not a decoded oct-snorm16 normal
};

// Reads an EXR written by writeExr back into raw planes: each hit's Y is encoded again with
// encodeDistance, the normal's RGB with encodeNormal; `report` counts values that were not exact.
Result<FieldData> readExr(const std::string& path, ExrReadReport* report);

// True when the file starts with the OpenEXR magic number.
bool looksLikeExr(const std::string& path);

// ---- Shared by the EXR and OpenVDB sides (interchange.cpp) ----------------------------------------
// The "vff.field" JSON: {"format": formatName, "field", "layout", "metadata", "codec", "mapsPerBlock"}.
// kUnsupported when the metadata holds a number beyond binary64, which nlohmann::json cannot hold.
Result<nlohmann::json> fieldJson(const FieldData& data, const char* formatName);
// Parses it into `data` (everything but the planes) and checks it with libvff; errors
// (kMetadataJson, or libvff's) start with `where`, e.g. "attribute vff.field".
Status parseFieldJson(const std::string& text, const char* formatName, const std::string& where, FieldData* data);
// cos(alpha) of every texel centre of a map (row-major), for unorm8-chord.
std::vector<float> texelCosines(const FieldDesc& field);
// True when the file at `path` starts with `magic` (at most 16 bytes); false when it cannot be read.
bool startsWithBytes(const std::string& path, std::span<const unsigned char> magic);
// v clamped to [0, m - 1]: the map texel a gutter texel replicates.
uint32_t clampToMap(int64_t v, uint32_t m);
// v rounded to HALF when `half` (to nearest even, as Imath::half and the EXR export do), else v.
float roundToType(float v, bool half);
// v, rounded to HALF when `half`, is exactly `stored` (the sign of a zero included).
bool sameValue(float v, float stored, bool half);
// encodeNormal, then, when its code does not decode to exactly `n` (rounded to HALF when `half`),
// the codes mirrored across the octahedron's seams; returns whether the stored code decodes to `n`.
bool encodeNormalExact(Vec3 n, bool half, uint8_t out[4]);

}  // namespace vff::convert
