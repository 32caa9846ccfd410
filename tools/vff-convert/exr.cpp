// exr.cpp - the OpenEXR side of vff-convert: a field's packed slices as a multi-part EXR and back.
//
// Layout of the EXR (see README.md, "vff-convert"):
//   part "slice.S"  (S = 0 .. sliceCount-1): channels Y (distance in object units, FLOAT or HALF) and
//                   miss (HALF: 1 miss, 0 hit). A miss has Y = +infinity: no surface at any
//                   distance; viewers show it as clipped white, and it compares and sorts cleanly
//                   (unlike NaN). Unused tiles are misses; gutters replicate edge texels.
//   part "normal.S" (with a normal field): channels R, G, B = the object-space unit normal of the
//                   hit (same pixel type as Y), 0 0 0 for a miss.
//   part 0 header:  string attribute "vff.field" = JSON {"format", "field", "layout", "metadata",
//                   "codec", "mapsPerBlock"}; every part: "vff.plane" and int "vff.slice".
#include <Imath/half.h>
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputPart.h>
#include <OpenEXR/ImfIntAttribute.h>
#include <OpenEXR/ImfMultiPartInputFile.h>
#include <OpenEXR/ImfMultiPartOutputFile.h>
#include <OpenEXR/ImfOutputPart.h>
#include <OpenEXR/ImfPartType.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <utility>

#include "convert.h"

namespace vff::convert {
namespace {

using nlohmann::json;

constexpr const char* kFormatName = "vff-convert-exr/1";
constexpr uint64_t kMaxPayload = uint64_t{8} << 30;  // refuse EXR headers that declare > 8 GiB of maps

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

json fieldJson(const FieldData& d) {
  const FieldDesc& f = d.field;
  const LayoutDesc& l = d.layout;
  json j;
  j["format"] = kFormatName;
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
  j["codec"] = codecName(d.codec);
  j["mapsPerBlock"] = d.mapsPerBlock;
  return j;
}

Error badField(const std::string& what) {
  return makeError(Code::kMetadataJson, "attribute vff.field: " + what);
}

// Parses the vff.field JSON into `d` (everything but the planes) and checks it with libvff.
Status parseFieldJson(const std::string& text, FieldData* d) {
  const json j = json::parse(text, nullptr, false);
  if (j.is_discarded() || !j.is_object()) return badField("is not a JSON object");
  if (j.value("format", std::string()) != kFormatName)
    return badField(std::string("format is not \"") + kFormatName + "\"");
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
  if (Status s = checkFieldDesc(d->field); !s) {
    Error e = s.error();
    e.message = "attribute vff.field: " + e.message;
    return e;
  }
  if (Status s = checkLayout(d->layout, d->field); !s) {
    Error e = s.error();
    e.message = "attribute vff.field: " + e.message;
    return e;
  }
  const uint64_t payload =
      uint64_t{d->field.mapCount} * (distanceMapBytes(d->field.distanceEncoding, d->field.mapResolution) +
                                     normalMapBytes(d->field.normalEncoding, d->field.mapResolution));
  if (payload > kMaxPayload)
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

uint32_t clampToMap(int64_t v, uint32_t m) {
  return static_cast<uint32_t>(std::clamp<int64_t>(v, 0, int64_t{m} - 1));
}

// A temporary file next to `path`, removed unless released.
class TempFile {
 public:
  explicit TempFile(const std::string& path) {
    std::string t = path + ".tmpXXXXXX";
    const int fd = mkstemp(t.data());
    if (fd >= 0) {
      // mkstemp makes the file 0600; give it the mode a newly created file would have.
      const mode_t mask = ::umask(0);
      ::umask(mask);
      (void)::fchmod(fd, 0666 & ~mask);
      ::close(fd);
      name_ = t;
    } else {
      errno_ = errno;
    }
  }
  ~TempFile() {
    if (!name_.empty()) std::remove(name_.c_str());
  }
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;
  bool ok() const { return !name_.empty(); }
  int error() const { return errno_; }
  const std::string& name() const { return name_; }
  void release() { name_.clear(); }

 private:
  std::string name_;
  int errno_ = 0;
};

float roundToType(float v, bool half) {
  return half ? float(Imath::half(v)) : v;
}

// v, rounded to the pixel type, is exactly `stored` (the sign of a zero included).
bool sameValue(float v, float stored, bool half) {
  const float r = roundToType(v, half);
  return r == stored && std::signbit(r) == std::signbit(stored);
}
bool sameNormal(Vec3 v, Vec3 stored, bool half) {
  return sameValue(v.x, stored.x, half) && sameValue(v.y, stored.y, half) && sameValue(v.z, stored.z, half);
}

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

}  // namespace

bool looksLikeExr(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return false;
  unsigned char b[4] = {};
  const size_t n = std::fread(b, 1, 4, f);
  std::fclose(f);
  return n == 4 && b[0] == 0x76 && b[1] == 0x2f && b[2] == 0x31 && b[3] == 0x01;
}

Status writeExr(const std::string& path, const FieldData& d, const ExrWriteOptions& options) {
  const FieldDesc& f = d.field;
  const LayoutDesc& l = d.layout;
  const uint32_t m = f.mapResolution;
  const int64_t g = l.gutter;
  const bool normals = f.normalEncoding != NormalEncoding::kNone;
  const uint64_t dBytes = distanceMapBytes(f.distanceEncoding, m);
  const uint64_t nBytes = normalMapBytes(f.normalEncoding, m);
  const uint32_t perSlice = l.tilesPerRow * l.tilesPerColumn;
  const Imf::PixelType type = options.half ? Imf::HALF : Imf::FLOAT;
  const int w = static_cast<int>(l.sliceWidth), h = static_cast<int>(l.sliceHeight);
  const std::vector<float> cosines = texelCosines(f);

  std::vector<Imf::Header> headers;
  for (uint32_t plane = 0; plane < (normals ? 2u : 1u); ++plane) {
    for (uint32_t s = 0; s < l.sliceCount; ++s) {
      Imf::Header hd(w, h);
      hd.setName((plane == 0 ? "slice." : "normal.") + std::to_string(s));
      hd.setType(Imf::SCANLINEIMAGE);
      hd.compression() = options.compression == ExrCompression::kNone  ? Imf::NO_COMPRESSION
                         : options.compression == ExrCompression::kPiz ? Imf::PIZ_COMPRESSION
                         : options.compression == ExrCompression::kDwaa ? Imf::DWAA_COMPRESSION
                                                                        : Imf::ZIP_COMPRESSION;
      if (plane == 0) {
        hd.channels().insert("Y", Imf::Channel(type));
        hd.channels().insert("miss", Imf::Channel(Imf::HALF));
      } else {
        for (const char* c : {"R", "G", "B"}) hd.channels().insert(c, Imf::Channel(type));
      }
      hd.insert("vff.plane", Imf::StringAttribute(plane == 0 ? "distance" : "normal"));
      hd.insert("vff.slice", Imf::IntAttribute(static_cast<int>(s)));
      if (headers.empty()) hd.insert("vff.field", Imf::StringAttribute(fieldJson(d).dump()));
      headers.push_back(std::move(hd));
    }
  }

  TempFile tmp(path);
  if (!tmp.ok())
    return makeError(Code::kIoWrite,
                     "cannot create a temporary file next to " + path + ": " + std::strerror(tmp.error()));
  try {
    Imf::MultiPartOutputFile out(tmp.name().c_str(), headers.data(), static_cast<int>(headers.size()));
    const uint64_t texels = uint64_t(w) * uint64_t(h);
    std::vector<float> y, rgb[3];
    std::vector<Imath::half> miss, halfBuffers[3];
    for (uint32_t plane = 0; plane < (normals ? 2u : 1u); ++plane) {
      for (uint32_t s = 0; s < l.sliceCount; ++s) {
        if (plane == 0) {
          y.assign(texels, std::numeric_limits<float>::infinity());
          miss.assign(texels, Imath::half(1.0f));
        } else {
          for (auto& c : rgb) c.assign(texels, 0.0f);
        }
        const uint32_t first = s * perSlice, last = std::min(f.mapCount, first + perSlice);
        for (uint32_t k = first; k < last; ++k) {
          const TilePlacement p = placeMap(l, k);
          const std::span<const uint8_t> dmap(d.distance.data() + k * dBytes, dBytes);
          for (int64_t ty = -g; ty < int64_t{m} + g; ++ty) {
            for (int64_t tx = -g; tx < int64_t{m} + g; ++tx) {
              const uint32_t i = clampToMap(tx, m), j = clampToMap(ty, m);
              const uint64_t at = uint64_t(int64_t{p.y} + ty) * uint64_t(w) + uint64_t(int64_t{p.x} + tx);
              const uint32_t code = loadCode(f.distanceEncoding, dmap, m, i, j);
              const Texel t = decodeDistance(f.distanceEncoding, code, f.sphere.radius, cosines[uint64_t{j} * m + i]);
              if (plane == 0) {
                if (t.hit) {
                  y[at] = t.distance;
                  miss[at] = Imath::half(0.0f);
                }
              } else if (t.hit) {
                const Vec3 n = decodeNormal(d.normals.data() + k * nBytes + 4 * (uint64_t{j} * m + i));
                rgb[0][at] = n.x;
                rgb[1][at] = n.y;
                rgb[2][at] = n.z;
              }
            }
          }
        }
        // Multi-part output does not convert pixel types: HALF channels get HALF buffers, rounded to
        // nearest even by Imath::half (the reader's exactness check rounds the same way).
        const Imath::Box2i dw = headers[plane * l.sliceCount + s].dataWindow();
        Imf::FrameBuffer fb;
        auto insert = [&](const char* name, std::vector<float>& values, std::vector<Imath::half>& halves) {
          if (!options.half) {
            fb.insert(name, Imf::Slice::Make(Imf::FLOAT, values.data(), dw));
            return;
          }
          halves.assign(values.begin(), values.end());
          fb.insert(name, Imf::Slice::Make(Imf::HALF, halves.data(), dw));
        };
        if (plane == 0) {
          insert("Y", y, halfBuffers[0]);
          fb.insert("miss", Imf::Slice::Make(Imf::HALF, miss.data(), dw));
        } else {
          const char* names[3] = {"R", "G", "B"};
          for (int c = 0; c < 3; ++c) insert(names[c], rgb[c], halfBuffers[c]);
        }
        Imf::OutputPart part(out, static_cast<int>(plane * l.sliceCount + s));
        part.setFrameBuffer(fb);
        part.writePixels(h);
      }
    }
  } catch (const std::exception& e) {
    return makeError(Code::kIoWrite, "cannot write " + path + ": " + e.what());
  }
  if (std::rename(tmp.name().c_str(), path.c_str()) != 0)
    return makeError(Code::kIoWrite, "cannot rename the temporary file to " + path + ": " + std::strerror(errno));
  tmp.release();
  return {};
}

Result<FieldData> readExr(const std::string& path, ExrReadReport* report) {
  *report = {};
  if (std::FILE* probe = std::fopen(path.c_str(), "rb")) {
    std::fclose(probe);
  } else {
    return makeError(Code::kIoOpen, "cannot open " + path + ": " + std::strerror(errno));
  }
  FieldData d;
  try {
    Imf::MultiPartInputFile in(path.c_str());
    const int parts = in.parts();
    std::map<std::string, int> byName;
    const Imf::StringAttribute* fieldAttr = nullptr;
    for (int i = 0; i < parts; ++i) {
      const Imf::Header& hd = in.header(i);
      if (hd.hasName()) byName[hd.name()] = i;
      if (!fieldAttr) fieldAttr = hd.findTypedAttribute<Imf::StringAttribute>("vff.field");
    }
    if (!fieldAttr)
      return makeError(Code::kMissingSection,
                       "no string attribute vff.field: the file was not written by vff-convert --to exr");
    if (Status s = parseFieldJson(fieldAttr->value(), &d); !s) return s.error();

    const FieldDesc& f = d.field;
    const LayoutDesc& l = d.layout;
    const uint32_t m = f.mapResolution;
    const bool normals = f.normalEncoding != NormalEncoding::kNone;
    const uint64_t dBytes = distanceMapBytes(f.distanceEncoding, m);
    const uint64_t nBytes = normalMapBytes(f.normalEncoding, m);
    const uint32_t perSlice = l.tilesPerRow * l.tilesPerColumn;
    const uint64_t texels = uint64_t{l.sliceWidth} * l.sliceHeight;
    const std::vector<float> cosines = texelCosines(f);

    // Check every part before allocating the planes.
    auto findPart = [&](const std::string& name, std::initializer_list<const char*> channels,
                        Imf::PixelType* type) -> Result<int> {
      const auto it = byName.find(name);
      if (it == byName.end()) return makeError(Code::kLayoutGeometry, "no part \"" + name + "\"");
      const Imf::Header& hd = in.header(it->second);
      const Imath::Box2i dw = hd.dataWindow();
      if (int64_t{dw.max.x} - dw.min.x + 1 != l.sliceWidth || int64_t{dw.max.y} - dw.min.y + 1 != l.sliceHeight)
        return makeError(Code::kLayoutGeometry, "part \"" + name + "\" is not " + std::to_string(l.sliceWidth) + "x" +
                                                    std::to_string(l.sliceHeight) + " pixels like the layout's slices");
      for (const char* c : channels) {
        const Imf::Channel* ch = hd.channels().findChannel(c);
        if (!ch) return makeError(Code::kLayoutGeometry, "part \"" + name + "\" has no channel " + c);
        if (ch->xSampling != 1 || ch->ySampling != 1)
          return makeError(Code::kLayoutGeometry, "part \"" + name + "\" channel " + c + " is subsampled");
        if (type) *type = ch->type;
      }
      return it->second;
    };
    std::vector<int> distParts, normParts;
    Imf::PixelType yType = Imf::FLOAT, nType = Imf::FLOAT;
    for (uint32_t s = 0; s < l.sliceCount; ++s) {
      Result<int> p = findPart("slice." + std::to_string(s), {"Y"}, &yType);
      if (!p) return p.error();
      distParts.push_back(*p);
      if (normals) {
        Result<int> q = findPart("normal." + std::to_string(s), {"R", "G", "B"}, &nType);
        if (!q) return q.error();
        normParts.push_back(*q);
      }
    }
    report->half = yType == Imf::HALF;

    d.distance.assign(uint64_t{f.mapCount} * dBytes, 0);
    if (normals) d.normals.assign(uint64_t{f.mapCount} * nBytes, 0);
    std::vector<float> y(texels), miss(texels), rgb[3];
    std::vector<bool> hitAt(uint64_t{m} * m);
    for (uint32_t s = 0; s < l.sliceCount; ++s) {
      {
        Imf::InputPart part(in, distParts[s]);
        const Imath::Box2i dw = part.header().dataWindow();
        const bool hasMiss = part.header().channels().findChannel("miss") != nullptr;
        Imf::FrameBuffer fb;
        fb.insert("Y", Imf::Slice::Make(Imf::FLOAT, y.data(), dw));
        fb.insert("miss", Imf::Slice::Make(Imf::FLOAT, miss.data(), dw, 0, 0, 1, 1, 0.0));
        part.setFrameBuffer(fb);
        part.readPixels(dw.min.y, dw.max.y);
        if (!hasMiss)  // without the miss channel, a miss is a non-finite Y
          for (uint64_t t = 0; t < texels; ++t) miss[t] = std::isfinite(y[t]) ? 0.0f : 1.0f;
      }
      if (normals) {
        for (auto& c : rgb) c.assign(texels, 0.0f);
        Imf::InputPart part(in, normParts[s]);
        const Imath::Box2i dw = part.header().dataWindow();
        Imf::FrameBuffer fb;
        const char* names[3] = {"R", "G", "B"};
        for (int c = 0; c < 3; ++c) fb.insert(names[c], Imf::Slice::Make(Imf::FLOAT, rgb[c].data(), dw));
        part.setFrameBuffer(fb);
        part.readPixels(dw.min.y, dw.max.y);
      }
      const uint32_t first = s * perSlice, last = std::min(f.mapCount, first + perSlice);
      for (uint32_t k = first; k < last; ++k) {
        const TilePlacement p = placeMap(l, k);
        const std::span<uint8_t> dmap(d.distance.data() + k * dBytes, dBytes);
        for (uint32_t j = 0; j < m; ++j) {
          for (uint32_t i = 0; i < m; ++i) {
            const uint64_t at = uint64_t{p.y + j} * l.sliceWidth + (p.x + i);
            const float cosAlpha = cosines[uint64_t{j} * m + i];
            const bool hit = !(miss[at] >= 0.5f);
            const uint32_t code = encodeDistance(f.distanceEncoding, hit, y[at], f.sphere.radius, cosAlpha);
            storeCode(f.distanceEncoding, dmap, m, i, j, code);
            const Texel back = decodeDistance(f.distanceEncoding, code, f.sphere.radius, cosAlpha);
            if (hit && roundToType(back.distance, report->half) != y[at]) {
              ++report->inexactTexels;
            } else if (hit && report->half && f.distanceEncoding != DistanceEncoding::kBit1) {
              // A neighbouring code that HALF stores as the same value makes the texel ambiguous.
              const auto same = [&](uint32_t c) {
                return roundToType(decodeDistance(f.distanceEncoding, c, f.sphere.radius, cosAlpha).distance, true) ==
                       y[at];
              };
              if ((code > 0 && same(code - 1)) || (code < maxHitCode(f.distanceEncoding) && same(code + 1)))
                ++report->ambiguousTexels;
            }
            if (normals && hit) {
              uint8_t* out = d.normals.data() + k * nBytes + 4 * (uint64_t{j} * m + i);
              const Vec3 n{rgb[0][at], rgb[1][at], rgb[2][at]};
              if (!encodeNormalExact(n, nType == Imf::HALF, out)) ++report->inexactNormals;
            }
          }
        }
      }
    }
  } catch (const std::exception& e) {
    // The file opened (checked above), so a failure here is a corrupt or truncated EXR.
    return makeError(Code::kSectionDecode, "cannot read " + path + " as OpenEXR: " + e.what());
  }
  return d;
}

}  // namespace vff::convert
