// In headless Chromium (WebGL2 on SwiftShader): VffOcclusion on a torus knot standing on a floor
// (its field baked by vff-bake from vff-procedural-mesh's knot). The floor AO of mode 'field'
// matches mode 'reference' (three-mesh-bvh's GPU ray casting against the knot's triangles, the
// same rays) within RMS 3 of 8 bits after accumulation; moving the knot restarts the accumulation
// and moves its shadow; mode 'off' draws what three.js draws alone; a second knot with a field of
// its own (a second copy of the query in the shader) darkens the floor and the first knot, and no
// knot darkens itself. VFF_WORK: scratch folder.
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import { join } from 'node:path';
import { BAKE, MESHGEN, SKIP, scratch, compare, openTestPage } from '../tools.js';

const RECEIVER = 4095;   // occlusion.js's id of a receiving surface that is no instance: the floor
const FRAMES = 10;
let session, page, errors = [];

before(async () => {
  if (SKIP) return;
  const dir = scratch('occlusion');
  const obj = join(dir, 'knot.obj'), vff = join(dir, 'knot.vff');
  execFileSync(MESHGEN, ['torus-knot', obj], { stdio: 'ignore' });
  execFileSync(BAKE, [obj, '-o', vff, '-n', '16', '-m', '32'], { stdio: 'ignore' });
  const vff2 = join(dir, 'knot-8.vff');
  execFileSync(BAKE, [obj, '-o', vff2, '-n', '8', '-m', '16'], { stdio: 'ignore' });
  session = await openTestPage({ '/knot.obj': obj, '/knot.vff': vff, '/knot-8.vff': vff2 });
  ({ page, errors } = session);
  await page.evaluate(() => window.setup('/knot.obj', '/knot.vff', { aoRange: 1, aoRays: 4, shadowRays: 2 }));
});
after(async () => { await session?.close(); });

test('field AO on the floor matches the three-mesh-bvh reference of the same rays', { skip: SKIP || false }, async () => {
  const f = await page.evaluate((n) => window.run('field', n), FRAMES);
  const r = await page.evaluate((n) => window.run('reference', n), FRAMES);
  assert.equal(f.frame, FRAMES);
  assert.equal(r.frame, FRAMES);
  assert.deepEqual(f.ids, r.ids);
  const floor = (i) => f.ids[i] === RECEIVER;
  const ao = compare(f.ao, r.ao, floor), shadow = compare(f.shadow, r.shadow, floor);
  const dark = r.ao.filter((v, i) => floor(i) && v >= 16).length;
  console.log(`${f.width}x${f.height}, ${FRAMES} frames of 4 AO + 2 shadow rays a pixel; ${ao.pixels} floor pixels, ${dark} with reference AO >= 16/255`);
  console.log(`floor AO: RMS ${ao.rms.toFixed(3)} (8-bit), ${(100 * ao.within).toFixed(2)}% within 8 levels`);
  console.log(`floor shadow: RMS ${shadow.rms.toFixed(3)}, ${(100 * shadow.within).toFixed(2)}% within 8 levels`);
  console.log(`ms a frame: field ${f.ms.toFixed(0)}, reference ${r.ms.toFixed(0)} (software rendering); first frame (compiling): field ${f.firstMs.toFixed(0)}, reference ${r.firstMs.toFixed(0)}`);
  assert.ok(dark > 500, `the knot darkens the floor (${dark} pixels)`);
  assert.ok(ao.rms <= 3, `floor AO RMS ${ao.rms}`);
  assert.ok(ao.within >= 0.98, `floor AO within 8 levels: ${ao.within}`);
  assert.ok(shadow.rms <= 8, `floor shadow RMS ${shadow.rms}`);
  assert.deepEqual(errors, []);
});

// The floor's AO-weighted centre, in pixels.
function centroid(run) {
  let w = 0, x = 0;
  for (let i = 0; i < run.ao.length; ++i) {
    if (run.ids[i] !== RECEIVER) continue;
    w += run.ao[i];
    x += run.ao[i] * (i % run.width);
  }
  return { weight: w, x: x / w };
}

test('moving the knot restarts the accumulation and moves its AO and shadow', { skip: SKIP || false }, async () => {
  const a = await page.evaluate(() => window.run('field', 3));
  await page.evaluate(() => window.move(0.8, 0));
  const b = await page.evaluate(() => window.run('field', 3));
  await page.evaluate(() => window.move(-0.8, 0));
  // run() resets; occ.render alone must notice the move too.
  const frames = await page.evaluate(() => window.renderMoved(0.8, 2));
  await page.evaluate(() => window.move(-0.8, 0));
  assert.deepEqual(frames, [3, 1, 2], 'occ.frame: still, moved, still');
  const ca = centroid(a), cb = centroid(b);
  console.log(`floor AO centre x: ${ca.x.toFixed(1)} -> ${cb.x.toFixed(1)} px after moving the knot 0.8 to +x`);
  assert.ok(cb.x - ca.x > 10, `the AO moved right: ${ca.x} -> ${cb.x}`);
  assert.ok(Math.abs(cb.weight - ca.weight) < 0.25 * ca.weight, `about as much AO: ${ca.weight} vs ${cb.weight}`);
  const changed = a.shadow.filter((v, i) => a.ids[i] === RECEIVER && b.ids[i] === RECEIVER && Math.abs(v - b.shadow[i]) > 128).length;
  assert.ok(changed > 50, `${changed} floor pixels changed shadow`);
  assert.deepEqual(errors, []);
});

test("mode 'off' draws the plain three.js image", { skip: SKIP || false }, async () => {
  const { plain, off, field } = await page.evaluate(() => window.plainAndOff());
  assert.equal(off.length, plain.length);
  assert.ok(off.every((v, i) => v === plain[i]), "mode 'off' equals renderer.render");
  const darker = field.filter((v, i) => i % 4 !== 3 && v < plain[i] - 4).length;
  assert.ok(darker > 300, `mode 'field' darkens ${darker} channels`);
  assert.deepEqual(errors, []);
});

test('two fields: each instance darkens the floor, a pixel on an instance skips that instance', { skip: SKIP || false }, async () => {
  const one = await page.evaluate(() => window.run('field', 2));
  const two = await page.evaluate(() => window.runTwoFields('/knot-8.vff', -2, 2));
  const floorAo = (r, left) => r.ao.reduce((s, v, i) => s + (r.ids[i] === RECEIVER && (i % r.width < r.width * 0.3) === left ? v : 0), 0);
  console.log(`floor AO left/right: one knot ${floorAo(one, true)}/${floorAo(one, false)}, two ${floorAo(two, true)}/${floorAo(two, false)}`);
  assert.ok(two.ids.includes(2), 'the second instance is drawn with id 2');
  assert.ok(floorAo(two, true) > 2 * floorAo(one, true) + 1000, 'the second knot darkens the floor on the left');
  // A ray from a pixel on instance k skips instance k: alone, the knot darkens none of its pixels;
  // beside a second knot, some.
  const onKnot = (r) => r.ao.map((v, i) => (r.ids[i] === 1 ? v + r.shadow[i] : -1)).filter((v) => v >= 0);
  const alone = onKnot(one), beside = onKnot(two);
  console.log(`knot pixels darkened: alone ${alone.filter((v) => v > 0).length} of ${alone.length}, beside another ${beside.filter((v) => v > 0).length} of ${beside.length}`);
  assert.ok(alone.length > 500 && alone.every((v) => v === 0), 'no self-occlusion');
  assert.ok(beside.filter((v) => v > 0).length > 20, 'the other knot darkens the first');
  assert.deepEqual(errors, []);
});
