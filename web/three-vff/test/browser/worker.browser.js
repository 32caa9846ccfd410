// In headless Chromium: decodeInWorker decodes conformance vectors in a module Worker (the page's
// import map does not reach it; worker.js resolves the decoder's bare imports) to the same uniforms
// and texture bytes as VffField.fromBytes, with progress, and rejects a broken file with the
// decoder's error ID.
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { join } from 'node:path';
import { ROOT, openTestPage } from '../tools.js';

const CONF = join(ROOT, 'spec', 'conformance');
let session, page, errors = [];

before(async () => {
  session = await openTestPage({
    '/a.vff': join(CONF, 'valid', 'u8d-zstd-normals-meta.vff'),
    '/b.vff': join(CONF, 'valid', 'bit1-zstd-normals-meta-3d.vff'),
    '/bad.vff': join(CONF, 'invalid', '2001', 'header-63-bytes.vff'),
  });
  ({ page, errors } = session);
});
after(async () => { await session?.close(); });

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
