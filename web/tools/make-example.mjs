// make-example.mjs - the example scene's asset (web/examples/contact-shadows): a floor and four
// objects as a glTF, baked by vff-bake into a .glb with a field on every mesh.
//
//   node tools/make-example.mjs [--meshes DIR] [--bake VFF_BAKE] [--procedural VFF_PROCEDURAL_MESH]
//                               [--out DIR] [-n N] [-m M]
//
// The objects are suzanne, spot, teapot and cow from DIR (default: $VFF_SHARED_MESHES, else
// ../shared/meshes beside the repository). Where DIR lacks them the objects are the shapes of
// vff-procedural-mesh (torus-knot, sphere, box, bowl), and it says so on stderr. Each object is
// rescaled to about one unit, its lowest point at y = 0 and its footprint centred on the origin, so the
// page places it on the floor by its x and z alone. The glTF goes to OUT/scene.gltf (+ .bin),
// the baked asset to OUT/example.glb (default OUT: examples/contact-shadows/assets). The default
// bake, -n 16 -m 32, is the smallest of those measured whose floor matches the exact reference
// within web.example.browser_reference's bound; -n 8 loads faster and misses it.
// Same inputs, same bytes: the glTF is written in a fixed order and vff-bake is deterministic.
// Exit codes: 0 written, 1 usage, 2 a file cannot be read or written, 4 vff-bake failed.
import { readFileSync, writeFileSync, mkdirSync, existsSync, mkdtempSync, rmSync, renameSync } from 'node:fs';
import { join, dirname, resolve } from 'node:path';
import { tmpdir } from 'node:os';
import { execFileSync } from 'node:child_process';
import { fileURLToPath } from 'node:url';
import { Document, NodeIO } from '@gltf-transform/core';

const WEB = fileURLToPath(new URL('../', import.meta.url));
const ROOT = resolve(WEB, '..');
const prog = 'make-example.mjs';

function usage(code = 1) {
  (code ? console.error : console.log)(`usage: node tools/${prog} [--meshes DIR] [--bake VFF_BAKE] ` +
    '[--procedural VFF_PROCEDURAL_MESH] [--out DIR] [-n N] [-m M]');
  process.exit(code);
}

const opt = {
  meshes: process.env.VFF_SHARED_MESHES || resolve(ROOT, '..', 'shared', 'meshes'),
  bake: process.env.VFF_BAKE || join(ROOT, 'build', 'tools', 'vff-bake', 'vff-bake'),
  procedural: process.env.VFF_PROCEDURAL_MESH || join(ROOT, 'build', 'samples', 'vff-procedural-mesh'),
  out: join(WEB, 'examples', 'contact-shadows', 'assets'),
  n: '16', m: '32',
};
const args = process.argv.slice(2);
for (let i = 0; i < args.length; ++i) {
  const a = args[i];
  const key = { '--meshes': 'meshes', '--bake': 'bake', '--procedural': 'procedural', '--out': 'out', '-n': 'n', '-m': 'm' }[a];
  if (a === '-h' || a === '--help') usage(0);
  if (!key || i + 1 >= args.length) usage();
  opt[key] = args[++i];
}
if (!/^[1-9]\d*$/.test(opt.n) || !/^[1-9]\d*$/.test(opt.m)) usage();

function die(code, message) {
  console.error(`${prog}: error: ${message}`);
  process.exit(code);
}

/** Positions and triangle indices of an OBJ (polygons as fans; texture and normal indices dropped). */
function readObj(path) {
  let text;
  try { text = readFileSync(path, 'utf8'); } catch (e) { die(2, `${path}: cannot read: ${e.message}`); }
  const v = [], idx = [];
  const lines = text.split('\n');
  for (let ln = 0; ln < lines.length; ++ln) {
    const t = lines[ln].trim().split(/\s+/);
    if (t[0] === 'v') {
      const p = t.slice(1, 4).map(Number);
      if (p.length < 3 || p.some((x) => !Number.isFinite(x))) die(2, `${path}:${ln + 1}: a vertex needs three numbers`);
      v.push(...p);
    } else if (t[0] === 'f') {
      const count = v.length / 3;
      const f = t.slice(1).map((s) => {
        const k = parseInt(s, 10);
        return k < 0 ? count + k : k - 1;
      });
      if (f.length < 3 || f.some((k) => !(k >= 0 && k < count))) die(2, `${path}:${ln + 1}: a face names a vertex that does not exist`);
      for (let j = 1; j + 1 < f.length; ++j) idx.push(f[0], f[j], f[j + 1]);
    }
  }
  if (!idx.length) die(2, `${path}: no faces`);
  return { positions: new Float32Array(v), indices: new Uint32Array(idx) };
}

/** Rescaled so the larger of width and depth is `size`, footprint centred, lowest point at y = 0. */
function standOnFloor(mesh, size) {
  const p = mesh.positions;
  const lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
  for (let i = 0; i < p.length; i += 3) for (let k = 0; k < 3; ++k) { lo[k] = Math.min(lo[k], p[i + k]); hi[k] = Math.max(hi[k], p[i + k]); }
  const s = size / Math.max(hi[0] - lo[0], hi[2] - lo[2]);
  const c = [(lo[0] + hi[0]) / 2, lo[1], (lo[2] + hi[2]) / 2];
  const out = new Float32Array(p.length);
  for (let i = 0; i < p.length; i += 3) for (let k = 0; k < 3; ++k) out[i + k] = (p[i + k] - c[k]) * s;
  return { positions: out, indices: mesh.indices };
}

/** Area-weighted vertex normals, so that the objects shade smoothly. */
function vertexNormals({ positions: p, indices }) {
  const n = new Float32Array(p.length);
  for (let t = 0; t < indices.length; t += 3) {
    const [a, b, c] = [indices[t] * 3, indices[t + 1] * 3, indices[t + 2] * 3];
    const e1 = [p[b] - p[a], p[b + 1] - p[a + 1], p[b + 2] - p[a + 2]];
    const e2 = [p[c] - p[a], p[c + 1] - p[a + 1], p[c + 2] - p[a + 2]];
    const x = e1[1] * e2[2] - e1[2] * e2[1], y = e1[2] * e2[0] - e1[0] * e2[2], z = e1[0] * e2[1] - e1[1] * e2[0];
    for (const v of [a, b, c]) { n[v] += x; n[v + 1] += y; n[v + 2] += z; }
  }
  for (let i = 0; i < n.length; i += 3) {
    const l = Math.hypot(n[i], n[i + 1], n[i + 2]) || 1;
    n[i] /= l; n[i + 1] /= l; n[i + 2] /= l;
    if (l === 1 && n[i] === 0 && n[i + 1] === 0 && n[i + 2] === 0) n[i + 1] = 1;
  }
  return n;
}

// The objects: a shared mesh each, or a procedural shape where the shared meshes are absent.
// size: footprint in scene units (the floor is FLOOR units wide); colour: linear base colour.
const FLOOR = 10;
const OBJECTS = [
  { name: 'suzanne', shape: 'torus-knot', size: 1.1, color: [0.80, 0.32, 0.18] },
  { name: 'spot', shape: 'sphere', size: 1.0, color: [0.85, 0.75, 0.35] },
  { name: 'teapot', shape: 'box', size: 1.3, color: [0.25, 0.45, 0.75] },
  { name: 'cow', shape: 'bowl', size: 1.4, color: [0.45, 0.60, 0.35] },
];

const work = mkdtempSync(join(tmpdir(), 'vff-example-'));
try {
  const shared = OBJECTS.every((o) => existsSync(join(opt.meshes, `${o.name}.obj`)));
  if (!shared) {
    console.error(`${prog}: ${opt.meshes} lacks ${OBJECTS.map((o) => o.name + '.obj').join(', ')}: ` +
      'using the shapes of vff-procedural-mesh instead');
    if (!existsSync(opt.procedural)) die(2, `${opt.procedural}: vff-procedural-mesh is not built (--procedural)`);
  }
  if (!existsSync(opt.bake)) die(2, `${opt.bake}: vff-bake is not built (--bake)`);

  const doc = new Document();
  const buffer = doc.createBuffer('scene');
  const scene = doc.createScene('example');
  const addMesh = (name, geom, color, roughness) => {
    const prim = doc.createPrimitive()
      .setAttribute('POSITION', doc.createAccessor(`${name}-positions`).setType('VEC3').setArray(geom.positions).setBuffer(buffer))
      .setAttribute('NORMAL', doc.createAccessor(`${name}-normals`).setType('VEC3').setArray(vertexNormals(geom)).setBuffer(buffer))
      .setIndices(doc.createAccessor(`${name}-indices`).setType('SCALAR').setArray(geom.indices).setBuffer(buffer))
      .setMaterial(doc.createMaterial(name).setBaseColorFactor([...color, 1]).setRoughnessFactor(roughness).setMetallicFactor(0));
    return doc.createMesh(name).addPrimitive(prim);
  };

  // The floor: a square of two triangles at y = 0, facing up.
  const h = FLOOR / 2;
  const floor = {
    positions: new Float32Array([-h, 0, -h, -h, 0, h, h, 0, h, h, 0, -h]),
    indices: new Uint32Array([0, 1, 2, 0, 2, 3]),
  };
  scene.addChild(doc.createNode('floor').setMesh(addMesh('floor', floor, [0.50, 0.50, 0.48], 0.9)));

  OBJECTS.forEach((o, i) => {
    let path = join(opt.meshes, `${o.name}.obj`);
    if (!shared) {
      path = join(work, `${o.shape}.obj`);
      execFileSync(opt.procedural, [o.shape, path], { stdio: 'ignore' });
    }
    const name = shared ? o.name : o.shape;
    const geom = standOnFloor(readObj(path), o.size);
    // Start places on a circle; the page moves them from there.
    const a = (i / OBJECTS.length) * 2 * Math.PI;
    scene.addChild(doc.createNode(name).setMesh(addMesh(name, geom, o.color, 0.6))
      .setTranslation([1.8 * Math.cos(a), 0, 1.8 * Math.sin(a)]));
  });

  const gltf = join(work, 'scene.gltf');
  await new NodeIO().write(gltf, doc);
  const glb = join(work, 'example.glb');
  try {
    execFileSync(opt.bake, [gltf, '-o', glb, '-n', opt.n, '-m', opt.m, '-q'], { stdio: ['ignore', 'ignore', 'pipe'] });
  } catch (e) {
    die(4, `vff-bake failed: ${String(e.stderr ?? e.message).trim()}`);
  }
  // Written only when everything above succeeded, each file by a rename.
  try {
    mkdirSync(opt.out, { recursive: true });
    for (const f of ['scene.gltf', 'scene.bin', 'example.glb']) {
      writeFileSync(join(opt.out, `.${f}.tmp`), readFileSync(join(work, f)));
      renameSync(join(opt.out, `.${f}.tmp`), join(opt.out, f));
    }
  } catch (e) {
    die(2, `${opt.out}: cannot write: ${e.message}`);
  }
  console.log(`wrote ${join(opt.out, 'example.glb')} (${readFileSync(join(opt.out, 'example.glb')).length} bytes; ` +
    `${shared ? 'shared meshes' : 'procedural shapes'}; -n ${opt.n} -m ${opt.m})`);
} finally {
  rmSync(work, { recursive: true, force: true });
}
