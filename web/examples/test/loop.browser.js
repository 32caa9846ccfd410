// In headless Chromium: the example page's own loop: paused, the view holds still and the effect
// accumulates; running, the objects move and the status line shows the frame time and the frames
// accumulated. Then a still frame, accumulated, kept as $VFF_WORK/three-example.png; no console error.
import { test, after, before } from 'node:test';
import assert from 'node:assert/strict';
import { join } from 'node:path';
import { openExample, frame, WORK } from './common.js';

let ex;
before(async () => { ex = await openExample({ query: 'noloop=1&paused=1&t=1&rays=1', viewport: { width: 240, height: 160 } }); });
after(async () => { await ex?.close(); });

test('its own loop: paused, the view accumulates; running, the objects move and the status shows ms/frame', async () => {
  const p = ex.page;
  const at = () => p.evaluate(() => window.example.movers[0].position.toArray());
  const before = await at();
  await p.evaluate(() => window.example.setLoop(true));
  await p.waitForFunction(() => window.example.occ.frame >= 2, null, { timeout: 60000 });
  assert.deepEqual(await at(), before, 'paused: nothing moves');
  await p.getByRole('checkbox', { name: 'pause' }).uncheck();
  await p.waitForFunction((x) => window.example.movers[0].position.x !== x, before[0], { timeout: 60000 });
  await p.waitForTimeout(300);
  const status = await p.locator('#status').textContent();
  console.log(`status: ${status}`);
  assert.match(status, /^field · \d+ ms\/frame \(draw [\d.]+ ms\) · \d+ frame\(s\) accumulated/);
  await p.getByRole('checkbox', { name: 'pause' }).check();
  await p.evaluate(() => window.example.setLoop(false));
});

test('a still frame after accumulation, kept as a screenshot; no console error', async () => {
  const p = ex.page;
  await p.evaluate(() => window.example.setTime(3));
  const f = await frame(p, 4);
  console.log(`accumulated ${f.frame} frames at ${f.width}x${f.height}`);
  await p.evaluate(() => { document.getElementById('status').textContent = `field · ${window.example.occ.frame} frames accumulated`; });
  await p.screenshot({ path: join(WORK, 'three-example.png') });
  assert.deepEqual(ex.errors, []);
});
