// field_textures.js - what a GPU needs of a decoded .vff for the GLSL ES query (gpu/glsl/vff_query.glsl
// through vff_query_es.js), as plain typed arrays: the distance and normal slices of a layout, the
// field block and the positions table. gpu.js uploads them with raw WebGL2, three-vff as three.js
// textures; a Worker can build them and transfer the buffers.
import { composeSlice } from './layout.js';
import { buildQueryTables } from './query_tables.js';

/**
 * The texel format and the composed layer `s` of each plane. bc4-diameter maps are decoded to their
 * unorm8 codes here (R8UI, which every WebGL2 context has); gpu.js uploads the blocks themselves
 * when the context decodes BC4.
 * @returns {{maps: {format: 'r8ui'|'r16ui', width: number, height: number, layers: number, slice(s): Uint8Array|Uint16Array},
 *   normals: null | {format: 'rg16i', width: number, height: number, layers: number, slice(s): Int16Array},
 *   is3d: boolean, defines: string[]}}
 */
export function fieldSlices(file, layout) {
  const fd = file.field, e = fd.distanceEncoding, M = fd.mapResolution, L = layout;
  const plane = (kind, texelBytes, fill) => ({ kind, texelBytes, fill, M, mapCount: fd.mapCount });
  const is3d = L.target === 2;
  const maps = { format: 'r8ui', width: L.sliceWidth, height: L.sliceHeight, layers: L.sliceCount, slice: null };
  if (e === 3) {
    maps.format = 'r16ui';
    maps.slice = (s) => { const b = composeSlice(L, plane('bytes', 2, 0xff), s, (k) => file.mapBytes('distance', k)); return new Uint16Array(b.buffer, b.byteOffset, b.length / 2); };
  } else if (e === 4) {
    maps.width = L.sliceWidth / 8;
    maps.slice = (s) => composeSlice(L, plane('bit1', 1, 0), s, (k) => file.mapBytes('distance', k));
  } else if (e === 5) maps.slice = (s) => composeSlice(L, plane('bytes', 1, 0xff), s, (k) => file.codes(k));
  else maps.slice = (s) => composeSlice(L, plane('bytes', 1, 0xff), s, (k) => file.mapBytes('distance', k));
  const defines = is3d ? ['VFF_MAPS_3D'] : [];
  let normals = null;
  if (file.planes.normal) {
    normals = {
      format: 'rg16i', width: L.sliceWidth, height: L.sliceHeight, layers: L.sliceCount,
      slice: (s) => { const b = composeSlice(L, plane('bytes', 4, 0), s, (k) => file.mapBytes('normal', k)); return new Int16Array(b.buffer, b.byteOffset, b.length / 2); },
    };
  } else defines.push('VFF_NO_NORMALS');
  return { maps, normals, is3d, defines };
}

/** The positions table as the rows of an RGBA32F texture at most 2048 texels wide (vffPositionsTex). */
export function positionsTexture(table) {
  const vec4s = table.length / 4, width = Math.min(vec4s, 2048), height = Math.ceil(vec4s / width);
  const data = new Float32Array(width * height * 4);
  data.set(table);
  return { width, height, data };
}

/**
 * Every layer of a plane in one array (layer after layer), as a DataArrayTexture or Data3DTexture
 * takes it. onLayer(s) is called after each layer (progress).
 */
export function joinSlices(p, onLayer = null) {
  let out = null;
  for (let s = 0; s < p.layers; ++s) {
    const a = p.slice(s);
    if (!out) out = new a.constructor(a.length * p.layers);
    out.set(a, s * a.length);
    onLayer?.(s);
  }
  return out;
}

/**
 * The whole texture data of a field at a layout, transferable (a Worker can post it):
 * {maps: {format, width, height, layers, data}, normals: null | {...}, is3d, defines,
 *  block: ArrayBuffer (std140 VffFieldBlock), table: Float32Array, positions: {width, height, data}}.
 */
export function fieldTextureData(file, layout, onLayer = null) {
  const sl = fieldSlices(file, layout);
  const total = sl.maps.layers + (sl.normals ? sl.normals.layers : 0);
  let done = 0;
  const tick = onLayer ? () => onLayer(++done, total) : null;
  const { block, table } = buildQueryTables(file, layout);
  const plain = (p) => p && { format: p.format, width: p.width, height: p.height, layers: p.layers, data: joinSlices(p, tick) };
  return { maps: plain(sl.maps), normals: plain(sl.normals), is3d: sl.is3d, defines: sl.defines, block, table, positions: positionsTexture(table) };
}
