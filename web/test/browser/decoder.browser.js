// The decoder inside headless Chromium: the page's module decodes every conformance vector as
// node does (valid ones to their expected values, invalid ones to their folder's ID); the viewer
// (its decoding Worker and three.js view) names an invalid file's ID and draws every valid one.
import { test, after, before } from 'node:test';
import assert from 'node:assert/strict';
import { readdirSync } from 'node:fs';
import { join } from 'node:path';
import { serve, launch, WEB } from './harness.js';

const CONF = join(WEB, '..', 'spec', 'conformance');
let srv, browser, page;
before(async () => {
  const extra = {};
  for (const n of readdirSync(join(CONF, 'valid'))) extra[`/conf/valid/${n}`] = join(CONF, 'valid', n);
  for (const id of readdirSync(join(CONF, 'invalid')))
    for (const n of readdirSync(join(CONF, 'invalid', id))) extra[`/conf/invalid/${id}/${n}`] = join(CONF, 'invalid', id, n);
  srv = await serve(extra);
  browser = await launch();
  page = await browser.newPage({ viewport: { width: 480, height: 700 } });
  await page.goto(`${srv.url}/index.html`);
  await page.waitForFunction(() => window.vffViewer?.view);
  // No ground accumulation: each vector's object and lowest-point passes are compiled and drawn, and
  // the accumulation pass (the same query) is the render test's; software compiles are slow.
  await page.evaluate(() => window.vffViewer.view.setOptions({ maxFrames: 0 }));
});
after(async () => { await browser?.close(); srv?.server.close(); });

test('valid vectors decode in the browser as their expected.json says', async () => {
  const names = readdirSync(join(CONF, 'valid')).filter((n) => n.endsWith('.vff'));
  const results = await page.evaluate(async (names) => {
    const { initVff, openVff, xxh3Hex } = await import('./src/vff.js');
    await initVff();
    const out = [];
    for (const n of names) {
      const bytes = new Uint8Array(await (await fetch(`/conf/valid/${n}`)).arrayBuffer());
      const exp = await (await fetch(`/conf/valid/${n.replace(/\.vff$/, '.expected.json')}`)).json();
      const bad = [];
      try {
        const f = openVff(bytes);
        f.validateDeep();
        for (const m of exp.maps) {
          if (xxh3Hex(f.mapBytes('distance', m.map)) !== m.distanceXxh3) bad.push(`map ${m.map} hash`);
          const d = f.distances(m.map);
          m.distance.forEach((v, t) => {
            const ok = v === null ? Number.isNaN(d[t]) : f.field.distanceEncoding === 4 ? !Number.isNaN(d[t]) === (v === 1) : Math.abs(d[t] - v) <= 2e-6 * Math.max(1, Math.abs(v));
            if (!ok) bad.push(`map ${m.map} texel ${t}`);
          });
        }
        for (const [p, hs] of Object.entries(exp.slices)) hs.forEach((h, s) => { if (xxh3Hex(f.slice(p, s)) !== h) bad.push(`${p} slice ${s}`); });
      } catch (e) { bad.push(String(e.message)); }
      out.push({ n, bad: bad.slice(0, 3) });
    }
    return out;
  }, names);
  assert.equal(results.length, 18);
  for (const r of results) assert.deepEqual(r.bad, [], r.n);
});

test('invalid vectors are rejected in the browser with their IDs', async () => {
  const cases = [];
  for (const id of readdirSync(join(CONF, 'invalid')))
    for (const n of readdirSync(join(CONF, 'invalid', id)).filter((x) => x.endsWith('.vff'))) cases.push([id, n]);
  const got = await page.evaluate(async (cases) => {
    const { initVff, openVff } = await import('./src/vff.js');
    await initVff();
    const out = [];
    for (const [id, n] of cases) {
      const bytes = new Uint8Array(await (await fetch(`/conf/invalid/${id}/${n}`)).arrayBuffer());
      let code = 0;
      try {
        const f = openVff(bytes);
        f.validateDeep();
      } catch (e) { code = e.id ?? -1; }
      out.push([id, n, code]);
    }
    return out;
  }, cases);
  assert.ok(got.length >= 80);
  for (const [id, n, code] of got) assert.equal(code, Number(id), `${id}/${n}`);
});

test('the page names an invalid file\'s ID', async () => {
  const r = await page.evaluate(async () => {
    const bytes = new Uint8Array(await (await fetch('/conf/invalid/2002/magic-byte0.vff')).arrayBuffer());
    const res = await window.vffViewer.loadBytes(bytes, 'magic-byte0.vff');
    return { res, text: document.getElementById('problems').textContent };
  });
  assert.equal(r.res.id, 2002);
  assert.match(r.text, /^magic-byte0\.vff: /);
  assert.match(r.text, /bad-magic \(2002\)/);
});

test('the page uploads and renders every valid vector (2D array and 3D, every encoding, normals)', async () => {
  const names = readdirSync(join(CONF, 'valid')).filter((n) => n.endsWith('.vff'));
  const got = await page.evaluate(async (names) => {
    const out = [];
    for (const n of names) {
      const bytes = new Uint8Array(await (await fetch(`/conf/valid/${n}`)).arrayBuffer());
      let res, object = 0, glError = -1;
      try {
        window.vffViewer.view.setOptions({ interpolated: n.startsWith('u8c') });
        res = await window.vffViewer.loadBytes(bytes, n);
        window.vffViewer.redraw();
        glError = window.vffViewer.view.renderer.getContext().getError();
        object = window.vffViewer.objectPixels();
      } catch (e) { res = { error: String(e.message).slice(0, 300) }; }
      out.push({ n, res: { ok: res.ok, gl: res.gl, message: res.message, error: res.error }, glError, object });
    }
    return out;
  }, names);
  console.log(got.map((r) => `${r.n}: ${r.object} object pixels`).join('\n'));
  for (const r of got) {
    assert.ok(r.res.ok && r.res.gl, `${r.n}: ${JSON.stringify(r.res)}`);
    assert.equal(r.glError, 0, r.n);
  }
  // Fields whose object fills part of the default view show it (all but the tiny-map ones may).
  assert.ok(got.filter((r) => r.object > 0).length >= 6, JSON.stringify(got.map((r) => [r.n, r.object])));
});

test('bc4-diameter: blocks decoded to codes in the Worker answer as the CPU decoder', async () => {
  // The viewer uploads bc4-diameter maps as the codes the decoder's BC4 reading gives (R8UI), so
  // its reference view is the one of the same field written with unorm8-diameter codes.
  const got = await page.evaluate(async () => {
    const bytes = new Uint8Array(await (await fetch('/conf/valid/bc4-zstd-normals-slices.vff')).arrayBuffer());
    const r = await window.vffViewer.loadBytes(bytes, 'bc4.vff');
    const px = window.vffViewer.reference(48, false);
    return { r: { ok: r.ok, gl: r.gl }, occluded: px.filter((v) => v < 230).length, n: px.length };
  });
  console.log(`bc4: ${got.occluded} of ${got.n} reference pixels occluded`);
  assert.ok(got.r.ok && got.r.gl);
  assert.ok(got.occluded > 50);
});
