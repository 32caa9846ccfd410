// vff.js - the public entry point of the JavaScript .vff decoder (written from spec/).
//
//   import { initVff, openVff } from './src/vff.js';
//   await initVff();                          // loads the XXH3 WebAssembly once
//   const file = openVff(arrayBuffer);        // throws VffError {id, codeName, section, offset}
//   file.field, file.layout, file.metadata    // FDSC, LAYT, META
//   file.distance(k, i, j)                    // null for a miss
//   file.slice('distance', s)                 // the bytes of a texture layer
//   file.validateDeep()                       // padding, every block decoded, normals of misses
export { initChecksums as initVff, xxh3Hex } from './checksum.js';
export { openVff, DEFAULT_READ_OPTIONS, ENCODING_NAMES, POSITION_NAMES, DIRECTION_NAMES, distanceMapBytes } from './container.js';
export { VffError, CODE_NAMES } from './errors.js';
export { VffFile, decodeNormal } from './file.js';
export { PositionSet, sampleCount } from './positions.js';
export { computeLayout, placeMap } from './layout.js';
export * as geometry from './geometry.js';
