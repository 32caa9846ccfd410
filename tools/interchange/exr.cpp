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

// The pixels of one band of a slice as read: rows y0.. of the slice, sliceWidth floats a row.
struct ExrBand {
  uint64_t y0 = 0;
  const std::vector<float>* y = nullptr;     // distance
  const std::vector<float>* miss = nullptr;  // 1 miss, 0 hit
  const std::vector<float>* rgb = nullptr;   // the normal's three channels; null without normals
  bool halfNormals = false;                  // the normal parts are HALF
};

// Encodes map k, whose tile lies in `band`, into d's planes (already sized for it), counting in
// `report` the values that were not exact.
void importMap(FieldData& d, uint32_t k, const ExrBand& band, const std::vector<float>& cosines,
               ExrReadReport* report) {
  const FieldDesc& f = d.field;
  const uint32_t m = f.mapResolution;
  const std::vector<float>& y = *band.y;
  const std::vector<float>& miss = *band.miss;
  const std::vector<float>* rgb = band.rgb;
  const uint64_t dBytes = distanceMapBytes(f.distanceEncoding, m);
  const uint64_t nBytes = normalMapBytes(f.normalEncoding, m);
  const TilePlacement p = placeMap(d.layout, k);
  const std::span<uint8_t> dmap(d.distance.data() + k * dBytes, dBytes);
  for (uint32_t j = 0; j < m; ++j) {
    for (uint32_t i = 0; i < m; ++i) {
      const uint64_t at = (uint64_t{p.y + j} - band.y0) * d.layout.sliceWidth + (p.x + i);
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
      if (rgb != nullptr && hit) {
        uint8_t* out = d.normals.data() + k * nBytes + 4 * (uint64_t{j} * m + i);
        const Vec3 n{rgb[0][at], rgb[1][at], rgb[2][at]};
        if (!encodeNormalExact(n, band.halfNormals, out)) ++report->inexactNormals;
      }
    }
  }
}

}  // namespace

bool looksLikeExr(const std::string& path) {
  static constexpr unsigned char kExrMagic[4] = {0x76, 0x2f, 0x31, 0x01};
  return startsWithBytes(path, kExrMagic);
}

Status writeExr(const std::string& path, const FieldData& d, const ExrWriteOptions& options) {
  const FieldDesc& f = d.field;
  const LayoutDesc& l = d.layout;
  const auto [m, g, normals, dBytes, nBytes, perSlice] = packedPlanes(d);
  const Imf::PixelType type = options.half ? Imf::HALF : Imf::FLOAT;
  const int w = static_cast<int>(l.sliceWidth), h = static_cast<int>(l.sliceHeight);
  const std::vector<float> cosines = texelCosines(f);
  const Result<nlohmann::json> field = fieldJson(d, kFormatName);
  if (!field) return field.error();

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
      if (headers.empty()) hd.insert("vff.field", Imf::StringAttribute(field->dump()));
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
    if (Status s = parseFieldJson(fieldAttr->value(), kFormatName, "attribute vff.field", &d); !s) return s.error();

    const FieldDesc& f = d.field;
    const LayoutDesc& l = d.layout;
    const uint32_t m = f.mapResolution;
    const bool normals = f.normalEncoding != NormalEncoding::kNone;
    const uint64_t dBytes = distanceMapBytes(f.distanceEncoding, m);
    const uint64_t nBytes = normalMapBytes(f.normalEncoding, m);
    const uint32_t perSlice = l.tilesPerRow * l.tilesPerColumn;
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

    // Each part is read in bands of whole tile rows (about 2^20 texels), and the maps of a band are
    // appended to the planes as they are decoded: memory follows the pixel data actually read, not
    // the field's claim (a header can claim 16k x 16k slices over a file holding no pixels), and the
    // first missing or corrupt chunk ends the import.
    const uint32_t tile = l.tileSize;
    const uint64_t bandTiles = std::max<uint64_t>(1, (uint64_t{1} << 20) / (uint64_t{l.sliceWidth} * tile));
    const uint64_t bandRowsMax = std::min<uint64_t>(bandTiles * tile, l.sliceHeight);
    std::vector<float> y, miss, rgb[3];
    for (uint32_t s = 0; s < l.sliceCount; ++s) {
      const uint32_t first = s * perSlice, last = std::min(f.mapCount, first + perSlice);
      for (uint64_t y0 = 0; y0 < l.sliceHeight; y0 += bandRowsMax) {
        const uint64_t rows = std::min<uint64_t>(bandRowsMax, l.sliceHeight - y0);
        const uint64_t texels = rows * l.sliceWidth;
        // The pixel rows of this band, as a window in the part's coordinates.
        auto band = [&](const Imath::Box2i& dw) {
          return Imath::Box2i(Imath::V2i(dw.min.x, dw.min.y + static_cast<int>(y0)),
                              Imath::V2i(dw.max.x, dw.min.y + static_cast<int>(y0 + rows) - 1));
        };
        {
          y.resize(texels);
          miss.resize(texels);
          Imf::InputPart part(in, distParts[s]);
          const Imath::Box2i bw = band(part.header().dataWindow());
          const bool hasMiss = part.header().channels().findChannel("miss") != nullptr;
          Imf::FrameBuffer fb;
          fb.insert("Y", Imf::Slice::Make(Imf::FLOAT, y.data(), bw));
          fb.insert("miss", Imf::Slice::Make(Imf::FLOAT, miss.data(), bw, 0, 0, 1, 1, 0.0));
          part.setFrameBuffer(fb);
          part.readPixels(bw.min.y, bw.max.y);
          if (!hasMiss)  // without the miss channel, a miss is a non-finite Y
            for (uint64_t t = 0; t < texels; ++t) miss[t] = std::isfinite(y[t]) ? 0.0f : 1.0f;
        }
        if (normals) {
          for (auto& c : rgb) c.assign(texels, 0.0f);
          Imf::InputPart part(in, normParts[s]);
          const Imath::Box2i bw = band(part.header().dataWindow());
          Imf::FrameBuffer fb;
          const char* names[3] = {"R", "G", "B"};
          for (int c = 0; c < 3; ++c) fb.insert(names[c], Imf::Slice::Make(Imf::FLOAT, rgb[c].data(), bw));
          part.setFrameBuffer(fb);
          part.readPixels(bw.min.y, bw.max.y);
        }
        // The maps whose tiles lie in this band (tiles are placed row by row), appended in order.
        const uint64_t bandFirst = std::min<uint64_t>(last, first + y0 / tile * l.tilesPerRow);
        const uint64_t bandEnd = std::min<uint64_t>(last, first + (y0 + rows) / tile * l.tilesPerRow);
        if (bandFirst >= bandEnd) continue;
        d.distance.resize(bandEnd * dBytes, 0);
        if (normals) d.normals.resize(bandEnd * nBytes, 0);
        const ExrBand b{y0, &y, &miss, normals ? rgb : nullptr, nType == Imf::HALF};
        for (uint32_t k = static_cast<uint32_t>(bandFirst); k < bandEnd; ++k) importMap(d, k, b, cosines, report);
      }
    }
    if (d.distance.size() != uint64_t{f.mapCount} * dBytes)  // the layout places every map (checked by its parser)
      return makeError(Code::kLayoutGeometry, "the layout's slices do not hold all " + std::to_string(f.mapCount) + " maps");
  } catch (const std::exception& e) {
    // The file opened (checked above), so a failure here is a corrupt or truncated EXR.
    return makeError(Code::kSectionDecode, "cannot read " + path + " as OpenEXR: " + e.what());
  }
  return d;
}

}  // namespace vff::convert
