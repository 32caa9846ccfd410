// bench-frame.mjs FIELD.vff [WIDTHxHEIGHT] - the WebGL2 frame time of the viewer in headless
// Debian chromium (SwiftShader: software rendering on the CPU, not a GPU), median of 5 frames,
// for the default view (nearest, then interpolated, 16 AO rays; then the reduced rays used while
// dragging) beside a baseline measured in the same run: the same canvas seen from below the ground,
// looking up at the object, one camera-ray lookup per pixel and no ground shading.
//   node tools/bench-frame.mjs bunny.vff 640x400
import { readFileSync } from 'node:fs';
import { serve, launch } from '../test/browser/harness.js';

const [fieldPath, size = '640x400'] = process.argv.slice(2);
if (!fieldPath) { console.error('usage: node tools/bench-frame.mjs FIELD.vff [WxH]'); process.exit(1); }
const [w, h] = size.split('x').map(Number);
const cpu = (readFileSync('/proc/cpuinfo', 'utf8').match(/model name\s*:\s*(.*)/) ?? [])[1] ?? 'unknown CPU';
const srv = await serve({ '/field.vff': fieldPath });
const browser = await launch();
try {
  const page = await browser.newPage();
  await page.goto(`${srv.url}/index.html`);
  const r = await page.evaluate(async ({ w, h }) => {
    const v = window.vffViewer;
    const bytes = new Uint8Array(await (await fetch('/field.vff')).arrayBuffer());
    const res = await v.loadBytes(bytes, 'field.vff');
    if (!res.gl) return { error: res.message ?? 'no WebGL2' };
    const c = document.getElementById('view');
    c.width = w; c.height = h;
    const median = (set) => {
      Object.assign(v.view, set);
      v.redraw();
      const t = [];
      for (let i = 0; i < 5; ++i) t.push(v.redraw());
      return t.sort((a, b) => a - b)[2];
    };
    const base = { reference: false, aoRays: 16, pitch: -0.35, moving: false };
    return {
      nearest: median({ ...base, interpolated: false }),
      interpolated: median({ ...base, interpolated: true }),
      moving: median({ ...base, interpolated: false, moving: true }),
      below: median({ ...base, interpolated: false, pitch: 1.5 }),
      renderer: (() => { const gl = c.getContext('webgl2'); const d = gl.getExtension('WEBGL_debug_renderer_info'); return d ? gl.getParameter(d.UNMASKED_RENDERER_WEBGL) : gl.getParameter(gl.RENDERER); })(),
    };
  }, { w, h });
  if (r.error) { console.error(`bench-frame: ${fieldPath}: ${r.error}`); process.exitCode = 4; }
  else {
    console.log(`cpu: ${cpu}; renderer: ${r.renderer} (software rendering)`);
    console.log(`webgl2 frame ${w}x${h}, ${fieldPath}: nearest ${r.nearest.toFixed(1)} ms, interpolated ${r.interpolated.toFixed(1)} ms, nearest while dragging (4 AO + 2 shadow rays) ${r.moving.toFixed(1)} ms; baseline (from below the ground: object lookups only) ${r.below.toFixed(1)} ms`);
  }
} finally {
  await browser.close();
  srv.server.close();
}
