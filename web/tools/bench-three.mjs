// bench-three.mjs - the frame time of @vff/three's VffOcclusion in the example scene
// (web/examples/contact-shadows), in headless Debian chromium: the same page, the same frame (the
// objects held at one time, one view) and the same rays per pixel, answered by the fields and by
// three-mesh-bvh's exact GPU ray casting against the objects' triangles (the effect's 'reference'
// mode), and the plain scene without the effect as a floor. Prints the renderer WebGL names
// (SwiftShader: software rendering on the CPU) and a table of ms per frame, median of the frames.
//
//   node tools/bench-three.mjs [--asset example.glb] [--size WxH] [--rays N] [--frames N]
//
// --asset: the example's .glb (default examples/contact-shadows/assets/example.glb, which
// tools/make-example.mjs makes); --size: the canvas in CSS pixels at pixel ratio 1 (default
// 160x120); --rays: AO rays and shadow rays per pixel and frame (default 4); --frames: frames timed
// per mode after one untimed (default 3).
// Exit codes: 0 measured, 1 usage, 2 the asset cannot be read, 4 the page failed (no WebGL2, an
// error on the page).
import { existsSync, readFileSync } from 'node:fs';
import { fileURLToPath } from 'node:url';
import { serve, launch } from '../test/browser/harness.js';

const prog = 'bench-three.mjs';
const opt = {
  asset: fileURLToPath(new URL('../examples/contact-shadows/assets/example.glb', import.meta.url)),
  size: '160x120', rays: '4', frames: '3',
};
const args = process.argv.slice(2);
const usage = () => { console.error(`usage: node tools/${prog} [--asset FILE.glb] [--size WxH] [--rays N] [--frames N]`); process.exit(1); };
for (let i = 0; i < args.length; ++i) {
  const key = { '--asset': 'asset', '--size': 'size', '--rays': 'rays', '--frames': 'frames' }[args[i]];
  if (!key || i + 1 >= args.length) usage();
  opt[key] = args[++i];
}
const size = /^(\d+)x(\d+)$/.exec(opt.size);
const rays = Number(opt.rays), frames = Number(opt.frames);
if (!size || !(rays >= 1 && rays <= 64) || !(frames >= 1 && frames <= 100) || !Number.isInteger(rays) || !Number.isInteger(frames)) usage();
const [w, h] = [Number(size[1]), Number(size[2])];
if (!existsSync(opt.asset)) {
  console.error(`${prog}: error: ${opt.asset}: no such file (make it with node tools/make-example.mjs)`);
  process.exit(2);
}
const cpu = (readFileSync('/proc/cpuinfo', 'utf8').match(/model name\s*:\s*(.*)/) ?? [])[1] ?? 'unknown CPU';

const srv = await serve({ '/examples/contact-shadows/assets/example.glb': opt.asset });
const browser = await launch();
let code = 0;
try {
  const page = await browser.newPage({ viewport: { width: w, height: h }, deviceScaleFactor: 1 });
  const errors = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
  await page.goto(`${srv.url}/examples/contact-shadows/index.html?noloop=1&paused=1&t=3&rays=${rays}&dpr=1`);
  await page.waitForFunction(() => window.example?.ready || window.example?.error, null, { timeout: 120000 });
  const r = await page.evaluate(({ frames }) => {
    const ex = window.example;
    if (ex.error) return { error: ex.error };
    const gl = ex.renderer.getContext();
    const info = gl.getExtension('WEBGL_debug_renderer_info');
    const renderer = info ? gl.getParameter(info.UNMASKED_RENDERER_WEBGL) : gl.getParameter(gl.RENDERER);
    const vendor = info ? gl.getParameter(info.UNMASKED_VENDOR_WEBGL) : gl.getParameter(gl.VENDOR);
    const times = {};
    // Each mode in a block: its first frame (untimed) compiles its shaders, which a change of mode
    // may do again.
    const modes = ['field', 'reference', 'off'];
    for (const m of modes) {
      ex.setMode(m);
      ex.renderFrames(1);
      times[m] = [];
      for (let i = 0; i < frames; ++i) times[m].push(ex.renderFrames(1));
    }
    const median = (a) => { const s = [...a].sort((x, y) => x - y); return s[s.length >> 1]; };
    return { renderer, vendor, width: gl.drawingBufferWidth, height: gl.drawingBufferHeight, instances: ex.movers.length,
      ms: Object.fromEntries(modes.map((m) => [m, median(times[m])])) };
  }, { frames });
  if (r.error || errors.length) {
    console.error(`${prog}: error: the page failed: ${r.error ?? errors.join('; ')}`);
    code = 4;
  } else {
    const renderer = /SwiftShader/i.test(r.renderer) ? `${r.renderer} (software rendering on the CPU)` : r.renderer;
    console.log(`three.js frame time: ${r.vendor}, ${renderer}`);
    console.log(`cpu: ${cpu}`);
    console.log(`frame: ${r.width}x${r.height}, ${rays} AO rays and ${rays} shadow rays per pixel, ` +
      `${r.instances} moving instances, median of ${frames} frames`);
    console.log('');
    console.log('| effect | ms/frame | / field |');
    console.log('|---|---:|---:|');
    const row = (name, ms) => console.log(`| ${name} | ${ms.toFixed(1)} | ${(ms / r.ms.field).toFixed(2)} |`);
    row('field (VffOcclusion)', r.ms.field);
    row('exact (three-mesh-bvh GPU ray casting)', r.ms.reference);
    row('none (the scene alone)', r.ms.off);
    console.log('');
    console.log(`field speed-up over exact (exact ms / field ms): ${(r.ms.reference / r.ms.field).toFixed(2)}x`);
  }
} finally {
  await browser.close();
  srv.server.close();
}
process.exit(code);
