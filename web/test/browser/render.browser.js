// The page renders a baked bunny with three.js on WebGL2 (SwiftShader), and its deterministic
// reference view, ground AO seen from above with fixed rays, matches the C++ render of the same view
// (tests/web/web_reference.cpp, libvff's FieldQuery) within TOLERANCE; a screenshot of the page
// (AO accumulated over frames) is kept in $VFF_WORK/web-viewer.png.
// Needs vff-bake and vff_web_reference (VFF_BAKE, VFF_WEB_REFERENCE, else the default build folder)
// and glmark2's bunny, each case skipping with the reason otherwise; VFF_WORK: scratch folder.
import { test, after, before } from 'node:test';
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import { readFileSync, mkdirSync, existsSync } from 'node:fs';
import { join } from 'node:path';
import { serve, launch, builtTool } from './harness.js';

const WORK = process.env.VFF_WORK ?? '/tmp/vff-web-render';
const BUNNY = '/usr/share/glmark2/models/bunny.obj';
const BAKE = builtTool('VFF_BAKE', 'tools/vff-bake/vff-bake');
const REFERENCE = builtTool('VFF_WEB_REFERENCE', 'tests/web/vff_web_reference');
const SKIP = !BAKE ? 'vff-bake is not built (VFF_BAKE)' : !existsSync(BUNNY) ? `no ${BUNNY} (apt-get install glmark2-data)` : '';
const SKIP_REFERENCE = SKIP || (!REFERENCE ? 'vff_web_reference is not built (VFF_WEB_REFERENCE)' : '');
if (SKIP_REFERENCE) console.log(`SKIP: ${SKIP_REFERENCE}`);
const SIZE = 96;
// One AO ray that flips changes a pixel by 255/32 = 8 levels; binary32 rounding in the GLSL ES
// port (no fma, no `precise`) flips a few rays at texel and sample boundaries.
const TOLERANCE = { meanLevels: 1.5, within16Share: 0.98 };

let srv, browser, page;
const field = join(WORK, 'bunny.vff');
before(async () => {
  if (SKIP) return;
  mkdirSync(WORK, { recursive: true });
  execFileSync(BAKE, [BUNNY, '-o', field, '-n', '16', '-m', '32'], { stdio: 'ignore' });
  srv = await serve({ '/bunny.vff': field });
  browser = await launch();
  page = await browser.newPage({ viewport: { width: 1280, height: 800 } });
  await page.goto(`${srv.url}/index.html`);
  await page.waitForFunction(() => window.vffViewer?.view);
  const r = await page.evaluate(async () => {
    window.vffViewer.view.options.maxFrames = 1;
    const bytes = new Uint8Array(await (await fetch('/bunny.vff')).arrayBuffer());
    return window.vffViewer.loadBytes(bytes, 'bunny.vff');
  });
  assert.ok(r.ok && r.gl, JSON.stringify(r).slice(0, 300));
});
after(async () => { await browser?.close(); srv?.server.close(); });

function readPgm(path) {
  const b = readFileSync(path);
  const head = b.subarray(0, 20).toString('latin1').split(/\s+/);
  assert.equal(head[0], 'P5');
  return b.subarray(b.length - Number(head[1]) * Number(head[2]));
}

async function renderReference(interpolated) {
  return page.evaluate(({ size, interpolated }) => window.vffViewer.reference(size, interpolated), { size: SIZE, interpolated });
}

for (const mode of ['nearest', 'interpolated']) {
  test(`ground AO (${mode}) matches the C++ reference render`, { skip: SKIP_REFERENCE || false }, async () => {
    const pgm = join(WORK, `reference-${mode}.pgm`);
    execFileSync(REFERENCE, [field, pgm, String(SIZE), mode]);
    const ref = readPgm(pgm);
    const gpu = await renderReference(mode === 'interpolated');
    let sum = 0, within = 0, dark = 0;
    for (let i = 0; i < ref.length; ++i) {
      const d = Math.abs(ref[i] - gpu[i]);
      sum += d;
      within += d <= 16;
      dark += ref[i] < 230;
    }
    const mean = sum / ref.length, share = within / ref.length;
    console.log(`${mode}: mean |gpu - cpu| ${mean.toFixed(3)} levels, ${(100 * share).toFixed(2)}% of pixels within 16 levels, ${dark} occluded pixels`);
    assert.ok(dark > ref.length * 0.05, 'the reference shows some occlusion');
    assert.ok(mean <= TOLERANCE.meanLevels, `mean difference ${mean}`);
    assert.ok(share >= TOLERANCE.within16Share, `share within 16 levels ${share}`);
  });
}

test('the interactive view renders, accumulates, and a screenshot is kept', { skip: SKIP || false }, async () => {
  const FRAMES = 8;
  const ms = await page.evaluate((frames) => {
    const v = window.vffViewer;
    v.view.setOptions({ maxFrames: frames });
    v.view.invalidate();
    return v.redraw();
  }, FRAMES);
  console.log(`frame ${ms.toFixed(1)} ms (1280 x 800 page, software rendering)`);
  await page.waitForFunction((frames) => window.vffViewer.view.frame >= frames, FRAMES, { timeout: 600000 });
  await page.screenshot({ path: join(WORK, 'web-viewer.png') });
  const summary = await page.textContent('#summary');
  assert.match(summary, /1090 maps/);
});

// Every kind of file the tools write opens in the page and renders: the bunny baked with each
// encoding and option, and compressed by vff-compress (zstd + hits-med, and BC4).
test('files the tools write open and render in the page', { skip: SKIP || false }, async () => {
  const bake = (name, ...args) => {
    const out = join(WORK, `${name}.vff`);
    const n = args.includes('-n') ? [] : ['-n', '6'];
    execFileSync(BAKE, [BUNNY, '-o', out, ...n, '-m', '16', ...args], { stdio: 'ignore' });
    return out;
  };
  const files = {
    'normals-zstd': bake('normals-zstd', '--normals', '--codec', 'zstd'),
    chord: bake('chord', '--encoding', 'unorm8-chord', '--directions', 'hemi-oct'),
    unorm16: bake('unorm16', '--encoding', 'unorm16-diameter', '--positions', 'fibonacci', '-n', '300'),
    bit1: bake('bit1', '--encoding', 'bit1', '--target', '3d'),
    bc4: bake('bc4', '--encoding', 'bc4-diameter', '--normals'),
  };
  const compress = process.env.VFF_COMPRESS;
  if (compress) {
    files['hits-med'] = join(WORK, 'hits-med.vff');
    execFileSync(compress, [files['normals-zstd'].replace('normals-zstd', 'chord'), files['hits-med']], { stdio: 'ignore' });
    files['compress-bc4'] = join(WORK, 'compress-bc4.vff');
    execFileSync(compress, ['--bc4', field, files['compress-bc4']], { stdio: 'ignore' });
  } else console.log('note: VFF_COMPRESS not set: vff-compress outputs not tried');
  const results = {};
  for (const [name, path] of Object.entries(files)) {
    const bytes = readFileSync(path);
    results[name] = await page.evaluate(async (b64) => {
      const bytes = Uint8Array.from(atob(b64), (c) => c.charCodeAt(0));
      window.vffViewer.view.setOptions({ maxFrames: 0, interpolated: true });  // the object; accumulation is the test above's
      const r = await window.vffViewer.loadBytes(bytes, 'f.vff');
      window.vffViewer.redraw();
      const gl = window.vffViewer.view.renderer.getContext();
      return { ok: r.ok, gl: r.gl, message: r.message, glError: gl.getError(), objectPixels: window.vffViewer.objectPixels(), summary: document.getElementById('summary').textContent.slice(0, 2000) };
    }, bytes.toString('base64'));
  }
  for (const [name, r] of Object.entries(results)) {
    assert.ok(r.ok && r.gl && r.glError === 0 && r.objectPixels > 100, `${name}: ${JSON.stringify(r).slice(0, 300)}`);
  }
  assert.match(results['normals-zstd'].summary, /normals: +oct-snorm16/);
  assert.match(results.bit1.summary, /target: +3d/);
  assert.match(results.unorm16.summary, /fibonacci, param 300/);
  if (compress) assert.match(results['hits-med'].summary, /hits-med [1-9]/);
  if (compress) assert.match(results['compress-bc4'].summary, /bc4-diameter/);
});
