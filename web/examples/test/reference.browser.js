// In headless Chromium: one frame of the example (the objects held at one time, one view, the same
// rays per pixel) drawn three ways in the same page: the objects' fields (VffOcclusion 'field'),
// the exact reference ('reference': three-mesh-bvh's GPU ray casting against the objects'
// triangles) and no occlusion ('off'), each accumulated over the same frames. Prints the RMS
// (8-bit, RGB) and the share of pixels within 8 levels of the reference, over the whole image and
// over the floor; the fields must be close to the reference and far closer than no occlusion.
import { test, after, before } from 'node:test';
import assert from 'node:assert/strict';
import { openExample, frame, compare } from './common.js';

// Frames accumulated per mode: the reference costs seconds a frame in software rendering.
const FRAMES = 4;
let ex;
before(async () => { ex = await openExample({ query: 'noloop=1&paused=1&t=3&rays=4', viewport: { width: 160, height: 120 } }); });
after(async () => { await ex?.close(); });

async function draw(mode) {
  await ex.page.evaluate((m) => { window.example.setMode(m); window.example.setTime(3); window.example.occ.reset(); }, mode);
  return frame(ex.page, FRAMES);
}

test('fields against the exact reference, same frame, same rays', async () => {
  const field = await draw('field');
  const exact = await draw('reference');
  const none = await draw('off');
  assert.equal(field.frame, FRAMES);
  assert.equal(exact.frame, FRAMES);
  // The floor: pixels that differ from the background with the objects hidden, and that the
  // objects do not cover (the frame without occlusion is the same there with them shown).
  await ex.page.evaluate(() => window.example.movers.forEach((o) => { o.visible = false; }));
  const bare = await frame(ex.page);
  await ex.page.evaluate(() => window.example.movers.forEach((o) => { o.visible = true; }));
  const background = await ex.page.evaluate(() => window.example.scene.background.getStyle());
  const bg = background.match(/\d+/g).map(Number);
  const mask = [];
  for (let i = 0; i < bare.pixels.length; i += 4) {
    const d = (img, ref) => Math.max(...[0, 1, 2].map((k) => Math.abs(img.pixels[i + k] - ref[k])));
    mask.push(d(bare, bg) > 4 && d(none, bare.pixels.slice(i, i + 3)) === 0);
  }
  const all = compare(field, exact), floor = compare(field, exact, mask), floorNone = compare(none, exact, mask);
  const line = (name, c) => `${name}: RMS ${c.rms.toFixed(2)}, ${(100 * c.within).toFixed(1)}% of ${c.count} pixels within 8 levels`;
  console.log(`${field.width}x${field.height}, ${FRAMES} frames accumulated, ${field.ms.toFixed(0)} ms a field frame, ${exact.ms.toFixed(0)} ms a reference frame`);
  console.log(line('fields against the reference, whole image', all));
  console.log(line('fields against the reference, floor', floor));
  console.log(line('no occlusion against the reference, floor', floorNone));
  assert.ok(floor.count > 0.2 * mask.length, `the floor covers ${floor.count} pixels`);
  assert.ok(floorNone.rms > 2, 'the reference darkens the floor');
  assert.ok(floor.rms <= 3, `floor RMS ${floor.rms.toFixed(2)} against the reference`);
  assert.ok(floor.rms < 0.5 * floorNone.rms, 'the fields are far closer to the reference than no occlusion');
  assert.ok(floor.within >= 0.97, `${(100 * floor.within).toFixed(1)}% of the floor within 8 levels`);
  assert.deepEqual(ex.errors, []);
});
