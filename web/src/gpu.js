// gpu.js - the WebGL2 limits a field's slices must fit, and the layout that fits them (the file's
// own, or a repack: spec/format.md 10.4); field_textures.js and three-vff make the textures.
import { computeLayout } from './layout.js';

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

