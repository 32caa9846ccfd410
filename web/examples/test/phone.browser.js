// In headless Chromium: the example's canvas fills the window at any size, its drawing buffer the
// CSS size times the pixel ratio (at most 2), so nothing is stretched or blurred; on a phone's width
// the controls fit on the screen and the page does not scroll sideways; a resized window resizes
// the buffer.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { openExample } from './common.js';

const sizes = [
  { name: 'phone', viewport: { width: 390, height: 844 }, scale: 3, buffer: [780, 1688] },
  { name: 'desktop', viewport: { width: 1280, height: 720 }, scale: 1, buffer: [1280, 720] },
];

for (const s of sizes) {
  test(`${s.name} ${s.viewport.width}x${s.viewport.height} at pixel ratio ${s.scale}`, async () => {
    const ex = await openExample({ query: 'noloop=1&paused=1&t=1&mode=off', viewport: s.viewport, scale: s.scale });
    try {
      const r = await ex.page.evaluate(() => {
        const c = document.getElementById('view'), gl = window.example.renderer.getContext();
        const panel = document.getElementById('panel').getBoundingClientRect();
        return { css: [c.clientWidth, c.clientHeight], buffer: [gl.drawingBufferWidth, gl.drawingBufferHeight],
          aspect: window.example.camera.aspect, panel: [panel.left, panel.top, panel.right, panel.bottom],
          scroll: [document.scrollingElement.scrollWidth, document.scrollingElement.scrollHeight] };
      });
      console.log(JSON.stringify(r));
      assert.deepEqual(r.css, [s.viewport.width, s.viewport.height]);
      assert.deepEqual(r.buffer, s.buffer);
      assert.ok(Math.abs(r.aspect - s.viewport.width / s.viewport.height) < 1e-9);
      assert.ok(r.panel[0] >= 0 && r.panel[1] >= 0 && r.panel[2] <= s.viewport.width && r.panel[3] <= s.viewport.height,
        `the controls leave the screen: ${r.panel}`);
      assert.ok(r.scroll[0] <= s.viewport.width && r.scroll[1] <= s.viewport.height, `the page scrolls: ${r.scroll}`);
      // Covering less than half the screen keeps the scene visible.
      const area = (r.panel[2] - r.panel[0]) * (r.panel[3] - r.panel[1]);
      assert.ok(area < 0.5 * s.viewport.width * s.viewport.height, `the controls cover ${area} px²`);
      await ex.page.setViewportSize({ width: 600, height: 400 });
      await ex.page.waitForFunction(() => window.example.renderer.getContext().drawingBufferWidth !== 0 &&
        window.example.camera.aspect === 1.5, null, { timeout: 10000 });
      const after = await ex.page.evaluate(() => { const gl = window.example.renderer.getContext(); return [gl.drawingBufferWidth, gl.drawingBufferHeight]; });
      assert.deepEqual(after, [600 * Math.min(s.scale, 2), 400 * Math.min(s.scale, 2)]);
      assert.deepEqual(ex.errors, []);
    } finally {
      await ex.close();
    }
  });
}
