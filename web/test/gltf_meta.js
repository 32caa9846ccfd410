// gltf_meta.js - a whole valid field whose META is the given object: the conformance vector
// u16d-stored-meta-slices with its stored META section rewritten in place (sizes, section checksum
// and header checksum recomputed), for the tests of rules 14009 and 14010.
import { readFileSync } from 'node:fs';
import { join } from 'node:path';
import { initVff, xxh3Hex } from '../src/vff.js';
import { ROOT } from './gltf_assets.js';

await initVff();

export function withMeta(meta) {
  const b = new Uint8Array(readFileSync(join(ROOT, 'spec', 'conformance', 'valid', 'u16d-stored-meta-slices.vff')));
  const dv = new DataView(b.buffer);
  const table = Number(dv.getBigUint64(40, true)), count = dv.getUint32(48, true);
  const text = new TextEncoder().encode(JSON.stringify(meta));
  for (let i = 0; i < count; ++i) {
    const e = table + 64 * i;
    if (new TextDecoder().decode(b.subarray(e, e + 4)) !== 'META') continue;
    const off = Number(dv.getBigUint64(e + 8, true)), old = Number(dv.getBigUint64(e + 16, true));
    if (dv.getUint16(e + 32, true) !== 0 || text.length > old) throw new Error('the vector META is not stored or too short');
    b.fill(0, off, off + old);
    b.set(text, off);
    dv.setBigUint64(e + 16, BigInt(text.length), true);
    dv.setBigUint64(e + 24, BigInt(text.length), true);
    dv.setBigUint64(e + 40, BigInt('0x' + xxh3Hex(text)), true);
    dv.setBigUint64(56, BigInt('0x' + xxh3Hex(b.subarray(0, 56), b.subarray(table, table + 64 * count))), true);
    return b;
  }
  throw new Error('the vector has no META');
}
