// harness.js - a static server for web/ (and named extra files) and headless Debian chromium with
// WebGL2 on SwiftShader, driven by playwright-core (the research note's recipe).
import { createServer } from 'node:http';
import { existsSync } from 'node:fs';
import { readFile } from 'node:fs/promises';
import { join, extname, normalize } from 'node:path';
import { fileURLToPath } from 'node:url';
import { chromium } from 'playwright-core';

export const WEB = fileURLToPath(new URL('../../', import.meta.url));

/**
 * A program of the project's build: the environment variable `env` when set (ctest sets it), else
 * `rel` under the default build folder of the checkout when built there, else '' (the caller skips,
 * saying why).
 */
export function builtTool(env, rel) {
  if (process.env[env]) return process.env[env];
  const path = join(WEB, '..', 'build', rel);
  return existsSync(path) ? path : '';
}
const TYPES = { '.html': 'text/html', '.js': 'text/javascript', '.mjs': 'text/javascript', '.json': 'application/json', '.wasm': 'application/wasm' };

/**
 * Serves web/ on 127.0.0.1; `extra` maps URL paths to files (test data). options.hide: URL path
 * prefixes answered 404 (a checkout without web/node_modules).
 */
export async function serve(extra = {}, options = {}) {
  const server = createServer(async (req, res) => {
    const path = decodeURIComponent(new URL(req.url, 'http://x').pathname);
    if ((options.hide ?? []).some((p) => path.startsWith(p))) { res.writeHead(404); res.end(); return; }
    const file = extra[path] ?? join(WEB, normalize(path).replace(/^(\.\.[/\\])+/, ''));
    try {
      const body = await readFile(file.endsWith('/') ? join(file, 'index.html') : file);
      res.writeHead(200, { 'content-type': TYPES[extname(file)] ?? 'application/octet-stream', 'content-length': body.length });
      res.end(req.method === 'HEAD' ? undefined : body);
    } catch {
      res.writeHead(404);
      res.end();
    }
  });
  await new Promise((r) => server.listen(0, '127.0.0.1', r));
  return { server, url: `http://127.0.0.1:${server.address().port}` };
}

/** How long a page's actions (screenshots, clicks) wait by default: a software renderer on a loaded machine draws slowly. */
export const ACTION_TIMEOUT_MS = 300000;

/**
 * Headless Chromium on SwiftShader; {webgpu: true} also turns on WebGPU (its SwiftShader adapter),
 * with Vulkan compositing: without it a WebGPU canvas's first frame loses the GPU process. Its
 * pages' actions wait up to ACTION_TIMEOUT_MS (Playwright's default, 30 s, is short of a frame of
 * the viewer when the suites run side by side on two cores).
 */
export async function launch({ webgpu = false } = {}) {
  const args = ['--headless=new', '--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist'];
  if (webgpu) args.push('--enable-unsafe-webgpu', '--enable-features=Vulkan', '--use-vulkan=swiftshader');
  const browser = await chromium.launch({ executablePath: process.env.VFF_CHROMIUM_PATH ?? '/usr/bin/chromium', args });
  const newPage = browser.newPage.bind(browser);
  browser.newPage = async (options) => {
    const page = await newPage(options);
    page.setDefaultTimeout(ACTION_TIMEOUT_MS);
    return page;
  };
  return browser;
}
