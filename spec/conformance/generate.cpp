// generate.cpp - writes the .vff conformance vectors (see README.md in this folder).
//
//   vff-conformance-gen OUTDIR
//
// writes, deterministically (the same bytes on every run, host and thread count):
//   OUTDIR/valid/NAME.vff            small valid files covering the format's options
//   OUTDIR/valid/NAME.expected.json  what a reader must decode from each (computed from the source
//                                    data, not by reading the file back)
//   OUTDIR/invalid/ID/NAME.vff       mutations of the valid files, each raising validation ID `ID`
//   OUTDIR/invalid/ID/NAME.expect.json  what libvff does with it (validator issues, open and read
//                                    under each checksum policy), pinned KTX-CTS style
//   OUTDIR/manifest.json             every file with its XXH3-64 and whether it depends on zstd
// Files it wrote before are replaced; stale .vff/.json files under valid/ and invalid/ are removed.
//
// The generator uses libvff's public API to write the valid files and then edits bytes by hand,
// re-sealing the checksums it did not mean to break, so that each invalid file has one fault. It
// checks every vector it makes (valid ones decode to their source data; invalid ones raise their
// ID) and exits 1 on any disagreement.
#include <xxhash.h>
#include <zstd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "conformance.h"
#include "vff/vff.h"

namespace fs = std::filesystem;
using namespace vff;

namespace {

using Bytes = std::vector<uint8_t>;

constexpr int kZstdLevel = 19;
constexpr uint64_t kMaxValidBytes = 64 << 10;
constexpr uint64_t kMaxJsonBytes = 200 << 10;

int gFailures = 0;

void fail(const std::string& what) {
  std::fprintf(stderr, "vff-conformance-gen: error: %s\n", what.c_str());
  ++gFailures;
}

[[noreturn]] void die(const std::string& what) {
  std::fprintf(stderr, "vff-conformance-gen: error: %s\n", what.c_str());
  std::exit(1);
}

std::string hex64(uint64_t v) {
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(v));
  return buf;
}

uint64_t xxh(std::span<const uint8_t> b) {
  return XXH3_64bits(b.data(), b.size());
}

uint64_t alignUp(uint64_t v, uint64_t a) {
  return (v + a - 1) / a * a;
}

// ---- Little-endian field access ------------------------------------------------------------------
uint16_t ld16(const Bytes& b, uint64_t o) {
  return uint16_t(b.at(o) | b.at(o + 1) << 8);
}
uint32_t ld32(const Bytes& b, uint64_t o) {
  return uint32_t(ld16(b, o)) | uint32_t(ld16(b, o + 2)) << 16;
}
uint64_t ld64(const Bytes& b, uint64_t o) {
  return uint64_t(ld32(b, o)) | uint64_t(ld32(b, o + 4)) << 32;
}
void st16(Bytes& b, uint64_t o, uint16_t v) {
  b.at(o) = uint8_t(v);
  b.at(o + 1) = uint8_t(v >> 8);
}
void st32(Bytes& b, uint64_t o, uint32_t v) {
  st16(b, o, uint16_t(v));
  st16(b, o + 2, uint16_t(v >> 16));
}
void st64(Bytes& b, uint64_t o, uint64_t v) {
  st32(b, o, uint32_t(v));
  st32(b, o + 4, uint32_t(v >> 32));
}

bool inRange(uint64_t off, uint64_t size, uint64_t limit) {
  return off <= limit && size <= limit - off;
}

// ---- A .vff held in memory, edited by hand -------------------------------------------------------
// Offsets follow spec/format.md: header (64 B) with the section table offset at 40, the count at 48
// and the header checksum at 56; 64-byte table entries (tag, flags, offset @8, storedSize @16,
// rawSize @24, codec @32, sectionVersion @34, checksum @40); plane sections start with a 32-byte
// header (mapCount, mapBytes, mapsPerBlock, blockCount) and 32-byte block entries (offset relative
// to the section @0, storedSize @8, rawSize @16, codec @20, filter @21, checksum @24).
struct Vff {
  Bytes b;

  uint64_t tableOffset() const { return ld64(b, 40); }
  uint32_t count() const { return ld32(b, 48); }
  uint64_t entryAt(uint32_t i) const { return tableOffset() + uint64_t(i) * kSectionEntrySize; }
  int indexOf(uint32_t tag) const {
    for (uint32_t i = 0; i < count(); ++i)
      if (ld32(b, entryAt(i)) == tag) return int(i);
    return -1;
  }
  uint64_t entry(uint32_t tag) const {
    const int i = indexOf(tag);
    if (i < 0) die("mutation needs a '" + sectionTagName(tag) + "' section");
    return entryAt(uint32_t(i));
  }
  uint64_t sec(uint32_t tag) const { return ld64(b, entry(tag) + 8); }
  uint64_t secSize(uint32_t tag) const { return ld64(b, entry(tag) + 16); }
  uint64_t blockEntry(uint32_t tag, uint32_t i) const {
    return sec(tag) + kPlaneHeaderSize + uint64_t(i) * kBlockEntrySize;
  }
  uint64_t blockRel(uint32_t tag, uint32_t i) const { return ld64(b, blockEntry(tag, i)); }
  uint64_t block(uint32_t tag, uint32_t i) const { return sec(tag) + blockRel(tag, i); }
  uint64_t blockSize(uint32_t tag, uint32_t i) const { return ld64(b, blockEntry(tag, i) + 8); }
  uint32_t blockCount(uint32_t tag) const { return ld32(b, sec(tag) + 12); }

  void setFileSize() { st64(b, 16, b.size()); }

  // Re-computes every block checksum that can be computed (blocks inside their section).
  void sealBlocks() {
    for (uint32_t i = 0; i < count() && inRange(entryAt(i), kSectionEntrySize, b.size()); ++i) {
      const uint64_t e = entryAt(i);
      const uint32_t tag = ld32(b, e);
      if (tag != kTagDistance && tag != kTagNormal) continue;
      const uint64_t off = ld64(b, e + 8), size = ld64(b, e + 16);
      if (!inRange(off, size, b.size()) || size < kPlaneHeaderSize) continue;
      const uint32_t n = ld32(b, off + 12);
      for (uint32_t k = 0; k < n && kPlaneHeaderSize + uint64_t(k + 1) * kBlockEntrySize <= size; ++k) {
        const uint64_t be = off + kPlaneHeaderSize + uint64_t(k) * kBlockEntrySize;
        const uint64_t rel = ld64(b, be), stored = ld64(b, be + 8);
        if (inRange(rel, stored, size)) st64(b, be + 24, xxh(std::span(b).subspan(off + rel, stored)));
      }
    }
  }
  void sealSections() {
    for (uint32_t i = 0; i < count() && inRange(entryAt(i), kSectionEntrySize, b.size()); ++i) {
      const uint64_t e = entryAt(i);
      const uint64_t off = ld64(b, e + 8), size = ld64(b, e + 16);
      if (inRange(off, size, b.size())) st64(b, e + 40, xxh(std::span(b).subspan(off, size)));
    }
  }
  void sealHeader() {
    const uint64_t t = tableOffset(), n = uint64_t(count()) * kSectionEntrySize;
    if (b.size() < kHeaderSize || n > (64u << 10) || !inRange(t, n, b.size())) return;
    XXH3_state_t* s = XXH3_createState();
    XXH3_64bits_reset(s);
    XXH3_64bits_update(s, b.data(), 56);
    XXH3_64bits_update(s, b.data() + t, n);
    st64(b, 56, XXH3_64bits_digest(s));
    XXH3_freeState(s);
  }
  void sealAll() {
    sealBlocks();
    sealSections();
    sealHeader();
  }

  // Appends a section after the last one (at the next 4096-byte boundary) with a new table entry.
  void appendSection(uint32_t tag, uint32_t flags, std::span<const uint8_t> data, uint16_t codec = 0,
                     uint64_t rawSize = ~uint64_t{0}) {
    const uint64_t end = tableOffset() + uint64_t(count() + 1) * kSectionEntrySize;
    for (uint32_t i = 0; i < count(); ++i)
      if (ld64(b, entryAt(i) + 8) < end) die("no room in the section table");
    const uint64_t off = alignUp(b.size(), kSectionAlignment);
    b.resize(off);
    b.insert(b.end(), data.begin(), data.end());
    const uint64_t e = entryAt(count());
    std::fill(b.begin() + std::ptrdiff_t(e), b.begin() + std::ptrdiff_t(e + kSectionEntrySize), 0);
    st32(b, e, tag);
    st32(b, e + 4, flags);
    st64(b, e + 8, off);
    st64(b, e + 16, data.size());
    st64(b, e + 24, rawSize == ~uint64_t{0} ? data.size() : rawSize);
    st16(b, e + 32, codec);
    st16(b, e + 34, 1);
    st32(b, 48, count() + 1);
    setFileSize();
    sealAll();
  }

  // Removes a section's entry and bytes (the file is cut after the last remaining section).
  void removeSection(uint32_t tag) {
    const int idx = indexOf(tag);
    if (idx < 0) die("no section to remove");
    const uint64_t off = sec(tag), size = secSize(tag);
    std::fill(b.begin() + std::ptrdiff_t(off), b.begin() + std::ptrdiff_t(off + size), 0);
    const uint32_t n = count();
    for (uint32_t i = uint32_t(idx); i + 1 < n; ++i)
      std::copy_n(b.begin() + std::ptrdiff_t(entryAt(i + 1)), kSectionEntrySize,
                  b.begin() + std::ptrdiff_t(entryAt(i)));
    std::fill_n(b.begin() + std::ptrdiff_t(entryAt(n - 1)), kSectionEntrySize, 0);
    st32(b, 48, n - 1);
    uint64_t end = 0;
    for (uint32_t i = 0; i + 1 < n; ++i) end = std::max(end, ld64(b, entryAt(i) + 8) + ld64(b, entryAt(i) + 16));
    b.resize(end);
    setFileSize();
    sealAll();
  }

  // Replaces the stored bytes of the last block of plane `tag`, which must be the file's last
  // section: the block, section and file sizes follow, and everything is re-sealed.
  void replaceLastBlock(uint32_t tag, std::span<const uint8_t> stored) {
    const uint64_t e = entry(tag), off = sec(tag);
    if (off + secSize(tag) != b.size()) die("replaceLastBlock: '" + sectionTagName(tag) + "' is not the last section");
    const uint32_t last = blockCount(tag) - 1;
    const uint64_t rel = blockRel(tag, last);
    b.resize(off + rel);
    b.insert(b.end(), stored.begin(), stored.end());
    st64(b, blockEntry(tag, last) + 8, stored.size());
    st64(b, e + 16, rel + stored.size());
    st64(b, e + 24, rel + stored.size());
    setFileSize();
    sealAll();
  }

  // Replaces a stored section's bytes (it must keep fitting before the next section).
  void replaceStored(uint32_t tag, std::string_view text) {
    const uint64_t e = entry(tag), off = sec(tag), old = secSize(tag);
    std::fill(b.begin() + std::ptrdiff_t(off), b.begin() + std::ptrdiff_t(off + old), 0);
    if (off + text.size() > b.size()) b.resize(off + text.size());
    std::copy(text.begin(), text.end(), b.begin() + std::ptrdiff_t(off));
    st64(b, e + 16, text.size());
    st64(b, e + 24, text.size());
    setFileSize();
    sealAll();
  }
};

// ---- Source data: an analytic scene ---------------------------------------------------------------
// The maps hold the distance from the bounding sphere to an off-centre sphere of radius 0.7R, along
// each texel-centre ray, and its normal at the hit. The positional samples are the generator's own
// stand-ins (an octahedral low-discrepancy set; spec/geometry.md's schemes are not used for content),
// so the values are exact for these positions, not for the FDSC's scheme. Directions and frames are
// computed here in double precision, independently of libvff, and checked against it.
struct D3 {
  double x = 0, y = 0, z = 0;
};
D3 operator+(D3 a, D3 b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
D3 operator-(D3 a, D3 b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
D3 operator*(D3 a, double s) {
  return {a.x * s, a.y * s, a.z * s};
}
double dot(D3 a, D3 b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
D3 normalize(D3 a) {
  return a * (1.0 / std::sqrt(dot(a, a)));
}

D3 standInPosition(uint32_t k, uint32_t count) {
  const double u = 2.0 * ((k + 0.5) / count) - 1.0;
  const double v = 2.0 * std::fmod(k * 0.6180339887498949 + 0.25, 1.0) - 1.0;
  D3 p{u, v, 1.0 - std::fabs(u) - std::fabs(v)};
  if (p.z < 0) {
    p.x = (1.0 - std::fabs(v)) * (u >= 0 ? 1.0 : -1.0);
    p.y = (1.0 - std::fabs(u)) * (v >= 0 ? 1.0 : -1.0);
  }
  return normalize(p);
}

struct Frame3 {
  D3 t, b, n;
};
Frame3 duffFrame(D3 n) {
  const double s = n.z >= 0 ? 1.0 : -1.0;
  const double a = -1.0 / (s + n.z);
  const double k = n.x * n.y * a;
  return {{1.0 + s * n.x * n.x * a, s * k, -s * n.x}, {k, s + n.y * n.y * a, -n.y}, n};
}

D3 localDirection(DirectionScheme scheme, uint32_t m, uint32_t i, uint32_t j) {
  const double a = (2.0 * i + 1.0) / m - 1.0, b = (2.0 * j + 1.0) / m - 1.0;
  if (scheme == DirectionScheme::kHemiOctahedral) {
    const double x = (a + b) * 0.5, y = (a - b) * 0.5;
    return normalize({x, y, 1.0 - std::fabs(x) - std::fabs(y)});
  }
  constexpr double kQuarterPi = 0.78539816339744830962;
  double r = 0, phi = 0;
  if (std::fabs(a) > std::fabs(b)) {
    r = a;
    phi = kQuarterPi * (b / a);
  } else {
    r = b;
    phi = 2.0 * kQuarterPi - kQuarterPi * (a / b);
  }
  const double s = r * std::sqrt(2.0 - r * r);
  return {s * std::cos(phi), s * std::sin(phi), 1.0 - r * r};
}

struct Content {
  Bytes distance;  // mapCount maps, in file order
  Bytes codes;     // bc4-diameter: the unorm8-diameter codes the blocks were made from (M*M per map)
  Bytes normals;   // empty without a normal encoding
  uint64_t hits = 0, misses = 0;
};

Content makeContent(const FieldDesc& f) {
  Content c;
  const uint32_t m = f.mapResolution;
  const uint64_t mapBytes = distanceMapBytes(f.distanceEncoding, m);
  const bool withNormals = f.normalEncoding != NormalEncoding::kNone;
  c.distance.assign(mapBytes * f.mapCount, 0);
  if (withNormals) c.normals.assign(normalMapBytes(f.normalEncoding, m) * f.mapCount, 0);
  const double r = f.sphere.radius;
  const D3 centre{f.sphere.center[0], f.sphere.center[1], f.sphere.center[2]};
  const D3 inner = centre + D3{0.10, -0.08, 0.12} * r;
  const double innerRadius = 0.7 * r;
  for (uint32_t k = 0; k < f.mapCount; ++k) {
    const D3 p = standInPosition(k, f.mapCount);
    const D3 n = p * -1.0;
    const Frame3 fr = duffFrame(n);
    const Frame lib = frameFromNormal({float(n.x), float(n.y), float(n.z)});
    const double frameErr = std::fabs(lib.t.x - fr.t.x) + std::fabs(lib.t.y - fr.t.y) + std::fabs(lib.t.z - fr.t.z) +
                            std::fabs(lib.b.x - fr.b.x) + std::fabs(lib.b.y - fr.b.y) + std::fabs(lib.b.z - fr.b.z);
    if (frameErr > 1e-5) fail("libvff's frameFromNormal disagrees with the Duff et al. 2017 basis");
    const D3 origin = centre + p * r;
    auto map = std::span<uint8_t>(c.distance).subspan(k * mapBytes, mapBytes);
    const bool bc4 = f.distanceEncoding == DistanceEncoding::kBc4Diameter;
    if (bc4 && k == 0) c.codes.assign(uint64_t(m) * m * f.mapCount, 255);
    for (uint32_t j = 0; j < m; ++j)
      for (uint32_t i = 0; i < m; ++i) {
        const D3 l = localDirection(f.directionScheme, m, i, j);
        const Vec3 ll = texelDirection(f.directionScheme, m, i, j);
        if (std::fabs(ll.x - l.x) + std::fabs(ll.y - l.y) + std::fabs(ll.z - l.z) > 1e-5)
          fail(std::string("libvff's texelDirection disagrees for ") + directionSchemeName(f.directionScheme));
        const D3 w = fr.t * l.x + fr.b * l.y + fr.n * l.z;
        const D3 oc = origin - inner;
        const double bq = dot(oc, w), cq = dot(oc, oc) - innerRadius * innerRadius;
        const double disc = bq * bq - cq;
        const bool hit = disc >= 0;
        const double t = hit ? -bq - std::sqrt(disc) : 0.0;
        const uint32_t code = encodeDistance(f.distanceEncoding, hit, float(t), f.sphere.radius, ll.z);
        if (bc4) c.codes[(uint64_t(k) * m + j) * m + i] = uint8_t(code);
        else storeCode(f.distanceEncoding, map, m, i, j, code);
        (hit ? c.hits : c.misses)++;
        if (hit && withNormals) {
          const D3 nn = normalize(origin + w * t - inner);
          encodeNormal({float(nn.x), float(nn.y), float(nn.z)},
                       &c.normals[(uint64_t(k) * m * m + uint64_t(j) * m + i) * 4]);
        }
      }
    // bc4-diameter: the blocks come from libvff's encoder; the checks decode them with the reference
    // decoder below, written from spec/format.md 7.4.
    if (bc4) encodeBc4Map(std::span<const uint8_t>(c.codes).subspan(uint64_t(k) * m * m, uint64_t(m) * m), m, map);
  }
  return c;
}

// ---- bc4-diameter, decoded from spec/format.md 7.4 independently of libvff ------------------------
// The code of texel (i, j) of a map of (M/4)^2 blocks.
uint32_t referenceBc4Code(std::span<const uint8_t> map, uint32_t m, uint32_t i, uint32_t j) {
  const uint8_t* b = &map[8 * (uint64_t(j / 4) * (m / 4) + i / 4)];
  uint64_t w = 0;
  for (int k = 0; k < 6; ++k) w |= uint64_t(b[2 + k]) << (8 * k);
  const uint32_t u = 4 * (j % 4) + i % 4;
  const uint32_t k = uint32_t(w >> (3 * u)) & 7u, r0 = b[0], r1 = b[1];
  if (k == 0) return r0;
  if (k == 1) return r1;
  if (r0 > r1) return ((8 - k) * r0 + (k - 1) * r1 + 3) / 7;
  if (k == 6) return 0;
  if (k == 7) return 255;
  return ((6 - k) * r0 + (k - 1) * r1 + 2) / 5;
}

// ---- Filter 1 (hits-med), written from spec/format.md independently of libvff --------------------
// The filtered stream of a block of 8-bit maps: the hit mask (bit t % 8 of byte t / 8 set for a hit
// at block texel t), then one residual (code - prediction) mod 256 per hit, in texel order.
uint8_t hitsMedPrediction(const uint8_t* map, uint32_t m, uint32_t x, uint32_t y, uint8_t last) {
  auto at = [&](int xx, int yy) -> int {
    if (xx < 0 || yy < 0) return -1;
    const uint8_t c = map[uint32_t(yy) * m + uint32_t(xx)];
    return c == 255 ? -1 : c;
  };
  const int a = at(int(x) - 1, int(y)), b = at(int(x), int(y) - 1), c = at(int(x) - 1, int(y) - 1);
  if (a >= 0 && b >= 0) {
    if (c < 0) return uint8_t((a + b) / 2);
    if (c >= std::max(a, b)) return uint8_t(std::min(a, b));
    if (c <= std::min(a, b)) return uint8_t(std::max(a, b));
    return uint8_t(a + b - c);
  }
  if (a >= 0) return uint8_t(a);
  if (b >= 0) return uint8_t(b);
  if (c >= 0) return uint8_t(c);
  return last;
}

Bytes hitsMedStream(std::span<const uint8_t> raw, uint32_t m) {
  Bytes out((raw.size() + 7) / 8, 0);
  for (size_t t = 0; t < raw.size(); ++t)
    if (raw[t] != 255) out[t / 8] = uint8_t(out[t / 8] | 1u << (t % 8));
  for (size_t first = 0; first < raw.size(); first += size_t(m) * m) {
    uint8_t last = 0;
    for (uint32_t y = 0; y < m; ++y)
      for (uint32_t x = 0; x < m; ++x) {
        const uint8_t code = raw[first + size_t(y) * m + x];
        if (code == 255) continue;
        out.push_back(uint8_t(code - hitsMedPrediction(&raw[first], m, x, y, last)));
        last = code;
      }
  }
  return out;
}

Bytes zstdFrame(std::span<const uint8_t> raw) {
  Bytes out(ZSTD_compressBound(raw.size()));
  ZSTD_CCtx* c = ZSTD_createCCtx();
  ZSTD_CCtx_setParameter(c, ZSTD_c_compressionLevel, kZstdLevel);
  ZSTD_CCtx_setParameter(c, ZSTD_c_contentSizeFlag, 1);
  ZSTD_CCtx_setParameter(c, ZSTD_c_checksumFlag, 0);
  ZSTD_CCtx_setParameter(c, ZSTD_c_dictIDFlag, 0);
  const size_t n = ZSTD_compress2(c, out.data(), out.size(), raw.data(), raw.size());
  ZSTD_freeCCtx(c);
  if (ZSTD_isError(n)) die("zstd compression failed");
  out.resize(n);
  return out;
}

Bytes zstdContent(std::span<const uint8_t> frame) {
  const unsigned long long n = ZSTD_getFrameContentSize(frame.data(), frame.size());
  if (n == ZSTD_CONTENTSIZE_ERROR || n == ZSTD_CONTENTSIZE_UNKNOWN || n > (1u << 24)) die("not a sized zstd frame");
  Bytes out(n);
  if (ZSTD_decompress(out.data(), out.size(), frame.data(), frame.size()) != n) die("zstd frame does not decode");
  return out;
}

// ---- The packed slices, composed independently of File::readSlice --------------------------------
// Each map at its tile, gutters replicating the nearest edge texel (clamping), empty tiles holding the
// miss code (distance) or zero (normals). bit1 slices pack 8 texels of a row per byte, LSB first.
std::vector<Bytes> composeSlices(const FieldDesc& f, const LayoutDesc& l, const Content& c, Plane p) {
  const uint32_t m = f.mapResolution;
  const bool bit1 = p == Plane::kDistance && f.distanceEncoding == DistanceEncoding::kBit1;
  const uint32_t tb = p == Plane::kNormal ? 4 : f.distanceEncoding == DistanceEncoding::kUnorm16Diameter ? 2 : 1;
  const uint64_t rowBytes = bit1 ? l.sliceWidth / 8 : uint64_t(l.sliceWidth) * tb;
  const uint64_t mapBytes =
      p == Plane::kNormal ? normalMapBytes(f.normalEncoding, m) : distanceMapBytes(f.distanceEncoding, m);
  const Bytes& src = p == Plane::kNormal ? c.normals : c.distance;
  const uint32_t perSlice = l.tilesPerRow * l.tilesPerColumn;
  std::vector<Bytes> out;
  if (p == Plane::kDistance && f.distanceEncoding == DistanceEncoding::kBc4Diameter) {
    // Slices of 4x4 blocks, row-major; block (bx, by) of map k at slice block (x0/4 + bx, y0/4 + by);
    // all-miss blocks (FF bytes) in the unused tiles. No gutters.
    const uint32_t bw = l.sliceWidth / 4, bh = l.sliceHeight / 4, mb = m / 4;
    for (uint32_t s = 0; s < l.sliceCount; ++s) {
      Bytes slice(uint64_t(bw) * bh * 8, 0xFF);
      for (uint32_t by = 0; by < bh; ++by)
        for (uint32_t bx = 0; bx < bw; ++bx) {
          const uint64_t map = uint64_t(s) * perSlice + (by * 4 / l.tileSize) * l.tilesPerRow + bx * 4 / l.tileSize;
          if (map >= f.mapCount) continue;
          const uint64_t from = map * mapBytes + 8 * (uint64_t((by * 4 % l.tileSize) / 4) * mb + (bx * 4 % l.tileSize) / 4);
          std::copy_n(&src[from], 8, &slice[8 * (uint64_t(by) * bw + bx)]);
        }
      out.push_back(std::move(slice));
    }
    return out;
  }
  for (uint32_t s = 0; s < l.sliceCount; ++s) {
    Bytes slice(rowBytes * l.sliceHeight, 0);
    for (uint32_t y = 0; y < l.sliceHeight; ++y)
      for (uint32_t x = 0; x < l.sliceWidth; ++x) {
        const uint32_t tile = (y / l.tileSize) * l.tilesPerRow + x / l.tileSize;
        const uint64_t map = uint64_t(s) * perSlice + tile;
        const int64_t lx = std::clamp<int64_t>(int64_t(x % l.tileSize) - l.gutter, 0, m - 1);
        const int64_t ly = std::clamp<int64_t>(int64_t(y % l.tileSize) - l.gutter, 0, m - 1);
        const uint64_t t = uint64_t(ly) * m + uint64_t(lx);
        if (bit1) {
          const uint32_t bit = map < f.mapCount ? (src[map * mapBytes + t / 8] >> (t % 8)) & 1u : 0u;
          slice[y * rowBytes + x / 8] = uint8_t(slice[y * rowBytes + x / 8] | bit << (x % 8));
          continue;
        }
        for (uint32_t k = 0; k < tb; ++k)
          slice[y * rowBytes + uint64_t(x) * tb + k] =
              map < f.mapCount ? src[map * mapBytes + t * tb + k] : (p == Plane::kDistance ? 0xFF : 0x00);
      }
    out.push_back(std::move(slice));
  }
  return out;
}

// The canonical layout, computed here from spec/format.md's rule and checked against the writer's.
LayoutDesc canonicalLayout(const FieldDesc& f, const LayoutLimits& lim) {
  LayoutDesc l;
  l.target = lim.target;
  l.gutter = lim.gutter;
  l.tileSize = f.mapResolution + 2 * lim.gutter;
  const uint32_t fit = lim.maxTextureSize / l.tileSize;
  l.tilesPerRow = std::min(fit, f.mapCount);
  l.tilesPerColumn = std::min(fit, (f.mapCount + l.tilesPerRow - 1) / l.tilesPerRow);
  l.sliceWidth = l.tilesPerRow * l.tileSize;
  l.sliceHeight = l.tilesPerColumn * l.tileSize;
  l.sliceCount = (f.mapCount + l.tilesPerRow * l.tilesPerColumn - 1) / (l.tilesPerRow * l.tilesPerColumn);
  l.maxTextureSize = lim.maxTextureSize;
  l.maxLayers = lim.maxLayers;
  return l;
}

bool sameLayout(const LayoutDesc& a, const LayoutDesc& b) {
  return a.target == b.target && a.gutter == b.gutter && a.tileSize == b.tileSize && a.tilesPerRow == b.tilesPerRow &&
         a.tilesPerColumn == b.tilesPerColumn && a.sliceWidth == b.sliceWidth && a.sliceHeight == b.sliceHeight &&
         a.sliceCount == b.sliceCount && a.maxTextureSize == b.maxTextureSize && a.maxLayers == b.maxLayers;
}

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

// ---- The valid vectors ----------------------------------------------------------------------------
enum class Post { kNone, kUnknownOptional, kUnknownCopySafe, kRoCompat };

struct ValidCase {
  std::string name;
  std::string description;
  FieldDesc field;
  WriteOptions options;
  bool metadata = false;
  Post post = Post::kNone;
};

FieldDesc makeField(DistanceEncoding enc, NormalEncoding normals, PositionScheme scheme, uint32_t param,
                    DirectionScheme dir, uint32_t m, Sphere sphere) {
  FieldDesc f;
  f.sphere = sphere;
  f.positionScheme = scheme;
  f.positionParam = param;
  f.mapCount = positionCount(scheme, param).value();
  f.directionScheme = dir;
  f.mapResolution = m;
  f.distanceEncoding = enc;
  f.normalEncoding = normals;
  return f;
}

WriteOptions makeOptions(Codec codec, LayoutTarget target, uint32_t gutter, uint32_t maxTextureSize,
                         uint32_t mapsPerBlock) {
  WriteOptions o;
  o.codec = codec;
  o.zstdLevel = kZstdLevel;
  o.mapsPerBlock = mapsPerBlock;
  o.layout.target = target;
  o.layout.gutter = gutter;
  o.layout.maxTextureSize = maxTextureSize;
  o.sync = false;
  return o;
}

std::vector<ValidCase> validCases() {
  using DE = DistanceEncoding;
  using NE = NormalEncoding;
  using PS = PositionScheme;
  using DS = DirectionScheme;
  using LT = LayoutTarget;
  const Sphere unitish{{0, 0, 0}, 1.27f};  // 2R/254 = 0.01: unorm8-diameter codes decode to round numbers
  const Sphere u16{{0, 0, 0}, 32.767f};    // 2R/65534 = 0.001 for unorm16-diameter
  std::vector<ValidCase> v;
  v.push_back({"u8d-stored", "unorm8-diameter, stored, octa-hemi2 n=1 (10 maps of 8x8), one block, 2d-array",
               makeField(DE::kUnorm8Diameter, NE::kNone, PS::kOctaHemi2, 1, DS::kConcentricEqualArea, 8, unitish),
               makeOptions(Codec::kStored, LT::kTexture2DArray, 0, 2048, 0)});
  v.push_back({"u8d-zstd-normals-meta",
               "unorm8-diameter, zstd, oct-snorm16 normals, zstd metadata, octa-hemi2 n=2 (26 maps), hemi-octahedral, "
               "8 maps per block (last block 2)",
               makeField(DE::kUnorm8Diameter, NE::kOctSnorm16, PS::kOctaHemi2, 2, DS::kHemiOctahedral, 8,
                         {{0.5f, -1.0f, 2.0f}, 1.27f}),
               makeOptions(Codec::kZstd, LT::kTexture2DArray, 0, 2048, 8), true});
  v.push_back(
      {"u8c-stored-normals-3d-gutter1",
       "unorm8-chord, stored, normals, 3d target, gutter 1, maxTextureSize 30 (3x3 tiles, 2 slices), "
       "4 maps per block",
       makeField(DE::kUnorm8Chord, NE::kOctSnorm16, PS::kOctaHemi2, 1, DS::kConcentricEqualArea, 8, {{0, 0, 0}, 2.0f}),
       makeOptions(Codec::kStored, LT::kTexture3D, 1, 30, 4)});
  v.push_back(
      {"u8c-zstd-meta-1map-per-block",
       "unorm8-chord, zstd, zstd metadata, ea-octa-grid n=3 (9 maps of 16x16), hemi-octahedral, one map per block",
       makeField(DE::kUnorm8Chord, NE::kNone, PS::kEqualAreaOctaGrid, 3, DS::kHemiOctahedral, 16,
                 {{-3.0f, 1.0f, 0.25f}, 4.0f}),
       makeOptions(Codec::kZstd, LT::kTexture2DArray, 0, 2048, 1), true});
  v.push_back({"u16d-stored-meta-slices",
               "unorm16-diameter, stored, stored metadata, fibonacci n=7, maxTextureSize 16 (2x2 tiles, 2 slices), "
               "3 maps per block",
               makeField(DE::kUnorm16Diameter, NE::kNone, PS::kSphericalFibonacci, 7, DS::kConcentricEqualArea, 8,
                         {{1.0f, 2.0f, 3.0f}, 32.767f}),
               makeOptions(Codec::kStored, LT::kTexture2DArray, 0, 16, 3), true});
  v.push_back(
      {"u16d-zstd-normals-gutter2",
       "unorm16-diameter, zstd, normals, fibonacci n=5 (5 maps of 16x16), gutter 2, maxTextureSize 40 "
       "(2x2 tiles, 2 slices)",
       makeField(DE::kUnorm16Diameter, NE::kOctSnorm16, PS::kSphericalFibonacci, 5, DS::kConcentricEqualArea, 16, u16),
       makeOptions(Codec::kZstd, LT::kTexture2DArray, 2, 40, 0)});
  v.push_back({"bit1-stored", "bit1, stored, octa-hemi2 n=2 (26 maps of 8x8), hemi-octahedral, one block",
               makeField(DE::kBit1, NE::kNone, PS::kOctaHemi2, 2, DS::kHemiOctahedral, 8, {{0, 0, 0}, 1.0f}),
               makeOptions(Codec::kStored, LT::kTexture2DArray, 0, 2048, 0)});
  v.push_back({"bit1-zstd-normals-meta-3d",
               "bit1, zstd, normals, zstd metadata, fibonacci n=6 (6 maps of 16x16), 3d target, maxTextureSize 32 "
               "(2x2 tiles, 2 slices), 5 maps per block (last block 1)",
               makeField(DE::kBit1, NE::kOctSnorm16, PS::kSphericalFibonacci, 6, DS::kConcentricEqualArea, 16,
                         {{0.0f, 0.0f, -0.5f}, 1.0f}),
               makeOptions(Codec::kZstd, LT::kTexture3D, 0, 32, 5), true});
  v.push_back({"u8d-zstd-hits-med",
               "format 1.1: unorm8-diameter, zstd with filter 1 hits-med, octa-hemi2 n=2 (26 maps of 16x16), one block",
               makeField(DE::kUnorm8Diameter, NE::kNone, PS::kOctaHemi2, 2, DS::kConcentricEqualArea, 16, unitish),
               makeOptions(Codec::kZstd, LT::kTexture2DArray, 0, 2048, 26)});
  v.back().options.filter = Filter::kHitsMed;
  v.push_back({"bc4-zstd-normals-slices",
               "format 1.2: bc4-diameter, zstd, normals, octa-hemi2 n=2 (26 maps of 16x16), maxTextureSize 64 "
               "(4x4 tiles, 2 slices, the second with 6 unused tiles)",
               makeField(DE::kBc4Diameter, NE::kOctSnorm16, PS::kOctaHemi2, 2, DS::kConcentricEqualArea, 16, unitish),
               makeOptions(Codec::kZstd, LT::kTexture2DArray, 0, 64, 0)});
  ValidCase unknownOptional = v[0];
  unknownOptional.name = "unknown-section-optional";
  unknownOptional.description = "u8d-stored plus an unknown section 'XTST' with flags 0 (a reader skips it)";
  unknownOptional.post = Post::kUnknownOptional;
  v.push_back(unknownOptional);
  ValidCase unknownCopySafe = v[4];
  unknownCopySafe.name = "unknown-section-copysafe";
  unknownCopySafe.description = "u16d-stored-meta-slices plus an unknown section 'XTSC' with flags COPY_SAFE";
  unknownCopySafe.post = Post::kUnknownCopySafe;
  v.push_back(unknownCopySafe);
  ValidCase roCompat = v[0];
  roCompat.name = "rocompat-bit0";
  roCompat.description = "u8d-stored with roCompatFeatures bit 0 set: readable, validator warning 3008";
  roCompat.post = Post::kRoCompat;
  v.push_back(roCompat);
  return v;
}

std::string metadataFor(const ValidCase& c) {
  // Long and repetitive enough that zstd shrinks it (the writer stores a section that does not).
  std::string notes;
  for (int i = 0; i < 8; ++i) notes += "Conformance vector: a small precomputed visibility field. ";
  return R"({"conformance": {"vector": ")" + c.name + R"(", "generator": "vff-conformance-gen", "notes": ")" + notes +
         R"("}, "scene": {"shape": "sphere", "radiusOverR": 0.7, "offsetOverR": [0.1, -0.08, 0.12]}})";
}

struct BuiltValid {
  ValidCase c;
  Content content;
  LayoutDesc layout;
  std::string metadata;  // canonical text
  Bytes bytes;
  bool zstd = false;
};

const char* kUnknownPayload = "An unknown optional section: readers skip it, tools may copy it when COPY_SAFE.\n";

BuiltValid buildValid(const ValidCase& c) {
  BuiltValid v;
  v.c = c;
  v.content = makeContent(c.field);
  WriteOptions wo = c.options;
  if (c.metadata) wo.metadataJson = metadataFor(c);
  auto bytes = writeMemory(c.field, v.content.distance, v.content.normals, wo);
  if (!bytes) die(c.name + ": writeMemory failed: " + bytes.error().toString());
  Vff f{std::move(*bytes)};
  const auto* payload = reinterpret_cast<const uint8_t*>(kUnknownPayload);
  const std::span<const uint8_t> unknown(payload, std::strlen(kUnknownPayload));
  switch (c.post) {
    case Post::kNone:
      break;
    case Post::kUnknownOptional:
      f.appendSection(fourcc('X', 'T', 'S', 'T'), 0, unknown);
      break;
    case Post::kUnknownCopySafe:
      f.appendSection(fourcc('X', 'T', 'S', 'C'), kSectionCopySafe, unknown);
      break;
    case Post::kRoCompat:
      st64(f.b, 32, 1);
      f.sealHeader();
      break;
  }
  v.bytes = std::move(f.b);
  v.layout = canonicalLayout(c.field, c.options.layout);
  auto check = computeLayout(c.field, c.options.layout);
  if (!check || !sameLayout(*check, v.layout))
    fail(c.name + ": libvff's computeLayout differs from the canonical rule");
  if (c.metadata) v.metadata = nlohmann::json::parse(wo.metadataJson).dump();
  v.zstd = c.options.codec == Codec::kZstd;
  return v;
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

// The expected.json of a valid vector: computed from the source content and the writer's options,
// plus the parts of the file's structure a reader reports (sections, blocks), taken from the bytes.
std::string expectedJson(const BuiltValid& v) {
  const FieldDesc& f = v.c.field;
  const uint32_t m = f.mapResolution;
  const uint64_t dBytes = distanceMapBytes(f.distanceEncoding, m);
  const uint64_t nBytes = normalMapBytes(f.normalEncoding, m);
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
  s += "  \"sections\": [\n";
  for (uint32_t i = 0; i < file.count(); ++i) {
    const uint64_t e = file.entryAt(i);
    const uint32_t tag = ld32(v.bytes, e);
    const bool known =
        tag == kTagField || tag == kTagLayout || tag == kTagDistance || tag == kTagNormal || tag == kTagMetadata;
    s += "    {\"tag\": " + jstr(sectionTagName(tag)) + ", \"flags\": " + std::to_string(ld32(v.bytes, e + 4)) +
         ", \"codec\": " + jstr(codecName(Codec(ld16(v.bytes, e + 32)))) +
         ", \"known\": " + (known ? "true" : "false") + "}" + (i + 1 < file.count() ? "," : "") + "\n";
  }
  s += "  ],\n";
  s += "  \"field\": " + fieldJson(f) + ",\n";
  s += "  \"layout\": " + layoutJson(v.layout) + ",\n";
  s += "  \"metadata\": " + (v.metadata.empty() ? std::string("null") : v.metadata) + ",\n";
  // Blocks: maps per block and each block's codec, per plane.
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
  // Maps: decoded values and the XXH3-64 of the raw bytes.
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
      const uint32_t code = f.distanceEncoding == DistanceEncoding::kBc4Diameter ? referenceBc4Code(dmap, m, i, j)
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
          normals += "[" + jfix(n.x) + "," + jfix(n.y) + "," + jfix(n.z) + "]";
        } else {
          normals += "null";
        }
        if (t + 1 < m * m) normals += ",";
      }
    }
    s += "]";
    if (nBytes) s += ",\n     \"normals\": [" + normals + "]";
    s += "}" + std::string(k + 1 < f.mapCount ? "," : "") + "\n";
  }
  s += "  ],\n";
  // Packed slices: XXH3-64 of each composed slice, per plane.
  s += "  \"slices\": {";
  firstPlane = true;
  for (Plane p : {Plane::kDistance, Plane::kNormal}) {
    if (p == Plane::kNormal && !nBytes) continue;
    s += std::string(firstPlane ? "" : ",") + "\n    " + jstr(planeName(p)) + ": [";
    const auto slices = composeSlices(f, v.layout, v.content, p);
    for (size_t i = 0; i < slices.size(); ++i) s += std::string(i ? ", " : "") + jstr(hex64(xxh(slices[i])));
    s += "]";
    firstPlane = false;
  }
  s += "\n  }\n}\n";
  return s;
}

// Reads a valid vector back with libvff and compares it with the source data (a generator self-check).
void checkValid(const BuiltValid& v) {
  const std::string& n = v.c.name;
  if (v.bytes.size() >= kMaxValidBytes) fail(n + ": " + std::to_string(v.bytes.size()) + " bytes, above 64 KiB");
  Report rep = validate(v.bytes);
  if (!rep.valid())
    for (const Issue& i : rep.issues) fail(n + ": validator: " + codeName(i.code) + ": " + i.message);
  for (ChecksumPolicy policy : conformance::kPolicies) {
    ReadOptions ro;
    ro.checksums = policy;
    auto f = File::openMemory(v.bytes, ro);
    if (!f) {
      fail(n + ": open failed: " + f.error().toString());
      continue;
    }
    if (!sameLayout(f->layout(), v.layout)) fail(n + ": the file's layout differs from the canonical layout");
    if (std::string(f->metadata()) != v.metadata) fail(n + ": metadata differs");
    for (Plane p : {Plane::kDistance, Plane::kNormal}) {
      if (p == Plane::kNormal && !f->hasNormals()) continue;
      const Bytes& src = p == Plane::kDistance ? v.content.distance : v.content.normals;
      const uint64_t mb = f->plane(p).mapBytes;
      for (uint32_t k = 0; k < v.c.field.mapCount; ++k) {
        auto d = f->mapData(p, k);
        if (!d || !std::equal(d->begin(), d->end(), src.begin() + std::ptrdiff_t(k * mb),
                              src.begin() + std::ptrdiff_t((k + 1) * mb)))
          fail(n + ": map " + std::to_string(k) + " of the " + planeName(p) + " plane reads back differently");
      }
      const auto slices = composeSlices(v.c.field, v.layout, v.content, p);
      Bytes buf(f->sliceBytes(p));
      for (uint32_t s = 0; s < slices.size(); ++s) {
        Status st = f->readSlice(p, s, buf);
        if (!st || buf != slices[s])
          fail(n + ": slice " + std::to_string(s) + " of the " + planeName(p) +
               " plane differs from the composed slice");
      }
    }
  }
  const Vff file{v.bytes};
  if (v.c.options.codec == Codec::kZstd) {
    bool anyZstdBlock = false;
    for (uint32_t tag : {kTagDistance, kTagNormal})
      if (file.indexOf(tag) >= 0)
        for (uint32_t b = 0; b < file.blockCount(tag); ++b) anyZstdBlock |= v.bytes[file.blockEntry(tag, b) + 20] == 1;
    if (!anyZstdBlock) fail(n + ": a zstd vector without any zstd block");
    if (v.c.metadata && ld16(v.bytes, file.entry(kTagMetadata) + 32) != 1) fail(n + ": metadata was not compressed");
  }
  if (v.c.options.filter == Filter::kHitsMed) {
    // Every distance block is filtered, and its frame holds exactly the stream the spec defines.
    const uint64_t mb = distanceMapBytes(v.c.field.distanceEncoding, v.c.field.mapResolution);
    const uint32_t g = ld32(v.bytes, file.sec(kTagDistance) + 8);
    for (uint32_t b = 0; b < file.blockCount(kTagDistance); ++b) {
      if (v.bytes[file.blockEntry(kTagDistance, b) + 21] != uint8_t(Filter::kHitsMed)) {
        fail(n + ": distance block " + std::to_string(b) + " is not filtered");
        continue;
      }
      const uint64_t first = uint64_t(b) * g * mb;
      const uint64_t size = std::min<uint64_t>(uint64_t(g) * mb, v.content.distance.size() - first);
      const auto raw = std::span<const uint8_t>(v.content.distance).subspan(first, size);
      const auto stored = std::span<const uint8_t>(v.bytes).subspan(file.block(kTagDistance, b),
                                                                     file.blockSize(kTagDistance, b));
      if (zstdContent(stored) != hitsMedStream(raw, v.c.field.mapResolution))
        fail(n + ": distance block " + std::to_string(b) + " does not hold the hits-med stream of its maps");
    }
    if (ld16(v.bytes, 10) != 1 || ld64(v.bytes, 24) != (kFeatureZstd | kFeatureFilters))
      fail(n + ": a filtered file must be version 1.1 with incompatFeatures zstd | filters");
  } else if (v.c.field.distanceEncoding == DistanceEncoding::kBc4Diameter) {
    if (ld16(v.bytes, 10) != 2 || !(ld64(v.bytes, 24) & kFeatureBc4))
      fail(n + ": a bc4-diameter file must be version 1.2 with incompatFeatures bit 2");
    // spec/format.md 7.4's writer rules, checked with the reference decoder: a miss decodes to 255,
    // a hit to a code <= 254 near the code it was made from; libvff's loadCode agrees texel for texel.
    const uint32_t m = v.c.field.mapResolution;
    const uint64_t mb = distanceMapBytes(v.c.field.distanceEncoding, m);
    uint32_t worst = 0;
    for (uint32_t k = 0; k < v.c.field.mapCount; ++k) {
      const auto map = std::span<const uint8_t>(v.content.distance).subspan(k * mb, mb);
      for (uint32_t j = 0; j < m; ++j)
        for (uint32_t i = 0; i < m; ++i) {
          const uint32_t want = v.content.codes[(uint64_t(k) * m + j) * m + i];
          const uint32_t got = referenceBc4Code(map, m, i, j);
          if (got != loadCode(v.c.field.distanceEncoding, map, m, i, j))
            fail(n + ": libvff's loadCode differs from the reference BC4 decoder");
          if ((want == 255) != (got == 255)) fail(n + ": a BC4 block turned a miss into a hit or a hit into a miss");
          if (want != 255) worst = std::max(worst, uint32_t(std::abs(int(got) - int(want))));
        }
    }
    if (worst > 8) fail(n + ": a BC4 texel is " + std::to_string(worst) + " codes from the code it was made from");
  } else if (ld16(v.bytes, 10) != 0) {
    fail(n + ": a file without 1.1 or 1.2 features must be version 1.0");
  }
  if (v.content.hits == 0 || v.content.misses == 0) fail(n + ": the content needs both hits and misses");
}

// ---- The invalid vectors --------------------------------------------------------------------------
struct InvalidCase {
  uint32_t id = 0;
  std::string name;
  std::string base;
  std::string mutation;
  Bytes bytes;
  bool zstd = false;
};

// Offsets of fields inside the FDSC and LAYT payloads.
constexpr uint64_t kFdscRadius = 12, kFdscScheme = 16, kFdscParam = 20, kFdscMapCount = 24, kFdscDirection = 28,
                   kFdscResolution = 32, kFdscFrame = 36, kFdscEncoding = 40, kFdscMiss = 44, kFdscNormals = 48;
constexpr uint64_t kLaytTarget = 0, kLaytTileSize = 8, kLaytSliceCount = 28;

std::vector<InvalidCase> invalidCases(const std::map<std::string, BuiltValid>& valid) {
  std::vector<InvalidCase> out;
  auto add = [&](uint32_t id, std::string name, const std::string& base, std::string mutation,
                 const std::function<void(Vff&)>& edit) {
    auto it = valid.find(base);
    if (it == valid.end()) die("unknown base vector " + base);
    Vff v{it->second.bytes};
    edit(v);
    out.push_back({id, std::move(name), base, std::move(mutation), std::move(v.b), it->second.zstd});
  };
  const std::string A = "u8d-stored";                     // FDSC, LAYT, DIST (1 block of 10 maps)
  const std::string Z = "u8d-zstd-normals-meta";          // FDSC, LAYT, META (zstd), DIST, NORM (4 zstd blocks each)
  const std::string S = "u8c-stored-normals-3d-gutter1";  // FDSC, LAYT, DIST, NORM (3 stored blocks each)
  const std::string M = "u16d-stored-meta-slices";        // FDSC, LAYT, META (stored), DIST
  const std::string B = "bit1-stored";
  const uint32_t D = kTagDistance, F = kTagField, L = kTagLayout, T = kTagMetadata, NM = kTagNormal;

  // 2xxx: identity
  add(2001, "empty", A, "a zero-byte file", [](Vff& v) { v.b.clear(); });
  add(2001, "header-63-bytes", A, "the first 63 bytes of the header", [](Vff& v) { v.b.resize(63); });
  add(2002, "magic-byte0", A, "magic byte 0 is 0x88 instead of 0x89", [](Vff& v) { v.b[0] = 0x88; });
  add(2003, "major-2", A, "versionMajor 2 (header re-sealed)", [](Vff& v) {
    st16(v.b, 8, 2);
    v.sealHeader();
  });
  add(2004, "incompat-bit3", A, "incompatFeatures bit 3 (unknown) set (header re-sealed)", [](Vff& v) {
    st64(v.b, 24, 8);
    v.sealHeader();
  });
  // 3xxx: header
  add(3001, "header-size-65", A, "headerSize 65 (header re-sealed)", [](Vff& v) {
    st32(v.b, 12, 65);
    v.sealHeader();
  });
  add(3002, "truncated-1", A, "the last byte cut off", [](Vff& v) { v.b.pop_back(); });
  add(3002, "appended-1", A, "one zero byte appended", [](Vff& v) { v.b.push_back(0); });
  add(3003, "reserved-byte55", A, "header byte 55 (reserved) is 1 (header re-sealed)", [](Vff& v) {
    v.b[55] = 1;
    v.sealHeader();
  });
  add(3004, "algorithm-0", A, "checksumAlgorithm 0 (header re-sealed)", [](Vff& v) {
    v.b[54] = 0;
    v.sealHeader();
  });
  add(3005, "checksum-flipped", A, "headerChecksum with bit 0 flipped", [](Vff& v) { v.b[56] ^= 1; });
  add(3005, "table-edit-unsealed", A, "DIST entry checksum changed, header checksum left stale",
      [&](Vff& v) { v.b[v.entry(D) + 40] ^= 1; });
  add(3006, "table-past-eof", A, "sectionTableOffset at the end of the file",
      [](Vff& v) { st64(v.b, 40, v.b.size()); });
  add(3007, "count-0", A, "sectionCount 0 (header re-sealed)", [](Vff& v) {
    st32(v.b, 48, 0);
    v.sealHeader();
  });
  // 4xxx: section table and sections
  add(4001, "dist-past-eof", A, "DIST storedSize/rawSize 4096 bytes longer than the file has", [&](Vff& v) {
    st64(v.b, v.entry(D) + 16, v.secSize(D) + 4096);
    st64(v.b, v.entry(D) + 24, v.secSize(D));
    v.sealHeader();
  });
  add(4002, "layt-misaligned", A, "LAYT moved 64 bytes down to offset 8128", [&](Vff& v) {
    const uint64_t off = v.sec(L);
    std::copy_n(v.b.begin() + std::ptrdiff_t(off), 64, v.b.begin() + std::ptrdiff_t(off - 64));
    std::fill_n(v.b.begin() + std::ptrdiff_t(off), 64, 0);
    st64(v.b, v.entry(L) + 8, off - 64);
    v.sealAll();
  });
  add(4003, "layt-overlaps-fdsc", A, "LAYT offset set to FDSC's (4096); the old LAYT bytes zeroed", [&](Vff& v) {
    std::fill_n(v.b.begin() + std::ptrdiff_t(v.sec(L)), 64, 0);
    st64(v.b, v.entry(L) + 8, v.sec(F));
    v.sealAll();
  });
  add(4004, "unknown-required", A, "an unknown section 'XREQ' with flags REQUIRED appended", [](Vff& v) {
    const uint8_t data[16] = {1, 2, 3, 4};
    v.appendSection(fourcc('X', 'R', 'E', 'Q'), kSectionRequired, data);
  });
  add(4005, "duplicate-layt", A, "a second LAYT section appended", [&](Vff& v) {
    const Bytes layt(v.b.begin() + std::ptrdiff_t(v.sec(L)), v.b.begin() + std::ptrdiff_t(v.sec(L) + 64));
    v.appendSection(kTagLayout, kSectionRequired, layt);
  });
  add(4006, "missing-dist", A, "the DIST entry and its bytes removed", [&](Vff& v) { v.removeSection(D); });
  add(4007, "layt-codec-7", A, "LAYT codec 7 (unknown)", [&](Vff& v) {
    st16(v.b, v.entry(L) + 32, 7);
    v.sealAll();
  });
  add(4008, "layt-checksum", A, "LAYT checksum with bit 0 flipped (header re-sealed)", [&](Vff& v) {
    v.b[v.entry(L) + 40] ^= 1;
    v.sealHeader();
  });
  add(4008, "dist-stale-after-block-edit", A,
      "a DIST block byte changed and its block checksum re-sealed, the section checksum left stale", [&](Vff& v) {
        v.b[v.block(D, 0) + 100] ^= 0x5A;
        v.sealBlocks();
        v.sealHeader();
      });
  add(4009, "entry-reserved", A, "DIST entry reserved u32 at +36 is 1", [&](Vff& v) {
    st32(v.b, v.entry(D) + 36, 1);
    v.sealAll();
  });
  add(4010, "fdsc-60-bytes", A, "FDSC storedSize and rawSize 60", [&](Vff& v) {
    st64(v.b, v.entry(F) + 16, 60);
    st64(v.b, v.entry(F) + 24, 60);
    v.sealAll();
  });
  add(4011, "meta-raw-size", Z, "zstd META with rawSize one more than its frame declares", [&](Vff& v) {
    st64(v.b, v.entry(T) + 24, ld64(v.b, v.entry(T) + 24) + 1);
    v.sealAll();
  });
  add(4012, "after-table", A, "a nonzero byte in the padding after the section table (no checksum covers it)",
      [](Vff& v) { v.b[1000] = 1; });
  add(4012, "in-plane-section", Z, "a nonzero byte between the DIST block index and the first block (re-sealed)",
      [&](Vff& v) {
        const uint64_t indexEnd = v.sec(D) + kPlaneHeaderSize + uint64_t(v.blockCount(D)) * kBlockEntrySize;
        if (v.block(D, 0) <= indexEnd) die("in-plane-section: no gap after the block index");
        v.b[indexEnd] = 1;
        v.sealAll();
      });
  add(4013, "layt-version-2", A, "LAYT sectionVersion 2", [&](Vff& v) {
    st16(v.b, v.entry(L) + 34, 2);
    v.sealAll();
  });
  add(4014, "meta-above-limit", Z, "zstd META with rawSize 64 MiB + 1, above the default section limit", [&](Vff& v) {
    st64(v.b, v.entry(T) + 24, (uint64_t{64} << 20) + 1);
    v.sealAll();
  });
  // 5xxx: field description (each edit re-seals)
  auto fdsc = [&](uint32_t id, std::string name, std::string what, std::function<void(Vff&, uint64_t)> edit,
                  const std::string& base = "u8d-stored") {
    add(id, std::move(name), base, std::move(what), [edit](Vff& v) {
      edit(v, v.sec(kTagField));
      v.sealAll();
    });
  };
  fdsc(5001, "radius-nan", "sphere radius NaN", [](Vff& v, uint64_t p) { st32(v.b, p + kFdscRadius, 0x7FC00000u); });
  fdsc(5002, "scheme-0", "positionScheme 0 (invalid)", [](Vff& v, uint64_t p) { st32(v.b, p + kFdscScheme, 0); });
  fdsc(5003, "map-count-11", "mapCount 11 where octa-hemi2 n=1 yields 10",
       [](Vff& v, uint64_t p) { st32(v.b, p + kFdscMapCount, 11); });
  fdsc(5004, "direction-3", "directionScheme 3 (unknown)",
       [](Vff& v, uint64_t p) { st32(v.b, p + kFdscDirection, 3); });
  fdsc(
      5005, "bit1-resolution-12", "bit1 with mapResolution 12 (not a multiple of 8)",
      [](Vff& v, uint64_t p) { st32(v.b, p + kFdscResolution, 12); }, B);
  fdsc(5006, "frame-2", "frame convention 2 (unknown)", [](Vff& v, uint64_t p) { st32(v.b, p + kFdscFrame, 2); });
  fdsc(5007, "encoding-6", "distanceEncoding 6 (unknown)", [](Vff& v, uint64_t p) { st32(v.b, p + kFdscEncoding, 6); });
  const std::string C = "bc4-zstd-normals-slices";  // FDSC, LAYT, DIST, NORM (bc4-diameter, zstd blocks)
  fdsc(
      5005, "bc4-resolution-18", "bc4-diameter with mapResolution 18 (not a multiple of 4)",
      [](Vff& v, uint64_t p) { st32(v.b, p + kFdscResolution, 18); }, C);
  fdsc(5008, "miss-code-0", "unorm8-diameter with missCode 0 (255 is reserved)",
       [](Vff& v, uint64_t p) { st32(v.b, p + kFdscMiss, 0); });
  fdsc(5009, "normal-encoding-2", "normalEncoding 2 (unknown)",
       [](Vff& v, uint64_t p) { st32(v.b, p + kFdscNormals, 2); });
  fdsc(5010, "reserved-52", "FDSC reserved u32 at 52 is 1", [](Vff& v, uint64_t p) { st32(v.b, p + 52, 1); });
  fdsc(5011, "payload-above-limit",
       "fibonacci n=1000, unorm16 4096x4096 maps with normals: 100 GB of payload, above the default 64 GiB",
       [](Vff& v, uint64_t p) {
         st32(v.b, p + kFdscScheme, uint32_t(PositionScheme::kSphericalFibonacci));
         st32(v.b, p + kFdscParam, 1000);
         st32(v.b, p + kFdscMapCount, 1000);
         st32(v.b, p + kFdscResolution, 4096);
         st32(v.b, p + kFdscEncoding, uint32_t(DistanceEncoding::kUnorm16Diameter));
         st32(v.b, p + kFdscMiss, 65535);
         st32(v.b, p + kFdscNormals, uint32_t(NormalEncoding::kOctSnorm16));
       });
  // 6xxx: planes and blocks (each edit re-seals unless it is about a checksum)
  auto edit = [&](uint32_t id, std::string name, const std::string& base, std::string what,
                  std::function<void(Vff&)> e) {
    add(id, std::move(name), base, std::move(what), [e](Vff& v) {
      e(v);
      v.sealAll();
    });
  };
  edit(6001, "map-count", A, "DIST plane header mapCount 11", [&](Vff& v) { st32(v.b, v.sec(D), 11); });
  edit(6002, "encoding-without-norm", A, "FDSC normalEncoding oct-snorm16 without a NORM section",
       [&](Vff& v) { st32(v.b, v.sec(F) + kFdscNormals, 1); });
  edit(6003, "block-past-section", A, "DIST block 0 offset past the section end",
       [&](Vff& v) { st64(v.b, v.blockEntry(D, 0), v.secSize(D) + 64); });
  edit(6004, "block-misaligned", S, "DIST block 1 offset moved by 32 bytes",
       [&](Vff& v) { st64(v.b, v.blockEntry(D, 1), v.blockRel(D, 1) + 32); });
  edit(6005, "blocks-overlap", S, "DIST block 1 offset equal to block 0's",
       [&](Vff& v) { st64(v.b, v.blockEntry(D, 1), v.blockRel(D, 0)); });
  edit(6006, "raw-size", Z, "zstd DIST block 0 rawSize 64 bytes too large",
       [&](Vff& v) { st32(v.b, v.blockEntry(D, 0) + 16, ld32(v.b, v.blockEntry(D, 0) + 16) + 64); });
  edit(6007, "codec-2", A, "DIST block 0 codec 2 (unknown)", [&](Vff& v) { v.b[v.blockEntry(D, 0) + 20] = 2; });
  const std::string H = "u8d-zstd-hits-med";             // FDSC, LAYT, DIST (1 zstd block, filter hits-med)
  edit(6008, "filter-2", H, "DIST block 0 filter 2 (unknown)", [&](Vff& v) { v.b[v.blockEntry(D, 0) + 21] = 2; });
  edit(6008, "filter-on-stored-block", A, "DIST block 0 (stored) with filter 1 hits-med, filters bit set",
       [&](Vff& v) {
         v.b[v.blockEntry(D, 0) + 21] = 1;
         st64(v.b, 24, ld64(v.b, 24) | kFeatureFilters);
       });
  edit(6008, "filter-on-normals", Z, "NORM block 0 (zstd) with filter 1 hits-med, filters bit set", [&](Vff& v) {
    v.b[v.blockEntry(NM, 0) + 21] = 1;
    st64(v.b, 24, ld64(v.b, 24) | kFeatureFilters);
  });
  edit(6008, "filter-on-unorm16", "u16d-zstd-normals-gutter2",
       "unorm16-diameter DIST block 0 (zstd) with filter 1 hits-med, filters bit set", [&](Vff& v) {
         if (v.b[v.blockEntry(D, 0) + 20] != 1) die("filter-on-unorm16: DIST block 0 is not zstd");
         v.b[v.blockEntry(D, 0) + 21] = 1;
         st64(v.b, 24, ld64(v.b, 24) | kFeatureFilters);
       });
  add(6009, "checksum-field", A, "DIST block 0 checksum bit 0 flipped (section and header re-sealed)", [&](Vff& v) {
    v.b[v.blockEntry(D, 0) + 24] ^= 1;
    v.sealSections();
    v.sealHeader();
  });
  add(6009, "data-unsealed", A, "a DIST block byte changed, block checksum left stale (section, header re-sealed)",
      [&](Vff& v) {
        v.b[v.block(D, 0) + 100] ^= 0x5A;
        v.sealSections();
        v.sealHeader();
      });
  edit(6010, "not-a-zstd-frame", Z, "zstd DIST block 0 with a broken frame magic (checksums re-sealed)",
       [&](Vff& v) { v.b[v.block(D, 0)] ^= 0xFF; });
  edit(6010, "trailing-byte", Z, "a zstd DIST block whose storedSize takes one padding byte after its frame",
       [&](Vff& v) {
         for (uint32_t i = 0; i + 1 < v.blockCount(D); ++i) {
           const uint64_t end = v.blockRel(D, i) + v.blockSize(D, i);
           if (v.b[v.blockEntry(D, i) + 20] == 1 && end % kBlockAlignment != 0) {
             st64(v.b, v.blockEntry(D, i) + 8, v.blockSize(D, i) + 1);
             return;
           }
         }
         die("trailing-byte: no zstd block with a gap after it");
       });
  // hits-med streams that are not what a writer makes (the one block of H is the file's last bytes).
  auto refilter = [&](uint32_t id, std::string name, std::string what, std::function<void(Bytes&)> change) {
    add(id, std::move(name), H, std::move(what), [change](Vff& v) {
      Bytes stream = zstdContent(std::span<const uint8_t>(v.b).subspan(v.block(kTagDistance, 0),
                                                                         v.blockSize(kTagDistance, 0)));
      change(stream);
      v.replaceLastBlock(kTagDistance, zstdFrame(stream));
    });
  };
  const uint64_t hMaskBytes = valid.at(H).content.distance.size() / 8;
  refilter(6010, "hits-med-missing-residual", "hits-med stream without its last residual",
           [](Bytes& s) { s.pop_back(); });
  refilter(6010, "hits-med-extra-residual", "hits-med stream with one residual more than the mask has hits",
           [](Bytes& s) { s.push_back(0); });
  refilter(6010, "hits-med-hit-decodes-to-miss",
           "the first residual changed so that the first hit decodes to 255, the miss code", [&](Bytes& s) {
             const Bytes& raw = valid.at(H).content.distance;
             const uint32_t m = valid.at(H).c.field.mapResolution;
             for (uint32_t t = 0; t < m * m; ++t)
               if (raw[t] != 255) {
                 s[hMaskBytes] = uint8_t(255 - hitsMedPrediction(raw.data(), m, t % m, t / m, 0));
                 return;
               }
             die("hits-med-hit-decodes-to-miss: map 0 has no hit");
           });
  refilter(6010, "hits-med-frame-too-large",
           "the zstd frame declares rawSize + rawSize/8 + 1 bytes, one more than any hits-med stream of the block",
           [&](Bytes& s) { s.resize(valid.at(H).content.distance.size() + hMaskBytes + 1, 0); });
  edit(6012, "filter-without-feature-bit", H, "a filtered block, incompatFeatures filters bit (1) clear",
       [&](Vff& v) { st64(v.b, 24, kFeatureZstd); });
  edit(6011, "reserved", A, "DIST block entry reserved byte 22 is 1",
       [&](Vff& v) { v.b[v.blockEntry(D, 0) + 22] = 1; });
  edit(6012, "zstd-without-feature-bit", Z, "zstd sections and blocks, incompatFeatures zstd bit clear",
       [&](Vff& v) { st64(v.b, 24, 0); });
  edit(6012, "bc4-without-feature-bit", C, "bc4-diameter field, incompatFeatures bit 2 (bc4) clear",
       [&](Vff& v) { st64(v.b, 24, ld64(v.b, 24) & ~kFeatureBc4); });
  edit(6008, "filter-on-bc4", C, "bc4-diameter DIST block 0 (zstd) with filter 1 hits-med, filters bit set",
       [&](Vff& v) {
         if (v.b[v.blockEntry(D, 0) + 20] != 1) die("filter-on-bc4: DIST block 0 is not zstd");
         v.b[v.blockEntry(D, 0) + 21] = 1;
         st64(v.b, 24, ld64(v.b, 24) | kFeatureFilters);
       });
  edit(6013, "normal-of-miss", S, "a nonzero normal at a texel whose distance is a miss", [&](Vff& v) {
    const uint64_t dist = v.block(D, 0), norm = v.block(NM, 0);
    for (uint32_t t = 0; t < 64; ++t)
      if (v.b[dist + t] == 255) {
        v.b[norm + 4 * t + 3] = 0x40;
        return;
      }
    die("normal-of-miss: map 0 has no miss");
  });
  // 7xxx: packed layout
  auto layt = [&](uint32_t id, std::string name, std::string what, uint64_t at, uint32_t value,
                  const std::string& base = "u8d-stored") {
    edit(id, std::move(name), base, std::move(what), [at, value](Vff& f) { st32(f.b, f.sec(kTagLayout) + at, value); });
  };
  layt(7001, "target-0", "LAYT target 0 (invalid)", kLaytTarget, 0);
  layt(7002, "tile-size", "LAYT tileSize 9 for 8x8 maps without gutter", kLaytTileSize, 9);
  layt(7003, "slice-count", "LAYT sliceCount 2 where 1 holds every map", kLaytSliceCount, 2);
  layt(7004, "reserved-40", "LAYT reserved u32 at 40 is 1", 40, 1);
  layt(7001, "bc4-target-3d", "bc4-diameter field with LAYT target 2 (3d)", kLaytTarget, 2, C);
  edit(7002, "bc4-gutter-1", C, "bc4-diameter field with LAYT gutter 1 and tileSize 18", [&](Vff& f) {
    st32(f.b, f.sec(kTagLayout) + 4, 1);
    st32(f.b, f.sec(kTagLayout) + kLaytTileSize, 18);
  });
  // 8xxx: metadata (stored META rewritten)
  auto meta = [&](uint32_t id, std::string name, std::string what, std::string text) {
    add(id, std::move(name), M, std::move(what), [text](Vff& v) { v.replaceStored(kTagMetadata, text); });
  };
  meta(8001, "invalid-utf8", "metadata with the invalid UTF-8 sequence C3 28 in a string", "{\"a\":\"\xC3\x28\"}");
  meta(8001, "too-deep", "metadata nesting 65 levels (the reader's limit is 64)",
       "{\"a\":" + std::string(64, '[') + std::string(64, ']') + "}");
  meta(8002, "array", "metadata '[1,2]' (valid JSON, not an object)", "[1,2]");
  return out;
}

// Invalid cases that libvff does not handle as the format requires: generated and checked, but not
// written, so that the suite stays green; each is reported (README.md) and comes back by deleting its
// line here once the library is fixed.
// Entries look like {"invalid/4012/in-plane-section", "why (file:line)"}.
const std::map<std::string, const char*> kKnownLibraryBugs = {};

void writeFile(const fs::path& p, std::span<const uint8_t> bytes) {
  fs::create_directories(p.parent_path());
  std::ofstream o(p, std::ios::binary | std::ios::trunc);
  o.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
  if (!o) die("cannot write " + p.string());
}
void writeText(const fs::path& p, const std::string& s) {
  writeFile(p, std::span(reinterpret_cast<const uint8_t*>(s.data()), s.size()));
}

// Removes what an earlier run wrote (.vff and .json files under valid/ and invalid/, then the
// folders left empty), so that renamed or dropped vectors do not linger.
void clean(const fs::path& out) {
  for (const char* sub : {"valid", "invalid"}) {
    const fs::path dir = out / sub;
    if (!fs::exists(dir)) continue;
    std::vector<fs::path> files, dirs;
    for (const auto& e : fs::recursive_directory_iterator(dir)) {
      if (e.is_directory())
        dirs.push_back(e.path());
      else if (e.path().extension() == ".vff" || e.path().extension() == ".json")
        files.push_back(e.path());
    }
    for (const auto& f : files) fs::remove(f);
    std::sort(dirs.rbegin(), dirs.rend());
    for (const auto& d : dirs)
      if (fs::is_empty(d)) fs::remove(d);
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2 || argv[1][0] == '-') {
    std::fprintf(stderr, "usage: vff-conformance-gen OUTDIR\n");
    return argc == 2 && std::strcmp(argv[1], "--help") == 0 ? 0 : 1;
  }
  const fs::path out = argv[1];
  fs::create_directories(out);
  clean(out);

  nlohmann::json manifest;
  manifest["format"] = "vff conformance vectors";
  manifest["vffVersion"] = std::to_string(kVersionMajor) + "." + std::to_string(kVersionMinor);
  manifest["generator"] = "vff-conformance-gen (spec/conformance/generate.cpp)";
  manifest["zstdVersion"] = ZSTD_versionString();
  manifest["zstdLevel"] = kZstdLevel;
  nlohmann::json files = nlohmann::json::object();
  auto record = [&](const std::string& rel, std::span<const uint8_t> bytes, bool zstd) {
    writeFile(out / rel, bytes);
    files[rel] = {{"size", bytes.size()}, {"xxh3", hex64(xxh(bytes))}, {"zstd", zstd}};
  };

  std::map<std::string, BuiltValid> valid;
  for (const ValidCase& c : validCases()) {
    BuiltValid v = buildValid(c);
    checkValid(v);
    const std::string json = expectedJson(v);
    if (json.size() >= kMaxJsonBytes) fail(c.name + ": expected.json is " + std::to_string(json.size()) + " bytes");
    if (!nlohmann::json::accept(json)) fail(c.name + ": expected.json is not valid JSON");
    record("valid/" + c.name + ".vff", v.bytes, v.zstd);
    record("valid/" + c.name + ".expected.json", std::span(reinterpret_cast<const uint8_t*>(json.data()), json.size()),
           v.zstd);
    valid.emplace(c.name, std::move(v));
  }

  std::map<std::string, int> names;
  for (const InvalidCase& c : invalidCases(valid)) {
    const std::string rel = "invalid/" + std::to_string(c.id) + "/" + c.name;
    if (names[rel]++) fail(rel + ": duplicate name");
    const nlohmann::json seen = conformance::observe(c.bytes);
    // The vector must raise its ID in the validator, as an error.
    bool raised = false;
    for (const auto& i : seen["validate"]) raised |= i["code"] == c.id && i["severity"] == "error";
    if (auto bug = kKnownLibraryBugs.find(rel); bug != kKnownLibraryBugs.end()) {
      // Not written while libvff gets it wrong (README.md, "Known library deviations").
      std::fprintf(stderr, "vff-conformance-gen: note: %s not written: %s%s\n", rel.c_str(), bug->second,
                   raised ? " (it now raises its ID: drop it from kKnownLibraryBugs)" : "");
      continue;
    }
    if (!raised) fail(rel + ": the validator does not report " + std::to_string(c.id) + ": " + seen.dump());
    // File::open with the default policy fails with the ID, unless the ID is one open does not check.
    const nlohmann::json& va = seen["open"]["verify-all"];
    if (conformance::isValidatorOnly(Code(c.id))) {
      const uint32_t wantRead = c.id == uint32_t(Code::kBlockDecode) ? c.id : 0;
      if (va["open"] != 0 || va["read"] != wantRead) fail(rel + ": unexpected open/read result " + va.dump());
    } else if (va["open"] != c.id) {
      fail(rel + ": File::openMemory fails with " + va["open"].dump() + ", not " + std::to_string(c.id));
    }
    nlohmann::json expect;
    expect["id"] = c.id;
    expect["name"] = codeName(Code(c.id));
    expect["base"] = "valid/" + c.base + ".vff";
    expect["mutation"] = c.mutation;
    expect["observed"] = seen;
    const std::string text = expect.dump(1) + "\n";
    record(rel + ".vff", c.bytes, c.zstd);
    record(rel + ".expect.json", std::span(reinterpret_cast<const uint8_t*>(text.data()), text.size()), c.zstd);
  }

  manifest["files"] = std::move(files);
  const std::string m = manifest.dump(1) + "\n";
  writeText(out / "manifest.json", m);
  if (gFailures) {
    std::fprintf(stderr, "vff-conformance-gen: %d problem(s)\n", gFailures);
    return 1;
  }
  return 0;
}
