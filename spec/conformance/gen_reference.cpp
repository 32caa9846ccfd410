// gen_reference.cpp - what the conformance vectors must decode to (gen_reference.h).
#include "gen_reference.h"

#include <algorithm>

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

}  // namespace vff::gen
