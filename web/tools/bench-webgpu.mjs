// bench-webgpu.mjs - field queries per second through WebGPU: the WGSL kernel generated from the
// Vulkan one (gpu/wgsl/kernels/vff_vk_query.wgsl, _3d for 3D layouts) in headless Debian chromium,
// the field decoded and uploaded by the viewer's own code (viewer/webgpu_ground.js). The counterpart
// of vff-gpu-bench's GL and Vulkan tables: the same two queries (kNearest occlusion, kInterpolated
// visibility) over 2^20 and 2^21 incoherent rays, the adapter named (SwiftShader: the CPU).
//
//   node tools/bench-webgpu.mjs --field FILE.vff [--log2 20,21] [--repeat 2]
//
// The rays: ground-AO rays around the object, as the ground pass casts them: origins uniform on the
// square of side 4 R centred under the sphere, on the plane touching its bottom; cosine-weighted
// directions about +y; tmax 2 R (fixed seed). Each time is the wall time from submitting the
// dispatches to onSubmittedWorkDone (rays and field uploaded before, answers not read back), the best
// of --repeat after one untimed run. The last column is a check that the kernel answered: the share
// of nearest rays that hit, the mean interpolated visibility.
// Exit codes: 0 measured, 1 usage, 2 the field cannot be read, 4 the page failed (no WebGPU, an
// error on the page), 77 no WebGPU adapter (printed as SKIP with the reason).
import { existsSync } from 'node:fs';
import { serve, launch } from '../test/browser/harness.js';

const prog = 'bench-webgpu.mjs';
const opt = { field: '', log2: '20,21', repeat: '2' };
const args = process.argv.slice(2);
const usage = () => { console.error(`usage: node tools/${prog} --field FILE.vff [--log2 20,21] [--repeat 2]`); process.exit(1); };
for (let i = 0; i < args.length; ++i) {
  const key = { '--field': 'field', '--log2': 'log2', '--repeat': 'repeat' }[args[i]];
  if (!key || i + 1 >= args.length) usage();
  opt[key] = args[++i];
}
const logs = opt.log2.split(',').map(Number), repeat = Number(opt.repeat);
if (!opt.field || !logs.every((l) => Number.isInteger(l) && l >= 6 && l <= 22) || !(Number.isInteger(repeat) && repeat >= 1 && repeat <= 20)) usage();
if (!existsSync(opt.field)) {
  console.error(`${prog}: error: ${opt.field}: no such file`);
  process.exit(2);
}

const srv = await serve({ '/bench/field.vff': opt.field });
const browser = await launch({ webgpu: true });
let code = 0;
try {
  const page = await browser.newPage({ viewport: { width: 320, height: 240 } });
  const errors = [];
  page.on('pageerror', (e) => errors.push(String(e)));
  // ?ground=webgl2: the page's own ground stays off WebGPU; the bench opens its device.
  await page.goto(`${srv.url}/index.html?ground=webgl2`);
  await page.waitForFunction(() => window.vffViewer?.view);
  const r = await page.evaluate(async ({ logs, repeat }) => {
    const bytes = new Uint8Array(await (await fetch('/bench/field.vff')).arrayBuffer());
    const loaded = await window.vffViewer.loadBytes(bytes, 'field.vff');
    if (!loaded.ok || !loaded.gl) return { error: `the page cannot show the field: ${loaded.message ?? ''}` };
    const view = window.vffViewer.view, src = view.field.source;
    const g = await import('./src/viewer/webgpu_ground.js');
    const w = await import('./src/vff_wgsl.js');
    const gpu = await g.openWebGpu({ allowFallback: true });
    if (!gpu.device) return { skip: gpu.reason };
    const d = gpu.device;
    const field = g.uploadField(d, src);
    const module = d.createShaderModule({ code: src.is3d ? w.VFF_VK_QUERY_3D_WGSL : w.VFF_VK_QUERY_WGSL });
    const pipe = await d.createComputePipelineAsync({ layout: 'auto', compute: { module, entryPoint: 'main' } });
    const c = view.field.center, R = view.field.radius;
    // A fixed-seed generator (mulberry32): the same rays in every run.
    let seed = 0x9e3779b9;
    const rnd = () => { seed = (seed + 0x6d2b79f5) | 0; let t = Math.imul(seed ^ (seed >>> 15), 1 | seed); t = (t + Math.imul(t ^ (t >>> 7), 61 | t)) ^ t; return ((t ^ (t >>> 14)) >>> 0) / 4294967296; };
    const rows = [];
    for (const log2 of logs) {
      const n = 2 ** log2;
      const rays = new Float32Array(n * 12);  // VffVkRay: origin, direction, range (tmin, tmax, intraBias, unused)
      for (let i = 0; i < n; ++i) {
        const u1 = rnd(), u2 = rnd(), r = Math.sqrt(u1), phi = 2 * Math.PI * u2;
        rays.set([c.x + (rnd() * 4 - 2) * R, c.y - R, c.z + (rnd() * 4 - 2) * R, 0,
          r * Math.cos(phi), Math.sqrt(Math.max(0, 1 - u1)), r * Math.sin(phi), 0, 0, 2 * R, -1, 0], i * 12);
      }
      const rayBuf = d.createBuffer({ size: rays.byteLength, usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_DST });
      d.queue.writeBuffer(rayBuf, 0, rays);
      const answers = d.createBuffer({ size: n * 80, usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC });
      const g0 = d.createBindGroup({ layout: pipe.getBindGroupLayout(0), entries: [...field.entries, { binding: 4, resource: { buffer: rayBuf } }, { binding: 5, resource: { buffer: answers } }] });
      // The dispatches: one a part of at most the device's workgroup count, each with its push
      // uniform {which, firstRay, rayCount} (as the Vulkan pipeline's parts).
      const parts = [];
      for (let first = 0; first < n; first += d.limits.maxComputeWorkgroupsPerDimension * 64) {
        const buf = d.createBuffer({ size: 16, usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST });
        const group = d.createBindGroup({ layout: pipe.getBindGroupLayout(1), entries: [{ binding: 0, resource: { buffer: buf } }] });
        parts.push({ first, buf, group, groups: Math.min(d.limits.maxComputeWorkgroupsPerDimension, Math.ceil((n - first) / 64)) });
      }
      const run = async (which) => {
        for (const p of parts) d.queue.writeBuffer(p.buf, 0, new Uint32Array([which, p.first, n, 0]));
        const enc = d.createCommandEncoder();
        for (const p of parts) {
          const pass = enc.beginComputePass();
          pass.setPipeline(pipe);
          pass.setBindGroup(0, g0);
          pass.setBindGroup(1, p.group);
          pass.dispatchWorkgroups(p.groups);
          pass.end();
        }
        await d.queue.onSubmittedWorkDone();  // the uploads before the clock starts
        const t0 = performance.now();
        d.queue.submit([enc.finish()]);
        await d.queue.onSubmittedWorkDone();
        return (performance.now() - t0) / 1000;
      };
      // The check column: read the answers of the last run back.
      const check = async (which) => {
        const read = d.createBuffer({ size: n * 80, usage: GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST });
        const enc = d.createCommandEncoder();
        enc.copyBufferToBuffer(answers, 0, read, 0, n * 80);
        d.queue.submit([enc.finish()]);
        await read.mapAsync(GPUMapMode.READ);
        const u = new Uint32Array(read.getMappedRange()), f = new Float32Array(u.buffer);
        let s = 0;
        for (let i = 0; i < n; ++i) s += which === 1 ? (u[i * 20] & 1) : f[i * 20 + 7];
        read.unmap();
        read.destroy();
        return s / n;
      };
      for (const [which, name] of [[1, 'nearest occluded'], [2, 'interpolated visibility']]) {
        await run(which);  // untimed: the first run pays for the driver's first use
        let best = Infinity;
        for (let k = 0; k < repeat; ++k) best = Math.min(best, await run(which));
        rows.push({ log2, name, rate: n / best, check: await check(which) });
      }
      for (const b of [rayBuf, answers, ...parts.map((p) => p.buf)]) b.destroy();
    }
    field.destroy();
    return { adapter: gpu.name, rows, is3d: src.is3d };
  }, { logs, repeat });
  if (r.skip) {
    console.error(`SKIP: ${r.skip}`);
    code = 77;
  } else if (r.error || errors.length) {
    console.error(`${prog}: error: ${r.error ?? errors.join('; ')}`);
    code = 4;
  } else {
    console.log(`WebGPU: ${r.adapter}; field queries/s through the WGSL kernel (gpu/wgsl/kernels/vff_vk_query${r.is3d ? '_3d' : ''}.wgsl) on ground-AO rays`);
    console.log(`(wall time from submit to onSubmittedWorkDone, uploads excluded; best of ${repeat})`);
    console.log('| rays | query | WebGPU rays/s | hit share or mean visibility |\n|---|---|---|---|');
    for (const row of r.rows) console.log(`| 2^${row.log2} | ${row.name} | ${row.rate.toExponential(3)} | ${row.check.toFixed(4)} |`);
  }
} catch (e) {
  console.error(`${prog}: error: ${e.message}`);
  code = 4;
} finally {
  await browser.close();
  srv.server.close();
}
process.exit(code);
