// Assets with VFF_visibility_field as vff-bake writes them (`vff-bake SCENE.gltf -o x.glb`) and as
// the glTF-Transform extension writes them: glTF-Validator finds no error and no warning (its infos
// are only UNSUPPORTED_EXTENSION and UNUSED_OBJECT), and the JavaScript reader matches every field
// exactly; the sample scene of vff-procedural-mesh, and suzanne and spot from the shared meshes.
// glTF-Transform reads vff-bake's .glb and writes it back (draco included) with the payloads intact.
// Needs VFF_BAKE (vff-bake) and VFF_PROCEDURAL_MESH (vff-procedural-mesh); VFF_SHARED_MESHES
// (default ../shared/meshes) for suzanne and spot. Each case skips with the reason otherwise.
import { test, after } from 'node:test';
import assert from 'node:assert/strict';
import { execFileSync, spawnSync } from 'node:child_process';
import { existsSync, mkdtempSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import validator from 'gltf-validator';
import { Document } from '@gltf-transform/core';
import { draco } from '@gltf-transform/functions';
import { readGltfFields } from '../src/gltf_fields.js';
import { openVff } from '../src/vff.js';
import { ROOT, EXT, boxDocument, makeIO, splitGlb } from './gltf_assets.js';

const WORK = mkdtempSync(join(process.env.VFF_WORK ?? tmpdir(), 'vff-gltf-bake-'));
after(() => { if (!process.env.VFF_WORK) rmSync(WORK, { recursive: true, force: true }); });
const BAKE = process.env.VFF_BAKE, MESHGEN = process.env.VFF_PROCEDURAL_MESH;
const SHARED = process.env.VFF_SHARED_MESHES || join(ROOT, '..', 'shared', 'meshes');

/** Bakes `input` to `output` (.glb); vff-bake's complaint, or ''. */
function bakeGlb(input, output, extra = []) {
  const r = spawnSync(BAKE, [input, '-o', output, '-n', '2', '-m', '8', ...extra], { encoding: 'utf8' });
  if (r.status !== 0) return `vff-bake ${input} -o ${output} exited ${r.status}: ${r.stderr.trim().split('\n').pop()}`;
  return '';
}

const sceneSkip = !BAKE || !existsSync(BAKE) ? 'VFF_BAKE is not set to vff-bake'
  : !MESHGEN || !existsSync(MESHGEN) ? 'VFF_PROCEDURAL_MESH is not set to vff-procedural-mesh' : '';
const scene = join(WORK, 's.gltf'), sceneGlb = join(WORK, 's.glb');
let sceneError = '';
if (!sceneSkip) {
  execFileSync(MESHGEN, ['--gltf-scene', scene]);
  sceneError = bakeGlb(scene, sceneGlb);
}
if (sceneSkip) console.log(`SKIP (vff-bake cases): ${sceneSkip}`);

/**
 * glTF-Validator's report: asserts no error and no warning, infos only UNSUPPORTED_EXTENSION (ours)
 * and UNUSED_OBJECT (the payload bufferViews; Draco's, which it cannot decode), and hints only those `input` (the asset baked) has.
 */
async function validate(bytes, name, input = null) {
  const report = await validator.validateBytes(new Uint8Array(bytes), { maxIssues: 0 });
  const { numErrors, numWarnings, messages } = report.issues;
  assert.equal(numErrors, 0, `${name}: ${JSON.stringify(messages.filter((m) => m.severity === 0))}`);
  assert.equal(numWarnings, 0, `${name}: ${JSON.stringify(messages.filter((m) => m.severity === 1))}`);
  const infos = messages.filter((m) => m.severity === 2);
  for (const m of infos) assert.ok(['UNSUPPORTED_EXTENSION', 'UNUSED_OBJECT'].includes(m.code), `${name}: ${m.code}`);
  assert.ok(infos.some((m) => m.code === 'UNSUPPORTED_EXTENSION' && m.message.includes(EXT)), name);
  const { json } = splitGlb(new Uint8Array(bytes));
  // Unused to the validator: the payloads, and Draco's data (it does not know KHR_draco_mesh_compression).
  const unused = new Set((json.meshes ?? []).flatMap((m) => [m.extensions?.[EXT]?.bufferView,
    ...(m.primitives ?? []).map((p) => p.extensions?.KHR_draco_mesh_compression?.bufferView)]).filter((v) => v !== undefined));
  const payloadViews = (json.meshes ?? []).map((m) => m.extensions?.[EXT]?.bufferView).filter((v) => v !== undefined);
  const reported = infos.filter((m) => m.code === 'UNUSED_OBJECT').map((m) => m.pointer);
  for (const v of payloadViews) assert.ok(reported.includes(`/bufferViews/${v}`), `${name}: payload bufferView ${v}`);
  for (const p of reported) assert.ok(unused.has(Number(p.replace('/bufferViews/', ''))), `${name}: ${p} unused`);
  const hints = messages.filter((m) => m.severity === 3).map((m) => [m.code, m.pointer]);
  const inputHints = input ? (await validator.validateBytes(new Uint8Array(readFileSync(input)), { maxIssues: 0, externalResourceFunction: (uri) => Promise.resolve(new Uint8Array(readFileSync(join(WORK, decodeURIComponent(uri))))) }))
    .issues.messages.filter((m) => m.severity === 3).map((m) => [m.code, m.pointer]) : [];
  const known = new Set(inputHints.map((h) => h.join(' ')));
  for (const h of hints) assert.ok(known.has(h.join(' ')), `${name}: hint ${h} is not one of the input's`);
  return report;
}

test('glTF-Validator: an asset the glTF-Transform extension writes has no error or warning', async () => {
  const glb = await (await makeIO()).writeBinary(boxDocument({ meshes: 2 }));
  const report = await validate(glb, 'boxes.glb');
  assert.deepEqual(report.issues.messages.map((m) => m.code), ['UNSUPPORTED_EXTENSION', 'UNUSED_OBJECT', 'UNUSED_OBJECT']);
});

test('vff-bake SCENE.gltf -o x.glb: valid for glTF-Validator, every field exact and as --split mesh bakes it', { skip: sceneSkip || false }, async () => {
  assert.equal(sceneError, '');
  const glb = new Uint8Array(readFileSync(sceneGlb));
  const report = await validate(glb, 's.glb', scene);
  console.log(`s.glb: ${glb.length} bytes, validator: ${report.issues.numInfos} infos, ${report.issues.numHints} hints (the input's): ${[...new Set(report.issues.messages.map((m) => m.code))].join(', ')}`);
  const r = await readGltfFields(glb);
  // The main scene uses the box (twice, similarities) and the knot (a stretched node: 14104).
  assert.deepEqual(r.problems.map((p) => [p.rule, p.path]), [[14104, '/nodes/3']]);
  assert.deepEqual(r.fields.map((f) => [f.mesh, f.meshName, f.match, f.usable]), [[0, 'box', 'exact', true], [1, 'knot', 'exact', true]]);
  assert.deepEqual(r.fields[0].nodes.map((n) => [n.name, n.answered]), [['boxA', true], ['boxB', true]]);
  const { json } = splitGlb(glb);
  assert.deepEqual(json.extensionsUsed, [EXT]);
  assert.equal(json.extensionsRequired, undefined);
  for (const f of r.fields) {
    const bv = json.bufferViews[f.bufferView];
    assert.equal((glbBinOffset(glb) + (bv.byteOffset ?? 0)) % 64, 0, 'the payload starts at a multiple of 64 bytes in the file');
    assert.equal(openVff(f.bytes).metadata.value['vff.source'].geometryHash, f.geometryHash);
  }
  // The box's payload is the file --split mesh writes for mesh 0 (its own frame there too).
  execFileSync(BAKE, [scene, '--split', 'mesh', '-o', join(WORK, 'split.vffscene.json'), '-n', '2', '-m', '8'], { stdio: 'ignore' });
  assert.deepEqual(Buffer.from(r.fields[0].bytes), readFileSync(join(WORK, 'split.mesh0.vff')));
});

/** The file offset of a GLB's binary chunk data. */
function glbBinOffset(glb) {
  const jsonLength = new DataView(glb.buffer, glb.byteOffset).getUint32(12, true);
  return 20 + jsonLength + 8;
}

test('glTF-Transform reads vff-bake\'s .glb and writes it back: payloads intact, also after draco', { skip: sceneSkip || false }, async () => {
  assert.equal(sceneError, '');
  const glb = new Uint8Array(readFileSync(sceneGlb));
  const before = await readGltfFields(glb);
  const io = await makeIO();
  const doc = await io.readBinary(glb);
  const out = await io.writeBinary(doc);
  const after = await readGltfFields(out);
  assert.deepEqual(after.fields.map((f) => [f.mesh, f.match, Buffer.from(f.bytes).equals(Buffer.from(before.fields[f.mesh === 0 ? 0 : 1].bytes))]),
    [[0, 'exact', true], [1, 'exact', true]]);
  await validate(out, 'round trip', scene);
  await doc.transform(draco());
  const compressed = await io.writeBinary(doc);
  await validate(compressed, 'draco');
  const { decodedGeometryFrom } = await import('../src/gltf_transform_vff.js');
  const r = await readGltfFields(compressed, { decodedGeometry: decodedGeometryFrom(await io.readBinary(compressed)) });
  assert.ok(r.fields.every((f) => f.usable && ['exact', 'close'].includes(f.match)), JSON.stringify(r.problems));
  console.log(`draco: ${r.fields.map((f) => `${f.meshName} ${f.match} (bounds ${f.boundsDifference.toExponential(2)}, tau ${f.tolerance.toExponential(2)})`).join(', ')}; ${glb.length} -> ${compressed.length} bytes`);
});

/** A .glb of the triangles of an OBJ file (v and f lines; polygons fanned), one mesh, one node. */
async function objToGlb(objPath, name) {
  const pos = [], idx = [];
  for (const line of readFileSync(objPath, 'utf8').split('\n')) {
    const t = line.trim().split(/\s+/);
    if (t[0] === 'v') pos.push(+t[1], +t[2], +t[3]);
    else if (t[0] === 'f') {
      const f = t.slice(1).map((s) => { const i = parseInt(s, 10); return i < 0 ? pos.length / 3 + i : i - 1; });
      for (let k = 1; k + 1 < f.length; ++k) idx.push(f[0], f[k], f[k + 1]);
    }
  }
  const doc = new Document();
  const buffer = doc.createBuffer();
  const prim = doc.createPrimitive()
    .setAttribute('POSITION', doc.createAccessor().setType('VEC3').setArray(new Float32Array(pos)).setBuffer(buffer))
    .setIndices(doc.createAccessor().setType('SCALAR').setArray(new Uint32Array(idx)).setBuffer(buffer));
  const node = doc.createNode(name).setMesh(doc.createMesh(name).addPrimitive(prim));
  doc.createScene().addChild(node);
  return (await makeIO({ vff: false })).writeBinary(doc);
}

const meshesSkip = sceneSkip || (!['suzanne.obj', 'spot.obj'].every((m) => existsSync(join(SHARED, m))) ? `no suzanne.obj and spot.obj in ${SHARED}` : '');
test('vff-bake on suzanne and spot as .glb: valid for glTF-Validator, fields exact', { skip: meshesSkip || false }, async () => {
  for (const name of ['suzanne', 'spot']) {
    const input = join(WORK, `${name}.in.glb`), output = join(WORK, `${name}.glb`);
    writeFileSync(input, await objToGlb(join(SHARED, `${name}.obj`), name));
    const why = bakeGlb(input, output);
    assert.equal(why, '');
    const glb = new Uint8Array(readFileSync(output));
    await validate(glb, `${name}.glb`);
    const r = await readGltfFields(glb);
    assert.deepEqual(r.problems, [], name);
    assert.deepEqual(r.fields.map((f) => [f.meshName, f.match]), [[name, 'exact']]);
    console.log(`${name}: ${glb.length} bytes, field ${r.fields[0].bytes.length} bytes, geometryHash ${r.fields[0].geometryHash}`);
  }
});
