// In headless Chromium: decodeInWorker decodes conformance vectors in a module Worker (the page's
// import map does not reach it; worker.js resolves the decoder's bare imports) to the same uniforms
// and texture bytes as VffField.fromBytes, with progress, and rejects a broken file with the
// decoder's error ID.
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { join } from 'node:path';
import { serve, launch } from '../../../test/browser/harness.js';
import { ROOT } from '../tools.js';

const CONF = join(ROOT, 'spec', 'conformance');
let srv, browser, page;
const errors = [];

before(async () => {
  srv = await serve({
    '/a.vff': join(CONF, 'valid', 'u8d-zstd-normals-meta.vff'),
    '/b.vff': join(CONF, 'valid', 'bit1-zstd-normals-meta-3d.vff'),
    '/bad.vff': join(CONF, 'invalid', '2001', 'header-63-bytes.vff'),
  });
  browser = await launch();
  page = await browser.newPage();
  page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
  page.on('pageerror', (e) => errors.push(String(e)));
  await page.goto(`${srv.url}/three-vff/test/browser/occlusion.html`);
  await page.waitForFunction(() => window.ready === true);
});
after(async () => { await browser?.close(); srv?.server.close(); });

test('decodeInWorker: the same field as fromBytes, progress, errors', async () => {
  for (const url of ['/a.vff', '/b.vff']) {
    const r = await page.evaluate((u) => window.workerDecode(u), url);
    console.log(url, JSON.stringify(r));
    assert.deepEqual(r.stages, ['open', 'check', 'textures', 'done'], url);
    assert.ok(r.uniforms && r.maps && r.normals && r.positions && r.uploaded, url);
  }
  const bad = await page.evaluate(() => window.workerDecode('/bad.vff'));
  console.log('/bad.vff', JSON.stringify(bad));
  assert.equal(bad.error.name, 'VffError');
  assert.equal(bad.error.id, 2001);
  assert.deepEqual(errors, []);
});
