// Worked examples of the spec text: the hits-med stream (format.md 4), BC4 blocks (7.4), normals
// (7.3), positions (positions.md 3.2, 4.2, 5.1) and the canonical layout (format.md 12).
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { unfilterHitsMed } from '../src/filters.js';
import { decodeBc4Block } from '../src/bc4.js';
import { decodeNormal } from '../src/file.js';
import { PositionSet } from '../src/positions.js';
import { computeLayout } from '../src/layout.js';

const close = (a, b, eps = 1e-7) => a.every((v, i) => Math.abs(v - b[i]) <= eps);

test('hits-med example of format.md section 4', () => {
  const r = unfilterHitsMed(Uint8Array.from([0x3b, 0x01, 0x0a, 0x02, 0x01, 0x01, 0x01, 0x01]), 9, 3);
  assert.deepEqual([...r.bytes], [10, 12, 255, 11, 13, 14, 255, 255, 15]);
  assert.ok(unfilterHitsMed(Uint8Array.from([0x3b, 0x01, 0x0a]), 9, 3).error);
});

test('BC4 examples of format.md 7.4', () => {
  const out = new Uint8Array(16);
  decodeBc4Block(Uint8Array.from([0xc8, 0x3c, 0x88, 0xc6, 0xfa, 0x88, 0xc6, 0xfa]), 0, out);
  assert.deepEqual([...out], [200, 60, 180, 160, 140, 120, 100, 80, 200, 60, 180, 160, 140, 120, 100, 80]);
  decodeBc4Block(Uint8Array.from([0x0a, 0x1e, 0x88, 0xc6, 0xfa, 0x88, 0xc6, 0xfa]), 0, out);
  assert.deepEqual([...out.subarray(0, 8)], [10, 30, 14, 18, 22, 26, 0, 255]);
});

test('oct-snorm16 examples of format.md 7.3', () => {
  assert.ok(close(decodeNormal(0, 0), [0, 0, 1]));
  assert.ok(close(decodeNormal(32767, 0), [1, 0, 0]));
  assert.ok(close(decodeNormal(0, -32767), [0, -1, 0]));
  assert.ok(close(decodeNormal(32767, 32767), [0, 0, -1]));
});

test('sample positions of positions.md', () => {
  const o = new PositionSet(1, 32);
  assert.ok(close(o.position(1), [-0.0322412923, -0.999480128, 0]));
  assert.ok(close(o.position(1056), [0, 0, 1]) && close(o.position(2113), [0, -1, 0]));
  const e = new PositionSet(2, 3);
  assert.ok(close(e.position(5), [0.83147943, 0, 0.555555582]));
  assert.ok(close(e.position(0), [-0.587944746, -0.587944746, -0.555555582]));
  const f = new PositionSet(3, 4226);
  assert.ok(close(f.position(1), [-0.0277791265, -0.0254479554, 0.999290109]));
  assert.ok(close(f.position(4225), [0.00754809286, 0.0204017423, -0.99976337]));
});

test('nearest sample equals a brute-force search', () => {
  for (const [scheme, n] of [[1, 8], [2, 9], [3, 200]]) {
    const p = new PositionSet(scheme, n);
    let seed = 12345;
    const rnd = () => ((seed = (seed * 1103515245 + 12345) % 2 ** 31) / 2 ** 31) * 2 - 1;
    for (let q = 0; q < 2000; ++q) {
      const d = [rnd(), rnd(), rnd()];
      const l = Math.hypot(...d);
      let best = -2;
      for (let k = 0; k < p.count; ++k) best = Math.max(best, (d[0] * p.exact[3 * k] + d[1] * p.exact[3 * k + 1] + d[2] * p.exact[3 * k + 2]) / l);
      const k = p.nearest(d);
      const got = (d[0] * p.exact[3 * k] + d[1] * p.exact[3 * k + 1] + d[2] * p.exact[3 * k + 2]) / l;
      assert.ok(got >= best - 1e-6, `scheme ${scheme} query ${q}`);
    }
  }
});

test('canonical layout of format.md section 12', () => {
  const l = computeLayout({ mapCount: 4226, mapResolution: 64, distanceEncoding: 1 });
  assert.deepEqual([l.tilesPerRow, l.tilesPerColumn, l.sliceCount, l.sliceWidth], [32, 32, 5, 2048]);
  assert.equal(computeLayout({ mapCount: 4226, mapResolution: 64, distanceEncoding: 1 }, { gutter: 1 }).tilesPerRow, 31);
  assert.equal(computeLayout({ mapCount: 4226, mapResolution: 64, distanceEncoding: 1 }, { maxLayers: 4 }).id, 7003);
});

test('a layout beyond the context limits is repacked, naming the limit and vff-convert options', async () => {
  const { chooseLayout } = await import('../src/gpu.js');
  const field = { mapCount: 4226, mapResolution: 64, distanceEncoding: 1 };
  const layout = { target: 1, gutter: 0, tileSize: 64, tilesPerRow: 64, tilesPerColumn: 64, sliceWidth: 4096, sliceHeight: 4096, sliceCount: 2 };
  assert.equal(chooseLayout({ field, layout }, { maxTextureSize: 8192, maxLayers: 2048, max3d: 2048 }).layout, layout);
  const r = chooseLayout({ field, layout }, { maxTextureSize: 2048, maxLayers: 256, max3d: 256 });
  assert.equal(r.layout.sliceWidth, 2048);
  assert.equal(r.layout.sliceCount, 5);
  assert.match(r.note, /exceed MAX_TEXTURE_SIZE 2048/);
  assert.match(r.note, /vff-convert in\.vff --to vff out\.vff --target 2d-array --max-texture-size 2048 --max-layers 256/);
  const none = chooseLayout({ field, layout }, { maxTextureSize: 2048, maxLayers: 4, max3d: 256 });
  assert.match(none.error, /5 slices exceed the layer limit 4/);
  assert.match(none.error, /--map-size 32/);
});
