// gen.cpp - vff_limits_gen: writes the hostile inputs of the limits tests (limits_tests.sh).
//
//   vff_limits_gen NAME OUT     writes the input NAME to the file OUT
//   vff_limits_gen --list       prints every NAME
//
// Every input is small (at most a few KiB) but claims something huge: a .vff whose counts, sizes or
// offsets are far beyond its bytes (re-sealed, so that the claim and not a checksum is what a reader
// meets first), or a mesh whose header claims 10^9 faces or vertices over a body of a few. The
// .vff inputs start from a valid file that libvff's writer makes, then edit bytes by hand; the
// offsets follow spec/format.md (header: section table offset @40, count @48, checksum @56; table
// entries: tag, flags, offset @8, storedSize @16, rawSize @24, codec @32, checksum @40; plane header:
// mapCount, mapBytes, mapsPerBlock, blockCount; block entries: offset @0, storedSize @8, rawSize @16,
// codec @20, filter @21, checksum @24). Deterministic: the same bytes on every run.
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfMultiPartOutputFile.h>
#include <OpenEXR/ImfPartType.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <xxhash.h>
#include <zstd.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <iterator>
#include <map>
#include <string>
#include <vector>

#include "vff/vff.h"

namespace {

using Bytes = std::vector<uint8_t>;
using namespace vff;

[[noreturn]] void die(const std::string& what) {
  std::fprintf(stderr, "vff_limits_gen: error: %s\n", what.c_str());
  std::exit(1);
}

uint32_t ld32(const Bytes& b, uint64_t o) {
  return uint32_t(b.at(o)) | uint32_t(b.at(o + 1)) << 8 | uint32_t(b.at(o + 2)) << 16 | uint32_t(b.at(o + 3)) << 24;
}
uint64_t ld64(const Bytes& b, uint64_t o) { return uint64_t(ld32(b, o)) | uint64_t(ld32(b, o + 4)) << 32; }
void st32(Bytes& b, uint64_t o, uint32_t v) {
  for (int k = 0; k < 4; ++k) b.at(o + uint64_t(k)) = uint8_t(v >> (8 * k));
}
void st64(Bytes& b, uint64_t o, uint64_t v) {
  st32(b, o, uint32_t(v));
  st32(b, o + 4, uint32_t(v >> 32));
}
uint64_t xxh(const Bytes& b, uint64_t off, uint64_t size) { return XXH3_64bits(b.data() + off, size); }

// A valid .vff held in memory, edited by hand.
struct Vff {
  Bytes b;
  uint64_t table() const { return ld64(b, 40); }
  uint32_t count() const { return ld32(b, 48); }
  uint64_t entry(uint32_t tag) const {
    for (uint32_t i = 0; i < count(); ++i)
      if (ld32(b, table() + uint64_t(i) * kSectionEntrySize) == tag) return table() + uint64_t(i) * kSectionEntrySize;
    die("no section " + sectionTagName(tag));
  }
  uint64_t sec(uint32_t tag) const { return ld64(b, entry(tag) + 8); }
  uint64_t block(uint32_t tag, uint32_t i) const { return sec(tag) + kPlaneHeaderSize + uint64_t(i) * kBlockEntrySize; }

  // Re-computes the block, section and header checksums wherever the claims leave them computable.
  void seal() {
    for (uint32_t i = 0; i < count(); ++i) {
      const uint64_t e = table() + uint64_t(i) * kSectionEntrySize;
      const uint32_t tag = ld32(b, e);
      const uint64_t off = ld64(b, e + 8), size = ld64(b, e + 16);
      if (off > b.size() || size > b.size() - off) continue;
      if (tag == kTagDistance || tag == kTagNormal) {
        const uint32_t n = ld32(b, off + 12);
        for (uint32_t k = 0; k < n && kPlaneHeaderSize + uint64_t(k + 1) * kBlockEntrySize <= size; ++k) {
          const uint64_t be = off + kPlaneHeaderSize + uint64_t(k) * kBlockEntrySize;
          const uint64_t rel = ld64(b, be), stored = ld64(b, be + 8);
          if (rel <= size && stored <= size - rel) st64(b, be + 24, xxh(b, off + rel, stored));
        }
      }
      st64(b, e + 40, xxh(b, off, size));
    }
    XXH3_state_t* s = XXH3_createState();
    XXH3_64bits_reset(s);
    XXH3_64bits_update(s, b.data(), 56);
    XXH3_64bits_update(s, b.data() + table(), uint64_t(count()) * kSectionEntrySize);
    st64(b, 56, XXH3_64bits_digest(s));
    XXH3_freeState(s);
  }
  // Makes META a zstd section holding `frame` (in place: it fits before the next section) that
  // claims `rawSize` bytes.
  void setMeta(const Bytes& frame, uint64_t rawSize) {
    const uint64_t e = entry(kTagMetadata), off = sec(kTagMetadata);
    std::fill_n(b.begin() + std::ptrdiff_t(off), ld64(b, e + 16), 0);
    std::copy(frame.begin(), frame.end(), b.begin() + std::ptrdiff_t(off));
    st64(b, e + 16, frame.size());
    st64(b, e + 24, rawSize);
    b[e + 32] = 1;  // codec zstd
  }
  // Replaces the stored bytes of block `i` (the section is resized; later blocks are not moved, so
  // use it on the last block).
  void setLastBlock(uint32_t tag, uint32_t i, const Bytes& stored, uint32_t rawSize) {
    const uint64_t e = entry(tag), off = sec(tag), be = block(tag, i), rel = ld64(b, be);
    b.resize(off + rel);
    b.insert(b.end(), stored.begin(), stored.end());
    st64(b, be + 8, stored.size());
    st32(b, be + 16, rawSize);
    st64(b, e + 16, rel + stored.size());
    st64(b, e + 24, rel + stored.size());
    st64(b, 16, b.size());
  }
};

const char* kMeta = R"({"vff.generator":"vff_limits_gen"})";

// The small valid file every .vff input starts from: 4 fibonacci maps of 8x8, unorm8-diameter, one
// zstd block per plane, optional zstd metadata.
Vff base(bool metadata) {
  FieldDesc f;
  f.sphere.radius = 1;
  f.positionScheme = PositionScheme::kSphericalFibonacci;
  f.positionParam = f.mapCount = 4;
  f.directionScheme = DirectionScheme::kConcentricEqualArea;
  f.mapResolution = 8;
  f.distanceEncoding = DistanceEncoding::kUnorm8Diameter;
  Bytes dist(4 * 64);
  for (size_t i = 0; i < dist.size(); ++i) dist[i] = uint8_t(i % 200);
  WriteOptions w;
  w.codec = Codec::kZstd;
  w.mapsPerBlock = 4;
  if (metadata) w.metadataJson = kMeta;
  auto bytes = writeMemory(f, dist, {}, w);
  if (!bytes) die("cannot write the base file: " + bytes.error().message);
  return Vff{std::move(*bytes)};
}

// Makes the FDSC, LAYT and DIST plane header describe `f` (one block holding every map), so that
// the parser accepts the claim up to the block itself.
void claimField(Vff& v, const FieldDesc& f) {
  const uint64_t fd = v.sec(kTagField);
  st32(v.b, fd + 20, f.positionParam);
  st32(v.b, fd + 24, f.mapCount);
  st32(v.b, fd + 32, f.mapResolution);
  auto l = computeLayout(f, LayoutLimits{});
  if (!l) die("claimed field has no layout: " + l.error().message);
  const uint32_t lv[] = {uint32_t(l->target), l->gutter,      l->tileSize,   l->tilesPerRow,    l->tilesPerColumn,
                         l->sliceWidth,       l->sliceHeight, l->sliceCount, l->maxTextureSize, l->maxLayers};
  for (size_t k = 0; k < std::size(lv); ++k) st32(v.b, v.sec(kTagLayout) + 4 * k, lv[k]);
  const uint64_t mapBytes = distanceMapBytes(f.distanceEncoding, f.mapResolution);
  const uint64_t ph = v.sec(kTagDistance);
  st32(v.b, ph + 0, f.mapCount);
  st32(v.b, ph + 4, uint32_t(mapBytes));
  st32(v.b, ph + 8, f.mapCount);
  st32(v.b, ph + 12, 1);
  st32(v.b, v.block(kTagDistance, 0) + 16, uint32_t(mapBytes * f.mapCount));
}

FieldDesc fibonacci(uint32_t n, uint32_t m) {
  FieldDesc f;
  f.sphere.radius = 1;
  f.positionScheme = PositionScheme::kSphericalFibonacci;
  f.positionParam = f.mapCount = n;
  f.directionScheme = DirectionScheme::kConcentricEqualArea;
  f.mapResolution = m;
  f.distanceEncoding = DistanceEncoding::kUnorm8Diameter;
  return f;
}

// The largest single block the format allows with 64x64 maps: 2^20-1 maps, 4294963200 bytes (u32).
constexpr uint32_t kBigMaps = (1u << 20) - 1;
constexpr uint32_t kBigRaw = kBigMaps * 4096u;

// A zstd frame by hand: magic, a frame header declaring `content` bytes (8-byte field, single
// segment), then one RLE block of `rle` bytes, marked last.
Bytes zstdFrameClaiming(uint64_t content, uint32_t rle) {
  Bytes f = {0x28, 0xB5, 0x2F, 0xFD, 0xE0};
  for (int k = 0; k < 8; ++k) f.push_back(uint8_t(content >> (8 * k)));
  const uint32_t header = 1u | (1u << 1) | (rle << 3);  // last, RLE, size
  f.insert(f.end(), {uint8_t(header), uint8_t(header >> 8), uint8_t(header >> 16), 0x00});
  return f;
}

// A real zstd frame of `content` bytes equal to `byte`: the frame header (8-byte content size,
// single segment) and RLE blocks of 128 KiB (the largest a frame allows), 4 bytes each, the last
// one marked. It decodes without error: 4 GiB from 128 KiB, what zstd itself writes for such data.
Bytes zstdRleFrame(uint64_t content, uint8_t byte) {
  Bytes f = {0x28, 0xB5, 0x2F, 0xFD, 0xE0};
  for (int k = 0; k < 8; ++k) f.push_back(uint8_t(content >> (8 * k)));
  for (uint64_t left = content; left > 0;) {
    const uint32_t n = uint32_t(std::min<uint64_t>(left, 128u << 10));
    left -= n;
    const uint32_t header = (left == 0 ? 1u : 0u) | (1u << 1) | (n << 3);  // last?, RLE, size
    f.insert(f.end(), {uint8_t(header), uint8_t(header >> 8), uint8_t(header >> 16), byte});
  }
  if (ZSTD_getFrameContentSize(f.data(), f.size()) != content || ZSTD_findFrameCompressedSize(f.data(), f.size()) != f.size())
    die("zstdRleFrame: zstd does not read the frame back");
  return f;
}

Bytes zstdOf(const Bytes& raw) {
  Bytes out(ZSTD_compressBound(raw.size()));
  const size_t n = ZSTD_compress(out.data(), out.size(), raw.data(), raw.size(), 19);
  if (ZSTD_isError(n)) die("zstd");
  out.resize(n);
  return out;
}

Bytes text(const std::string& s) { return Bytes(s.begin(), s.end()); }

// Replaces the DIST section (the file's last) with `blockCount` blocks of `g` maps, every one the
// real zstd frame of its maps all at `byte` (the first frame stands for every full block), at the
// canonical offsets. Makes a valid file once sealed.
void setBlocks(Vff& v, uint32_t g, uint8_t byte) {
  const uint64_t e = v.entry(kTagDistance), off = v.sec(kTagDistance);
  const uint32_t mapCount = ld32(v.b, off), mapBytes = ld32(v.b, off + 4);
  const uint32_t blockCount = (mapCount + g - 1) / g;
  const Bytes full = zstdOf(Bytes(uint64_t{g} * mapBytes, byte));
  const Bytes last = zstdOf(Bytes(uint64_t{mapCount - (blockCount - 1) * g} * mapBytes, byte));
  Bytes sec(kPlaneHeaderSize + uint64_t{blockCount} * kBlockEntrySize, 0);
  st32(sec, 0, mapCount);
  st32(sec, 4, mapBytes);
  st32(sec, 8, g);
  st32(sec, 12, blockCount);
  for (uint32_t i = 0; i < blockCount; ++i) {
    const Bytes& frame = i + 1 < blockCount ? full : last;
    sec.resize((sec.size() + kBlockAlignment - 1) / kBlockAlignment * kBlockAlignment, 0);
    const uint64_t be = kPlaneHeaderSize + uint64_t{i} * kBlockEntrySize;
    st64(sec, be, sec.size());
    st64(sec, be + 8, frame.size());
    st32(sec, be + 16, uint32_t(std::min(g, mapCount - i * g)) * mapBytes);
    sec[be + 20] = 1;  // zstd
    sec.insert(sec.end(), frame.begin(), frame.end());
  }
  v.b.resize(off);
  v.b.insert(v.b.end(), sec.begin(), sec.end());
  st64(v.b, e + 16, sec.size());
  st64(v.b, e + 24, sec.size());
  st64(v.b, 16, v.b.size());
}

// A .glb holding `json` and a binary chunk of `bin` bytes.
Bytes glb(std::string json, const Bytes& bin) {
  while (json.size() % 4) json += ' ';
  Bytes b = text("glTF");
  auto u32 = [&](uint32_t v) { for (int k = 0; k < 4; ++k) b.push_back(uint8_t(v >> (8 * k))); };
  u32(2);
  u32(uint32_t(12 + 8 + json.size() + 8 + bin.size()));
  u32(uint32_t(json.size()));
  b.insert(b.end(), {'J', 'S', 'O', 'N'});
  b.insert(b.end(), json.begin(), json.end());
  u32(uint32_t(bin.size()));
  b.insert(b.end(), {'B', 'I', 'N', 0});
  b.insert(b.end(), bin.begin(), bin.end());
  return b;
}

// One triangle: 3 float VEC3 positions (36 bytes) then 3 u32 indices (12 bytes).
Bytes triangleBin() {
  const float p[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const uint32_t i[3] = {0, 1, 2};
  Bytes b(48);
  std::memcpy(b.data(), p, 36);
  std::memcpy(b.data() + 36, i, 12);
  return b;
}

// glTF JSON for one triangle primitive whose POSITION accessor claims `count` vertices and whose
// index accessor claims `indices`, over a buffer of 48 bytes (`uri` empty: the GLB chunk).
std::string gltfJson(const std::string& count, const std::string& indices, const std::string& uri,
                     const std::string& bufferBytes = "48") {
  return R"({"asset":{"version":"2.0"},"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],)"
         R"("meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1}]}],)"
         R"("accessors":[{"bufferView":0,"componentType":5126,"count":)" + count +
         R"(,"type":"VEC3","min":[0,0,0],"max":[1,1,0]},)"
         R"({"bufferView":1,"componentType":5125,"count":)" + indices + R"(,"type":"SCALAR"}],)"
         R"("bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":36},{"buffer":0,"byteOffset":36,"byteLength":12}],)"
         R"("buffers":[{"byteLength":)" + bufferBytes + (uri.empty() ? "" : R"(,"uri":")" + uri + "\"") + "}]}";
}

std::string base64(const Bytes& b) {
  static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string s;
  for (size_t i = 0; i < b.size(); i += 3) {
    const uint32_t v = uint32_t(b[i]) << 16 | (i + 1 < b.size() ? uint32_t(b[i + 1]) << 8 : 0) |
                       (i + 2 < b.size() ? uint32_t(b[i + 2]) : 0);
    s += k[v >> 18 & 63];
    s += k[v >> 12 & 63];
    s += i + 1 < b.size() ? k[v >> 6 & 63] : '=';
    s += i + 2 < b.size() ? k[v & 63] : '=';
  }
  return s;
}

const std::string kTriangleUri = "data:application/octet-stream;base64," + base64(triangleBin());

// An EXR in vff-convert's layout (one part "slice.0", channels Y and miss, the attribute vff.field)
// whose field claims 65026 maps of 64x64 (octa-hemi2 n=127) in one 16384x16320 slice, and whose
// part has that data window but no pixel data: written with OpenEXR, then read back as bytes.
Bytes exrClaimingSlice(const std::string& tmp) {
  const std::string field =
      R"({"codec":"stored","field":{"directionScheme":"concentric-equal-area","distanceEncoding":"unorm8-diameter",)"
      R"("frame":"duff2017","mapCount":65026,"mapResolution":64,"normalEncoding":"none","positionParam":127,)"
      R"("positionScheme":"octa-hemi2","sphere":{"center":[0,0,0],"radius":1}},"format":"vff-convert-exr/1",)"
      R"("layout":{"gutter":0,"maxLayers":2048,"maxTextureSize":16384,"sliceCount":1,"sliceHeight":16320,)"
      R"("sliceWidth":16384,"target":"2d-array","tileSize":64,"tilesPerColumn":255,"tilesPerRow":256},)"
      R"("mapsPerBlock":0,"metadata":null})";
  Imf::Header h(16384, 16320);
  h.setName("slice.0");
  h.setType(Imf::SCANLINEIMAGE);
  h.compression() = Imf::ZIP_COMPRESSION;
  h.channels().insert("Y", Imf::Channel(Imf::FLOAT));
  h.channels().insert("miss", Imf::Channel(Imf::HALF));
  h.insert("vff.field", Imf::StringAttribute(field));
  { Imf::MultiPartOutputFile out(tmp.c_str(), &h, 1); }  // no pixels: every chunk offset stays 0
  std::ifstream in(tmp, std::ios::binary);
  Bytes b((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::remove(tmp.c_str());
  return b;
}

std::string gOut;  // the output path (the EXR writer needs a file of its own next to it)

const std::map<std::string, std::function<Bytes()>> kInputs = {
    // ---- .vff: header and section table ------------------------------------------------------------
    {"vff-file-size-2e63.vff", [] {  // the header claims 2^63 bytes
       Vff v = base(false);
       st64(v.b, 16, uint64_t{1} << 63);
       v.seal();
       return v.b;
     }},
    {"vff-section-count-4e9.vff", [] {  // 2^32-1 sections
       Vff v = base(false);
       st32(v.b, 48, 0xFFFFFFFFu);
       return v.b;  // not sealable: the table it claims does not exist
     }},
    {"vff-table-offset-2e64.vff", [] {  // section table at 2^64 - 64: offset + size overflows
       Vff v = base(false);
       st64(v.b, 40, ~uint64_t{0} - 63);
       return v.b;
     }},
    {"vff-section-offset-2e64.vff", [] {  // DIST at 2^64 - 4096
       Vff v = base(false);
       st64(v.b, v.entry(kTagDistance) + 8, ~uint64_t{0} - 4095);
       v.seal();
       return v.b;
     }},
    {"vff-section-size-2e62.vff", [] {  // DIST claims 2^62 stored bytes
       Vff v = base(false);
       st64(v.b, v.entry(kTagDistance) + 16, uint64_t{1} << 62);
       st64(v.b, v.entry(kTagDistance) + 24, uint64_t{1} << 62);
       v.seal();
       return v.b;
     }},
    {"vff-meta-raw-64mib.vff", [] {  // zstd META whose rawSize says 64 MiB (the default limit); frame: 34 bytes
       Vff v = base(true);
       v.setMeta(zstdOf(text(kMeta)), uint64_t{64} << 20);
       v.seal();
       return v.b;
     }},
    {"vff-meta-frame-64mib.vff", [] {  // rawSize and frame both claim 64 MiB; the frame holds 16 bytes
       Vff v = base(true);
       v.setMeta(zstdFrameClaiming(uint64_t{64} << 20, 16), uint64_t{64} << 20);
       v.seal();
       return v.b;
     }},
    // ---- .vff: field description -------------------------------------------------------------------
    {"vff-map-count-2e24p1.vff", [] {  // mapCount 2^24 + 1 (fibonacci n too): above the reader's limit
       Vff v = base(false);
       st32(v.b, v.sec(kTagField) + 20, (1u << 24) + 1);
       st32(v.b, v.sec(kTagField) + 24, (1u << 24) + 1);
       v.seal();
       return v.b;
     }},
    {"vff-payload-512tib.vff", [] {  // 2^24 maps of 4096^2 unorm16: 2^49 payload bytes
       Vff v = base(false);
       const uint64_t fd = v.sec(kTagField);
       st32(v.b, fd + 20, 1u << 24);
       st32(v.b, fd + 24, 1u << 24);
       st32(v.b, fd + 32, 4096);
       st32(v.b, fd + 40, uint32_t(DistanceEncoding::kUnorm16Diameter));
       st32(v.b, fd + 44, 65535);
       v.seal();
       return v.b;
     }},
    // ---- .vff: plane and blocks ---------------------------------------------------------------------
    {"vff-blocks-2e24.vff", [] {  // 2^24 maps of 8x8 in 2^24 blocks: a 512 MiB block index in 4 KiB
       Vff v = base(false);
       claimField(v, fibonacci(1u << 24, 8));
       st32(v.b, v.sec(kTagDistance) + 8, 1);
       st32(v.b, v.sec(kTagDistance) + 12, 1u << 24);
       v.seal();
       return v.b;
     }},
    {"vff-block-offset-2e64.vff", [] {  // block 0 at 2^64 - 64 inside its section
       Vff v = base(false);
       st64(v.b, v.block(kTagDistance, 0), ~uint64_t{0} - 63);
       v.seal();
       return v.b;
     }},
    {"vff-block-stored-2e63.vff", [] {  // block 0 claims 2^63 stored bytes
       Vff v = base(false);
       st64(v.b, v.block(kTagDistance, 0) + 8, uint64_t{1} << 63);
       v.seal();
       return v.b;
     }},
    {"vff-block-raw-4gib.vff", [] {  // one block of 2^20-1 maps of 64x64 (rawSize 4294963200); frame: 256 bytes
       Vff v = base(false);
       claimField(v, fibonacci(kBigMaps, 64));
       Bytes raw(256, 7);
       v.setLastBlock(kTagDistance, 0, zstdOf(raw), kBigRaw);
       v.seal();
       return v.b;
     }},
    {"vff-block-frame-4gib.vff", [] {  // the same block; its frame too claims 4294963200 bytes, holds 16
       Vff v = base(false);
       claimField(v, fibonacci(kBigMaps, 64));
       v.setLastBlock(kTagDistance, 0, zstdFrameClaiming(kBigRaw, 16), kBigRaw);
       v.seal();
       return v.b;
     }},
    // ---- .vff: real zstd bombs (valid checksums, frames that decode without error) ----------------
    {"vff-bomb-block-4gib.vff", [] {  // one block of 2^20-1 maps of 64x64, a 128 KiB frame of 4294963200 0xFF
       Vff v = base(false);
       claimField(v, fibonacci(kBigMaps, 64));
       v.setLastBlock(kTagDistance, 0, zstdRleFrame(kBigRaw, 0xFF), kBigRaw);
       v.seal();
       return v.b;
     }},
    {"vff-bomb-blocks-4gib.vff", [] {  // the same field in 16384 blocks of 64 maps (256 KiB, the writer's
       Vff v = base(false);             // own G), each a 40-byte frame: a valid all-miss field of 4 GiB
       claimField(v, fibonacci(kBigMaps, 64));
       setBlocks(v, 64, 0xFF);
       v.seal();
       return v.b;
     }},
    {"vff-miss-blocks-128mib.vff", [] {  // as above with 32768 maps: a valid all-miss field of 128 MiB in
       Vff v = base(false);                // 512 blocks of 256 KiB, for the peak of a whole-field rewrite
       claimField(v, fibonacci(1u << 15, 64));
       setBlocks(v, 64, 0xFF);
       v.seal();
       return v.b;
     }},
    {"vff-block-frame-stored.vff", [] {  // a 256-byte block whose frame claims 4294963200 bytes
       Vff v = base(false);
       v.setLastBlock(kTagDistance, 0, zstdFrameClaiming(kBigRaw, 16), 256);
       v.seal();
       return v.b;
     }},
    // ---- EXR (vff-convert's input) ----------------------------------------------------------------
    {"exr-slice-16k.exr", [] { return exrClaimingSlice(gOut + ".tmp.exr"); }},
    // ---- Meshes -------------------------------------------------------------------------------------
    {"ply-ascii-1e9-faces.ply", [] {
       return text("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                   "element face 1000000000\nproperty list uchar int vertex_indices\nend_header\n"
                   "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
     }},
    {"ply-binary-1e9-faces.ply", [] {
       Bytes b = text("ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                      "property float z\nelement face 1000000000\nproperty list uchar int vertex_indices\nend_header\n");
       const size_t at = b.size();
       b.resize(at + 36 + 13, 0);
       const float p[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
       std::memcpy(b.data() + at, p, 36);
       const uint8_t face[13] = {3, 0, 0, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0};
       std::memcpy(b.data() + at + 36, face, 13);
       return b;
     }},
    {"ply-binary-1e9-vertices.ply", [] {
       Bytes b = text("ply\nformat binary_little_endian 1.0\nelement vertex 1000000000\nproperty float x\n"
                      "property float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                      "end_header\n");
       b.resize(b.size() + 36 + 13, 0);
       return b;
     }},
    {"off-1e9-faces.off", [] { return text("OFF\n3 1000000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"); }},
    {"off-1e8-faces.off", [] { return text("OFF\n3 100000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"); }},
    {"stl-binary-1e9-faces.stl", [] {
       Bytes b(80 + 4 + 50, ' ');  // header, count, one record (normal, 3 corners, attribute count)
       st32(b, 80, 1000000000);
       const float t[12] = {0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0};
       std::memcpy(b.data() + 84, t, 48);
       b[132] = b[133] = 0;
       return b;
     }},
    {"obj-index-1e9.obj", [] { return text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 1000000000\n"); }},
    {"gltf-accessor-1e9.gltf", [] { return text(gltfJson("1000000000", "3", kTriangleUri)); }},
    {"gltf-indices-1e9.gltf", [] { return text(gltfJson("3", "1000000000", kTriangleUri)); }},
    {"gltf-accessor-wraps.gltf", [] {  // 2^62 + 1 vertices of 12 bytes: 12 * 2^62 wraps to 0 in 64 bits
       return text(gltfJson("4611686018427387905", "3", kTriangleUri));
     }},
    {"gltf-buffer-1e12.gltf", [] { return text(gltfJson("3", "3", kTriangleUri, "1000000000000")); }},
    {"glb-accessor-1e9.glb", [] { return glb(gltfJson("1000000000", "3", ""), triangleBin()); }},
    {"glb-chunk-4gib.glb", [] {  // the JSON chunk claims 4 GiB - 16 bytes
       Bytes b = glb(gltfJson("3", "3", ""), triangleBin());
       st32(b, 12, 0xFFFFFFF0u);
       return b;
     }},
};

}  // namespace

int main(int argc, char** argv) {
  if (argc == 2 && std::string(argv[1]) == "--list") {
    for (const auto& [name, make] : kInputs) std::printf("%s\n", name.c_str());
    return 0;
  }
  if (argc != 3) {
    std::fprintf(stderr, "usage: vff_limits_gen NAME OUT | --list\n");
    return 1;
  }
  const auto it = kInputs.find(argv[1]);
  if (it == kInputs.end()) die(std::string("unknown input ") + argv[1]);
  gOut = argv[2];
  const Bytes b = it->second();
  std::ofstream out(argv[2], std::ios::binary);
  out.write(reinterpret_cast<const char*>(b.data()), std::streamsize(b.size()));
  if (!out) die(std::string("cannot write ") + argv[2]);
  return 0;
}
