// web/src/gltf_transform_vff.js, VFF_visibility_field for glTF-Transform: a read/write round trip
// keeps the payload byte for byte; dedup and prune keep it; draco keeps it and the reader matches
// the decoded mesh (exact or close); quantize and meshopt re-frame positions, and the writer drops
// the field with a 14103 warning exactly when the JS reader would call it a mismatch; a reader
// without the extension registered drops it with a warning.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { dedup, prune, draco, quantize, meshopt, weld } from '@gltf-transform/functions';
import { EXTMeshoptCompression } from '@gltf-transform/extensions';
import { readGltfFields } from '../src/gltf_fields.js';
import { decodedGeometryFrom, meshGeometry } from '../src/gltf_transform_vff.js';
import { EXT, KeepLogger, vectorPayload, boxDocument, makeIO, splitGlb, viewBytes } from './gltf_assets.js';

const { bytes: PAYLOAD } = vectorPayload();

/** The payload bytes of each mesh's field in a GLB (null: none). */
function payloads(glb) {
  const { json } = splitGlb(glb);
  return (json.meshes ?? []).map((m) => {
    const e = m.extensions?.[EXT];
    return e ? Array.from(viewBytes(glb, e.bufferView)) : null;
  });
}

/** The reader's report, Draco and meshopt decoded by glTF-Transform. */
async function read(glb) {
  const io = await makeIO();
  return readGltfFields(glb, { decodedGeometry: decodedGeometryFrom(await io.readBinary(glb)) });
}

test('read and write with the extension: the payload byte for byte, the declared geometry kept', async () => {
  const io = await makeIO();
  const glb = await io.writeBinary(boxDocument({ meshes: 2 }));
  const doc = await io.readBinary(glb);
  const f = doc.getRoot().listMeshes()[1].getExtension(EXT);
  assert.deepEqual([...f.getPayload()], [...PAYLOAD]);
  assert.deepEqual(f.getMin(), [0.5, -0.30000001192092896, -0.20000000298023224]);
  const again = await io.writeBinary(doc);
  assert.deepEqual(payloads(again), [[...PAYLOAD], [...PAYLOAD]]);
  const { json } = splitGlb(again);
  assert.deepEqual(json.extensionsUsed, [EXT]);
  assert.equal(json.extensionsRequired, undefined);
  assert.deepEqual(Object.keys(json.meshes[0].extensions[EXT]).sort(), ['bufferView', 'geometryHash', 'max', 'mimeType', 'min']);
  assert.equal(json.bufferViews[json.meshes[0].extensions[EXT].bufferView].byteStride, undefined);
  const r = await readGltfFields(again);
  assert.deepEqual(r.problems, []);
  assert.deepEqual(r.fields.map((x) => x.match), ['exact', 'exact']);
  // Writing the same document twice gives the same bytes.
  assert.deepEqual(await io.writeBinary(doc), again);
});

test('dedup and prune keep each payload byte for byte', async () => {
  const io = await makeIO();
  const doc = await io.readBinary(await io.writeBinary(boxDocument({ meshes: 2 })));
  // An unused accessor for prune to remove.
  doc.createAccessor().setType('SCALAR').setArray(new Float32Array([1, 2, 3])).setBuffer(doc.getRoot().listBuffers()[0]);
  await doc.transform(dedup(), prune());
  assert.equal(doc.getRoot().listAccessors().length, 3, 'the unused one pruned, the two index lists merged');
  const glb = await io.writeBinary(doc);
  assert.deepEqual(payloads(glb), [[...PAYLOAD], [...PAYLOAD]]);
  const r = await readGltfFields(glb);
  assert.deepEqual(r.problems, []);
  assert.deepEqual(r.fields.map((x) => x.match), ['exact', 'exact']);
});

test('draco keeps the field; the reader matches the decoded mesh (exact or close), and without a decoder reports 14011', async () => {
  const io = await makeIO();
  const doc = await io.readBinary(await io.writeBinary(boxDocument()));
  await doc.transform(draco({ quantizePosition: 14 }));
  const logger = new KeepLogger();
  doc.setLogger(logger);
  const glb = await io.writeBinary(doc);
  assert.deepEqual(logger.warnings, []);
  const { json } = splitGlb(glb);
  assert.ok(json.extensionsUsed.includes('KHR_draco_mesh_compression'));
  assert.deepEqual(payloads(glb), [[...PAYLOAD]]);
  const r = await read(glb);
  assert.ok(['exact', 'close'].includes(r.fields[0].match), r.fields[0].match);
  assert.equal(r.fields[0].usable, true);
  assert.ok(r.fields[0].boundsDifference <= r.fields[0].tolerance);
  console.log(`draco 14 bits: ${r.fields[0].match}, bounds differ by ${r.fields[0].boundsDifference} (tau ${r.fields[0].tolerance})`);
  const plain = await readGltfFields(glb);
  assert.deepEqual(plain.problems.map((p) => [p.rule, p.path]), [[14011, '/meshes/0']]);
  // Read back through glTF-Transform (decoded) and written again: the field is kept (within tau).
  const back = await io.readBinary(glb);
  assert.deepEqual([...back.getRoot().listMeshes()[0].getExtension(EXT).getPayload()], [...PAYLOAD]);
});

test('EXT_meshopt_compression without quantization keeps the field; the decoded mesh is exact', async () => {
  const io = await makeIO();
  const doc = await io.readBinary(await io.writeBinary(boxDocument()));
  doc.createExtension(EXTMeshoptCompression).setRequired(true).setEncoderOptions({ method: EXTMeshoptCompression.EncoderMethod.FILTER });
  const glb = await io.writeBinary(doc);
  const { json } = splitGlb(glb);
  assert.ok(json.bufferViews[json.accessors[0].bufferView].extensions.EXT_meshopt_compression);
  assert.deepEqual(payloads(glb), [[...PAYLOAD]]);
  const r = await read(glb);
  assert.deepEqual(r.problems, []);
  assert.equal(r.fields[0].match, 'exact');
  assert.deepEqual((await readGltfFields(glb)).problems.map((p) => [p.rule, p.path]), [[14011, '/meshes/0']]);
});

const { MeshoptEncoder } = await import('meshoptimizer');
for (const [name, transforms] of [
  ['quantize', () => [quantize()]],
  ['meshopt', () => [meshopt({ encoder: MeshoptEncoder, level: 'medium' })]],
]) {
  test(`${name} re-frames positions: the writer drops the field with a 14103 warning, as the reader would rule`, async () => {
    const io = await makeIO();
    const source = await io.readBinary(await io.writeBinary(boxDocument({ meshes: 2 })));
    const doc = await io.readBinary(await io.writeBinary(source));
    await doc.transform(...transforms());
    // What the reader would say of the mesh now: its geometry against the declared one.
    const declared = source.getRoot().listMeshes().map((m) => m.getExtension(EXT));
    const now = doc.getRoot().listMeshes().map((m) => meshGeometry(m));
    const tau = vectorPayload().radius * 2 / 255;
    const within = now.map((g, i) => [0, 1, 2].every((c) => Math.abs(g.min[c] - declared[i].getMin()[c]) <= tau && Math.abs(g.max[c] - declared[i].getMax()[c]) <= tau));
    const logger = new KeepLogger();
    doc.setLogger(logger);
    const glb = await io.writeBinary(doc);
    const kept = payloads(glb).map((p) => p !== null);
    assert.deepEqual(kept, within, `kept ${kept}, within tau ${within}`);
    const dropped = kept.filter((k) => !k).length;
    assert.equal(logger.warnings.filter((w) => /gltf-geometry-mismatch \(14103\)/.test(w)).length, dropped);
    console.log(`${name}: ${dropped} of 2 fields dropped; warnings: ${logger.warnings.join(' | ')}`);
    // The kept ones the reader uses; the asset is valid either way.
    const r = await read(glb);
    assert.deepEqual(r.problems.filter((p) => p.severity !== 'note'), []);
    assert.ok(r.fields.every((f) => f.usable));
    assert.equal(r.fields.length, kept.filter(Boolean).length);
    if (name === 'quantize') assert.equal(dropped, 2, 'quantize moves the box into [-1, 1]');
    if (!dropped) assert.ok(splitGlb(glb).json.extensionsUsed.includes(EXT));
    else if (dropped === 2) assert.ok(!(splitGlb(glb).json.extensionsUsed ?? []).includes(EXT));
  });
}

test('an edit that moves vertices past tau drops the field on write; within tau keeps it', async () => {
  const io = await makeIO();
  const tau = vectorPayload().radius * 2 / 255;
  for (const [steps, kept] of [[0.5, true], [2, false]]) {
    const doc = await io.readBinary(await io.writeBinary(boxDocument()));
    const pos = doc.getRoot().listMeshes()[0].listPrimitives()[0].getAttribute('POSITION');
    const a = pos.getArray().slice();
    for (let i = 1; i < a.length; i += 3) if (a[i] > 0) a[i] += steps * tau;
    pos.setArray(a);
    const logger = new KeepLogger();
    doc.setLogger(logger);
    const glb = await io.writeBinary(doc);
    assert.deepEqual(payloads(glb), [kept ? [...PAYLOAD] : null]);
    assert.equal(logger.warnings.length, kept ? 0 : 1);
    if (!kept) assert.match(logger.warnings[0], /mesh 0 'box0': gltf-geometry-mismatch \(14103\)/);
    const r = await readGltfFields(glb);
    assert.deepEqual(r.fields.map((f) => f.match), kept ? ['close'] : []);
  }
});

test('a reader without the extension registered drops it, and its bufferView, with a warning', async () => {
  const glb = await (await makeIO()).writeBinary(boxDocument());
  const logger = new KeepLogger();
  const io = await makeIO({ vff: false, logger });
  const doc = await io.readBinary(glb);
  assert.deepEqual(logger.warnings, [`Missing optional extension, "${EXT}".`]);
  const out = await io.writeBinary(doc);
  const { json, bin } = splitGlb(out);
  assert.equal(json.extensionsUsed, undefined);
  assert.equal(json.meshes[0].extensions, undefined);
  assert.equal(json.bufferViews.length, 2);
  assert.ok(bin.length < PAYLOAD.length);
  assert.deepEqual((await readGltfFields(out)).fields, []);
  // weld and friends then run as on any asset
  await doc.transform(weld());
});
