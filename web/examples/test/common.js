// common.js - what the example page's browser tests share: the asset made by
// tools/make-example.mjs into $VFF_WORK (from the shared meshes, or vff-procedural-mesh's shapes),
// the page served with that asset, console errors collected, and image comparisons.
import { execFileSync } from 'node:child_process';
import { mkdirSync, existsSync } from 'node:fs';
import { join } from 'node:path';
import { serve, launch, WEB } from '../../test/browser/harness.js';

export const WORK = process.env.VFF_WORK ?? '/tmp/vff-web-example';
export const PAGE = '/examples/contact-shadows/index.html';

/** The example's .glb in WORK (made once per case); null when vff-bake is not at hand. */
export function makeAsset() {
  mkdirSync(WORK, { recursive: true });
  const out = join(WORK, 'example');
  const args = [join(WEB, 'tools', 'make-example.mjs'), '--out', out];
  if (process.env.VFF_BAKE) args.push('--bake', process.env.VFF_BAKE);
  if (process.env.VFF_PROCEDURAL_MESH) args.push('--procedural', process.env.VFF_PROCEDURAL_MESH);
  if (process.env.VFF_SHARED_MESHES) args.push('--meshes', process.env.VFF_SHARED_MESHES);
  const note = execFileSync(process.execPath, args, { encoding: 'utf8', stdio: ['ignore', 'pipe', 'pipe'] });
  console.log(note.trim());
  return join(out, 'example.glb');
}

/** A browser page on the example (URL parameters `query`), its errors in `errors`. */
export async function openExample({ query = '', viewport = { width: 480, height: 320 }, scale = 1, extra } = {}) {
  const glb = makeAsset();
  if (!existsSync(glb)) throw new Error(`${glb} was not made`);
  const srv = await serve(extra ?? { '/examples/contact-shadows/assets/example.glb': glb });
  const browser = await launch();
  const page = await browser.newPage({ viewport, deviceScaleFactor: scale });
  const errors = [];
  page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
  page.on('pageerror', (e) => errors.push(String(e)));
  page.on('response', (res) => { if (res.status() >= 400) errors.push(`${res.status()} ${res.url()}`); });
  await page.goto(`${srv.url}${PAGE}${query ? '?' + query : ''}`);
  await page.waitForFunction(() => window.example?.ready || window.example?.error, null, { timeout: 90000 });
  const close = async () => { await browser.close(); srv.server.close(); };
  return { page, errors, close, srv };
}

/** Draws n frames in the page and returns its canvas's pixels (RGBA, rows from the top). */
export async function frame(page, n = 1) {
  return page.evaluate(async (n) => {
    const ex = window.example;
    const ms = ex.renderFrames(n);
    const c = ex.renderer.domElement;
    ex.renderer.setRenderTarget(null);
    const gl = ex.renderer.getContext();
    const w = gl.drawingBufferWidth, h = gl.drawingBufferHeight;
    const px = new Uint8Array(w * h * 4);
    gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
    const rows = new Uint8Array(px.length);
    for (let y = 0; y < h; ++y) rows.set(px.subarray((h - 1 - y) * w * 4, (h - y) * w * 4), y * w * 4);
    // Base64: a plain array of numbers would cost seconds to pass back.
    let text = '';
    for (let i = 0; i < rows.length; i += 0x8000) text += String.fromCharCode(...rows.subarray(i, i + 0x8000));
    return { width: w, height: h, pixels: btoa(text), ms, frame: ex.occ.frame, canvas: [c.clientWidth, c.clientHeight] };
  }, n).then((f) => ({ ...f, pixels: new Uint8Array(Buffer.from(f.pixels, 'base64')) }));
}

/** RMS over the RGB channels, share of pixels whose channels are all within `within`, in `mask`. */
export function compare(a, b, mask = null, within = 8) {
  let sum = 0, count = 0, close = 0;
  for (let i = 0, p = 0; i < a.pixels.length; i += 4, ++p) {
    if (mask && !mask[p]) continue;
    let worst = 0;
    for (let k = 0; k < 3; ++k) {
      const d = a.pixels[i + k] - b.pixels[i + k];
      sum += d * d;
      worst = Math.max(worst, Math.abs(d));
    }
    ++count;
    close += worst <= within;
  }
  return { rms: Math.sqrt(sum / (3 * Math.max(1, count))), within: close / Math.max(1, count), count };
}
