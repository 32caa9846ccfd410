// worker.js - decodes a .vff off the main thread: decodeInWorker(bytes, onProgress) runs decode.js's
// steps in a module Worker (this file) and resolves to the same data VffField.fromDecoded takes.
// The page keeps answering while a large field decodes; progress arrives as events.
import { decodeVff, transferables } from './decode.js';

const IN_WORKER = typeof WorkerGlobalScope !== 'undefined' && globalThis instanceof WorkerGlobalScope;

if (IN_WORKER) {
  globalThis.onmessage = async ({ data: { bytes, limits } }) => {
    try {
      const { data } = await decodeVff(bytes, { limits, onProgress: (p) => globalThis.postMessage({ progress: p }) });
      globalThis.postMessage({ data }, transferables(data));
    } catch (e) {
      // A VffError's fields travel as plain values; decodeInWorker rebuilds the error.
      globalThis.postMessage({ error: { name: e.name, message: e.message, id: e.id, codeName: e.codeName, section: e.section, offset: e.offset, detail: e.detail } });
    }
  };
}

/**
 * Decodes `bytes` (Uint8Array or ArrayBuffer; a copy is posted, the caller's stays usable) in a
 * Worker. onProgress({stage, done, total}) reports 'open', 'check', 'textures' (layers composed) and
 * 'done'. options.limits: the context's limits (see decode.js). Resolves to {field, layout, note,
 * metadata, textures}; rejects with an Error carrying the decoder's {id, codeName, section, offset}.
 */
export function decodeInWorker(bytes, onProgress = null, options = {}) {
  const worker = new Worker(new URL('./worker.js', import.meta.url), { type: 'module' });
  const copy = (bytes instanceof Uint8Array ? bytes : new Uint8Array(bytes)).slice();
  return new Promise((resolve, reject) => {
    worker.onmessage = ({ data }) => {
      if (data.progress) { onProgress?.(data.progress); return; }
      worker.terminate();
      if (data.error) reject(Object.assign(new Error(data.error.message), data.error));
      else resolve(data.data);
    };
    worker.onerror = (e) => { worker.terminate(); reject(new Error(`the decode worker failed: ${e.message ?? e}`)); };
    worker.postMessage({ bytes: copy, limits: options.limits ?? null }, [copy.buffer]);
  });
}
