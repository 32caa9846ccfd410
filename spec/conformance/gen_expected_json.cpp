// gen_expected_json.cpp - the expected.json of each valid conformance vector (gen_valid.h): computed
// from the source content and the writer's options, plus the parts of the file's structure a reader
// reports (sections, blocks), taken from the bytes. Written by hand, not with a JSON library, for
// compact rows (one map row per line).
#include <cstdio>
#include <cstring>
#include <span>
#include <string>
#include <string_view>

#include "gen_reference.h"
#include "gen_valid.h"
#include "gen_vff.h"

namespace vff::gen {

namespace {

// ---- Small JSON text writer (the expected.json files are written by hand for compact rows) --------
std::string jstr(std::string_view s) {
  std::string o = "\"";
  for (char ch : s) {
    const auto c = static_cast<unsigned char>(ch);
    if (c == '"' || c == '\\') {
      o += '\\';
      o += ch;
    } else if (c < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      o += buf;
    } else {
      o += ch;
    }
  }
  return o + "\"";
}
std::string jnum(double v, int digits = 9) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.*g", digits, v);
  return buf;
}
std::string jfix(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.6f", v);
  if (std::strcmp(buf, "-0.000000") == 0) return "0.000000";
  return buf;
}

std::string fieldJson(const FieldDesc& f) {
  std::string s = "{\n";
  s += "    \"sphere\": {\"center\": [" + jnum(f.sphere.center[0]) + ", " + jnum(f.sphere.center[1]) + ", " +
       jnum(f.sphere.center[2]) + "], \"radius\": " + jnum(f.sphere.radius) + "},\n";
  s += "    \"positionScheme\": " + jstr(positionSchemeName(f.positionScheme)) +
       ", \"positionParam\": " + std::to_string(f.positionParam) + ", \"mapCount\": " + std::to_string(f.mapCount) +
       ",\n";
  s += "    \"directionScheme\": " + jstr(directionSchemeName(f.directionScheme)) +
       ", \"mapResolution\": " + std::to_string(f.mapResolution) +
       ", \"frame\": " + jstr(frameConventionName(f.frame)) + ",\n";
  s += "    \"distanceEncoding\": " + jstr(distanceEncodingName(f.distanceEncoding)) +
       ", \"missCode\": " + std::to_string(missCode(f.distanceEncoding)) +
       ", \"normalEncoding\": " + jstr(normalEncodingName(f.normalEncoding)) + "\n  }";
  return s;
}

std::string layoutJson(const LayoutDesc& l) {
  return "{\"target\": " + jstr(layoutTargetName(l.target)) + ", \"gutter\": " + std::to_string(l.gutter) +
         ", \"tileSize\": " + std::to_string(l.tileSize) + ", \"tilesPerRow\": " + std::to_string(l.tilesPerRow) +
         ", \"tilesPerColumn\": " + std::to_string(l.tilesPerColumn) +
         ",\n    \"sliceWidth\": " + std::to_string(l.sliceWidth) +
         ", \"sliceHeight\": " + std::to_string(l.sliceHeight) + ", \"sliceCount\": " + std::to_string(l.sliceCount) +
         ", \"maxTextureSize\": " + std::to_string(l.maxTextureSize) +
         ", \"maxLayers\": " + std::to_string(l.maxLayers) + "}";
}

// "sections": each table entry's tag, flags and codec, and whether the format knows the tag.
void appendSections(std::string& s, const BuiltValid& v, const Vff& file) {
  s += "  \"sections\": [\n";
  for (uint32_t i = 0; i < file.count(); ++i) {
    const uint64_t e = file.entryAt(i);
    const uint32_t tag = ld32(v.bytes, e);
    const bool known = tag == kTagField || tag == kTagLayout || tag == kTagDistance || tag == kTagNormal ||
                       tag == kTagMetadata || tag == kTagRefinement;
    s += "    {\"tag\": " + jstr(sectionTagName(tag)) + ", \"flags\": " + std::to_string(ld32(v.bytes, e + 4)) +
         ", \"codec\": " + jstr(codecName(Codec(ld16(v.bytes, e + 32)))) +
         ", \"known\": " + (known ? "true" : "false") + "}" + (i + 1 < file.count() ? "," : "") + "\n";
  }
  s += "  ],\n";
}

// "planes": maps per block and each block's codec (and filter, where any block has one), per plane.
void appendPlanes(std::string& s, const BuiltValid& v, const Vff& file) {
  s += "  \"planes\": {";
  bool firstPlane = true;
  for (uint32_t tag : {kTagDistance, kTagNormal}) {
    if (file.indexOf(tag) < 0) continue;
    const uint64_t sec = file.sec(tag);
    s += std::string(firstPlane ? "" : ",") + "\n    " + jstr(tag == kTagDistance ? "distance" : "normal") +
         ": {\"mapBytes\": " + std::to_string(ld32(v.bytes, sec + 4)) +
         ", \"mapsPerBlock\": " + std::to_string(ld32(v.bytes, sec + 8)) + ", \"blockCodecs\": [";
    bool filtered = false;
    for (uint32_t b = 0; b < file.blockCount(tag); ++b) {
      s += std::string(b ? ", " : "") + jstr(codecName(Codec(v.bytes[file.blockEntry(tag, b) + 20])));
      filtered |= v.bytes[file.blockEntry(tag, b) + 21] != 0;
    }
    s += "]";
    if (filtered) {  // format 1.1 files only: the 1.0 vectors keep their expected text
      s += ", \"blockFilters\": [";
      for (uint32_t b = 0; b < file.blockCount(tag); ++b)
        s += std::string(b ? ", " : "") + jstr(filterName(Filter(v.bytes[file.blockEntry(tag, b) + 21])));
      s += "]";
    }
    s += "}";
    firstPlane = false;
  }
  s += "\n  },\n";
}

// "refinement" (format 1.3, only when the file has REFN): what a reader decodes from REFN, from the
// source refinement: margin, unsureTexels, per map the texels (j * M + i) whose bit is set, the XXH3-64
// of the U bytes of bits, the counts, every vertex and triangle, and the XXH3-64 of the positions'
// and indices' little-endian bytes as REFN stores them.
void appendRefinement(std::string& s, const BuiltValid& v) {
  if (!v.c.refined) return;
  const Refinement& r = v.refinement;
  const FieldDesc& f = v.c.field;
  const uint64_t mm = uint64_t(f.mapResolution) * f.mapResolution;
  const Bytes raw = referenceRefinementBytes(f, r);
  const uint64_t posAt = raw.size() - 4 * (r.positions.size() + r.indices.size());
  const auto bytes = std::span<const uint8_t>(raw);
  s += "  \"refinement\": {\"margin\": " + jnum(r.margin) + ", \"unsureTexels\": " + std::to_string(r.unsureTexels) +
       ", \"unsureBytes\": " + std::to_string(r.unsure.size()) + ", \"unsureXxh3\": " + jstr(hex64(xxh(r.unsure))) +
       ",\n    \"unsure\": [";
  for (uint32_t k = 0; k < f.mapCount; ++k) {
    s += k ? ",\n               [" : "[";
    bool first = true;
    for (uint64_t t = 0; t < mm; ++t) {
      const uint64_t x = k * mm + t;
      if (!((r.unsure[x / 8] >> (x % 8)) & 1)) continue;
      if (!first) s += ',';
      s += std::to_string(t);
      first = false;
    }
    s += "]";
  }
  s += "],\n    \"vertexCount\": " + std::to_string(r.positions.size() / 3) +
       ", \"triangleCount\": " + std::to_string(r.indices.size() / 3) +
       ", \"positionsXxh3\": " + jstr(hex64(xxh(bytes.subspan(posAt, 4 * r.positions.size())))) +
       ", \"indicesXxh3\": " + jstr(hex64(xxh(bytes.subspan(posAt + 4 * r.positions.size())))) +
       ",\n    \"positions\": [";
  for (size_t p = 0; p < r.positions.size(); p += 3) {
    // Appended piece by piece: GCC 12 warns (-Wrestrict, a false positive) on "[" + std::string.
    if (p) s += ",\n                  ";
    s += '[';
    s += jnum(r.positions[p]) + ", " + jnum(r.positions[p + 1]) + ", " + jnum(r.positions[p + 2]);
    s += ']';
  }
  s += "],\n    \"indices\": [";
  for (size_t t = 0; t < r.indices.size(); t += 3) {
    if (t) s += t % 24 ? ", " : ",\n                ";
    s += '[';
    s += std::to_string(r.indices[t]) + "," + std::to_string(r.indices[t + 1]) + "," + std::to_string(r.indices[t + 2]);
    s += ']';
  }
  s += "]},\n";
}

// "maps": decoded values and the XXH3-64 of the raw bytes.
void appendMaps(std::string& s, const BuiltValid& v) {
  const FieldDesc& f = v.c.field;
  const uint32_t m = f.mapResolution;
  const uint64_t dBytes = distanceMapBytes(f.distanceEncoding, m);
  const uint64_t nBytes = normalMapBytes(f.normalEncoding, m);
  s += "  \"maps\": [\n";
  for (uint32_t k = 0; k < f.mapCount; ++k) {
    const auto dmap = std::span<const uint8_t>(v.content.distance).subspan(k * dBytes, dBytes);
    s += "    {\"map\": " + std::to_string(k) + ", \"distanceXxh3\": " + jstr(hex64(xxh(dmap)));
    if (nBytes)
      s += ", \"normalXxh3\": " +
           jstr(hex64(xxh(std::span<const uint8_t>(v.content.normals).subspan(k * nBytes, nBytes))));
    s += ",\n     \"distance\": [";
    std::string normals;
    for (uint32_t t = 0; t < m * m; ++t) {
      const uint32_t i = t % m, j = t / m;
      const uint32_t code = f.distanceEncoding == DistanceEncoding::kBc4Diameter
                                ? referenceBc4Code(dmap, m, i, j)
                                : loadCode(f.distanceEncoding, dmap, m, i, j);
      const Texel tx =
          decodeDistance(f.distanceEncoding, code, f.sphere.radius, texelDirection(f.directionScheme, m, i, j).z);
      if (t % m == 0) s += t ? "\n                  " : "";
      if (f.distanceEncoding == DistanceEncoding::kBit1)
        s += tx.hit ? "1" : "0";
      else
        s += tx.hit ? jnum(tx.distance, 7) : "null";
      if (t + 1 < m * m) s += ",";
      if (nBytes) {
        if (t % m == 0) normals += t ? "\n                 " : "";
        if (tx.hit) {
          const Vec3 n = decodeNormal(&v.content.normals[k * nBytes + uint64_t(t) * 4]);
          // Appended piece by piece: GCC 12 warns (-Wrestrict, a false positive) on "[" + std::string
          // in this function.
          normals += '[';
          normals += jfix(n.x) + "," + jfix(n.y) + "," + jfix(n.z);
          normals += ']';
        } else {
          normals += "null";
        }
        if (t + 1 < m * m) normals += ",";
      }
    }
    s += "]";
    if (nBytes) {
      s += ",\n     \"normals\": [";
      s += normals;
      s += ']';
    }
    s += k + 1 < f.mapCount ? "},\n" : "}\n";
  }
  s += "  ],\n";
}

// "slices": XXH3-64 of each composed slice, per plane.
void appendSlices(std::string& s, const BuiltValid& v) {
  const FieldDesc& f = v.c.field;
  const uint64_t nBytes = normalMapBytes(f.normalEncoding, f.mapResolution);
  s += "  \"slices\": {";
  bool firstPlane = true;
  for (Plane p : {Plane::kDistance, Plane::kNormal}) {
    if (p == Plane::kNormal && !nBytes) continue;
    s += std::string(firstPlane ? "" : ",") + "\n    " + jstr(planeName(p)) + ": [";
    const auto slices = composeSlices(f, v.layout, v.content, p);
    for (size_t i = 0; i < slices.size(); ++i) s += std::string(i ? ", " : "") + jstr(hex64(xxh(slices[i])));
    s += "]";
    firstPlane = false;
  }
  s += "\n  }\n}\n";
}

}  // namespace

std::string expectedJson(const BuiltValid& v) {
  const FieldDesc& f = v.c.field;
  const Vff file{v.bytes};
  std::string s = "{\n";
  s += "  \"name\": " + jstr(v.c.name) + ",\n";
  s += "  \"description\": " + jstr(v.c.description) + ",\n";
  s += "  \"fileSize\": " + std::to_string(v.bytes.size()) + ",\n";
  s += "  \"fileXxh3\": " + jstr(hex64(xxh(v.bytes))) + ",\n";
  s += "  \"versionMajor\": " + std::to_string(ld16(v.bytes, 8)) +
       ", \"versionMinor\": " + std::to_string(ld16(v.bytes, 10)) + ",\n";
  s += "  \"incompatFeatures\": " + std::to_string(ld64(v.bytes, 24)) +
       ", \"roCompatFeatures\": " + std::to_string(ld64(v.bytes, 32)) + ",\n";
  s += "  \"warnings\": [" + std::string(v.c.post == Post::kRoCompat ? "3008" : "") + "],\n";
  appendSections(s, v, file);
  s += "  \"field\": " + fieldJson(f) + ",\n";
  s += "  \"layout\": " + layoutJson(v.layout) + ",\n";
  // A non-canonical META text goes in as a string: it need not survive a JSON library's number range.
  const std::string meta = v.c.post == Post::kMetaText ? jstr(v.metadata) : v.metadata;
  s += "  \"metadata\": " + (v.metadata.empty() ? std::string("null") : meta) + ",\n";
  appendPlanes(s, v, file);
  appendRefinement(s, v);
  appendMaps(s, v);
  appendSlices(s, v);
  return s;
}

}  // namespace vff::gen
