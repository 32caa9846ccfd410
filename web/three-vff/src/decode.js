// decode.js - a .vff's bytes to what VffField uploads: the checked file (every block decoded once,
// spec/validation.md) and, at a layout, its texture data (web/src/field_textures.js). The main
// thread (VffField.fromBytes) and the Worker (worker.js) run the same steps.
import { initVff, openVff } from '../../src/vff.js';
import { chooseLayout } from '../../src/gpu.js';
import { fieldTextureData } from '../../src/field_textures.js';

/**
 * Opens and checks a .vff (throws the decoder's VffError) and builds its texture data.
 * options.limits: {maxTextureSize, maxLayers, max3d} of the context the field is for; the file's
 * layout is repacked when it does not fit them (else the file's own layout is used).
 * options.onProgress({stage: 'open'|'check'|'textures'|'done', done, total}).
 * @returns {Promise<{file: import('../../src/file.js').VffFile, data: object}>} data: {field, layout,
 *   note, metadata, textures} (plain values and typed arrays: a Worker can post it)
 */
export async function decodeVff(bytes, options = {}) {
  const progress = options.onProgress ?? (() => {});
  await initVff();
  progress({ stage: 'open', done: 0, total: 1 });
  const file = openVff(bytes instanceof Uint8Array ? bytes : new Uint8Array(bytes));
  progress({ stage: 'check', done: 0, total: 1 });
  file.validateDeep();
  return { file, data: textureDataOf(file, options.limits, progress) };
}

/** The texture data of an opened file for a context's limits (null: the file's layout). */
export function textureDataOf(file, limits, progress = () => {}) {
  let layout = file.layout, note = null;
  if (limits) {
    const chosen = chooseLayout(file, limits);
    if (chosen.error) throw new Error(chosen.error);
    layout = chosen.layout;
    note = chosen.note ?? null;
  }
  const textures = fieldTextureData(file, layout, (done, total) => progress({ stage: 'textures', done, total }));
  progress({ stage: 'done', done: 1, total: 1 });
  return {
    field: file.field, layout, note, metadata: file.metadata?.value ?? null, textures,
  };
}

/** The transferable buffers of decodeVff's data (for postMessage). */
export function transferables(data) {
  const t = data.textures, out = [t.maps.data.buffer, t.block, t.positions.data.buffer];
  if (t.normals) out.push(t.normals.data.buffer);
  return out;
}
