// In headless Chromium: the example page loads its .glb (made by tools/make-example.mjs), finds a
// field on every mesh, stands the four moving objects on the floor, draws frames, moves the objects
// with time, accumulates while the view holds still, answers its controls, and logs no console error.
import { test, after, before } from 'node:test';
import assert from 'node:assert/strict';
import { openExample, frame, compare } from './common.js';

let ex;
before(async () => { ex = await openExample({ query: 'noloop=1&paused=1&t=1&rays=1', viewport: { width: 240, height: 160 } }); });
after(async () => { await ex?.close(); });

test('the asset: a field on each of the five meshes, four objects moving, each standing on the floor', async () => {
  const r = await ex.page.evaluate(() => {
    const e = window.example;
    if (e.error) return { error: e.error };
    const Vector3 = e.camera.position.constructor;
    return {
      fields: e.gltf.userData.vffFields.map((f) => ({ name: f.name, usable: !!f.field, match: f.match })),
      problems: e.problems.map((p) => p.rule ?? p.id ?? p),
      movers: e.movers.map((o) => o.name),
      // Lowest world-space vertex of each object: 0 is on the floor.
      lowest: e.movers.map((o) => {
        o.updateWorldMatrix(true, true);
        let low = Infinity;
        o.traverse((m) => {
          if (!m.isMesh) return;
          const p = m.geometry.attributes.position, v = new Vector3();
          for (let i = 0; i < p.count; ++i) low = Math.min(low, v.fromBufferAttribute(p, i).applyMatrix4(m.matrixWorld).y);
        });
        return low;
      }),
    };
  });
  assert.equal(r.error, undefined, r.error);
  console.log('fields:', JSON.stringify(r.fields), 'problems:', JSON.stringify(r.problems));
  assert.equal(r.fields.length, 5);
  assert.ok(r.fields.every((f) => f.usable && f.match === 'exact'), JSON.stringify(r.fields));
  assert.equal(r.movers.length, 4);
  assert.ok(!r.movers.includes('floor'));
  console.log('lowest point of each object:', r.lowest.map((y) => y.toFixed(5)).join(' '));
  for (const y of r.lowest) assert.ok(Math.abs(y) < 1e-4, `an object's lowest point is at y = ${y}, not on the floor`);
});

test('frames render, the objects move with time, and the effect accumulates while still', async () => {
  await ex.page.evaluate(() => window.example.setTime(1));
  const a1 = await frame(ex.page);
  const a4 = await frame(ex.page, 3);
  console.log(`frames accumulated at a still view: ${a1.frame}, then ${a4.frame}; ${a1.ms.toFixed(0)} ms a frame`);
  assert.ok(a4.frame > a1.frame, `the effect's frame count went ${a1.frame} -> ${a4.frame}`);
  // Not one flat colour: the floor, the objects and the background differ.
  const colours = new Set();
  for (let i = 0; i < a1.pixels.length; i += 4 * 97) colours.add(a1.pixels.slice(i, i + 3).join());
  assert.ok(colours.size > 20, `only ${colours.size} colours in the frame`);
  const positions = () => ex.page.evaluate(() => window.example.movers.map((o) => o.position.toArray()));
  const p1 = await positions();
  await ex.page.evaluate(() => window.example.setTime(2.5));
  const b = await frame(ex.page);
  const p2 = await positions();
  assert.equal(b.frame, 1, 'moving the objects restarts the accumulation');
  const moved = p1.map((p, i) => Math.hypot(p[0] - p2[i][0], p[2] - p2[i][2]));
  console.log('moved by:', moved.map((d) => d.toFixed(3)).join(' '));
  assert.ok(moved.every((d) => d > 0.2));
  assert.ok(p2.every((p) => p[1] === 0), 'the objects stay on the floor');
  let changed = 0;
  for (let i = 0; i < b.pixels.length; i += 4) changed += Math.max(...[0, 1, 2].map((k) => Math.abs(b.pixels[i + k] - a1.pixels[i + k]))) > 8;
  const share = changed / (b.pixels.length / 4);
  console.log(`pixels changed between t = 1 and t = 2.5: ${(100 * share).toFixed(1)}%; RMS ${compare(a1, b).rms.toFixed(1)}`);
  assert.ok(share > 0.02, `only ${(100 * share).toFixed(2)}% of the pixels changed`);
});

test('the controls: modes, AO range, rays, pause', async () => {
  const p = ex.page;
  await p.getByRole('radio', { name: 'off', exact: true }).check();
  assert.equal(await p.evaluate(() => window.example.occ.mode), 'off');
  const off = await frame(p);
  await p.getByRole('radio', { name: 'fields', exact: true }).check();
  assert.equal(await p.evaluate(() => window.example.occ.mode), 'field');
  const on = await frame(p);
  const d = compare(off, on);
  console.log(`fields on against off: RMS ${d.rms.toFixed(2)}, ${(100 * (1 - d.within)).toFixed(1)}% of pixels differ by more than 8`);
  assert.ok(d.rms > 1, 'turning the fields on changes the image');
  await p.getByRole('radio', { name: 'exact reference', exact: true }).check();
  assert.equal(await p.evaluate(() => window.example.occ.mode), 'reference');
  await p.getByRole('radio', { name: 'fields', exact: true }).check();
  await p.locator('#range').fill('1.2');
  assert.equal(await p.evaluate(() => window.example.occ.options.aoRange), 1.2);
  await p.locator('#rays').fill('2');
  assert.equal(await p.evaluate(() => window.example.occ.options.aoRays), 2);
  assert.equal(await p.locator('#rays-out').textContent(), '2');
  await p.locator('#rays').fill('4');
  await p.locator('#range').fill('0.6');
  await p.getByRole('checkbox', { name: 'pause' }).check();
  assert.equal(await p.evaluate(() => window.example.ui.paused), true);
  assert.deepEqual(ex.errors, []);
});
