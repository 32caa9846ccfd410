// run-wgsl.mjs - runs WGSL compute kernels through WebGPU in headless Chromium (SwiftShader where
// there is no GPU) and writes what they leave in their buffers to files: the WebGPU side of the
// C++ GPU-vs-CPU suites (tests/gpu/wgsl_runner.h writes the jobs and reads the answers).
//
//   node web/tools/run-wgsl.mjs <job folder>
//
// <job folder>/job.json holds one run, or {"runs": [...]} several, run in order on one device:
//   kernel         the .wgsl file (absolute, or relative to the job folder)
//   entry          the compute entry point (default "main")
//   workgroups     work groups along x; more than maxComputeWorkgroupsPerDimension are split into
//                  several dispatches, each told its first item through `firstItem`
//   workgroupSize  items a work group (for firstItem; default 64)
//   firstItem      optional {group, binding, offset}: a uniform binding whose u32 at `offset`
//                  receives the first item of each dispatch (as the Vulkan kernels' firstRay)
//   maxWorkgroupsPerDispatch  optional, below the device's limit (to exercise the split)
//   bindings       [{group, binding, kind, file, size}], kind one of
//                    uniform | storage-read | storage-rw   a buffer of the file's bytes (zero-padded
//                                                          to 16-byte multiples, at least 256 bytes,
//                                                          or `size` zero bytes without a file)
//                    texture   also dimension ('2d-array' | '3d'), format ('r8uint', 'r16uint',
//                              'rg16sint', 'rgba8sint', 'bc4-r-unorm'), width, height, layers and
//                              optionally writes: [{offset, origin: [x, y, z], size: [w, h, d]}]
//                              (default: the whole texture from offset 0); rows are tightly
//                              packed, BC4 rows are rows of 4x4 blocks of 8 bytes; a BC4
//                              texture may name fallback: {format: 'r8unorm', file}, its texels
//                              decoded, bound instead where the adapter does not decode BC4
//                              (the kernel's texture_2d_array<f32> reads both alike), with a note
//                    sampler   a nearest, clamped sampler
//   outputs        [{group, binding, file, size}]: the first `size` bytes of a storage-rw buffer,
//                  written to the file (relative to the job folder) after the run
//
// Prints the adapter (vendor, architecture) and exits 0; exits 77 after 'SKIP: <reason>' where
// Chromium or WebGPU is not available (no adapter); exits 1 with the reason otherwise (a shader
// compile error prints every message of getCompilationInfo; no result within VFF_WGSL_TIMEOUT_S
// seconds, default 300, is a failure too).
import { existsSync, readFileSync, writeFileSync, mkdirSync } from 'node:fs';
import { dirname, isAbsolute, join, resolve } from 'node:path';

const SKIP = 77;

function fail(message, code = 1) {
  console.log(code === SKIP ? `SKIP: ${message}` : `run-wgsl: ${message}`);
  process.exit(code);
}

const folder = process.argv[2];
if (!folder) fail('usage: node run-wgsl.mjs <job folder>');
let job;
try {
  job = JSON.parse(readFileSync(join(folder, 'job.json'), 'utf8'));
} catch (e) {
  fail(`cannot read ${join(folder, 'job.json')}: ${e.message}`);
}
const runs = job.runs ?? [job];
const inFolder = (p) => (isAbsolute(p) ? p : resolve(folder, p));

// What the page needs: each run with its kernel's text, the files by name (served as /job/<i>).
const files = new Map();
const fileId = (name) => {
  const path = inFolder(name);
  if (!files.has(path)) files.set(path, `/job/${files.size}`);
  return files.get(path);
};
const pageRuns = runs.map((r, n) => {
  const kernelPath = inFolder(r.kernel ?? '');
  if (!r.kernel || !existsSync(kernelPath)) fail(`run ${n}: no kernel file ${r.kernel}`);
  return {
    name: r.name ?? `run ${n}`,
    kernel: readFileSync(kernelPath, 'utf8'),
    kernelPath,
    entry: r.entry ?? 'main',
    workgroups: r.workgroups,
    workgroupSize: r.workgroupSize ?? 64,
    maxWorkgroups: r.maxWorkgroupsPerDispatch ?? null,
    firstItem: r.firstItem ?? null,
    bindings: (r.bindings ?? []).map((b) => ({
      ...b,
      url: b.file ? fileId(b.file) : null,
      fallback: b.fallback ? { ...b.fallback, url: fileId(b.fallback.file) } : null,
    })),
    outputs: r.outputs ?? [],
  };
});

// Chromium (harness.js's, VFF_CHROMIUM_PATH) and playwright-core (web/node_modules) are needed;
// without them the caller skips.
let harness;
try {
  harness = await import('../test/browser/harness.js');
} catch (e) {
  fail(`cannot load playwright-core (npm ci in web/): ${e.message}`, SKIP);
}

// The page: an empty document (the project's index.html would start the viewer), served with the files.
mkdirSync(folder, { recursive: true });
const blank = join(folder, 'run-wgsl.html');
writeFileSync(blank, '<!doctype html><meta charset="utf-8"><title>run-wgsl</title>\n');
const extra = { '/index.html': blank, '/favicon.ico': blank };
for (const [path, url] of files) extra[url] = path;
const srv = await harness.serve(extra);
let browser;
// A kernel that SwiftShader is very slow to compile, or a device that stops answering, ends the
// run with a failure rather than holding the test until ctest's own limit.
const timeoutS = Number(process.env.VFF_WGSL_TIMEOUT_S ?? 300);
setTimeout(() => {
  console.log(`run-wgsl: no result after ${timeoutS} s (VFF_WGSL_TIMEOUT_S); the browser is closed`);
  browser?.close().finally(() => process.exit(1));
  setTimeout(() => process.exit(1), 5000);
}, timeoutS * 1000);
try {
  browser = await harness.launch({ webgpu: true });
} catch (e) {
  srv.server.close();
  fail(`chromium does not start (VFF_CHROMIUM_PATH): ${e.message.split('\n')[0]}`, SKIP);
}
let result;
try {
  const page = await browser.newPage();
  page.on('console', (m) => {
    if (m.type() === 'error' || m.type() === 'warning') console.log(`page ${m.type()}: ${m.text()}`);
  });
  await page.goto(`${srv.url}/index.html`);
  await page.addScriptTag({ content: pageFunctions().map(String).join('\n') });
  result = await page.evaluate((r) => runInPage(r), pageRuns);
} catch (e) {
  result = { error: `the page failed: ${e.message}` };
} finally {
  await browser.close();
  srv.server.close();
}
if (result.adapter) console.log(`adapter: vendor ${result.adapter.vendor || '?'}, architecture ${result.adapter.architecture || '?'}${result.adapter.description ? `, ${result.adapter.description}` : ''}`);
for (const note of result.notes ?? []) console.log(`note: ${note}`);
if (result.skip) fail(result.skip, SKIP);
if (result.error) fail(result.error);
for (const [n, outs] of result.outputs.entries())
  for (const [o, b64] of outs.entries()) {
    const path = inFolder(runs[n].outputs[o].file);
    mkdirSync(dirname(path), { recursive: true });
    writeFileSync(path, Buffer.from(b64, 'base64'));
  }
console.log(`run-wgsl: ${runs.length} run(s), ${result.dispatches} dispatch(es)`);
process.exit(0);

// ---- In the page (injected as a script; page.evaluate then calls runInPage) ---------------------

function pageFunctions() {
  return [pageTables, checkBc4, openDevice, makeBindGroups, readBack, runInPage];
}

function pageTables() {
  return {
    FORMATS: {
      r8uint: { bytes: 1, block: 1, sampleType: 'uint' },
      r16uint: { bytes: 2, block: 1, sampleType: 'uint' },
      r8unorm: { bytes: 1, block: 1, sampleType: 'float' },
      rg16sint: { bytes: 4, block: 1, sampleType: 'sint' },
      rgba8sint: { bytes: 4, block: 1, sampleType: 'sint' },
      'bc4-r-unorm': { bytes: 8, block: 4, sampleType: 'float' },
    },
    BUFFER_TYPES: { uniform: 'uniform', 'storage-read': 'read-only-storage', 'storage-rw': 'storage' },
    // Buffers are zero-padded to 16 bytes, at least 256: a runtime-sized array's binding must hold
    // one element even where the Vulkan buffer holds none (an empty scene's instances).
    bufferSize: (b, data) => Math.max(256, Math.ceil((data ? data.length : b.size ?? 0) / 16) * 16),
  };
}

// A device that advertises texture-compression-bc may still read other texels than a block holds;
// it cannot run a bc4-diameter field as it is. One block, red0 = 200, red1 = 10, index 0 in the
// first texel and 1 in the second: 200 / 255 and 10 / 255. Returns '' or what was read.
async function checkBc4(device) {
  const texture = device.createTexture({ size: [4, 4, 1], format: 'bc4-r-unorm', usage: GPUTextureUsage.TEXTURE_BINDING | GPUTextureUsage.COPY_DST });
  device.queue.writeTexture({ texture }, new Uint8Array([200, 10, 8, 0, 0, 0, 0, 0]), { bytesPerRow: 8, rowsPerImage: 1 }, [4, 4, 1]);
  const module = device.createShaderModule({ code: `@group(0) @binding(0) var t: texture_2d<f32>;
    @group(0) @binding(1) var<storage, read_write> o: array<f32>;
    @compute @workgroup_size(1) fn main() { o[0] = textureLoad(t, vec2i(0, 0), 0).x; o[1] = textureLoad(t, vec2i(1, 0), 0).x; }` });
  const pipeline = device.createComputePipeline({ layout: 'auto', compute: { module, entryPoint: 'main' } });
  const out = device.createBuffer({ size: 8, usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC });
  const read = device.createBuffer({ size: 8, usage: GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST });
  const group = device.createBindGroup({ layout: pipeline.getBindGroupLayout(0), entries: [{ binding: 0, resource: texture.createView() }, { binding: 1, resource: { buffer: out } }] });
  const enc = device.createCommandEncoder();
  const pass = enc.beginComputePass();
  pass.setPipeline(pipeline);
  pass.setBindGroup(0, group);
  pass.dispatchWorkgroups(1);
  pass.end();
  enc.copyBufferToBuffer(out, 0, read, 0, 8);
  device.queue.submit([enc.finish()]);
  await read.mapAsync(GPUMapMode.READ);
  const got = [...new Float32Array(read.getMappedRange())].map((v) => Math.round(v * 255));
  read.unmap();
  return got[0] === 200 && got[1] === 10 ? '' : `a block of texels 200 and 10 (/255) reads as ${got[0]} and ${got[1]}`;
}

// The adapter and device: BC4 where a run binds it, limits raised to what the runs need (up to the
// adapter's). Returns {device, adapter, notes, bcFallback} or {skip | error, adapter}.
async function openDevice(runs, load) {
  const { FORMATS, BUFFER_TYPES, bufferSize } = pageTables();
  if (!navigator.gpu) return { skip: 'WebGPU is not available in this chromium (navigator.gpu is undefined)' };
  const gpuAdapter = await navigator.gpu.requestAdapter();
  if (!gpuAdapter) return { skip: 'WebGPU has no adapter in this chromium' };
  const info = gpuAdapter.info ?? {};
  const adapter = { vendor: info.vendor, architecture: info.architecture, description: info.description };
  const defaults = { maxStorageBufferBindingSize: 134217728, maxBufferSize: 268435456, maxTextureArrayLayers: 256,
    maxTextureDimension2D: 8192, maxTextureDimension3D: 2048, maxUniformBufferBindingSize: 65536 };
  const need = {};
  const want = (name, value) => { if (value > (need[name] ?? defaults[name])) need[name] = value; };
  let bc = false;
  for (const r of runs)
    for (const b of r.bindings) {
      const data = b.url ? await load(b.url) : null;
      if (b.kind in BUFFER_TYPES) {
        want('maxBufferSize', bufferSize(b, data));
        want(b.kind === 'uniform' ? 'maxUniformBufferBindingSize' : 'maxStorageBufferBindingSize', bufferSize(b, data));
      } else if (b.kind === 'texture') {
        if (!FORMATS[b.format]) return { adapter, error: `${r.name}: unknown texture format ${b.format}` };
        bc ||= b.format.startsWith('bc');
        if (b.dimension === '3d') want('maxTextureDimension3D', Math.max(b.width, b.height, b.layers));
        else { want('maxTextureDimension2D', Math.max(b.width, b.height)); want('maxTextureArrayLayers', b.layers); }
      }
    }
  for (const [name, value] of Object.entries(need))
    if (value > gpuAdapter.limits[name]) return { adapter, error: `the runs need ${name} ${value}; the adapter has ${gpuAdapter.limits[name]}` };
  const hasBc = gpuAdapter.features.has('texture-compression-bc');
  const device = await gpuAdapter.requestDevice({ requiredFeatures: bc && hasBc ? ['texture-compression-bc'] : [], requiredLimits: need });
  // Where the adapter cannot sample BC4 (or reads wrong texels): the BC4 textures' fallbacks.
  const notes = [];
  let bcFallback = false;
  if (bc) {
    const wrong = hasBc ? await checkBc4(device) : 'no texture-compression-bc';
    if (wrong) {
      const all = runs.every((r) => r.bindings.every((b) => !(b.kind === 'texture' && b.format.startsWith('bc')) || b.fallback));
      if (!all) return { skip: `the WebGPU adapter does not decode BC4: ${wrong}`, adapter };
      bcFallback = true;
      notes.push(`the WebGPU adapter does not decode BC4 (${wrong}): the BC4 textures are bound decoded, as their fallbacks (r8unorm); the kernels are run, the adapter's BC4 decoder is not tested`);
    }
  }
  return { device, adapter, notes, bcFallback };
}

// A run's resources and bind groups, with an explicit layout (so that a kernel declaring other
// bindings than the Vulkan descriptor set's is an error, not silently another layout). Returns
// {bindGroups, layouts, buffers} or {error}.
async function makeBindGroups(device, r, load, bcFallback) {
  const { FORMATS, BUFFER_TYPES, bufferSize } = pageTables();
  const groups = new Map();
  const buffers = new Map();
  for (let b of r.bindings) {
    let data = b.url ? await load(b.url) : null;
    let resource, layout;
    if (b.kind in BUFFER_TYPES) {
      const usage = (b.kind === 'uniform' ? GPUBufferUsage.UNIFORM : GPUBufferUsage.STORAGE) | GPUBufferUsage.COPY_DST | GPUBufferUsage.COPY_SRC;
      const buffer = device.createBuffer({ size: bufferSize(b, data), usage, label: `${b.group}.${b.binding}` });
      if (data) {
        const padded = new Uint8Array(Math.ceil(data.length / 4) * 4);
        padded.set(data);
        device.queue.writeBuffer(buffer, 0, padded);
      }
      buffers.set(`${b.group}.${b.binding}`, buffer);
      resource = { buffer };
      layout = { buffer: { type: BUFFER_TYPES[b.kind] } };
    } else if (b.kind === 'texture') {
      if (bcFallback && b.format.startsWith('bc')) {
        b = { ...b, ...b.fallback, writes: b.fallback.writes ?? b.writes };
        data = await load(b.url);
      }
      const f = FORMATS[b.format];
      const is3D = b.dimension === '3d';
      const texture = device.createTexture({ size: [b.width, b.height, b.layers], format: b.format, dimension: is3D ? '3d' : '2d',
        usage: GPUTextureUsage.TEXTURE_BINDING | GPUTextureUsage.COPY_DST, label: `${b.group}.${b.binding}` });
      // writeTexture takes tightly packed rows (the 256-byte row alignment is copyBufferToTexture's).
      for (const w of data ? b.writes ?? [{ offset: 0, origin: [0, 0, 0], size: [b.width, b.height, b.layers] }] : []) {
        const blocksWide = Math.ceil(w.size[0] / f.block), blocksHigh = Math.ceil(w.size[1] / f.block);
        device.queue.writeTexture({ texture, origin: w.origin }, data,
          { offset: w.offset, bytesPerRow: blocksWide * f.bytes, rowsPerImage: blocksHigh }, w.size);
      }
      resource = texture.createView({ dimension: is3D ? '3d' : '2d-array' });
      layout = { texture: { sampleType: f.sampleType, viewDimension: is3D ? '3d' : '2d-array' } };
    } else if (b.kind === 'sampler') {
      resource = device.createSampler({ magFilter: 'nearest', minFilter: 'nearest' });
      layout = { sampler: { type: 'non-filtering' } };
    } else {
      return { error: `${r.name}: binding ${b.group}.${b.binding}: unknown kind ${b.kind}` };
    }
    if (!groups.has(b.group)) groups.set(b.group, { layout: [], entries: [] });
    groups.get(b.group).layout.push({ binding: b.binding, visibility: GPUShaderStage.COMPUTE, ...layout });
    groups.get(b.group).entries.push({ binding: b.binding, resource });
  }
  const layouts = [];
  for (let g = 0; g <= Math.max(-1, ...groups.keys()); ++g)
    layouts.push(device.createBindGroupLayout({ entries: groups.get(g)?.layout ?? [] }));
  const bindGroups = layouts.map((layout, g) => device.createBindGroup({ layout, entries: groups.get(g)?.entries ?? [] }));
  return { bindGroups, layouts, buffers };
}

// Copies the run's outputs out of their buffers; returns their bytes in base64, or {error}.
async function readBack(device, r, buffers) {
  const reads = [];
  const enc = device.createCommandEncoder();
  for (const o of r.outputs) {
    const src = buffers.get(`${o.group}.${o.binding}`);
    if (!src) return { error: `${r.name}: output ${o.group}.${o.binding} is no buffer binding` };
    const size = Math.ceil(o.size / 4) * 4;
    const dst = device.createBuffer({ size, usage: GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST });
    enc.copyBufferToBuffer(src, 0, dst, 0, size);
    reads.push({ dst, size: o.size });
  }
  device.queue.submit([enc.finish()]);
  const outs = [];
  for (const { dst, size } of reads) {
    await dst.mapAsync(GPUMapMode.READ);
    const bytes = new Uint8Array(dst.getMappedRange(), 0, size);
    let s = '';
    for (let i = 0; i < bytes.length; i += 0x8000) s += String.fromCharCode(...bytes.subarray(i, i + 0x8000));
    outs.push(btoa(s));
    dst.unmap();
    dst.destroy();
  }
  return { outs };
}

async function runInPage(runs) {
  const fetched = new Map();
  const load = async (url) => {
    if (!fetched.has(url)) {
      const res = await fetch(url);
      if (!res.ok) throw new Error(`cannot fetch ${url}: ${res.status}`);
      fetched.set(url, new Uint8Array(await res.arrayBuffer()));
    }
    return fetched.get(url);
  };
  const opened = await openDevice(runs, load);
  if (!opened.device) return opened;
  const { device, adapter, notes, bcFallback } = opened;
  const errors = [];
  device.addEventListener('uncapturederror', (e) => errors.push(e.error.message));
  const outputs = [];
  let dispatches = 0;
  for (const r of runs) {
    device.pushErrorScope('validation');
    const module = device.createShaderModule({ code: r.kernel, label: r.kernelPath });
    const compile = await module.getCompilationInfo();
    const messages = compile.messages.map((m) => `${r.kernelPath}:${m.lineNum}:${m.linePos}: ${m.type}: ${m.message}`);
    if (compile.messages.some((m) => m.type === 'error'))
      return { adapter, error: `${r.name}: the kernel does not compile:\n${messages.join('\n')}` };
    if (messages.length) console.warn(messages.join('\n'));
    const made = await makeBindGroups(device, r, load, bcFallback);
    if (made.error) return { adapter, error: made.error };
    const pipeline = device.createComputePipeline({ layout: device.createPipelineLayout({ bindGroupLayouts: made.layouts }),
      compute: { module, entryPoint: r.entry } });
    // The dispatches: at most maxGroups work groups each, the first item patched into the uniform
    // (queue writes and submissions run in order, so each dispatch sees its own).
    const maxGroups = Math.min(device.limits.maxComputeWorkgroupsPerDimension, r.maxWorkgroups ?? Infinity);
    for (let first = 0; first < r.workgroups; first += maxGroups) {
      if (r.firstItem) {
        const at = made.buffers.get(`${r.firstItem.group}.${r.firstItem.binding}`);
        if (!at) return { adapter, error: `${r.name}: firstItem names no buffer binding` };
        device.queue.writeBuffer(at, r.firstItem.offset, new Uint32Array([first * r.workgroupSize]));
      } else if (first > 0) {
        return { adapter, error: `${r.name}: ${r.workgroups} work groups exceed ${maxGroups} and the run has no firstItem` };
      }
      const enc = device.createCommandEncoder();
      const pass = enc.beginComputePass();
      pass.setPipeline(pipeline);
      made.bindGroups.forEach((bg, g) => pass.setBindGroup(g, bg));
      pass.dispatchWorkgroups(Math.min(maxGroups, r.workgroups - first));
      pass.end();
      device.queue.submit([enc.finish()]);
      ++dispatches;
    }
    const scope = await device.popErrorScope();
    if (scope) return { adapter, error: `${r.name}: WebGPU validation error: ${scope.message}` };
    const read = await readBack(device, r, made.buffers);
    if (read.error) return { adapter, error: read.error };
    for (const b of made.buffers.values()) b.destroy();
    outputs.push(read.outs);
  }
  if (errors.length) return { adapter, error: `WebGPU errors:\n${errors.join('\n')}` };
  return { adapter, outputs, dispatches, notes };
}
