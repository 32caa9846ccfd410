// In headless Chromium: three.js's GLTFLoader loads the .glb vff-bake writes for the sample scene
// of vff-procedural-mesh (VFF_visibility_field on its meshes, which three does not know) and draws
// it: at the triangle centroids of every mesh the pixels differ from the background, the console has no
// error, and the JavaScript reader finds the fields in the page. Needs VFF_BAKE and
// VFF_PROCEDURAL_MESH; VFF_WORK: scratch folder.
import { test, after, before } from 'node:test';
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import { mkdirSync } from 'node:fs';
import { join } from 'node:path';
import { serve, launch, WEB } from './harness.js';

const WORK = process.env.VFF_WORK ?? '/tmp/vff-web-gltf-three';
let srv, browser, page;
const errors = [];

const SKIP = !process.env.VFF_BAKE || !process.env.VFF_PROCEDURAL_MESH ? 'VFF_BAKE and VFF_PROCEDURAL_MESH are not set' : '';
if (SKIP) console.log(`SKIP: ${SKIP}`);

before(async () => {
  if (SKIP) return;
  mkdirSync(WORK, { recursive: true });
  const scene = join(WORK, 's.gltf'), glb = join(WORK, 's.glb');
  execFileSync(process.env.VFF_PROCEDURAL_MESH, ['--gltf-scene', scene], { stdio: 'ignore' });
  execFileSync(process.env.VFF_BAKE, [scene, '-o', glb, '-n', '2', '-m', '8'], { stdio: 'ignore' });
  srv = await serve({ '/s.glb': glb, '/gltf_three.html': join(WEB, 'test', 'browser', 'gltf_three.html') });
  browser = await launch();
  page = await browser.newPage();
  page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
  page.on('pageerror', (e) => errors.push(String(e)));
  page.on('response', (res) => { if (res.status() >= 400) errors.push(`${res.status()} ${res.url()}`); });
  await page.goto(`${srv.url}/gltf_three.html`);
  await page.waitForFunction(() => window.ready === true);
});
after(async () => { await browser?.close(); srv?.server.close(); });

test('GLTFLoader draws the meshes of a .glb with fields; no console error', { skip: SKIP || false }, async () => {
  const r = await page.evaluate(() => window.drawGlb('/s.glb'));
  assert.deepEqual(r.extensionsUsed, ['VFF_visibility_field']);
  const at = (x, y) => r.pixels.slice(4 * (y * r.width + x), 4 * (y * r.width + x) + 3);
  const isBackground = (p) => p.every((c, i) => Math.abs(c - r.background[i]) <= 2);
  let background = 0;
  for (let i = 0; i < r.pixels.length; i += 4) background += isBackground(r.pixels.slice(i, i + 3));
  const share = 1 - background / (r.width * r.height);
  // The main scene: boxA and boxB (mesh 0 twice), knotStretched (mesh 1).
  assert.deepEqual(r.meshes.map((m) => m.name).sort(), ['boxA', 'boxB', 'knotStretched']);
  for (const m of r.meshes) {
    const inside = m.points.filter(([x, y]) => x >= 0 && y >= 0 && x < r.width && y < r.height);
    const drawn = inside.filter(([x, y]) => !isBackground(at(x, y))).length;
    console.log(`${m.name}: ${drawn} of ${inside.length} triangle-centroid pixels drawn`);
    assert.ok(inside.length > 0, `${m.name} is in view`);
    assert.ok(drawn >= 0.9 * inside.length, `${m.name}: ${drawn} of ${inside.length} triangle-centroid pixels differ from the background`);
  }
  console.log(`${(100 * share).toFixed(1)}% of the ${r.width}x${r.height} pixels covered`);
  assert.ok(share > 0.05 && share < 0.95, `covered share ${share}`);
  assert.deepEqual(r.fields.map((f) => [f.mesh, f.match]), [[0, 'exact'], [1, 'exact']]);
  assert.deepEqual(r.problems, [14104]);
  assert.deepEqual(errors, []);
  await page.locator('#view').screenshot({ path: join(WORK, 'gltf-three.png') });
});
