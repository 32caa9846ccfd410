// gen_reference.cpp - what the conformance vectors must decode to (gen_reference.h).
#include "gen_reference.h"

#include <algorithm>
#include <bit>
#include <cmath>

namespace vff::gen {

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
          const uint64_t from =
              map * mapBytes + 8 * (uint64_t((by * 4 % l.tileSize) / 4) * mb + (bx * 4 % l.tileSize) / 4);
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

// ---- REFN, written from spec/format.md section 14 independently of libvff ---------------------------
// Raw layout: u32 headerSize (64), u32 vertexCount V, u32 triangleCount T, f32 margin, u32
// unsureTexels, 44 reserved zero bytes; U = ceil(mapCount * M^2 / 8) bytes of unsure bits (texel
// x = (k * M + j) * M + i at bit x % 8 of byte x / 8); zero padding to a multiple of 4; 3V f32
// positions; 3T u32 indices.
namespace {
uint64_t refnUnsureBytes(const FieldDesc& f) {
  return (uint64_t(f.mapCount) * f.mapResolution * f.mapResolution + 7) / 8;
}
}  // namespace

Bytes referenceRefinementBytes(const FieldDesc& f, const Refinement& r) {
  const uint64_t u = refnUnsureBytes(f), posAt = 64 + alignUp(u, 4);
  Bytes b(posAt + 4 * r.positions.size() + 4 * r.indices.size(), 0);
  st32(b, 0, 64);
  st32(b, 4, uint32_t(r.positions.size() / 3));
  st32(b, 8, uint32_t(r.indices.size() / 3));
  st32(b, 12, std::bit_cast<uint32_t>(r.margin));
  st32(b, 16, r.unsureTexels);
  std::copy(r.unsure.begin(), r.unsure.end(), b.begin() + 64);
  for (size_t v = 0; v < r.positions.size(); ++v) st32(b, posAt + 4 * v, std::bit_cast<uint32_t>(r.positions[v]));
  const uint64_t idxAt = posAt + 4 * r.positions.size();
  for (size_t x = 0; x < r.indices.size(); ++x) st32(b, idxAt + 4 * x, r.indices[x]);
  return b;
}

uint32_t referenceDecodeRefinement(const FieldDesc& f, std::span<const uint8_t> raw, ReferenceRefinement* out,
                                   std::string* why) {
  const Bytes b(raw.begin(), raw.end());
  const auto bad = [&](uint32_t id, std::string text) {
    *why = std::move(text);
    return id;
  };
  // Rule 8501: bit1 fields have no REFN; the header; the total size.
  if (f.distanceEncoding == DistanceEncoding::kBit1) return bad(8501, "REFN in a bit1 field");
  if (b.size() < 64) return bad(8501, "REFN shorter than its 64-byte header");
  if (ld32(b, 0) != 64) return bad(8501, "headerSize is not 64");
  const uint32_t v = ld32(b, 4), t = ld32(b, 8);
  const float margin = std::bit_cast<float>(ld32(b, 12));
  if (v < 3 || t < 1) return bad(8501, "vertexCount < 3 or triangleCount < 1");
  if (!std::isfinite(margin) || margin < 0) return bad(8501, "margin not finite or negative");
  for (uint64_t at = 20; at < 64; ++at)
    if (b[at] != 0) return bad(8501, "reserved byte " + std::to_string(at) + " is not zero");
  const uint64_t u = refnUnsureBytes(f), p = alignUp(u, 4) - u;
  const uint64_t posAt = 64 + u + p, idxAt = posAt + 12 * uint64_t(v);
  if (b.size() != idxAt + 12 * uint64_t(t)) return bad(8501, "rawSize is not 64 + U + P + 12V + 12T");
  // Rule 8502: the bits past the last texel and the padding are zero; unsureTexels counts the bits.
  const uint64_t texels = uint64_t(f.mapCount) * f.mapResolution * f.mapResolution;
  for (uint64_t x = texels; x < 8 * u; ++x)
    if ((b[64 + x / 8] >> (x % 8)) & 1) return bad(8502, "bit " + std::to_string(x) + " past the last texel is set");
  for (uint64_t at = 64 + u; at < posAt; ++at)
    if (b[at] != 0) return bad(8502, "padding byte " + std::to_string(at) + " is not zero");
  uint64_t set = 0;
  for (uint64_t x = 0; x < texels; ++x) set += (b[64 + x / 8] >> (x % 8)) & 1;
  if (set != ld32(b, 16)) return bad(8502, "unsureTexels is not the number of bits set");
  // Rule 8503: positions finite and within (1 + 1e-4) R + 1e-6 of the centre; indices < V.
  const double lim = double(f.sphere.radius) * (1 + 1e-4) + 1e-6;
  std::vector<float> pos(3 * size_t(v));
  for (size_t k = 0; k < pos.size(); ++k) pos[k] = std::bit_cast<float>(ld32(b, posAt + 4 * k));
  for (size_t k = 0; k < v; ++k) {
    double d2 = 0;
    bool finite = true;
    for (int a = 0; a < 3; ++a) {
      const double d = double(pos[3 * k + a]) - double(f.sphere.center[a]);
      finite = finite && std::isfinite(d);
      d2 += d * d;
    }
    if (!finite || d2 > lim * lim) return bad(8503, "vertex " + std::to_string(k) + " not finite or outside the sphere");
  }
  std::vector<uint32_t> idx(3 * size_t(t));
  for (size_t k = 0; k < idx.size(); ++k) {
    idx[k] = ld32(b, idxAt + 4 * k);
    if (idx[k] >= v) return bad(8503, "index " + std::to_string(k) + " is not below vertexCount");
  }
  out->vertexCount = v;
  out->triangleCount = t;
  out->margin = margin;
  out->unsureTexels = ld32(b, 16);
  out->unsure.assign(b.begin() + 64, b.begin() + std::ptrdiff_t(64 + u));
  out->positions = std::move(pos);
  out->indices = std::move(idx);
  return 0;
}

}  // namespace vff::gen
