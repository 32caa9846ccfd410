// VffField in node (no GPU): every valid conformance vector decodes to uniforms equal to the std140
// block the raw WebGL2 page uploads (web/src/query_tables.js), defines that name its texture kinds,
// and texture data of the layout's size; invalid vectors throw the decoder's VffError with the
// spec's ID; the occlusion shader's per-field copies of the query keep no unprefixed name.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFileSync, readdirSync } from 'node:fs';
import { join } from 'node:path';
import { ROOT } from './tools.js';
import { VffField } from '../src/field.js';
import { decodeVff } from '../src/decode.js';
import { slotGlsl } from '../src/occlusion.js';
import { buildQueryTables } from '../../src/query_tables.js';
import { openVff, initVff } from '../../src/vff.js';

const CONF = join(ROOT, 'spec', 'conformance');
const valid = readdirSync(join(CONF, 'valid')).filter((f) => f.endsWith('.vff')).sort();

test('valid vectors: uniforms, defines and texture sizes', async () => {
  assert.ok(valid.length >= 10, `${valid.length} valid vectors`);
  await initVff();
  for (const name of valid) {
    const bytes = readFileSync(join(CONF, 'valid', name));
    const field = await VffField.fromBytes(bytes, { name });
    const file = openVff(bytes), fd = file.field, L = file.layout;
    const v = field.uniforms.vffField.value;
    const { block } = buildQueryTables(file, L);
    const F = new Float32Array(block), U = new Uint32Array(block);
    assert.deepEqual(v.sphereCenter.toArray(), Array.from(F.slice(0, 3)), name);
    assert.equal(v.sphereRadius, F[3], name);
    assert.deepEqual([v.positionScheme, v.mapCount, v.mapResolution, v.distanceEncoding, v.sliceWidth, v.sliceCount, v.neighbourOffset],
      [U[4], U[6], U[8], U[9], U[17], U[19], U[24]], name);
    assert.deepEqual([v.intraBias, v.distanceScale, v.invRadius, v.kernelRadius2], [F[20], F[21], F[22], F[25]], name);
    assert.equal('VFF_NO_NORMALS' in field.defines, !file.planes.normal, name);
    assert.equal('VFF_MAPS_3D' in field.defines, L.target === 2, name);
    const t = field.data.textures;
    const texelBytes = fd.distanceEncoding === 3 ? 2 : 1;
    const width = fd.distanceEncoding === 4 ? L.sliceWidth / 8 : L.sliceWidth;
    assert.equal(t.maps.data.byteLength, width * L.sliceHeight * L.sliceCount * texelBytes, name);
    if (file.planes.normal) assert.equal(t.normals.data.byteLength, L.sliceWidth * L.sliceHeight * L.sliceCount * 4, name);
    assert.equal(field.radius, fd.sphere.radius);
    assert.ok(field.glsl.includes('uniform VffFieldData vffField;'));
    assert.equal(JSON.stringify({ f: field }), '{}', 'a field is left out of JSON copies (three.js clones userData so)');
  }
});

test('decodeVff reports progress up to done', async () => {
  const events = [];
  await decodeVff(readFileSync(join(CONF, 'valid', 'u8d-zstd-normals-meta.vff')), { onProgress: (p) => events.push(p.stage) });
  assert.deepEqual([...new Set(events)], ['open', 'check', 'textures', 'done']);
});

test('invalid vectors throw the VffError of their ID', async () => {
  let n = 0;
  for (const id of readdirSync(join(CONF, 'invalid')).sort()) {
    for (const f of readdirSync(join(CONF, 'invalid', id)).filter((x) => x.endsWith('.vff'))) {
      const expect = JSON.parse(readFileSync(join(CONF, 'invalid', id, f.replace(/\.vff$/, '.expect.json'))));
      const codes = expect.observed.validate.filter((p) => p.severity === 'error').map((p) => p.code);
      if (!codes.length) continue;
      await assert.rejects(VffField.fromBytes(readFileSync(join(CONF, 'invalid', id, f))), (e) => {
        assert.equal(e.name, 'VffError', `${id}/${f}: ${e}`);
        assert.ok(codes.includes(e.id), `${id}/${f}: ${e.id} not in ${codes}`);
        return true;
      });
      ++n;
    }
  }
  assert.ok(n >= 20, `${n} invalid vectors`);
});

test("the occlusion shader's copy of the query for slot 2 has only prefixed names", async () => {
  const field = await VffField.fromBytes(readFileSync(join(CONF, 'valid', 'bit1-zstd-normals-meta-3d.vff')));
  const src = slotGlsl(2, field);
  const names = new Set(src.replace(/\/\/.*$/gm, '').match(/\b(vff|Vff|VFF_?|kVff)[A-Za-z0-9_]*/g));
  for (const n of names) assert.match(n, /^(vff2_|Vff2_|VFF2_|kVff2_)/, n);
  // Every top-level declaration of the query (functions, constants, structs, uniforms) is renamed, so
  // several copies live in one shader.
  const declared = new Set();
  for (const line of src.split('\n')) {
    const m = /^(?:const\s+)?(?:uniform\s+)?(?:highp\s+|precise\s+)?(?:struct\s+(\w+)|\w+\s+(\w+)\s*[=(;[])/.exec(line);
    if (m) declared.add(m[1] ?? m[2]);
  }
  assert.ok(declared.size > 40, `${declared.size} top-level names`);
  for (const n of declared) assert.match(n, /^(vff2_|Vff2_|VFF2_|kVff2_)/, `top-level ${n}`);
  assert.ok(src.includes('#define VFF2_MAPS_3D'));
  assert.ok(src.includes('bool vff2_Occluded('));
  assert.ok(src.includes('uniform Vff2_FieldData vff2_Field;'));
});
