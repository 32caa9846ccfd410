// checksum.js - XXH3-64, seed 0, default secret (spec/format.md section 4, checksumAlgorithm 1).
//
// hash-wasm's xxhash3 is the xxHash library's XXH3_64bits compiled to WebAssembly; its output is
// checked against the conformance manifest's hashes by the tests. The hasher is created once
// (asynchronously, it instantiates WebAssembly); after initChecksums() every call is synchronous.
import { createXXHash3 } from 'hash-wasm';

let hasher = null;

/** Loads the WebAssembly hasher; call (and await) once before decoding. */
export async function initChecksums() {
  if (!hasher) hasher = await createXXHash3(0, 0);
}

/** XXH3-64 of the concatenation of the given byte arrays, as a 16-digit lowercase hex string. */
export function xxh3Hex(...parts) {
  if (!hasher) throw new Error('initChecksums() was not awaited');
  hasher.init();
  for (const p of parts) hasher.update(p);
  return hasher.digest('hex');
}
