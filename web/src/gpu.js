// gpu.js - uploads a decoded .vff for the GLSL ES query: distance (and normal) slices as
// TEXTURE_2D_ARRAY (or TEXTURE_3D) layers within the limits the context reports, the field block
// and the positions table (spec/format.md 10.4).
import { computeLayout, composeSlice } from './layout.js';
import { buildQueryTables } from './query_tables.js';
import { fieldSlices, positionsTexture } from './field_textures.js';

/** The limits of a WebGL2 context that a layout must respect. */
export function contextLimits(gl) {
  return {
    maxTextureSize: gl.getParameter(gl.MAX_TEXTURE_SIZE),
    maxLayers: gl.getParameter(gl.MAX_ARRAY_TEXTURE_LAYERS),
    max3d: gl.getParameter(gl.MAX_3D_TEXTURE_SIZE),
  };
}

/**
 * Checks the file's layout against the context. Returns {layout, note}: the file's LAYT when it fits,
 * else the canonical layout for the context's limits (format.md 10.4 lets a loader repack), with a
 * note naming the limit and the vff-convert options that would make a file that fits; or {error}.
 */
export function chooseLayout(file, lim) {
  const L = file.layout;
  const is3d = L.target === 2;
  const size = is3d ? lim.max3d : lim.maxTextureSize;
  const problems = [];
  if (L.sliceWidth > size || L.sliceHeight > size)
    problems.push(`slices of ${L.sliceWidth} x ${L.sliceHeight} exceed ${is3d ? 'MAX_3D_TEXTURE_SIZE' : 'MAX_TEXTURE_SIZE'} ${size}`);
  if (!is3d && L.sliceCount > lim.maxLayers) problems.push(`${L.sliceCount} slices exceed MAX_ARRAY_TEXTURE_LAYERS ${lim.maxLayers}`);
  if (is3d && L.sliceCount > lim.max3d) problems.push(`${L.sliceCount} slices exceed MAX_3D_TEXTURE_SIZE ${lim.max3d}`);
  if (!problems.length) return { layout: L };
  const mine = computeLayout(file.field, { maxTextureSize: lim.maxTextureSize, maxLayers: lim.maxLayers });
  const fix = `vff-convert in.vff --to vff out.vff --target 2d-array --max-texture-size ${lim.maxTextureSize} --max-layers ${lim.maxLayers}`;
  if (mine.error) {
    return { error: `The layout does not fit this GPU: ${problems.join('; ')}; no packing of ${file.field.mapCount} maps of ${file.field.mapResolution}² fits (${mine.error}). Try fewer or smaller maps: vff-convert in.vff --to vff out.vff --map-size ${Math.max(4, file.field.mapResolution / 2)} (or --count).` };
  }
  return { layout: mine, note: `The file's layout does not fit this GPU (${problems.join('; ')}); repacked here as ${mine.sliceCount} slices of ${mine.sliceWidth} x ${mine.sliceHeight}. A file that fits as it is: ${fix}` };
}

function texture(gl, is3d, fmt, width, height, layers, sliceData) {
  const target = is3d ? gl.TEXTURE_3D : gl.TEXTURE_2D_ARRAY;
  const t = gl.createTexture();
  gl.bindTexture(target, t);
  gl.texParameteri(target, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
  gl.texParameteri(target, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
  gl.pixelStorei(gl.UNPACK_ALIGNMENT, 1);
  gl.texStorage3D(target, 1, fmt.internal, width, height, layers);
  for (let s = 0; s < layers; ++s)
    gl.texSubImage3D(target, 0, 0, 0, s, width, height, 1, fmt.format, fmt.type, sliceData(s));
  return t;
}

/**
 * Uploads a file. Returns {field: {defines, center, radius}, layout, note} or {error}.
 * bc4-diameter blocks are uploaded as they are (COMPRESSED_RED_RGTC1) when the context has
 * EXT_texture_compression_rgtc and options.bc4OnCpu is not set; otherwise they are decoded to unorm8
 * codes on the CPU and uploaded as R8UI, which every WebGL2 context has.
 */
export function uploadField(gl, file, options = {}) {
  const chosen = chooseLayout(file, contextLimits(gl));
  if (chosen.error) return chosen;
  const L = chosen.layout, fd = file.field, e = fd.distanceEncoding, M = fd.mapResolution;
  const sl = fieldSlices(file, L);
  const is3d = sl.is3d;
  const FORMATS = {
    r8ui: { internal: gl.R8UI, format: gl.RED_INTEGER, type: gl.UNSIGNED_BYTE },
    r16ui: { internal: gl.R16UI, format: gl.RED_INTEGER, type: gl.UNSIGNED_SHORT },
    rg16i: { internal: gl.RG16I, format: gl.RG_INTEGER, type: gl.SHORT },
  };
  const defines = [];
  const rgtc = e === 5 && !options.bc4OnCpu ? gl.getExtension('EXT_texture_compression_rgtc') : null;
  gl.activeTexture(gl.TEXTURE0);
  if (rgtc) {
    defines.push('VFF_MAPS_BC4');
    const plane = { kind: 'bc4', texelBytes: 1, fill: 0xff, M, mapCount: fd.mapCount };
    const t = gl.createTexture();
    gl.bindTexture(gl.TEXTURE_2D_ARRAY, t);
    gl.texParameteri(gl.TEXTURE_2D_ARRAY, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
    gl.texParameteri(gl.TEXTURE_2D_ARRAY, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
    gl.texStorage3D(gl.TEXTURE_2D_ARRAY, 1, rgtc.COMPRESSED_RED_RGTC1_EXT, L.sliceWidth, L.sliceHeight, L.sliceCount);
    for (let s = 0; s < L.sliceCount; ++s)
      gl.compressedTexSubImage3D(gl.TEXTURE_2D_ARRAY, 0, 0, 0, s, L.sliceWidth, L.sliceHeight, 1, rgtc.COMPRESSED_RED_RGTC1_EXT,
        composeSlice(L, plane, s, (k) => file.mapBytes('distance', k)));
  } else texture(gl, is3d, FORMATS[sl.maps.format], sl.maps.width, sl.maps.height, sl.maps.layers, sl.maps.slice);
  defines.push(...sl.defines);
  if (sl.normals) {
    gl.activeTexture(gl.TEXTURE1);
    texture(gl, is3d, FORMATS.rg16i, sl.normals.width, sl.normals.height, sl.normals.layers, sl.normals.slice);
  }
  const { block, table } = buildQueryTables(file, L);
  const ubo = gl.createBuffer();
  gl.bindBuffer(gl.UNIFORM_BUFFER, ubo);
  gl.bufferData(gl.UNIFORM_BUFFER, block, gl.STATIC_DRAW);
  gl.bindBufferBase(gl.UNIFORM_BUFFER, 0, ubo);
  const pos = positionsTexture(table);
  gl.activeTexture(gl.TEXTURE2);
  const pt = gl.createTexture();
  gl.bindTexture(gl.TEXTURE_2D, pt);
  gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
  gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
  gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA32F, pos.width, pos.height, 0, gl.RGBA, gl.FLOAT, pos.data);
  return { field: { defines, center: fd.sphere.center, radius: fd.sphere.radius }, layout: L, note: chosen.note, bc4: rgtc ? 'gpu' : e === 5 ? 'cpu' : null };
}
