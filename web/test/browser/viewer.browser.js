// The viewer page (index.html) driven as a user would, in headless Chromium: a sample opened with
// ?file=, the object standing on the ground at its lowest point, decoding in a Worker with progress
// while the page keeps answering, a clean page with every problem listed after a bad file, PNG and
// JSON downloads (the JSON as vff-inspect's), size at 1280 and 390 CSS pixels wide and at device
// pixel ratio 2, keyboard and accessible names, and the message when web/node_modules is missing.
// Optional: VFF_PROCEDURAL_MESH (the sample's mesh), VFF_BAKE (a large field), VFF_INSPECT; VFF_WORK.
import { test, after, before } from 'node:test';
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import { readFileSync, writeFileSync, mkdirSync, existsSync } from 'node:fs';
import { join } from 'node:path';
import { serve, launch, WEB } from './harness.js';
import { initVff, openVff } from '../../src/vff.js';

const WORK = process.env.VFF_WORK ?? '/tmp/vff-web-viewer';
const SAMPLE = join(WEB, 'samples', 'knot.vff');
let srv, browser;
const extra = {};

before(async () => {
  mkdirSync(WORK, { recursive: true });
  // Two blocks of the sample damaged: two block-checksum problems, both to be listed.
  await initVff();
  const bytes = new Uint8Array(readFileSync(SAMPLE));
  const blocks = openVff(bytes).planes.distance.blocks;
  assert.ok(blocks.length >= 2, 'the sample has two blocks');
  const bad = bytes.slice();
  for (const b of blocks.slice(0, 2)) bad[b.offset + 17] ^= 0x5a;
  writeFileSync(join(WORK, 'two-bad-blocks.vff'), bad);
  extra['/two-bad-blocks.vff'] = join(WORK, 'two-bad-blocks.vff');
  srv = await serve(extra);
  browser = await launch();
});
after(async () => { await browser?.close(); srv?.server.close(); });

/** A page with the viewer started, few frames accumulated (software rendering is slow). */
async function open(query = '', viewport = { width: 1280, height: 800 }, deviceScaleFactor = 1) {
  const page = await browser.newPage({ viewport, deviceScaleFactor, acceptDownloads: true });
  const errors = [];
  page.on('pageerror', (e) => errors.push(e.message));
  page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
  await page.goto(`${srv.url}/index.html${query}`);
  await page.waitForFunction(() => window.vffViewer?.view);
  await page.evaluate(() => { window.vffViewer.view.options.maxFrames = 1; });
  return { page, errors };
}
// Loaded: the progress bar gone, and a file shown or its problems listed.
// One page serves most cases: each new page compiles the field's shaders again (slow in software).
let shared = null;
async function sharedPage() {
  if (!shared) {
    shared = await open('?file=samples/knot.vff');
    await loaded(shared.page);
  }
  return shared;
}
const reopenSample = async (page) => {
  await page.evaluate(() => window.vffViewer.loadUrl('samples/knot.vff'));
  await loaded(page);
};

const loaded = (page) => page.waitForFunction(() => document.getElementById('progress').hidden
  && (window.vffViewer.state || !document.getElementById('problems-box').hidden), null, { timeout: 180000 });

test('?file= opens a sample: summary, maps, legends, and the object standing on its lowest point', async () => {
  const { page, errors } = await sharedPage();
  const r = await page.evaluate(() => {
    const s = window.vffViewer.state, v = window.vffViewer.view;
    return {
      summary: document.getElementById('summary').textContent, status: document.getElementById('status').textContent,
      groundY: v.groundY, lowest: v.lowest, center: s.result.field.center, radius: s.result.field.radius,
      legend: !document.getElementById('maps-legend').hidden, legendText: document.getElementById('maps-legend').textContent,
      objectPixels: window.vffViewer.objectPixels(),
    };
  });
  assert.match(r.summary, /file: +knot\.vff/);
  assert.match(r.summary, /1090 maps/);
  assert.ok(r.legend && /miss/.test(r.legendText) && /2R/.test(r.legendText), r.legendText);
  assert.ok(r.objectPixels > 1000, `object pixels ${r.objectPixels}`);
  const sphereBottom = r.center[1] - r.radius;
  let meshLow = null;
  if (process.env.VFF_PROCEDURAL_MESH) {
    const obj = join(WORK, 'knot.obj');
    execFileSync(process.env.VFF_PROCEDURAL_MESH, ['torus-knot', obj]);
    meshLow = Math.min(...readFileSync(obj, 'utf8').split('\n').filter((l) => l.startsWith('v ')).map((l) => Number(l.split(/\s+/)[2])));
  }
  console.log(`ground y ${r.groundY.toFixed(5)} from ${r.lowest.hits} of ${r.lowest.rays} upward rays; mesh's lowest vertex ${meshLow?.toFixed(5) ?? '(VFF_PROCEDURAL_MESH not set)'}; bounding sphere's bottom ${sphereBottom.toFixed(5)}`);
  if (meshLow !== null) {
    // One distance step of unorm8-diameter (2R/254) and the gap between upward rays.
    assert.ok(Math.abs(r.groundY - meshLow) <= 0.03 * r.radius, `ground ${r.groundY} vs mesh ${meshLow}`);
  }
  assert.ok(r.groundY > sphereBottom + 0.01 * r.radius || (meshLow !== null && meshLow <= sphereBottom + 0.01 * r.radius), 'the ground is not the bounding sphere\'s bottom');
  assert.deepEqual(errors, []);
});

test('decoding runs in a Worker with progress, and the page answers meanwhile', async (t) => {
  const big = join(WORK, 'big.vff');
  if (!process.env.VFF_BAKE || !process.env.VFF_PROCEDURAL_MESH) { t.skip('VFF_BAKE and VFF_PROCEDURAL_MESH not set'); return; }
  if (!existsSync(big)) {
    execFileSync(process.env.VFF_PROCEDURAL_MESH, ['torus-knot', join(WORK, 'knot.obj')]);
    execFileSync(process.env.VFF_BAKE, [join(WORK, 'knot.obj'), '-o', big, '-n', '16', '-m', '64', '--codec', 'zstd'], { stdio: 'ignore' });
  }
  extra['/big.vff'] = big;
  const { page } = await sharedPage();
  // The sample's frames drawn first: its shader compiles are not the decoding's.
  await page.waitForFunction(() => { const v = window.vffViewer.view; return !v.raf && v.frame >= v.options.maxFrames; }, null, { timeout: 180000 });
  const r = await page.evaluate(async () => {
    const bytes = new Uint8Array(await (await fetch('/big.vff')).arrayBuffer());
    const shares = [];
    let worst = 0, last = performance.now(), ticks = 0, decoding = true, decodeMs = 0;
    const t0 = performance.now();
    // The decoding stages end when the page shows the Worker's last progress (share 1), in the task
    // that shows it: what follows (uploading the textures, compiling the shaders) is not decoding.
    new MutationObserver(() => {
      const share = Number(document.getElementById('progress').value);
      shares.push(share);
      if (decoding && share >= 1) { worst = Math.max(worst, performance.now() - last); decoding = false; decodeMs = performance.now() - t0; }
    }).observe(document.getElementById('progress'), { attributes: true });
    const timer = setInterval(() => { const now = performance.now(); if (decoding) { worst = Math.max(worst, now - last); ++ticks; } last = now; }, 10);
    const done = window.vffViewer.loadBytes(bytes, 'big.vff');
    const res = await done;
    clearInterval(timer);
    return { ok: res.ok, shares, worst, ticks, decodeMs, size: bytes.length };
  });
  const stages = new Set(r.shares.map((s) => s.toFixed(2)));
  console.log(`${(r.size / 1048576).toFixed(1)} MiB decoded in ${r.decodeMs.toFixed(0)} ms; ${r.shares.length} progress updates (${stages.size} distinct); longest gap between 10 ms timer ticks meanwhile ${r.worst.toFixed(0)} ms over ${r.ticks} ticks`);
  assert.ok(r.ok);
  assert.ok(stages.size >= 5, `progress values ${[...stages]}`);
  assert.ok(r.worst < 250, `the page stalled ${r.worst} ms while decoding`);
});

test('a bad file after a good one: a clean page and every problem listed', async () => {
  const { page } = await sharedPage();
  await reopenSample(page);
  const r = await page.evaluate(async () => {
    const bytes = new Uint8Array(await (await fetch('/two-bad-blocks.vff')).arrayBuffer());
    const res = await window.vffViewer.loadBytes(bytes, 'two-bad-blocks.vff');
    const $ = (id) => document.getElementById(id);
    return {
      res, items: [...$('problems').children].map((li) => li.textContent), title: $('problems-title').textContent,
      summary: $('summary').textContent, state: window.vffViewer.state, objectPixels: window.vffViewer.objectPixels(),
      field: !!window.vffViewer.view.field, png: $('save-png').disabled, json: $('save-json').disabled, legend: $('maps-legend').hidden,
    };
  });
  console.log(r.items.join('\n'));
  assert.equal(r.res.ok, false);
  assert.equal(r.items.length, 2);
  for (const i of r.items) assert.match(i, /two-bad-blocks\.vff: .*block-checksum \(6009\)/);
  assert.match(r.items[0], /block 0/);
  assert.match(r.items[1], /block 1/);
  assert.match(r.title, /cannot be shown: 2 problems/);
  assert.equal(r.summary, '');
  assert.equal(r.state, null);
  assert.equal(r.field, false);
  assert.equal(r.objectPixels, 0);
  assert.ok(r.png && r.json && r.legend);
});

test('PNG and JSON downloads; the JSON is vff-inspect\'s', async () => {
  const { page } = await sharedPage();
  await reopenSample(page);
  // Clicked from the page: a software-rendered frame can hold Playwright's click past its timeout.
  const click = (id) => page.evaluate((i) => { document.getElementById(i).click(); }, id);
  const [png] = await Promise.all([page.waitForEvent('download', { timeout: 120000 }), click('save-png')]);
  const [json] = await Promise.all([page.waitForEvent('download', { timeout: 120000 }), click('save-json')]);
  assert.equal(png.suggestedFilename(), 'knot.png');
  assert.equal(json.suggestedFilename(), 'knot.json');
  const pngBytes = readFileSync(await png.path());
  assert.deepEqual([...pngBytes.subarray(1, 4)].map((c) => String.fromCharCode(c)).join(''), 'PNG');
  const w = pngBytes.readUInt32BE(16), h = pngBytes.readUInt32BE(20);
  const size = await page.evaluate(() => [document.getElementById('view').width, document.getElementById('view').height]);
  assert.deepEqual([w, h], size);
  const doc = JSON.parse(readFileSync(await json.path(), 'utf8'));
  assert.equal(doc.file, 'knot.vff');
  if (process.env.VFF_INSPECT) {
    const ref = JSON.parse(execFileSync(process.env.VFF_INSPECT, [SAMPLE, '--format', 'json'], { encoding: 'utf8' }));
    for (const k of ['format', 'field', 'layout', 'sections', 'metadata']) assert.deepEqual(doc[k], ref[k], k);
    console.log(`JSON: ${Object.keys(doc).join(', ')} as vff-inspect gives them`);
  } else console.log('note: VFF_INSPECT not set: the JSON not compared with vff-inspect');
});

for (const [width, height, dpr] of [[1280, 800, 1], [390, 844, 1], [390, 844, 2]]) {
  test(`size at ${width} x ${height} CSS pixels, device pixel ratio ${dpr}`, async () => {
    // Device pixel ratio 2 needs a page of its own; the others resize the shared one.
    const own = dpr !== 1;
    const { page, errors } = own ? await open('?file=samples/knot.vff', { width, height }, dpr) : await sharedPage();
    if (own) await loaded(page);
    else await page.setViewportSize({ width, height });
    await page.waitForFunction(() => { const c = document.getElementById('view'); return c.width === Math.floor(c.getBoundingClientRect().width) * devicePixelRatio; });
    const r = await page.evaluate(() => {
      const rect = (id) => { const b = document.getElementById(id).getBoundingClientRect(); return { x: b.x, w: b.width, h: b.height }; };
      const c = document.getElementById('view');
      return { scrollWidth: document.documentElement.scrollWidth, inner: window.innerWidth, view: rect('view'), sheet: rect('sheet'), buffer: [c.width, c.height] };
    });
    console.log(`${width}x${height}@${dpr}: view ${r.view.w}x${r.view.h} CSS px, drawing buffer ${r.buffer.join('x')}; page ${r.scrollWidth} wide`);
    assert.ok(r.scrollWidth <= r.inner, `the page is ${r.scrollWidth} px wide in ${r.inner}`);
    assert.ok(r.view.x >= 0 && r.view.x + r.view.w <= width && r.view.w > width * 0.5, JSON.stringify(r.view));
    assert.equal(r.buffer[0], Math.floor(r.view.w) * dpr);
    assert.ok(Math.abs(r.buffer[1] - r.view.h * dpr) <= dpr, `${r.buffer[1]} vs ${r.view.h * dpr}`);
    // A resize follows the container (ResizeObserver), without reloading.
    await page.setViewportSize({ width: Math.round(width * 0.8), height });
    await page.waitForFunction((w) => document.getElementById('view').width !== w, r.buffer[0]);
    const after = await page.evaluate(() => [document.getElementById('view').width, document.getElementById('view').getBoundingClientRect().width,
      document.documentElement.scrollWidth, window.innerWidth]);
    assert.equal(after[0], Math.floor(after[1]) * dpr);
    assert.ok(after[2] <= after[3], `after the resize the page is ${after[2]} px wide in ${after[3]}`);
    if (width === 1280 && dpr === 1) await page.screenshot({ path: join(WORK, 'viewer-1280.png') });
    if (width === 390 && dpr === 2) await page.screenshot({ path: join(WORK, 'viewer-390.png'), fullPage: true });
    assert.deepEqual(errors, []);
    if (own) await page.close();
    else await page.setViewportSize({ width: 1280, height: 800 });
  });
}

test('keyboard: Tab reaches every control, arrow keys orbit; every control has a name', async () => {
  const { page } = await sharedPage();
  await reopenSample(page);
  await page.evaluate(() => document.activeElement?.blur());
  const order = [];
  for (let i = 0; i < 16; ++i) {
    await page.keyboard.press('Tab');
    order.push(await page.evaluate(() => document.activeElement?.id || document.activeElement?.tagName));
  }
  console.log(`Tab order: ${order.join(', ')}`);
  for (const id of ['open', 'sample', 'save-png', 'save-json', 'interp', 'show', 'light-az', 'light-el', 'view', 'sheet']) assert.ok(order.includes(id), `${id} is not reached by Tab`);
  await page.focus('#view');
  const before = await page.evaluate(() => window.vffViewer.view.camera.position.toArray());
  await page.keyboard.press('ArrowLeft');
  await page.keyboard.press('ArrowUp');
  const moved = await page.evaluate(() => window.vffViewer.view.camera.position.toArray());
  assert.ok(Math.hypot(...moved.map((v, i) => v - before[i])) > 1e-3, 'arrow keys orbit the camera');
  const unnamed = await page.evaluate(() => [...document.querySelectorAll('input, select, button, canvas')]
    .filter((e) => !(e.getAttribute('aria-label') || e.labels?.length || e.textContent.trim())).map((e) => e.id));
  assert.deepEqual(unnamed, []);
});

test('without web/node_modules the page says so and how to install them', async () => {
  const bare = await serve({}, { hide: ['/node_modules/'] });
  const page = await browser.newPage();
  await page.goto(`${bare.url}/index.html`);
  await page.waitForFunction(() => window.vffViewer?.missing);
  const r = await page.evaluate(() => ({ shown: !document.getElementById('deps').hidden, text: document.getElementById('deps').textContent, disabled: document.getElementById('open').disabled }));
  assert.ok(r.shown && r.disabled);
  assert.match(r.text, /missing: three, fzstd, hash-wasm/);
  assert.match(r.text, /npm ci/);
  await page.close();
  bare.server.close();
});
