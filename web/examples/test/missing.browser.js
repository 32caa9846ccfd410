// In headless Chromium: the example page says what is missing, on the page, instead of staying
// blank: web/node_modules (served here as absent: `npm ci`), and the example's .glb (an asset URL
// that is not there: tools/make-example.mjs).
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { createServer } from 'node:http';
import { readFile } from 'node:fs/promises';
import { join, extname, normalize } from 'node:path';
import { launch, WEB } from '../../test/browser/harness.js';
import { PAGE } from './common.js';

/** web/ served as a fresh clone before `npm ci`: every path under node_modules is 404. */
async function serveWithoutModules() {
  const types = { '.html': 'text/html', '.js': 'text/javascript' };
  const server = createServer(async (req, res) => {
    const path = normalize(decodeURIComponent(new URL(req.url, 'http://x').pathname)).replace(/^(\.\.[/\\])+/, '');
    try {
      if (path.startsWith('/node_modules/')) throw new Error('absent');
      const body = await readFile(join(WEB, path));
      res.writeHead(200, { 'content-type': types[extname(path)] ?? 'application/octet-stream' });
      res.end(body);
    } catch {
      res.writeHead(404);
      res.end();
    }
  });
  await new Promise((r) => server.listen(0, '127.0.0.1', r));
  return { server, url: `http://127.0.0.1:${server.address().port}` };
}

test('without node_modules: the page names the missing folder and the command', async () => {
  const srv = await serveWithoutModules();
  const browser = await launch();
  try {
    const page = await browser.newPage();
    await page.goto(`${srv.url}${PAGE}`);
    const box = page.locator('#message');
    await box.waitFor({ state: 'visible', timeout: 30000 });
    const text = await box.textContent();
    console.log(`message: ${text}`);
    assert.match(text, /web\/node_modules/);
    assert.match(text, /npm ci/);
    assert.equal(await box.getAttribute('role'), 'alert');
    assert.equal(await page.locator('#status').textContent(), 'not running');
  } finally {
    await browser.close();
    srv.server.close();
  }
});

test('without the asset: the page names it and the command that makes it', async () => {
  const { serve } = await import('../../test/browser/harness.js');
  const srv = await serve();
  const browser = await launch();
  try {
    const page = await browser.newPage();
    await page.goto(`${srv.url}${PAGE}?asset=assets/absent.glb&noloop=1`);
    await page.waitForFunction(() => window.example?.error, null, { timeout: 60000 });
    const text = await page.locator('#message').textContent();
    console.log(`message: ${text}`);
    assert.match(text, /assets\/absent\.glb/);
    assert.match(text, /make-example\.mjs/);
    assert.ok(await page.locator('#message').isVisible());
  } finally {
    await browser.close();
    srv.server.close();
  }
});
