// The page's WebGPU ground (web/src/viewer/webgpu_ground.js: the generated WGSL query) in headless
// Chromium with WebGPU on (its SwiftShader adapter, taken with ?ground=webgpu): the ground is drawn
// through WebGPU, its reference view matches the C++ render of the same view
// (tests/web/web_reference.cpp) as the WebGL2 one does and equals the WebGL2 one, its accumulated
// ground matches the WebGL2 ground pixel for pixel (the same rays from the same random numbers),
// and a browser without WebGPU, or ?ground=webgl2, gets the WebGL2 ground. Screenshots of both
// grounds at a desktop and a phone size are kept in $VFF_WORK.
import { test, after, before } from 'node:test';
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import { readFileSync, mkdirSync, existsSync, writeFileSync } from 'node:fs';
import { join } from 'node:path';
import { serve, launch, builtTool } from './harness.js';

const WORK = process.env.VFF_WORK ?? '/tmp/vff-webgpu-view';
const BUNNY = '/usr/share/glmark2/models/bunny.obj';
const BAKE = builtTool('VFF_BAKE', 'tools/vff-bake/vff-bake');
const REFERENCE = builtTool('VFF_WEB_REFERENCE', 'tests/web/vff_web_reference');
const SKIP = !BAKE ? 'vff-bake is not built (VFF_BAKE)' : !existsSync(BUNNY) ? `no ${BUNNY} (apt-get install glmark2-data)` : '';
if (SKIP) console.log(`SKIP: ${SKIP}`);
const SIZE = 64;
// As render.browser.js: the WebGL2 reference view's tolerance against libvff.
const TOLERANCE = { meanLevels: 1.5, within16Share: 0.98 };
const FRAMES = 4;

let srv, browser;
const field = join(WORK, 'bunny.vff');
before(async () => {
  if (SKIP) return;
  mkdirSync(WORK, { recursive: true });
  execFileSync(BAKE, [BUNNY, '-o', field, '-n', '16', '-m', '32'], { stdio: 'ignore' });
  srv = await serve({ '/bunny.vff': field });
  browser = await launch({ webgpu: true });
});
after(async () => { await browser?.close(); srv?.server.close(); });

/** A page with the bunny loaded; with webgpu, once its ground is drawn through WebGPU. */
async function openPage(query, viewport = { width: 1280, height: 800 }, b = browser) {
  const page = await b.newPage({ viewport });
  const errors = [];
  page.on('pageerror', (e) => errors.push(e.message));
  await page.goto(`${srv.url}/index.html${query}`);
  await page.waitForFunction(() => window.vffViewer?.view);
  const r = await page.evaluate(async () => {
    window.vffViewer.view.setOptions({ maxFrames: 0 });
    const bytes = new Uint8Array(await (await fetch('/bunny.vff')).arrayBuffer());
    const r = await window.vffViewer.loadBytes(bytes, 'bunny.vff');
    return { ok: r.ok, gl: r.gl };
  });
  assert.ok(r.ok && r.gl, JSON.stringify(r));
  page.errors = errors;
  return page;
}

const backendOf = (page) => page.evaluate(() => ({ backend: window.vffViewer.view.backend, label: document.getElementById('backend').textContent }));
// Whether the page got a WebGPU device (a browser without an adapter leaves the ground to WebGL2);
// then waits until its ground is drawn through it (the pipelines compiled).
async function waitWebGpu(page) {
  const has = await page.evaluate(async () => { await window.vffViewer.gpuOpened; return !!window.vffViewer.view.gpuGround; });
  if (has) await page.waitForFunction(() => window.vffViewer.view.backend === 'webgpu', null, { timeout: 300000 });
  return has;
}
const NO_ADAPTER = 'this chromium offers no WebGPU adapter (--enable-unsafe-webgpu)';

/** The view after `frames` accumulation steps, as RGBA bytes of the composited canvas (view.png). */
async function accumulated(page, frames, file) {
  await page.evaluate((frames) => { window.vffViewer.view.setOptions({ maxFrames: frames }); window.vffViewer.view.invalidate(); }, frames);
  await page.waitForFunction((frames) => window.vffViewer.view.frame >= frames, frames, { timeout: 600000 });
  await page.locator('#view-box').screenshot({ path: join(WORK, file) });
  return page.evaluate(async () => {
    const blob = await window.vffViewer.view.png();
    const img = await createImageBitmap(blob);
    const c = new OffscreenCanvas(img.width, img.height), g = c.getContext('2d');
    g.drawImage(img, 0, 0);
    return { w: img.width, h: img.height, data: Array.from(g.getImageData(0, 0, img.width, img.height).data) };
  });
}

test('the ground is drawn through WebGPU, its reference view matches libvff and equals WebGL2\'s', { skip: SKIP || false }, async (t) => {
  const page = await openPage('?ground=webgpu');
  if (!await waitWebGpu(page)) { console.log(`SKIP: ${NO_ADAPTER}`); t.skip(NO_ADAPTER); return; }
  const b = await backendOf(page);
  console.log(`backend: ${b.backend} (${b.label})`);
  assert.match(b.label, /ground: WebGPU \(/);
  for (const mode of ['nearest', 'interpolated']) {
    const pgm = join(WORK, `reference-${mode}.pgm`);
    execFileSync(REFERENCE, [field, pgm, String(SIZE), mode]);
    const raw = readFileSync(pgm), ref = raw.subarray(raw.length - SIZE * SIZE);
    const [gpu, gl] = await page.evaluate(async ({ size, interpolated }) => [
      await window.vffViewer.reference(size, interpolated, 'webgpu'),
      window.vffViewer.reference(size, interpolated, 'webgl2'),
    ], { size: SIZE, interpolated: mode === 'interpolated' });
    let sum = 0, within = 0, dark = 0, vsGl = 0;
    for (let i = 0; i < ref.length; ++i) {
      const d = Math.abs(ref[i] - gpu[i]);
      sum += d;
      within += d <= 16;
      dark += ref[i] < 230;
      vsGl = Math.max(vsGl, Math.abs(gpu[i] - gl[i]));
    }
    const mean = sum / ref.length, share = within / ref.length;
    console.log(`${mode}: WebGPU against libvff: mean ${mean.toFixed(3)} levels, ${(100 * share).toFixed(2)}% within 16; against WebGL2: at most ${vsGl} levels; ${dark} occluded pixels`);
    assert.ok(dark > ref.length * 0.05, 'the reference shows some occlusion');
    assert.ok(mean <= TOLERANCE.meanLevels && share >= TOLERANCE.within16Share, `${mode}: mean ${mean}, share ${share}`);
    assert.ok(vsGl <= 8, `${mode}: WebGPU and WebGL2 reference views differ by ${vsGl} levels (one AO ray of 32 is 8)`);
  }
  assert.deepEqual(page.errors, []);
  await page.close();
});

test('the WebGPU ground is the WebGL2 ground, at a desktop and a phone size', { skip: SKIP || false }, async (t) => {
  for (const [name, viewport] of [['desktop', { width: 1280, height: 800 }], ['phone', { width: 390, height: 844 }]]) {
    const gpuPage = await openPage('?ground=webgpu', viewport);
    if (!await waitWebGpu(gpuPage)) { console.log(`SKIP: ${NO_ADAPTER}`); t.skip(NO_ADAPTER); return; }
    const a = await accumulated(gpuPage, FRAMES, `webgpu-${name}.png`);
    const glPage = await openPage('?ground=webgl2', viewport);
    assert.equal((await backendOf(glPage)).backend, 'webgl2');
    const b = await accumulated(glPage, FRAMES, `webgl2-${name}.png`);
    assert.deepEqual([a.w, a.h], [b.w, b.h]);
    let sum = 0, over = 0;
    for (let i = 0; i < a.data.length; i += 4) {
      const d = Math.max(Math.abs(a.data[i] - b.data[i]), Math.abs(a.data[i + 1] - b.data[i + 1]), Math.abs(a.data[i + 2] - b.data[i + 2]));
      sum += d;
      over += d > 16;
    }
    const n = a.data.length / 4;
    console.log(`${name} ${a.w} x ${a.h}: WebGPU against WebGL2 after ${FRAMES} frames: mean ${(sum / n).toFixed(3)} levels, ${over} pixels over 16`);
    writeFileSync(join(WORK, `webgpu-vs-webgl2-${name}.txt`), `mean ${sum / n}, over16 ${over} of ${n}\n`);
    assert.ok(sum / n < 1 && over <= n * 0.002, `${name}: mean ${sum / n}, ${over} pixels over 16 levels`);
    assert.deepEqual([...gpuPage.errors, ...glPage.errors], []);
    await gpuPage.close();
    await glPage.close();
  }
});

test('without WebGPU the ground is WebGL2', { skip: SKIP || false }, async () => {
  const plain = await launch();
  try {
    const page = await openPage('', { width: 800, height: 600 }, plain);
    const b = await backendOf(page);
    assert.equal(b.backend, 'webgl2');
    assert.match(b.label, /ground: WebGL2$/);
    assert.deepEqual(page.errors, []);
  } finally {
    await plain.close();
  }
});
