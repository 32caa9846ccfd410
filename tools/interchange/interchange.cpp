// interchange.cpp - what the EXR and OpenVDB sides of vff-convert share: the "vff.field" JSON that
// carries a field's description, layout and metadata, the texel cosines for unorm8-chord, tile
// clamping, and exact normal encoding.
#include <Imath/half.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <utility>

#include "convert.h"

namespace vff::convert {

using nlohmann::json;

namespace {

constexpr uint64_t kMaxInterchangePayload = uint64_t{8} << 30;  // refuse files that declare > 8 GiB of maps

// Inverse of one of libvff's xxxName() functions over the enum's small value range.
template <class E, class F>
bool parseEnum(const std::string& name, F nameOf, E* out) {
  for (uint32_t v = 0; v < 16; ++v) {
    if (name == nameOf(static_cast<E>(v)) && std::string(nameOf(static_cast<E>(v))) != "unknown") {
      *out = static_cast<E>(v);
      return true;
    }
  }
  return false;
}

}  // namespace

Result<json> fieldJson(const FieldData& d, const char* formatName) {
  const FieldDesc& f = d.field;
  const LayoutDesc& l = d.layout;
  json j;
  j["format"] = formatName;
  j["field"] = {
      {"sphere",
       {{"center", {f.sphere.center[0], f.sphere.center[1], f.sphere.center[2]}}, {"radius", f.sphere.radius}}},
      {"positionScheme", positionSchemeName(f.positionScheme)},
      {"positionParam", f.positionParam},
      {"mapCount", f.mapCount},
      {"directionScheme", directionSchemeName(f.directionScheme)},
      {"mapResolution", f.mapResolution},
      {"frame", frameConventionName(f.frame)},
      {"distanceEncoding", distanceEncodingName(f.distanceEncoding)},
      {"normalEncoding", normalEncodingName(f.normalEncoding)}};
  j["layout"] = {{"target", layoutTargetName(l.target)},
                 {"gutter", l.gutter},
                 {"tileSize", l.tileSize},
                 {"tilesPerRow", l.tilesPerRow},
                 {"tilesPerColumn", l.tilesPerColumn},
                 {"sliceWidth", l.sliceWidth},
                 {"sliceHeight", l.sliceHeight},
                 {"sliceCount", l.sliceCount},
                 {"maxTextureSize", l.maxTextureSize},
                 {"maxLayers", l.maxLayers}};
  j["metadata"] = d.metadata.empty() ? json(nullptr) : json::parse(d.metadata, nullptr, false);
  // The reader has checked META (rule 8001): a text nlohmann cannot hold has a number beyond binary64.
  if (j["metadata"].is_discarded())
    return makeError(Code::kUnsupported, "the source's META holds a number beyond the binary64 range");
  j["codec"] = codecName(d.codec);
  j["mapsPerBlock"] = d.mapsPerBlock;
  return j;
}

Status parseFieldJson(const std::string& text, const char* formatName, const std::string& where, FieldData* d) {
  const auto badField = [&](const std::string& what) { return makeError(Code::kMetadataJson, where + ": " + what); };
  const json j = json::parse(text, nullptr, false);
  if (j.is_discarded() || !j.is_object()) return badField("is not a JSON object");
  if (!j.contains("format") || !j["format"].is_string() || j["format"].get<std::string>() != formatName)
    return badField(std::string("format is not \"") + formatName + "\"");
  try {
    const json& f = j.at("field");
    const json& s = f.at("sphere");
    for (int k = 0; k < 3; ++k) d->field.sphere.center[k] = s.at("center").at(k).get<float>();
    d->field.sphere.radius = s.at("radius").get<float>();
    d->field.positionParam = f.at("positionParam").get<uint32_t>();
    d->field.mapCount = f.at("mapCount").get<uint32_t>();
    d->field.mapResolution = f.at("mapResolution").get<uint32_t>();
    if (!parseEnum(f.at("positionScheme").get<std::string>(), positionSchemeName, &d->field.positionScheme))
      return badField("unknown positionScheme");
    if (!parseEnum(f.at("directionScheme").get<std::string>(), directionSchemeName, &d->field.directionScheme))
      return badField("unknown directionScheme");
    if (!parseEnum(f.at("frame").get<std::string>(), frameConventionName, &d->field.frame))
      return badField("unknown frame");
    if (!parseEnum(f.at("distanceEncoding").get<std::string>(), distanceEncodingName, &d->field.distanceEncoding))
      return badField("unknown distanceEncoding");
    if (d->field.distanceEncoding == DistanceEncoding::kBc4Diameter)
      return makeError(Code::kUnsupported,
                       where + ": the field is bc4-diameter, whose BC4 blocks cannot be rebuilt exactly from the "
                               "decoded distances; export an unorm8-diameter field instead (vff-convert --encoding "
                               "unorm8-diameter gives the bc4 field's distances exactly)");
    if (!parseEnum(f.at("normalEncoding").get<std::string>(), normalEncodingName, &d->field.normalEncoding))
      return badField("unknown normalEncoding");
    const json& l = j.at("layout");
    if (!parseEnum(l.at("target").get<std::string>(), layoutTargetName, &d->layout.target))
      return badField("unknown layout target");
    d->layout.gutter = l.at("gutter").get<uint32_t>();
    d->layout.tileSize = l.at("tileSize").get<uint32_t>();
    d->layout.tilesPerRow = l.at("tilesPerRow").get<uint32_t>();
    d->layout.tilesPerColumn = l.at("tilesPerColumn").get<uint32_t>();
    d->layout.sliceWidth = l.at("sliceWidth").get<uint32_t>();
    d->layout.sliceHeight = l.at("sliceHeight").get<uint32_t>();
    d->layout.sliceCount = l.at("sliceCount").get<uint32_t>();
    d->layout.maxTextureSize = l.at("maxTextureSize").get<uint32_t>();
    d->layout.maxLayers = l.at("maxLayers").get<uint32_t>();
    const json& m = j.at("metadata");
    if (m.is_object())
      d->metadata = m.dump();
    else if (!m.is_null())
      return badField("metadata is neither an object nor null");
    if (!parseEnum(j.at("codec").get<std::string>(), codecName, &d->codec)) return badField("unknown codec");
    d->mapsPerBlock = j.at("mapsPerBlock").get<uint32_t>();
  } catch (const std::exception& e) {
    return badField(std::string("missing or mistyped member (") + e.what() + ")");
  }
  for (Status s : {checkFieldDesc(d->field), checkLayout(d->layout, d->field)}) {
    if (!s) {
      Error e = s.error();
      e.message = where + ": " + e.message;
      return e;
    }
  }
  const uint64_t payload =
      uint64_t{d->field.mapCount} * (distanceMapBytes(d->field.distanceEncoding, d->field.mapResolution) +
                                     normalMapBytes(d->field.normalEncoding, d->field.mapResolution));
  if (payload > kMaxInterchangePayload)
    return makeError(Code::kDecodedLimit, "the field declares " + std::to_string(payload) +
                                              " bytes of maps, more than this tool's 8 GiB limit");
  return {};
}

// cos(alpha) of every texel centre of a map (row-major), for unorm8-chord.
std::vector<float> texelCosines(const FieldDesc& f) {
  const uint32_t m = f.mapResolution;
  std::vector<float> c(uint64_t{m} * m);
  for (uint32_t j = 0; j < m; ++j)
    for (uint32_t i = 0; i < m; ++i) c[uint64_t{j} * m + i] = texelDirection(f.directionScheme, m, i, j).z;
  return c;
}

bool startsWithBytes(const std::string& path, std::span<const unsigned char> magic) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return false;
  unsigned char b[16] = {};
  const size_t want = std::min(magic.size(), sizeof b);
  const size_t n = std::fread(b, 1, want, f);
  std::fclose(f);
  return n == want && std::memcmp(b, magic.data(), want) == 0;
}

uint32_t clampToMap(int64_t v, uint32_t m) {
  return static_cast<uint32_t>(std::clamp<int64_t>(v, 0, int64_t{m} - 1));
}

float roundToType(float v, bool half) {
  return half ? float(Imath::half(v)) : v;
}

// v, rounded to the pixel type, is exactly `stored` (the sign of a zero included).
bool sameValue(float v, float stored, bool half) {
  const float r = roundToType(v, half);
  return r == stored && std::signbit(r) == std::signbit(stored);
}

namespace {

bool sameNormal(Vec3 v, Vec3 stored, bool half) {
  return sameValue(v.x, stored.x, half) && sameValue(v.y, stored.y, half) && sameValue(v.z, stored.z, half);
}

}  // namespace

// encodeNormal, then, when its code does not decode to exactly `n`, the codes mirrored across the
// octahedron's seams (X or Y negated): they decode to the same normal up to the sign of a zero
// component, and a baked file may hold either. Returns whether the stored code decodes to `n`.
bool encodeNormalExact(Vec3 n, bool half, uint8_t out[4]) {
  encodeNormal(n, out);
  if (sameNormal(decodeNormal(out), n, half)) return true;
  const auto x = static_cast<int16_t>(uint16_t(out[0] | out[1] << 8));
  const auto y = static_cast<int16_t>(uint16_t(out[2] | out[3] << 8));
  for (const auto& [sx, sy] : {std::pair{-1, 1}, std::pair{1, -1}, std::pair{-1, -1}}) {
    const auto cx = static_cast<uint16_t>(static_cast<int16_t>(sx * x));
    const auto cy = static_cast<uint16_t>(static_cast<int16_t>(sy * y));
    const uint8_t c[4] = {uint8_t(cx & 0xff), uint8_t(cx >> 8), uint8_t(cy & 0xff), uint8_t(cy >> 8)};
    if (sameNormal(decodeNormal(c), n, half)) {
      std::memcpy(out, c, 4);
      return true;
    }
  }
  return false;
}

}  // namespace vff::convert
