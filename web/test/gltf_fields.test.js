// web/src/gltf_fields.js, the JavaScript reader of VFF_visibility_field: every asset of
// spec/conformance/gltf against its manifest.json (problems in order, fields), and assets made here
// with glTF-Transform for each rule, the geometry match (exact, close, mismatch), quantized
// positions, strips and fans, uri and data: payloads, and the nodes no field answers for.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFileSync, existsSync } from 'node:fs';
import { join, dirname } from 'node:path';
import { KHRMeshQuantization } from '@gltf-transform/extensions';
import { readGltfFields, formatGltfProblem, canonicalGeometryHash } from '../src/gltf_fields.js';
import { xxh3Hex } from '../src/vff.js';
import { ROOT, EXT, vectorPayload, boxDocument, makeIO, editGlb, splitGlb, packGlb, attachField } from './gltf_assets.js';

const CONFORMANCE = process.env.VFF_GLTF_CONFORMANCE || join(ROOT, 'spec', 'conformance', 'gltf');  // or a generated copy
const MANIFEST = join(CONFORMANCE, 'manifest.json');
const near = (a, b) => Math.abs(a - b) <= 1e-9 * Math.max(1, Math.abs(b));

const rules = (r) => r.problems.map((p) => [p.rule, p.severity, p.path]);
const ext = (m = 0) => `/meshes/${m}/extensions/${EXT}`;

test('every conformance asset reads as its manifest says', { skip: existsSync(MANIFEST) ? false : `no ${MANIFEST} (the glTF conformance assets are not generated)` }, async () => {
  const manifest = JSON.parse(readFileSync(MANIFEST, 'utf8'));
  let checked = 0;
  for (const [file, want] of Object.entries(manifest.assets)) {
    const path = join(CONFORMANCE, file);
    const resolveUri = (p) => { const f = join(dirname(path), p); return existsSync(f) ? new Uint8Array(readFileSync(f)) : null; };
    const r = await readGltfFields(new Uint8Array(readFileSync(path)), { resolveUri });
    const shown = (p) => ({ rule: p.rule, name: p.name, severity: p.severity, path: p.path, ioError: p.ioError === true });
    assert.deepEqual(r.problems.map(shown), want.problems.map(shown), `${file}: problems ${JSON.stringify(r.problems)}`);
    if (want.meshes !== undefined) assert.equal(r.meshCount, want.meshes, `${file}: meshes`);
    assert.equal(r.fields.length, want.fields.length, `${file}: fields`);
    want.fields.forEach((wf, i) => {
      const f = r.fields[i];
      assert.equal(f.mesh, wf.mesh, `${file}: field ${i} mesh`);
      assert.equal(f.valid, wf.valid, `${file}: field ${i} valid`);
      assert.equal(f.usable, wf.usable, `${file}: usable`);
      assert.equal(f.match, wf.match, `${file}: match`);
      if (!wf.valid) return;
      assert.equal(f.meshName, wf.name, `${file}: name`);
      assert.equal(f.bufferView >= 0 ? 'bufferView' : 'uri', wf.source, `${file}: source`);
      assert.equal(f.geometryHash, wf.geometryHash, `${file}: geometryHash`);
      assert.equal(f.meshGeometryHash, wf.meshGeometryHash, `${file}: meshGeometryHash`);
      assert.equal(f.bytes.length, wf.bytes, `${file}: bytes`);
      assert.equal(xxh3Hex(f.bytes), wf.xxh3, `${file}: payload xxh3`);
      if (wf.tolerance !== undefined) assert.ok(near(f.tolerance, wf.tolerance), `${file}: tolerance ${f.tolerance} vs ${wf.tolerance}`);
      if (wf.boundsDifference !== undefined) assert.ok(near(f.boundsDifference, wf.boundsDifference), `${file}: boundsDifference`);
      assert.deepEqual(f.nodes.map((n) => ({ node: n.node, answered: n.answered })), wf.nodes, `${file}: nodes`);
    });
    ++checked;
  }
  console.log(`${checked} conformance assets read as the manifest says`);
  assert.ok(checked >= 20);
});

test('a field attached with glTF-Transform: exact, payload bytes unchanged, formatted problems', async () => {
  const { bytes: payload } = vectorPayload();
  const io = await makeIO();
  const glb = await io.writeBinary(boxDocument({ meshes: 2, payload }));
  const r = await readGltfFields(glb);
  assert.deepEqual(r.problems, []);
  assert.equal(r.meshCount, 2);
  assert.deepEqual(r.fields.map((f) => [f.mesh, f.meshName, f.match, f.usable, f.valid]), [[0, 'box0', 'exact', true, true], [1, 'box1', 'exact', true, true]]);
  assert.deepEqual([...r.fields[0].bytes], [...payload]);
  assert.equal(r.fields[0].meshGeometryHash, r.fields[0].geometryHash);
  assert.deepEqual(r.fields[1].meshMin, [0.5, -0.30000001192092896, -0.20000000298023224]);
  assert.deepEqual(r.fields[0].nodes, [{ node: 0, name: 'box0', answered: true, reason: '' }]);
  assert.equal(formatGltfProblem('a.glb', { rule: 14006, name: 'gltf-buffer-view', path: '/x', message: 'm' }), 'a.glb: /x: gltf-buffer-view (14006): m');
  assert.equal(formatGltfProblem('a.glb', { rule: 14001, name: 'gltf-container', path: '', message: 'm' }), 'a.glb: gltf-container (14001): m');
});

test('the canonical hash ignores vertex order, sharing, triangle order and rotation; not winding', async () => {
  await readGltfFields(new Uint8Array(0));  // loads the hasher
  const p = new Float32Array([0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1]);
  const h = canonicalGeometryHash(p, new Uint32Array([0, 1, 2, 0, 2, 3]));
  assert.equal(canonicalGeometryHash(p, new Uint32Array([2, 3, 0, 1, 2, 0])), h);
  const unshared = new Float32Array([0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0]);
  assert.equal(canonicalGeometryHash(unshared, new Uint32Array([0, 1, 2, 3, 4, 5])).length, 16);
  assert.equal(canonicalGeometryHash(unshared, new Uint32Array([1, 5, 3, 4, 3, 0])), canonicalGeometryHash(p, new Uint32Array([0, 1, 2, 0, 2, 3])));
  assert.notEqual(canonicalGeometryHash(p, new Uint32Array([0, 2, 1, 0, 2, 3])), h);
  const negZero = new Float32Array([-0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1]);
  assert.equal(canonicalGeometryHash(negZero, new Uint32Array([0, 1, 2, 0, 2, 3])), h);
});

test('close within tau = 2R/255 (note 14102), mismatch beyond (warning 14103)', async () => {
  const { bytes: payload, radius } = vectorPayload();
  const tau = (2 * radius) / 255;
  const io = await makeIO();
  // The asset is written exact, then its +x face moved out in the binary chunk (glTF-Transform's
  // writer would drop a mismatched field).
  const glb = await io.writeBinary(boxDocument({ payload }));
  for (const [steps, rule, match] of [[0.25, 14102, 'close'], [3, 14103, 'mismatch']]) {
    const moved = editGlb(glb, (json, bin) => {
      const a = json.accessors[json.meshes[0].primitives[0].attributes.POSITION];
      const v = json.bufferViews[a.bufferView];
      const dv = new DataView(bin.buffer, bin.byteOffset);
      for (let i = 0; i < a.count; ++i) {
        const at = (v.byteOffset ?? 0) + (a.byteOffset ?? 0) + i * (v.byteStride ?? 12);
        if (dv.getFloat32(at, true) > 0) dv.setFloat32(at, dv.getFloat32(at, true) + steps * tau, true);
      }
    });
    const r = await readGltfFields(moved);
    assert.deepEqual(rules(r), [[rule, rule === 14102 ? 'note' : 'warning', ext()]]);
    const f = r.fields[0];
    assert.equal(f.match, match);
    assert.equal(f.usable, match === 'close');
    assert.ok(near(f.tolerance, tau));
    assert.ok(Math.abs(f.boundsDifference - steps * tau) < 1e-6, `${f.boundsDifference} vs ${steps * tau}`);
    assert.match(r.problems[0].message, /tau = 2R\/255/);
  }
});

test('KHR_mesh_quantization positions (normalized or not) are read as glTF converts them', async () => {
  const { bytes: payload } = vectorPayload();
  const io = await makeIO();
  for (const [Type, normalized] of [[Int16Array, true], [Uint16Array, true], [Int8Array, true], [Uint8Array, true], [Int16Array, false], [Uint8Array, false]]) {
    const doc = boxDocument({ payload, fields: false });
    doc.createExtension(KHRMeshQuantization).setRequired(true);
    const mesh = doc.getRoot().listMeshes()[0];
    const pos = mesh.listPrimitives()[0].getAttribute('POSITION');
    const f = pos.getArray();
    const max = normalized ? { Int16Array: 32767, Uint16Array: 65535, Int8Array: 127, Uint8Array: 255 }[Type.name] : 1;
    const signed = Type === Int16Array || Type === Int8Array;
    // Unsigned types hold the box shifted into [0, 1] (normalized) or scaled integers.
    const q = Type.from(f, (x) => Math.round(normalized ? (signed ? x : x + 0.5) * max : (signed ? x * 100 : x * 100 + 60)));
    pos.setArray(q).setNormalized(normalized);
    attachField(doc, mesh, payload);
    const glb = await io.writeBinary(doc);
    assert.equal(splitGlb(glb).json.accessors[0].componentType, { Int16Array: 5122, Uint16Array: 5123, Int8Array: 5120, Uint8Array: 5121 }[Type.name]);
    const r = await readGltfFields(glb);
    assert.deepEqual(rules(r), [], `${Type.name} normalized ${normalized}`);
    assert.equal(r.fields[0].match, 'exact', `${Type.name} normalized ${normalized}`);
    // The bounds are the dequantized values as f32 (c / max, at least -1).
    const lo = Math.min(...q.filter((_, i) => i % 3 === 0));
    assert.equal(r.fields[0].meshMin[0], Math.fround(normalized ? Math.max(lo / max, -1) : lo));
  }
});

test('strips and fans give the triangles the importer reads', async () => {
  const { bytes: payload } = vectorPayload();
  const io = await makeIO();
  // A quad as TRIANGLES, as a strip (0 1 2, then 2 1 3 reversed to keep the winding) and as a fan.
  const quad = new Float32Array([0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0.5]);
  const hashes = [];
  for (const [mode, idx] of [[4, [0, 1, 2, 2, 1, 3]], [5, [0, 1, 2, 3]], [6, [0, 1, 3, 2]]]) {
    const doc = boxDocument({ payload, fields: false });
    const mesh = doc.getRoot().listMeshes()[0];
    const prim = mesh.listPrimitives()[0];
    prim.getAttribute('POSITION').setArray(quad.slice());
    prim.getIndices().setArray(new Uint16Array(idx));
    prim.setMode(mode);
    attachField(doc, mesh, payload);
    const r = await readGltfFields(await io.writeBinary(doc));
    assert.equal(r.fields[0].match, 'exact');
    hashes.push(r.fields[0].meshGeometryHash);
  }
  assert.equal(hashes[1], hashes[0], 'the strip');
  assert.notEqual(hashes[2], hashes[0], 'the fan has the other diagonal');
  // Points and lines beside a triangle primitive are skipped; alone they leave nothing (14011).
  const doc = boxDocument({ payload });
  const mesh = doc.getRoot().listMeshes()[0];
  const prim = mesh.listPrimitives()[0];
  mesh.addPrimitive(prim.clone().setMode(1));
  const r = await readGltfFields(await io.writeBinary(doc));
  assert.deepEqual(rules(r), []);
  assert.equal(r.fields[0].match, 'exact');
  const r2 = await readGltfFields(editGlb(await io.writeBinary(doc), (json) => { for (const p of json.meshes[0].primitives) p.mode = 0; }));
  assert.deepEqual(rules(r2), [[14011, 'error', '/meshes/0']]);
});

test('payloads by uri (relative, percent-decoded, resolved by the caller) and by data: uri', async () => {
  const { bytes: payload } = vectorPayload();
  const io = await makeIO();
  const glb = await io.writeBinary(boxDocument({ payload }));
  const asUri = (uri, mime) => editGlb(glb, (json) => {
    const e = json.meshes[0].extensions[EXT];
    delete e.bufferView;
    if (mime === undefined) delete e.mimeType; else e.mimeType = mime;
    e.uri = uri;
  });
  const asked = [];
  const resolveUri = (p) => { asked.push(p); return p === 'fields/box 0.vff' ? payload : null; };
  let r = await readGltfFields(asUri('fields/box%200.vff'), { resolveUri });
  assert.deepEqual(rules(r), []);
  assert.deepEqual(asked, ['fields/box 0.vff']);
  assert.equal(r.fields[0].uri, 'fields/box%200.vff');
  assert.deepEqual([...r.fields[0].bytes], [...payload]);
  r = await readGltfFields(asUri(`data:application/vnd.vff;base64,${Buffer.from(payload).toString('base64')}`, 'application/vnd.vff'));
  assert.deepEqual(rules(r), []);
  assert.equal(r.fields[0].match, 'exact');
  // A file that cannot be read: 14007, an I/O error.
  r = await readGltfFields(asUri('missing.vff'), { resolveUri });
  assert.deepEqual(rules(r), [[14007, 'error', `${ext()}/uri`]]);
  assert.equal(r.problems[0].ioError, true);
  for (const bad of ['/abs.vff', 'https://x/a.vff', '//host/a.vff', 'a.vff?x', 'a.vff#x', 'a\\b.vff', 'a%G0.vff', 'a%00.vff', 'data:application/vnd.vff,VFF', 'data:;base64,@@@@']) {
    r = await readGltfFields(asUri(bad), { resolveUri });
    assert.deepEqual(rules(r), [[14007, 'error', `${ext()}/uri`]], bad);
    assert.ok(!r.problems[0].ioError, bad);
  }
});

test('every rule 14001-14011 at its JSON pointer; each mesh stops at its first error, the next is checked', async () => {
  const { bytes: payload } = vectorPayload();
  const io = await makeIO();
  const glb = await io.writeBinary(boxDocument({ meshes: 2, payload }));
  const e0 = (json) => json.meshes[0].extensions[EXT];
  const cases = [
    ['bad magic', () => { const b = glb.slice(); b[0] = 0; return b; }, [[14001, 'error', '']]],
    ['GLB length', () => glb.slice(0, glb.length - 4), [[14001, 'error', '']]],
    ['JSON text', () => new TextEncoder().encode('{"asset": '), [[14001, 'error', '']]],
    ['asset.version', () => editGlb(glb, (j) => { j.asset.version = '1.0'; }), [[14001, 'error', '/asset/version']]],
    ['required', () => editGlb(glb, (j) => { j.extensionsRequired = [EXT]; }), [[14002, 'error', '/extensionsRequired']]],
    ['not used', () => editGlb(glb, (j) => { delete j.extensionsUsed; }), [[14003, 'error', '/extensionsUsed']]],
    ['not an object', () => editGlb(glb, (j) => { j.meshes[0].extensions[EXT] = [1]; }), [[14004, 'error', ext()]]],
    ['bufferView type', () => editGlb(glb, (j) => { e0(j).bufferView = '0'; }), [[14004, 'error', `${ext()}/bufferView`]]],
    ['bufferView negative', () => editGlb(glb, (j) => { e0(j).bufferView = -1; }), [[14004, 'error', `${ext()}/bufferView`]]],
    ['uri type', () => editGlb(glb, (j) => { e0(j).uri = 7; }), [[14004, 'error', `${ext()}/uri`]]],
    ['hash upper case', () => editGlb(glb, (j) => { e0(j).geometryHash = e0(j).geometryHash.toUpperCase().replace(/^./, 'A'); }), [[14004, 'error', `${ext()}/geometryHash`]]],
    ['hash missing', () => editGlb(glb, (j) => { delete e0(j).geometryHash; }), [[14004, 'error', `${ext()}/geometryHash`]]],
    ['min two numbers', () => editGlb(glb, (j) => { e0(j).min = [0, 0]; }), [[14004, 'error', `${ext()}/min`]]],
    ['max not finite', () => editGlb(glb, (j) => { e0(j).max = [1, 1, 1e39]; }), [[14004, 'error', `${ext()}/max`]]],
    ['min above max', () => editGlb(glb, (j) => { e0(j).min = [2, 0, 0]; }), [[14004, 'error', `${ext()}/min`]]],
    ['both sources', () => editGlb(glb, (j) => { e0(j).uri = 'a.vff'; }), [[14005, 'error', ext()]]],
    ['no source', () => editGlb(glb, (j) => { delete e0(j).bufferView; }), [[14005, 'error', ext()]]],
    ['no such bufferView', () => editGlb(glb, (j) => { e0(j).bufferView = 99; }), [[14006, 'error', `${ext()}/bufferView`]]],
    ['byteStride', () => editGlb(glb, (j) => { j.bufferViews[e0(j).bufferView].byteStride = 4; }), [[14006, 'error', `${ext()}/bufferView`]]],
    ['outside its buffer', () => editGlb(glb, (j) => { j.bufferViews[e0(j).bufferView].byteOffset = 1e6; }), [[14006, 'error', `${ext()}/bufferView`]]],
    ['no BIN chunk', () => { const { json } = splitGlb(glb); return packGlb(json, null); }, [[14006, 'error', `${ext()}/bufferView`], [14006, 'error', `${ext(1)}/bufferView`]]],
    ['mimeType missing', () => editGlb(glb, (j) => { delete e0(j).mimeType; }), [[14008, 'error', ext()]]],
    ['mimeType wrong', () => editGlb(glb, (j) => { e0(j).mimeType = 'application/octet-stream'; }), [[14008, 'error', `${ext()}/mimeType`]]],
    ['payload checksum', () => editGlb(glb, (j, bin) => { const v = j.bufferViews[e0(j).bufferView]; const b = bin.slice(); b[v.byteOffset + 64 * 64 + 8] ^= 1; return b; }), [[14009, 'error', ext()]]],
    ['lines only', () => editGlb(glb, (j) => { j.meshes[0].primitives[0].mode = 1; }), [[14011, 'error', '/meshes/0']]],
    ['draco without a decoder', () => editGlb(glb, (j) => { j.meshes[0].primitives[0].extensions = { KHR_draco_mesh_compression: { bufferView: 0, attributes: { POSITION: 0 } } }; }), [[14011, 'error', '/meshes/0']]],
  ];
  for (const [name, make, want] of cases) {
    const r = await readGltfFields(make());
    assert.deepEqual(rules(r), want, `${name}: ${JSON.stringify(r.problems)}`);
    for (const p of r.problems) assert.ok(p.message.length > 0, name);
    if (want[0][0] <= 14003) {
      assert.deepEqual(r.fields, [], name);
    } else {
      assert.deepEqual(r.fields.map((f) => f.valid), want.length === 2 ? [false, false] : [false, true], name);
      assert.equal(r.fields[0].usable, false, name);
      assert.equal(r.fields[0].bytes, null, name);
    }
  }
  const bad = await readGltfFields(cases.find((c) => c[0] === 'payload checksum')[1]());
  assert.match(bad.problems[0].message, /section-checksum \(4008\)/);
});

test('META vff.source.geometryHash must equal the extension (14010); a partial result is refused (14009)', async () => {
  // A field with META: the JS reader's own hash of the box, or another one.
  const { bytes: payload } = vectorPayload();
  const io = await makeIO();
  const glb = await io.writeBinary(boxDocument({ payload }));
  const hash = splitGlb(glb).json.meshes[0].extensions[EXT].geometryHash;
  const { withMeta } = await import('./gltf_meta.js');
  for (const [meta, want] of [
    [{ 'vff.source': { geometryHash: hash } }, []],
    [{ 'vff.source': { geometryHash: '0123456789abcdef' } }, [[14010, 'error', `${ext()}/geometryHash`]]],
    [{ 'vff.source': { name: 'x' } }, []],
    [{ 'vff.partial': { mapBegin: 0, mapEnd: 1, mapCount: 2 } }, [[14009, 'error', ext()]]],
  ]) {
    const p = withMeta(meta);
    const doc = boxDocument({ payload: p });
    const r = await readGltfFields(await io.writeBinary(doc));
    assert.deepEqual(rules(r), want, JSON.stringify(meta));
  }
});

test('nodes no field answers for: non-uniform scale, mirror, skin, morph weights (note 14104)', async () => {
  const { bytes: payload } = vectorPayload();
  const io = await makeIO();
  const doc = boxDocument({ meshes: 1, payload });
  const scene = doc.getRoot().listScenes()[0];
  const mesh = doc.getRoot().listMeshes()[0];
  const add = (name, f) => { const n = doc.createNode(name).setMesh(mesh); f(n); scene.addChild(n); return n; };
  add('similar', (n) => n.setScale([2, 2, 2]).setRotation([0, 0.7071067811865476, 0, 0.7071067811865476]).setTranslation([1, 2, 3]));
  add('stretched', (n) => n.setScale([1, 2, 1]));
  add('mirrored', (n) => n.setScale([-1, 1, 1]));
  const parent = doc.createNode('parent').setScale([1, 1, 3]);
  parent.addChild(doc.createNode('child').setMesh(mesh));
  scene.addChild(parent);
  let r = await readGltfFields(await io.writeBinary(doc));
  assert.deepEqual(rules(r), [[14104, 'note', '/nodes/2'], [14104, 'note', '/nodes/3'], [14104, 'note', '/nodes/5']]);
  assert.deepEqual(r.fields[0].nodes.map((n) => [n.name, n.answered, n.reason]),
    [['box0', true, ''], ['similar', true, ''], ['stretched', false, 'non-uniform scale'], ['mirrored', false, 'mirror'], ['child', false, 'non-uniform scale']]);
  assert.match(r.problems[1].message, /node 3 'mirrored' uses mesh 0 but has a mirroring transform/);
  // skin and morph weights, edited into the JSON
  const glb = await io.writeBinary(boxDocument({ payload }));
  r = await readGltfFields(editGlb(glb, (j) => { j.nodes[0].skin = 0; }));
  assert.deepEqual(r.fields[0].nodes.map((n) => n.reason), ['skin']);
  const morph = (weights) => editGlb(glb, (j) => { j.meshes[0].primitives[0].targets = [{ POSITION: 0 }]; if (weights) j.meshes[0].weights = weights; });
  assert.deepEqual((await readGltfFields(morph([0.5]))).fields[0].nodes.map((n) => n.reason), ['morph targets']);
  assert.deepEqual((await readGltfFields(morph([0]))).fields[0].nodes.map((n) => n.reason), ['']);
  assert.deepEqual(rules(await readGltfFields(morph([0.5]))), [[14104, 'note', '/nodes/0']]);
});
