#include <algorithm>
#include <string>

#include "vff/format.h"

namespace vff {

Result<LayoutDesc> computeLayout(const FieldDesc& field, const LayoutLimits& limits) {
  if (limits.target != LayoutTarget::kTexture2DArray && limits.target != LayoutTarget::kTexture3D)
    return makeError(Code::kLayoutTarget, "unknown texture target " + std::to_string(uint32_t(limits.target)));
  if (field.distanceEncoding == DistanceEncoding::kBc4Diameter && limits.target != LayoutTarget::kTexture2DArray)
    return makeError(Code::kLayoutTarget, "bc4-diameter fields need the 2d-array target (GL has no BC4 3D textures)");
  if (field.distanceEncoding == DistanceEncoding::kBit1 && limits.gutter != 0)
    return makeError(Code::kLayoutTile, "bit1 fields cannot have a gutter (8 texels share a byte)");
  if (field.distanceEncoding == DistanceEncoding::kBc4Diameter && limits.gutter != 0)
    return makeError(Code::kLayoutTile, "bc4-diameter fields cannot have a gutter (tiles start on 4x4 blocks)");
  if (limits.gutter > 64) return makeError(Code::kLayoutTile, "gutter must be at most 64 texels");
  const uint64_t tile = uint64_t(field.mapResolution) + 2ull * limits.gutter;
  if (field.mapCount == 0 || tile == 0) return makeError(Code::kLayoutGeometry, "field has no maps");
  if (tile > limits.maxTextureSize)
    return makeError(Code::kLayoutGeometry,
                     "a tile of " + std::to_string(tile) + " texels exceeds the maximum texture size " +
                         std::to_string(limits.maxTextureSize));
  const uint64_t fit = limits.maxTextureSize / tile;  // tiles per row or column that fit
  LayoutDesc l;
  l.target = limits.target;
  l.gutter = limits.gutter;
  l.tileSize = uint32_t(tile);
  l.tilesPerRow = uint32_t(std::min<uint64_t>(fit, field.mapCount));
  const uint64_t rowsNeeded = (field.mapCount + l.tilesPerRow - 1) / l.tilesPerRow;
  l.tilesPerColumn = uint32_t(std::min<uint64_t>(fit, rowsNeeded));
  const uint64_t perSlice = uint64_t(l.tilesPerRow) * l.tilesPerColumn;
  const uint64_t slices = (field.mapCount + perSlice - 1) / perSlice;
  if (slices > limits.maxLayers) {
    const uint64_t needSize = [&] {
      // The smallest square slice size (a multiple of the tile) that fits within maxLayers.
      for (uint64_t side = fit + 1;; ++side)
        if ((field.mapCount + side * side - 1) / (side * side) <= limits.maxLayers) return side * tile;
    }();
    return makeError(Code::kLayoutGeometry,
                     std::to_string(field.mapCount) + " maps of " + std::to_string(tile) + "x" +
                         std::to_string(tile) + " need " + std::to_string(slices) + " slices of " +
                         std::to_string(l.tilesPerRow * tile) + "x" + std::to_string(l.tilesPerColumn * tile) +
                         ", above the limit of " + std::to_string(limits.maxLayers) +
                         " layers; a maximum texture size of " + std::to_string(needSize) + " would fit");
  }
  l.sliceWidth = uint32_t(l.tilesPerRow * tile);
  l.sliceHeight = uint32_t(l.tilesPerColumn * tile);
  l.sliceCount = uint32_t(slices);
  l.maxTextureSize = limits.maxTextureSize;
  l.maxLayers = limits.maxLayers;
  return l;
}

Status checkLayout(const LayoutDesc& l, const FieldDesc& field) {
  if (l.target != LayoutTarget::kTexture2DArray && l.target != LayoutTarget::kTexture3D)
    return makeError(Code::kLayoutTarget, "unknown texture target " + std::to_string(uint32_t(l.target)));
  if (field.distanceEncoding == DistanceEncoding::kBc4Diameter && l.target != LayoutTarget::kTexture2DArray)
    return makeError(Code::kLayoutTarget, "bc4-diameter fields need the 2d-array target");
  if (field.distanceEncoding == DistanceEncoding::kBit1 && l.gutter != 0)
    return makeError(Code::kLayoutTile, "bit1 fields cannot have a gutter");
  if (field.distanceEncoding == DistanceEncoding::kBc4Diameter && l.gutter != 0)
    return makeError(Code::kLayoutTile, "bc4-diameter fields cannot have a gutter");
  if (l.gutter > 64) return makeError(Code::kLayoutTile, "gutter " + std::to_string(l.gutter) + " exceeds 64 texels");
  if (uint64_t(l.tileSize) != uint64_t(field.mapResolution) + 2ull * l.gutter)
    return makeError(Code::kLayoutTile, "tileSize " + std::to_string(l.tileSize) +
                                            " differs from mapResolution + 2*gutter = " +
                                            std::to_string(uint64_t(field.mapResolution) + 2ull * l.gutter));
  if (l.tilesPerRow == 0 || l.tilesPerColumn == 0)
    return makeError(Code::kLayoutGeometry, "tilesPerRow and tilesPerColumn must be at least 1");
  if (uint64_t(l.sliceWidth) != uint64_t(l.tilesPerRow) * l.tileSize ||
      uint64_t(l.sliceHeight) != uint64_t(l.tilesPerColumn) * l.tileSize)
    return makeError(Code::kLayoutGeometry, "slice size differs from tiles x tileSize");
  const uint64_t perSlice = uint64_t(l.tilesPerRow) * l.tilesPerColumn;
  const uint64_t slices = (uint64_t(field.mapCount) + perSlice - 1) / perSlice;
  if (slices != l.sliceCount)
    return makeError(Code::kLayoutGeometry, "sliceCount " + std::to_string(l.sliceCount) + " should be " +
                                                std::to_string(slices));
  if (l.maxTextureSize != 0 && (l.sliceWidth > l.maxTextureSize || l.sliceHeight > l.maxTextureSize))
    return makeError(Code::kLayoutGeometry, "slice exceeds the recorded maximum texture size");
  if (l.maxLayers != 0 && l.sliceCount > l.maxLayers)
    return makeError(Code::kLayoutGeometry, "sliceCount exceeds the recorded maximum layer count");
  return {};
}

TilePlacement placeMap(const LayoutDesc& l, uint32_t map) noexcept {
  const uint64_t perSlice = uint64_t(l.tilesPerRow) * l.tilesPerColumn;
  TilePlacement p;
  if (perSlice == 0) return p;
  p.slice = uint32_t(map / perSlice);
  const uint64_t r = map % perSlice;
  p.x = uint32_t((r % l.tilesPerRow) * l.tileSize + l.gutter);
  p.y = uint32_t((r / l.tilesPerRow) * l.tileSize + l.gutter);
  return p;
}

}  // namespace vff
