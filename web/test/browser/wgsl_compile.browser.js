// The generated WGSL (gpu/wgsl/, web/tools/gen-wgsl.mjs) compiles in Chromium's WebGPU: every
// library and kernel gives a shader module without errors, and every kernel a compute pipeline
// (layout 'auto', entry point main). Headless Chromium's WebGPU runs on SwiftShader, which offers
// texture-compression-bc for the BC4 variants.
import { test, after, before } from 'node:test';
import assert from 'node:assert/strict';
import { existsSync, readFileSync, writeFileSync, mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { serve, launch } from './harness.js';
import { OUTPUTS, WGSL_DIR } from '../../tools/gen-wgsl.mjs';

const CHROMIUM = process.env.VFF_CHROMIUM_PATH ?? '/usr/bin/chromium';
const SKIP = existsSync(CHROMIUM) ? '' : `no chromium at ${CHROMIUM} (VFF_CHROMIUM_PATH)`;
if (SKIP) console.log(`SKIP: ${SKIP}`);

// An empty page of the server's origin: the viewer's index.html starts its own rendering, with which
// the WebGPU instance was seen to drop ('Instance dropped') in some runs.
let srv, browser, page, dir;
before(async () => {
  if (SKIP) return;
  dir = mkdtempSync(join(tmpdir(), 'vff-wgsl-'));
  writeFileSync(join(dir, 'blank.html'), '<!doctype html><title>wgsl</title>\n');
  srv = await serve({ '/blank.html': join(dir, 'blank.html') });
  browser = await launch({ webgpu: true });
  page = await browser.newPage();
  await page.goto(`${srv.url}/blank.html`);
});
after(async () => { await browser?.close(); srv?.server.close(); if (dir) rmSync(dir, { recursive: true, force: true }); });

/** Compiles each { name, code, kernel } in the page: its compilation messages and pipeline error. */
async function compileAll(shaders) {
  return page.evaluate(async (shaders) => {
    if (!navigator.gpu) return { error: 'navigator.gpu is missing' };
    const adapter = await navigator.gpu.requestAdapter();
    if (!adapter) return { error: 'no WebGPU adapter' };
    const bc = adapter.features.has('texture-compression-bc');
    const device = await adapter.requestDevice({ requiredFeatures: bc ? ['texture-compression-bc'] : [] });
    const out = [];
    for (const s of shaders) {
      device.pushErrorScope('validation');
      const module = device.createShaderModule({ code: s.code });
      const info = await module.getCompilationInfo();
      const messages = info.messages.filter((m) => m.type === 'error').map((m) => `${m.lineNum}:${m.linePos} ${m.message}`);
      const warnings = info.messages.filter((m) => m.type !== 'error').map((m) => `${m.lineNum}:${m.linePos} ${m.message}`);
      let pipeline = '';
      if (s.kernel && !messages.length) {
        try {
          await device.createComputePipelineAsync({ layout: 'auto', compute: { module, entryPoint: 'main' } });
        } catch (e) { pipeline = String(e.message || e); }
      }
      const scope = await device.popErrorScope();
      out.push({ name: s.name, messages, warnings, pipeline, scope: scope ? scope.message : '' });
    }
    return { bc, results: out };
  }, shaders);
}

test('every generated WGSL module compiles, every kernel makes a compute pipeline', { skip: SKIP || false }, async () => {
  // The committed files (web/test/wgsl.test.js checks that they are the generator's output).
  const shaders = OUTPUTS.map((o) => ({ name: o.out, code: readFileSync(join(WGSL_DIR, o.out), 'utf8'), kernel: !!o.kernel }));
  const r = await compileAll(shaders);
  assert.equal(r.error, undefined, r.error);
  assert.equal(r.bc, true, 'the adapter lacks texture-compression-bc');
  assert.equal(r.results.length, OUTPUTS.length);
  for (const x of r.results) {
    console.log(`${x.name}: ${x.messages.length} errors, ${x.warnings.length} warnings${x.warnings.length ? `: ${x.warnings.join('; ')}` : ''}`);
    assert.deepEqual(x.messages, [], `${x.name}: compilation errors`);
    assert.equal(x.pipeline, '', `${x.name}: createComputePipelineAsync`);
    assert.equal(x.scope, '', `${x.name}: validation error`);
  }
});

// A kernel appended to the generated library runs its helpers and arithmetic on inputs from here:
// umulExtended (through vffFibTop32), isnan and isinf from the bits; and vffDivide and vffSqrt,
// correctly rounded where WGSL's fma is fused (one rounding), within an ulp where it is not.
const PROBE = `
@group(0) @binding(100) var<storage, read> probeIn: array<u32>;
@group(0) @binding(101) var<storage, read_write> probeOut: array<u32>;
@compute @workgroup_size(64)
fn probe(@builtin(global_invocation_id) id: vec3<u32>) {
  let i = id.x;
  if (i >= arrayLength(&probeIn) / 3u) { return; }
  let a = probeIn[3u * i];
  let b = probeIn[3u * i + 1u];
  let c = probeIn[3u * i + 2u];
  var hi: u32;
  var lo: u32;
  glsl_umulExtended(a, b, &hi, &lo);
  let fa = bitcast<f32>(a);
  let fb = bitcast<f32>(b);
  probeOut[7u * i] = hi;
  probeOut[7u * i + 1u] = lo;
  probeOut[7u * i + 2u] = vffFibTop32(a);
  probeOut[7u * i + 3u] = select(0u, 1u, glsl_isnan(fa)) | select(0u, 2u, glsl_isinf(fa));
  probeOut[7u * i + 4u] = bitcast<u32>(vffDivide(fa, fb));
  probeOut[7u * i + 5u] = bitcast<u32>(vffSqrt(fa));
  probeOut[7u * i + 6u] = bitcast<u32>(fma(fa, fb, bitcast<f32>(c)));
}`;

const f32 = (u) => new Float32Array(new Uint32Array([u]).buffer)[0];
const bits = (x) => new Uint32Array(new Float32Array([x]).buffer)[0];

/** The correctly rounded (to nearest even) binary32 bits of a * b + c, from exact integers; null for specials. */
function fmaBits(ua, ub, uc) {
  const dec = (u) => {
    const e = (u >>> 23) & 255, f = u & 0x7fffff;
    return e === 255 ? null : { s: u >>> 31, m: BigInt(e ? f | 0x800000 : f), e: Math.max(e, 1) - 150 };
  };
  const a = dec(ua), b = dec(ub), c = dec(uc);
  if (!a || !b || !c || a.m === 0n || b.m === 0n) return null;
  const E = Math.min(a.e + b.e, c.e);
  let N = (a.s ^ b.s ? -1n : 1n) * a.m * b.m * (1n << BigInt(a.e + b.e - E)) + (c.s ? -1n : 1n) * c.m * (1n << BigInt(c.e - E));
  if (N === 0n) return 0;
  const s = N < 0n ? 1 : 0;
  if (N < 0n) N = -N;
  const L = N.toString(2).length - 1;
  const sh = Math.max(L - 23, -149 - E);
  let m, f = E + sh;
  if (sh <= 0) m = N << BigInt(-sh);
  else {
    m = N >> BigInt(sh);
    const rem = N - (m << BigInt(sh)), half = 1n << BigInt(sh - 1);
    if (rem > half || (rem === half && (m & 1n))) m += 1n;
    if (m === 1n << 24n) { m >>= 1n; f += 1; }
  }
  m = Number(m);
  if (m < 0x800000) return ((s << 31) | m) >>> 0;
  if (f + 150 >= 255) return ((s << 31) | 0x7f800000) >>> 0;
  return ((s << 31) | ((f + 150) << 23) | (m & 0x7fffff)) >>> 0;
}

test('the generated helpers give the CPU answers on WebGPU; vffDivide, vffSqrt within fma\'s rounding', { skip: SKIP || false }, async () => {
  const inputs = [0x7f800000, 1, 0, 0xff800000, 2, 0, 0x7fc00000, 3, 0, 0x7f800001, 0x40490fdb, 0, 0, 0x3f800000, 0];
  let seed = 12345;
  const rnd = () => { seed = (Math.imul(seed, 1103515245) + 12345) >>> 0; return (seed ^ (seed >>> 15)) >>> 0; };
  const near = (lo, span) => lo + (rnd() % span);
  for (let k = 0; k < 1000; ++k) inputs.push(rnd(), rnd(), rnd());                           // any bits
  for (let k = 0; k < 1000; ++k) inputs.push(near(0x3e000000, 0x02000000), near(0x3e000000, 0x02000000), rnd());
  for (let k = 0; k < 1000; ++k) {  // c close to -a * b: cancellation
    const a = near(0x3f000000, 0x01000000), b = near(0x3f000000, 0x01000000);
    inputs.push(a, b, (bits(-Math.fround(f32(a) * f32(b))) + (rnd() % 5) - 2) >>> 0);
  }
  for (let k = 0; k < 500; ++k) inputs.push(near(0x00800000, 0x08000000), near(0x0c000000, 0x08000000), rnd() % 0x01000000);  // tiny results
  const code = readFileSync(join(WGSL_DIR, 'vff_query.wgsl'), 'utf8') + PROBE;
  const n = inputs.length / 3;
  const out = await page.evaluate(async ({ code, inputs, n }) => {
    const device = await (await navigator.gpu.requestAdapter()).requestDevice();
    const module = device.createShaderModule({ code });
    const pipeline = await device.createComputePipelineAsync({ layout: 'auto', compute: { module, entryPoint: 'probe' } });
    const inBuf = device.createBuffer({ size: inputs.length * 4, usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_DST });
    device.queue.writeBuffer(inBuf, 0, new Uint32Array(inputs));
    const outBuf = device.createBuffer({ size: n * 28, usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC });
    const read = device.createBuffer({ size: n * 28, usage: GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST });
    const group = device.createBindGroup({ layout: pipeline.getBindGroupLayout(0), entries: [
      { binding: 100, resource: { buffer: inBuf } }, { binding: 101, resource: { buffer: outBuf } }] });
    const enc = device.createCommandEncoder();
    const pass = enc.beginComputePass();
    pass.setPipeline(pipeline);
    pass.setBindGroup(0, group);
    pass.dispatchWorkgroups(Math.ceil(n / 64));
    pass.end();
    enc.copyBufferToBuffer(outBuf, 0, read, 0, n * 28);
    device.queue.submit([enc.finish()]);
    await read.mapAsync(GPUMapMode.READ);
    return Array.from(new Uint32Array(read.getMappedRange()));
  }, { code, inputs, n });
  const bad = { umul: [], fib: [], nan: [], divide: [], sqrt: [] };
  const normal = (x) => Number.isFinite(x) && (x === 0 || Math.abs(x) >= 1.1754943508222875e-38);
  const ulps = (u, x) => Math.abs((u | 0) - (bits(x) | 0));
  let unfused = 0, inexact = 0;
  const rounded = [];
  for (let i = 0; i < n; ++i) {
    const [a, b, c] = inputs.slice(3 * i, 3 * i + 3).map((u) => u >>> 0), o = out.slice(7 * i, 7 * i + 7);
    const p = BigInt(a) * BigInt(b);
    if (o[0] !== Number(p >> 32n) || o[1] !== Number(p & 0xffffffffn)) bad.umul.push(i);
    if (o[2] !== Number(((BigInt(a) * 0x9E3779B97F4A7C15n) & 0xffffffffffffffffn) >> 32n)) bad.fib.push(i);
    const fa = f32(a), fb = f32(b);
    if (o[3] !== ((Number.isNaN(fa) ? 1 : 0) | (Math.abs(fa) === Infinity ? 2 : 0))) bad.nan.push(i);
    const want = fmaBits(a, b, c);
    if (want !== null && normal(f32(want)) && normal(fa) && normal(fb) && normal(f32(c)) && o[6] !== want) ++unfused;
    // Normal operands and results only: WGSL lets an implementation flush subnormals in its arithmetic.
    const q = Math.fround(fa / fb), r = Math.fround(Math.sqrt(fa));
    if (normal(fa) && normal(fb) && fb !== 0 && normal(q)) rounded.push([`${fa} / ${fb}`, o[4], q, 'divide']);
    if (normal(fa) && fa >= 0) rounded.push([`sqrt ${fa}`, o[5], r, 'sqrt']);
  }
  const fused = unfused === 0;
  for (const [what, got, x, k] of rounded) {
    if (got !== bits(x)) ++inexact;
    if (ulps(got, x) > (fused ? 0 : 1)) bad[k].push(`${what}: ${f32(got)}, not ${x}`);
  }
  console.log(`probe over ${n} inputs: fma ${fused ? 'fused' : `unfused (${unfused} results differ from one rounding)`}; ` +
    `vffDivide/vffSqrt not correctly rounded in ${inexact} of ${rounded.length}`);
  for (const [k, v] of Object.entries(bad)) assert.deepEqual(v.slice(0, 5), [], k);
});
