// Damaged files: every valid conformance vector cut at many lengths and with single bytes changed
// (XOR 0xFF and 0x01, as tests/robustness does for libvff) either reads completely or is rejected
// with a file-problem ID (2xxx-8xxx) - never another exception (a RangeError, a TypeError).
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFileSync, readdirSync } from 'node:fs';
import { join, dirname } from 'node:path';
import { fileURLToPath } from 'node:url';
import { initVff, openVff } from '../src/vff.js';

const dir = join(dirname(fileURLToPath(import.meta.url)), '..', '..', 'spec', 'conformance', 'valid');
await initVff();

function outcome(bytes) {
  try {
    const f = openVff(bytes);
    f.validateDeep();
    for (let k = 0; k < f.field.mapCount; ++k) f.codes(k);
    for (const p of Object.keys(f.planes)) for (let s = 0; s < f.layout.sliceCount; ++s) f.slice(p, s);
    return 0;
  } catch (e) {
    if (!(e.id >= 2000 && e.id < 9000)) throw new Error(`not a file-problem ID: ${e.stack ?? e}`);
    return e.id;
  }
}

for (const name of readdirSync(dir).filter((n) => n.endsWith('.vff')).sort()) {
  test(`damaged ${name}`, () => {
    const good = new Uint8Array(readFileSync(join(dir, name)));
    const n = good.length;
    for (let i = 0; i < 64; ++i) outcome(good.slice(0, Math.floor((n * i) / 64)));
    // Every byte of the header, the table and the first 128 bytes of each 4 KiB page, then a stride.
    const at = new Set();
    for (let o = 0; o < Math.min(n, 512); ++o) at.add(o);
    for (let p = 4096; p < n; p += 4096) for (let o = p; o < Math.min(n, p + 128); ++o) at.add(o);
    for (let o = 0; o < n; o += 97) at.add(o);
    let rejected = 0;
    for (const o of at)
      for (const x of [0xff, 0x01]) {
        const b = good.slice();
        b[o] ^= x;
        rejected += outcome(b) !== 0;
      }
    assert.ok(rejected > 0);
  });
}
