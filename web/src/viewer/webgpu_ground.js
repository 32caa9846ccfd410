// webgpu_ground.js - the viewer's ground through WebGPU, where the browser offers it: the ground's AO
// and soft shadow accumulated over frames by a compute pass that includes the WGSL query
// (gpu/wgsl/vff_query.wgsl, generated from the same GLSL as the WebGL2 passes), shaded into a canvas
// under the three.js one, which then draws only the object and the grid over it. The reference view
// of the ground's AO (the tests' comparison with libvff) is a compute pass too.
//
// The accumulation is passes.js's ACCUMULATE, pixel for pixel: the same rays from the same random
// numbers at the same pixel (rows counted from the bottom, as gl_FragCoord), so the two paths draw
// the same ground up to binary32 rounding. The object stays a three.js impostor: it stands on the
// ground and the camera never goes below it, so drawing it over the ground needs no depth test.
import { VFF_QUERY_WGSL, VFF_QUERY_3D_WGSL } from '../vff_wgsl.js';
import { REFERENCE_AO_RAYS } from './passes.js';

const WGSL_FORMATS = { R8UI: 'r8uint', R16UI: 'r16uint', RG16I: 'rg16sint' };
const TEXEL_BYTES = { R8UI: 1, R16UI: 2, RG16I: 4 };

/**
 * A WebGPU device for the viewer: {device, name, limits} (limits as gpu.js's contextLimits), or
 * {reason} where the browser offers none. A software adapter (the fallback adapter, as SwiftShader)
 * is taken only with allowFallback: it compiles the query's shaders far more slowly than a WebGL2
 * context compiles the GLSL ES, so the page opens faster without it.
 */
export async function openWebGpu({ allowFallback = false } = {}) {
  if (!globalThis.navigator?.gpu) return { reason: 'this browser offers no WebGPU' };
  try {
    const adapter = await navigator.gpu.requestAdapter();
    if (!adapter) return { reason: 'WebGPU gave no adapter' };
    if ((adapter.isFallbackAdapter || adapter.info?.isFallbackAdapter) && !allowFallback)
      return { reason: 'WebGPU offers only a software adapter (?ground=webgpu takes it)' };
    const keys = ['maxTextureArrayLayers', 'maxTextureDimension2D', 'maxTextureDimension3D', 'maxStorageBufferBindingSize', 'maxBufferSize'];
    const device = await adapter.requestDevice({ requiredLimits: Object.fromEntries(keys.map((k) => [k, adapter.limits[k]])) });
    const info = adapter.info ?? {};
    const soft = adapter.isFallbackAdapter || info.isFallbackAdapter ? ', a software adapter' : '';
    const name = ([info.vendor, info.architecture, info.device].filter(Boolean).join(' ') || 'unnamed adapter') + soft;
    const l = device.limits;
    return { device, name, limits: { maxTextureSize: l.maxTextureDimension2D, maxLayers: l.maxTextureArrayLayers, max3d: l.maxTextureDimension3D } };
  } catch (e) {
    return { reason: `WebGPU failed: ${e.message}` };
  }
}

// The frame's parameters (GroundParams below: 160 bytes, WGSL uniform layout).
const PARAMS_BYTES = 160;
const PASSES = `
struct GroundParams {
  invViewProjection: mat4x4<f32>,
  light: vec3<f32>, lightAngle: f32,     // unit direction towards the light; its cone's half-angle
  color: vec3<f32>, fade: f32,           // the ground's colour; where it fades into the sky
  sky: vec3<f32>, groundY: f32,
  aim: vec3<f32>, aoRange: f32,          // the camera's target (the fade's centre)
  size: vec2<u32>, frame: u32, aoRays: u32,
  shadowRays: u32, interpolated: u32, show: u32, unused: u32,
}
@group(1) @binding(0) var<uniform> P: GroundParams;
@group(1) @binding(1) var<storage, read_write> accum: array<vec2<f32>>;

fn openShare(o: vec3<f32>, d: vec3<f32>, tmax: f32, interpolated: bool) -> f32 {
  if (interpolated) { return vffVisibility(o, d, 0.0, tmax, VFF_OFF_OBJECT); }
  return select(1.0, 0.0, vffOccluded(o, d, 0.0, tmax, VFF_OFF_OBJECT));
}

// passes.js's pcg and random2, at the pixel whose gl_FragCoord is (x + 0.5, y + 0.5).
fn pcg(v: u32) -> u32 {
  let s = v * 747796405u + 2891336453u;
  let w = ((s >> ((s >> 28u) + 4u)) ^ s) * 277803737u;
  return (w >> 22u) ^ w;
}
fn random2(px: vec2<u32>, ray: u32) -> vec2<f32> {
  let h = pcg(px.x + pcg(px.y + pcg(P.frame * 64u + ray)));
  let h2 = pcg(h);
  return vec2<f32>(f32(h >> 8u), f32(h2 >> 8u)) / 16777216.0;
}

// Rows from the bottom, as gl_FragCoord counts them.
@compute @workgroup_size(8, 8)
fn accumulate(@builtin(global_invocation_id) id: vec3<u32>) {
  if (id.x >= P.size.x || id.y >= P.size.y) { return; }
  let at = id.y * P.size.x + id.x;
  let ndc = 2.0 * (vec2<f32>(id.xy) + 0.5) / vec2<f32>(P.size) - 1.0;
  let a = P.invViewProjection * vec4<f32>(ndc, -1.0, 1.0);
  let b = P.invViewProjection * vec4<f32>(ndc, 1.0, 1.0);
  let ro = a.xyz / a.w;
  let rd = normalize(b.xyz / b.w - ro);
  var t = -1.0;
  if (rd.y < 0.0) { t = (P.groundY - ro.y) / rd.y; }
  if (t <= 0.0) { accum[at] = vec2<f32>(1.0, 1.0); return; }
  let p = ro + rd * t;
  let interpolated = P.interpolated != 0u;
  var open = 0.0;
  for (var i = 0u; i < P.aoRays; i++) {
    let u = random2(id.xy, i);
    let r = sqrt(u.x);
    let phi = 6.28318531 * u.y;  // cosine-weighted about +y
    open += openShare(p, vec3<f32>(r * cos(phi), sqrt(max(1.0 - u.x, 0.0)), r * sin(phi)), P.aoRange, interpolated);
  }
  var up = vec3<f32>(1.0, 0.0, 0.0);
  if (abs(P.light.y) < 0.9) { up = vec3<f32>(0.0, 1.0, 0.0); }
  let tl = normalize(cross(up, P.light));
  let bl = cross(P.light, tl);
  var lit = 0.0;
  for (var i = 0u; i < P.shadowRays; i++) {
    let u = random2(id.xy, 16u + i);
    let c = mix(1.0, cos(P.lightAngle), u.x);
    let s = sqrt(max(1.0 - c * c, 0.0));
    let phi = 6.28318531 * u.y;
    lit += openShare(p, normalize(c * P.light + s * (cos(phi) * tl + sin(phi) * bl)), 1e30, interpolated);
  }
  let fresh = vec2<f32>(open / f32(max(P.aoRays, 1u)), lit / f32(max(P.shadowRays, 1u)));
  let w = 1.0 / f32(P.frame + 1u);
  var previous = fresh;
  if (P.frame > 0u) { previous = accum[at]; }
  accum[at] = mix(previous, fresh, w);
}

struct ReferenceParams { center: vec3<f32>, radius: f32, size: u32, interpolated: u32, unused0: u32, unused1: u32, }
@group(1) @binding(2) var<uniform> RP: ReferenceParams;
@group(1) @binding(3) var<storage, read_write> reference: array<f32>;

// passes.js's REFERENCE: web_reference.cpp aoDirection, a Fibonacci spiral cosine-weighted about +y.
@compute @workgroup_size(8, 8)
fn referenceView(@builtin(global_invocation_id) id: vec3<u32>) {
  if (id.x >= RP.size || id.y >= RP.size) { return; }
  let c = RP.center;
  let R = RP.radius;
  let q = (2.0 * (vec2<f32>(id.xy) + 0.5) / f32(RP.size) - 1.0) * 2.0 * R;
  let p = vec3<f32>(c.x + q.x, c.y - R, c.z + q.y);
  var open = 0.0;
  for (var i = 0; i < ${REFERENCE_AO_RAYS}; i++) {
    let u = (f32(i) + 0.5) / f32(${REFERENCE_AO_RAYS});
    let r = sqrt(u);
    let phi = f32(i) * 2.39996323;
    open += openShare(p, vec3<f32>(r * cos(phi), sqrt(1.0 - u), r * sin(phi)), 4.0 * R, RP.interpolated != 0u);
  }
  reference[id.y * RP.size + id.x] = open / f32(${REFERENCE_AO_RAYS});
}
`;

// The ground shaded from the accumulation (view3d.js's GROUND_FRAGMENT), into the canvas.
const SHADE = `
${PASSES.slice(PASSES.indexOf('struct GroundParams'), PASSES.indexOf('@group(1)'))}
@group(0) @binding(0) var<uniform> P: GroundParams;
@group(0) @binding(1) var<storage, read> accum: array<vec2<f32>>;
@vertex
fn corner(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
  let xy = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u)) * 2.0 - 1.0;  // one triangle over the screen
  return vec4<f32>(xy, 0.0, 1.0);
}
@fragment
fn shade(@builtin(position) fc: vec4<f32>) -> @location(0) vec4<f32> {
  let x = u32(fc.x);
  let y = P.size.y - 1u - u32(fc.y);  // rows from the bottom, as the accumulation
  let ndc = 2.0 * vec2<f32>(f32(x) + 0.5, f32(y) + 0.5) / vec2<f32>(P.size) - 1.0;
  let a = P.invViewProjection * vec4<f32>(ndc, -1.0, 1.0);
  let b = P.invViewProjection * vec4<f32>(ndc, 1.0, 1.0);
  let ro = a.xyz / a.w;
  let rd = normalize(b.xyz / b.w - ro);
  if (rd.y >= 0.0) { return vec4<f32>(P.sky, 1.0); }
  let t = (P.groundY - ro.y) / rd.y;
  if (t <= 0.0) { return vec4<f32>(P.sky, 1.0); }
  let world = ro + rd * t;
  let v = accum[y * P.size.x + x];
  var col = P.color * (0.55 * v.x + 0.6 * v.y * max(P.light.y, 0.0));
  if (P.show == 1u) { col = vec3<f32>(v.x); }
  if (P.show == 2u) { col = vec3<f32>(v.y); }
  let f = smoothstep(0.6 * P.fade, P.fade, length(world.xz - P.aim.xz));
  return vec4<f32>(mix(col, P.sky, f), 1.0);
}
`;

/**
 * The field's resources at the WGSL include's bindings (group 0: entries for createBindGroup), from
 * field_three's result.gpu; destroy() frees them. (Also tools/bench-webgpu.mjs's upload.)
 */
export function uploadField(device, g) {
  const dimension = g.is3d ? '3d' : '2d';
  const plane = (p) => {
    const tex = device.createTexture({
      size: [p.width, p.height, p.depth], dimension, format: WGSL_FORMATS[p.format],
      usage: GPUTextureUsage.TEXTURE_BINDING | GPUTextureUsage.COPY_DST,
    });
    const row = p.width * TEXEL_BYTES[p.format];
    device.queue.writeTexture({ texture: tex }, p.data, { bytesPerRow: row, rowsPerImage: p.height }, [p.width, p.height, p.depth]);
    return tex;
  };
  const maps = plane(g.distance);
  // A field without normals still binds the include's normal texture (the query reads it only when
  // the field block says there is a normal plane).
  const normals = g.normal ? plane(g.normal) : plane({ width: 1, height: 1, depth: 1, format: 'RG16I', data: new Int16Array(2) });
  const positions = device.createBuffer({ size: Math.max(16, g.table.byteLength), usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_DST });
  device.queue.writeBuffer(positions, 0, g.table);
  const block = device.createBuffer({ size: g.block.byteLength, usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST });
  device.queue.writeBuffer(block, 0, g.block);
  const view = (t) => t.createView({ dimension: g.is3d ? '3d' : '2d-array' });
  return {
    is3d: g.is3d,
    entries: [
      { binding: 0, resource: { buffer: block } }, { binding: 1, resource: view(maps) },
      { binding: 2, resource: { buffer: positions } }, { binding: 3, resource: view(normals) },
    ],
    destroy() { for (const r of [maps, normals, positions, block]) r.destroy(); },
  };
}

/** The ground of FieldView (view3d.js) through WebGPU, drawn into `canvas`. */
export class WebGpuGround {
  /**
   * Starts compiling the passes (compile(is3d) resolves when those of 2D-array or 3D fields are
   * ready: a software adapter takes minutes), so the view draws with WebGL2 until then.
   */
  constructor(gpu, canvas) {
    this.device = gpu.device;
    this.name = gpu.name;
    this.canvas = canvas;
    this.context = canvas.getContext('webgpu');
    this.format = navigator.gpu.getPreferredCanvasFormat();
    this.context.configure({ device: this.device, format: this.format, alphaMode: 'opaque' });
    this.params = this.device.createBuffer({ size: PARAMS_BYTES, usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST });
    const shade = this.device.createShaderModule({ code: SHADE });
    this.shadePipeline = null;
    this.shading = this.device.createRenderPipelineAsync({
      layout: 'auto', vertex: { module: shade, entryPoint: 'corner' },
      fragment: { module: shade, entryPoint: 'shade', targets: [{ format: this.format }] },
    }).then((p) => { this.shadePipeline = p; });
    this.pipelines = new Map();  // per maps target (is3d): the compute pipelines, once compiled
    this.compiling = new Map();  // per maps target: the compile in progress
    this.field = null;
    this.accum = null;
    this.size = [0, 0];
  }

  /** Whether the passes of 3D (or 2D-array) fields are compiled. */
  ready(is3d) { return !!this.shadePipeline && this.pipelines.has(is3d); }

  /** Compiles the passes of 3D (or 2D-array) fields, once; resolves when they are ready. */
  compile(is3d) {
    if (!this.compiling.has(is3d)) {
      const module = this.device.createShaderModule({ code: `${is3d ? VFF_QUERY_3D_WGSL : VFF_QUERY_WGSL}\n${PASSES}` });
      const make = (entryPoint) => this.device.createComputePipelineAsync({ layout: 'auto', compute: { module, entryPoint } });
      this.compiling.set(is3d, Promise.all([make('accumulate'), make('referenceView'), this.shading]).then(([accumulate, reference]) => {
        this.pipelines.set(is3d, { accumulate, reference });
      }));
    }
    return this.compiling.get(is3d);
  }

  computePipelines(is3d) { return this.pipelines.get(is3d); }

  /** Shows a field (field_three.js's result.gpu); null: none. */
  setField(g) {
    this.field?.destroy();
    this.field = g ? uploadField(this.device, g) : null;
    this.bindings = null;
  }

  /** The canvas and the accumulation at the drawing buffer's size. */
  resize(w, h) {
    if (w === this.size[0] && h === this.size[1]) return;
    this.size = [w, h];
    this.canvas.width = w;
    this.canvas.height = h;
    this.accum?.destroy();
    this.accum = this.device.createBuffer({ size: Math.max(16, w * h * 8), usage: GPUBufferUsage.STORAGE });
    this.bindings = null;
  }

  makeBindings() {
    const p = this.computePipelines(this.field.is3d).accumulate;
    const group = (layout, entries) => this.device.createBindGroup({ layout, entries });
    this.bindings = {
      field: group(p.getBindGroupLayout(0), this.field.entries),
      accumulate: group(p.getBindGroupLayout(1), [{ binding: 0, resource: { buffer: this.params } }, { binding: 1, resource: { buffer: this.accum } }]),
      shade: group(this.shadePipeline.getBindGroupLayout(0), [{ binding: 0, resource: { buffer: this.params } }, { binding: 1, resource: { buffer: this.accum } }]),
    };
  }

  /**
   * One frame: with `accumulate`, one more accumulation step (frame f of the running mean); then the
   * shaded ground into the canvas. p: {invViewProjection (Matrix4), light, lightAngle, color, fade,
   * sky, groundY, aim, aoRange, frame, aoRays, shadowRays, interpolated, show}.
   */
  draw(p, accumulate) {
    const [w, h] = this.size;
    if (!w || !h) return;
    const buf = new ArrayBuffer(PARAMS_BYTES), f = new Float32Array(buf), u = new Uint32Array(buf);
    f.set(p.invViewProjection.elements, 0);
    f.set([p.light.x, p.light.y, p.light.z, p.lightAngle, p.color.r, p.color.g, p.color.b, p.fade], 16);
    f.set([p.sky.r, p.sky.g, p.sky.b, p.groundY, p.aim.x, p.aim.y, p.aim.z, p.aoRange], 24);
    u.set([w, h, p.frame, p.aoRays, p.shadowRays, p.interpolated ? 1 : 0, p.show, 0], 32);
    this.device.queue.writeBuffer(this.params, 0, buf);
    const enc = this.device.createCommandEncoder();
    if (this.field) {
      if (!this.bindings) this.makeBindings();
      if (accumulate) {
        const pass = enc.beginComputePass();
        pass.setPipeline(this.computePipelines(this.field.is3d).accumulate);
        pass.setBindGroup(0, this.bindings.field);
        pass.setBindGroup(1, this.bindings.accumulate);
        pass.dispatchWorkgroups(Math.ceil(w / 8), Math.ceil(h / 8));
        pass.end();
      }
    }
    const pass = enc.beginRenderPass({
      colorAttachments: [{ view: this.context.getCurrentTexture().createView(), loadOp: 'clear', storeOp: 'store', clearValue: { r: p.sky.r, g: p.sky.g, b: p.sky.b, a: 1 } }],
    });
    if (this.field) {
      pass.setPipeline(this.shadePipeline);
      pass.setBindGroup(0, this.bindings.shade);
      pass.draw(3);
    }
    pass.end();
    this.device.queue.submit([enc.finish()]);
  }

  /** passes.js's referenceView through WebGPU: size x size grey levels, row 0 at the bottom. */
  async reference(center, radius, size, interpolated) {
    if (!this.field) return null;
    const d = this.device, p = this.computePipelines(this.field.is3d).reference;
    const params = d.createBuffer({ size: 32, usage: GPUBufferUsage.UNIFORM | GPUBufferUsage.COPY_DST });
    const bytes = size * size * 4;
    const out = d.createBuffer({ size: bytes, usage: GPUBufferUsage.STORAGE | GPUBufferUsage.COPY_SRC });
    const read = d.createBuffer({ size: bytes, usage: GPUBufferUsage.MAP_READ | GPUBufferUsage.COPY_DST });
    const buf = new ArrayBuffer(32);
    new Float32Array(buf).set([center.x, center.y, center.z, radius]);
    new Uint32Array(buf).set([size, interpolated ? 1 : 0], 4);
    d.queue.writeBuffer(params, 0, buf);
    const enc = d.createCommandEncoder();
    const pass = enc.beginComputePass();
    pass.setPipeline(p);
    pass.setBindGroup(0, d.createBindGroup({ layout: p.getBindGroupLayout(0), entries: this.field.entries }));
    pass.setBindGroup(1, d.createBindGroup({ layout: p.getBindGroupLayout(1), entries: [{ binding: 2, resource: { buffer: params } }, { binding: 3, resource: { buffer: out } }] }));
    pass.dispatchWorkgroups(Math.ceil(size / 8), Math.ceil(size / 8));
    pass.end();
    enc.copyBufferToBuffer(out, 0, read, 0, bytes);
    d.queue.submit([enc.finish()]);
    await read.mapAsync(GPUMapMode.READ);
    // As the WebGL2 pass's RGBA8 target stores it: round(255 v).
    const levels = Array.from(new Float32Array(read.getMappedRange()), (v) => Math.round(255 * Math.min(Math.max(v, 0), 1)));
    read.unmap();
    for (const b of [params, out, read]) b.destroy();
    return levels;
  }

  /** Resolves once the GPU has done the work submitted so far. */
  done() { return this.device.queue.onSubmittedWorkDone(); }

  dispose() {
    this.setField(null);
    this.accum?.destroy();
    this.params.destroy();
    this.context.unconfigure();
  }
}
