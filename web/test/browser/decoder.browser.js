// The decoder inside headless Chromium: the page's module decodes every conformance vector as
// node does (valid ones to their expected values, invalid ones to their folder's ID).
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
  page = await browser.newPage();
  await page.goto(`${srv.url}/index.html`);
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
  assert.equal(results.length, 16);
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
    return { res, text: document.getElementById('error').textContent };
  });
  assert.equal(r.res.id, 2002);
  assert.match(r.text, /bad-magic \(2002\)/);
});

test('the page uploads and renders every valid vector (2D array and 3D, every encoding, normals)', async () => {
  const names = readdirSync(join(CONF, 'valid')).filter((n) => n.endsWith('.vff'));
  const got = await page.evaluate(async (names) => {
    const out = [];
    const canvas = document.getElementById('view');
    for (const n of names) {
      const bytes = new Uint8Array(await (await fetch(`/conf/valid/${n}`)).arrayBuffer());
      canvas.width = 24; canvas.height = 24;
      let res;
      try {
        res = await window.vffViewer.loadBytes(bytes, n);
        Object.assign(window.vffViewer.view, { reference: false, interpolated: n.startsWith('u8c'), aoRays: 4 });
        window.vffViewer.redraw();
      } catch (e) { res = { error: String(e.message).slice(0, 300) }; }
      const gl = canvas.getContext('webgl2');
      const px = new Uint8Array(24 * 24 * 4);
      gl.readPixels(0, 0, 24, 24, gl.RGBA, gl.UNSIGNED_BYTE, px);
      let object = 0;  // pixels of the object's warm colours (red clearly above blue)
      for (let i = 0; i < px.length; i += 4) object += px[i] > px[i + 2] + 40;
      out.push({ n, res, glError: gl.getError(), object });
    }
    return out;
  }, names);
  console.log(got.map((r) => `${r.n}: ${r.object} object pixels of 576`).join('\n'));
  for (const r of got) {
    assert.ok(r.res.ok && r.res.gl, `${r.n}: ${JSON.stringify(r.res)}`);
    assert.equal(r.glError, 0, r.n);
  }
  // Fields whose object fills part of the default view show it (all but the tiny-map ones may).
  assert.ok(got.filter((r) => r.object > 0).length >= 6, JSON.stringify(got.map((r) => [r.n, r.object])));
});

test('bc4-diameter: BC4 blocks sampled by the GPU (RGTC) answer as the CPU-decoded codes', async () => {
  const got = await page.evaluate(async () => {
    const bytes = new Uint8Array(await (await fetch('/conf/valid/bc4-zstd-normals-slices.vff')).arrayBuffer());
    const canvas = document.getElementById('view');
    const size = 48;
    const gl = canvas.getContext('webgl2');
    const has = !!gl.getExtension('EXT_texture_compression_rgtc');
    const shot = async (bc4OnCpu) => {
      canvas.width = size; canvas.height = size;
      const r = await window.vffViewer.loadBytes(bytes, 'bc4.vff', { bc4OnCpu });
      Object.assign(window.vffViewer.view, { reference: true, interpolated: false });
      window.vffViewer.redraw();
      const px = new Uint8Array(size * size * 4);
      gl.readPixels(0, 0, size, size, gl.RGBA, gl.UNSIGNED_BYTE, px);
      return { r, px: Array.from(px.filter((_, i) => i % 4 === 0)) };
    };
    const gpu = await shot(false), cpu = await shot(true);
    return { has, gpu, cpu };
  });
  if (!got.has) { console.log('SKIP: no EXT_texture_compression_rgtc in this context'); return; }
  assert.equal(got.gpu.r.bc4, 'gpu');
  assert.equal(got.cpu.r.bc4, 'cpu');
  let differ = 0, occluded = 0;
  got.gpu.px.forEach((v, i) => { differ += Math.abs(v - got.cpu.px[i]) > 16; occluded += got.cpu.px[i] < 230; });
  console.log(`bc4 RGTC vs CPU decode: ${differ} of ${got.cpu.px.length} pixels differ by more than 16 levels; ${occluded} occluded`);
  assert.ok(occluded > 50);
  // Texture units may round interpolated palette entries differently (format.md 7.4): a few flips.
  assert.ok(differ <= got.cpu.px.length * 0.02);
});
