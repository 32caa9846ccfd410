// shot-example.mjs - a picture of the example scene (web/examples/contact-shadows) as its page
// shows it, in headless Debian chromium: the objects held at one time, the effect accumulated over
// --frames frames, the page's panel included. It makes the README's docs/three-example.png:
//
//   node tools/make-example.mjs --out examples/contact-shadows/assets
//   node tools/shot-example.mjs --out ../docs/three-example.png
//
// Options: --asset FILE.glb (default examples/contact-shadows/assets/example.glb); --size WxH, CSS
// pixels at pixel ratio 1 (default 960x600); --rays N, AO and shadow rays per pixel and frame
// (default 4); --frames N accumulated (default 32); --mode field|reference|off (default field);
// --time T, the animation time in seconds (default 3).
// Exit codes: 0 written, 1 usage, 2 the asset cannot be read, 4 the page failed (no WebGL2, an error
// on the page). The picture is written whole or not at all.
import { existsSync, renameSync, writeFileSync } from 'node:fs';
import { fileURLToPath } from 'node:url';
import { serve, launch } from '../test/browser/harness.js';

const prog = 'shot-example.mjs';
const opt = {
  asset: fileURLToPath(new URL('../examples/contact-shadows/assets/example.glb', import.meta.url)),
  out: '', size: '960x600', rays: '4', frames: '32', mode: 'field', time: '3',
};
const KEYS = { '--asset': 'asset', '--out': 'out', '--size': 'size', '--rays': 'rays', '--frames': 'frames', '--mode': 'mode', '--time': 'time' };
const usage = () => {
  console.error(`usage: node tools/${prog} --out FILE.png [--asset FILE.glb] [--size WxH] [--rays N] [--frames N] [--mode field|reference|off] [--time T]`);
  process.exit(1);
};
const args = process.argv.slice(2);
for (let i = 0; i < args.length; ++i) {
  const key = KEYS[args[i]];
  if (!key || i + 1 >= args.length) usage();
  opt[key] = args[++i];
}
const size = /^(\d+)x(\d+)$/.exec(opt.size);
const rays = Number(opt.rays), frames = Number(opt.frames), time = Number(opt.time);
if (!opt.out || !size || !['field', 'reference', 'off'].includes(opt.mode) || !Number.isFinite(time)
    || !Number.isInteger(rays) || rays < 1 || rays > 64 || !Number.isInteger(frames) || frames < 1 || frames > 1024) usage();
if (!existsSync(opt.asset)) {
  console.error(`${prog}: error: ${opt.asset}: no such file (make it with node tools/make-example.mjs)`);
  process.exit(2);
}

const srv = await serve({ '/examples/contact-shadows/assets/example.glb': opt.asset });
const browser = await launch();
let code = 0;
try {
  const page = await browser.newPage({ viewport: { width: Number(size[1]), height: Number(size[2]) }, deviceScaleFactor: 1 });
  const errors = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
  await page.goto(`${srv.url}/examples/contact-shadows/index.html?noloop=1&paused=1&t=${time}&rays=${rays}&dpr=1&mode=${opt.mode}`);
  await page.waitForFunction(() => window.example?.ready || window.example?.error, null, { timeout: 120000 });
  const r = await page.evaluate((frames) => {
    const ex = window.example;
    if (ex.error) return { error: ex.error };
    ex.renderFrames(frames);
    // The status line as the running page shows it, without the frame time of one software frame.
    document.getElementById('status').textContent = `${ex.occ.mode} · ${ex.occ.frame} frames accumulated`;
    return { frame: ex.occ.frame };
  }, frames);
  if (r.error || errors.length) {
    console.error(`${prog}: error: the page failed: ${r.error ?? errors.join('; ')}`);
    code = 4;
  } else {
    const tmp = `${opt.out}.tmp`;
    writeFileSync(tmp, await page.screenshot());
    renameSync(tmp, opt.out);
    console.log(`${opt.out}: ${opt.size}, ${r.frame} frames of ${rays} AO and ${rays} shadow rays a pixel accumulated (${opt.mode})`);
  }
} finally {
  await browser.close();
  srv.server.close();
}
process.exit(code);
