// tools.js - what the browser tests of @vff/three share: the project's tools (vff-bake and
// vff-procedural-mesh, from the environment as ctest passes them, else the default build folder),
// a scratch folder, the test page in headless Chromium, and the figures that compare two 8-bit
// images.
import { mkdirSync } from 'node:fs';
import { join } from 'node:path';
import { fileURLToPath } from 'node:url';
import { serve, launch, builtTool } from '../../test/browser/harness.js';

export const ROOT = fileURLToPath(new URL('../../../', import.meta.url));
export const BAKE = builtTool('VFF_BAKE', 'tools/vff-bake/vff-bake');
export const MESHGEN = builtTool('VFF_PROCEDURAL_MESH', 'samples/vff-procedural-mesh');
export const SKIP = !BAKE || !MESHGEN ? 'vff-bake and vff-procedural-mesh are not built (VFF_BAKE, VFF_PROCEDURAL_MESH)' : '';
if (SKIP) console.log(`SKIP: ${SKIP}`);

export function scratch(name) {
  const dir = join(process.env.VFF_WORK ?? '/tmp', `three-vff-${name}`);
  mkdirSync(dir, { recursive: true });
  return dir;
}

/** RMS and the share within `tol` of a - b over the pixels where mask(i). */
export function compare(a, b, mask, tol = 8) {
  let n = 0, s2 = 0, within = 0;
  for (let i = 0; i < a.length; ++i) {
    if (!mask(i)) continue;
    const d = a[i] - b[i];
    ++n;
    s2 += d * d;
    within += Math.abs(d) <= tol;
  }
  return { pixels: n, rms: n ? Math.sqrt(s2 / n) : 0, within: n ? within / n : 1 };
}

/**
 * Serves web/ and `files` (URL path -> file), opens test/browser/occlusion.html in headless
 * Chromium and waits for its modules. Returns {srv, browser, page, errors (console errors and page
 * exceptions, collected), close()}.
 */
export async function openTestPage(files) {
  const srv = await serve(files);
  const browser = await launch();
  const page = await browser.newPage();
  const errors = [];
  page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
  page.on('pageerror', (e) => errors.push(String(e)));
  await page.goto(`${srv.url}/three-vff/test/browser/occlusion.html`);
  await page.waitForFunction(() => window.ready === true);
  return { srv, browser, page, errors, close: async () => { await browser.close(); srv.server.close(); } };
}
