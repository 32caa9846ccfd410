// layout.js - the packed slice layout: computeLayout, placeMap and slice composition
// (spec/format.md section 10).

export const TARGET_2D_ARRAY = 1;
export const TARGET_3D = 2;

/**
 * The canonical layout for a field and device limits (format.md 10.1), or {error, id} naming the
 * limit that does not hold (7001-7003).
 */
export function computeLayout({ mapCount, mapResolution: M, distanceEncoding }, limits = {}) {
  const target = limits.target ?? TARGET_2D_ARRAY;
  const S = limits.maxTextureSize ?? 2048, L = limits.maxLayers ?? 2048, g = limits.gutter ?? 0;
  const noGutter = distanceEncoding === 4 || distanceEncoding === 5;
  if (target !== 1 && target !== 2) return { id: 7001, error: 'target is neither 2d-array nor 3d' };
  if (target !== 1 && distanceEncoding === 5) return { id: 7001, error: 'bc4-diameter needs a 2d-array' };
  if ((noGutter && g !== 0) || g > 64) return { id: 7002, error: `gutter ${g} not allowed` };
  const tileSize = M + 2 * g;
  if (tileSize > S) return { id: 7003, error: `a tile of ${tileSize} texels exceeds the texture size ${S}` };
  const fit = Math.floor(S / tileSize);
  const tilesPerRow = Math.min(fit, mapCount);
  const tilesPerColumn = Math.min(fit, Math.ceil(mapCount / tilesPerRow));
  const sliceCount = Math.ceil(mapCount / (tilesPerRow * tilesPerColumn));
  if (sliceCount > L) return { id: 7003, error: `${sliceCount} slices exceed the layer limit ${L}` };
  return {
    target, gutter: g, tileSize, tilesPerRow, tilesPerColumn,
    sliceWidth: tilesPerRow * tileSize, sliceHeight: tilesPerColumn * tileSize, sliceCount,
    maxTextureSize: S, maxLayers: L,
  };
}

/** Where map k lies: its slice and the slice texel (x0, y0) of its texel (0, 0) (format.md 10.2). */
export function placeMap(layout, k) {
  const perSlice = layout.tilesPerRow * layout.tilesPerColumn;
  const slice = Math.floor(k / perSlice), r = k % perSlice;
  return {
    slice,
    x0: (r % layout.tilesPerRow) * layout.tileSize + layout.gutter,
    y0: Math.floor(r / layout.tilesPerRow) * layout.tileSize + layout.gutter,
  };
}

/**
 * One composed slice of a plane (format.md 10.3): the bytes glTexSubImage3D / glCompressedTexSubImage3D
 * take for layer `s`.
 * @param {object} layout the LAYT values
 * @param {{M: number, mapCount: number, kind: 'bytes'|'bit1'|'bc4', texelBytes: number, fill: number}} plane
 *   kind 'bytes': texelBytes bytes per texel; fill is the byte of the unused area (0xFF for a
 *   distance miss code of 255 or 65535, 0 for normals and bit1)
 * @param {(k: number) => Uint8Array} getMap the raw bytes of map k
 */
export function composeSlice(layout, plane, s, getMap) {
  const { M, mapCount, kind } = plane;
  const perSlice = layout.tilesPerRow * layout.tilesPerColumn;
  const first = s * perSlice, last = Math.min(mapCount, first + perSlice);
  if (kind === 'bit1' || kind === 'bc4') {
    const unit = kind === 'bit1' ? 8 : 4;                  // texels per byte column / per block
    const rowBytes = kind === 'bit1' ? layout.sliceWidth / 8 : (layout.sliceWidth / 4) * 8;
    const rows = kind === 'bit1' ? layout.sliceHeight : layout.sliceHeight / 4;
    const mapRowBytes = kind === 'bit1' ? M / 8 : (M / 4) * 8;
    const mapRows = kind === 'bit1' ? M : M / 4;
    const out = new Uint8Array(rowBytes * rows).fill(plane.fill);
    for (let k = first; k < last; ++k) {
      const { x0, y0 } = placeMap(layout, k);
      const src = getMap(k);
      const xb = kind === 'bit1' ? x0 / 8 : (x0 / 4) * 8;
      const yr = y0 / (kind === 'bit1' ? 1 : unit);
      for (let j = 0; j < mapRows; ++j)
        out.set(src.subarray(j * mapRowBytes, (j + 1) * mapRowBytes), (yr + j) * rowBytes + xb);
    }
    return out;
  }
  const tb = plane.texelBytes, g = layout.gutter;
  const rowBytes = layout.sliceWidth * tb;
  const out = new Uint8Array(rowBytes * layout.sliceHeight).fill(plane.fill);
  for (let k = first; k < last; ++k) {
    const { x0, y0 } = placeMap(layout, k);
    const src = getMap(k);
    for (let j = 0; j < M; ++j) {
      const row = (y0 + j) * rowBytes;
      out.set(src.subarray(j * M * tb, (j + 1) * M * tb), row + x0 * tb);
      for (let e = 1; e <= g; ++e) {
        out.copyWithin(row + (x0 - e) * tb, row + x0 * tb, row + (x0 + 1) * tb);
        out.copyWithin(row + (x0 + M - 1 + e) * tb, row + (x0 + M - 1) * tb, row + (x0 + M) * tb);
      }
    }
    const a = (x0 - g) * tb, b = (x0 + M + g) * tb;
    for (let e = 1; e <= g; ++e) {
      out.copyWithin((y0 - e) * rowBytes + a, y0 * rowBytes + a, y0 * rowBytes + b);
      out.copyWithin((y0 + M - 1 + e) * rowBytes + a, (y0 + M - 1) * rowBytes + a, (y0 + M - 1) * rowBytes + b);
    }
  }
  return out;
}
