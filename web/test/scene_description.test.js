// The JavaScript scene-description reader against spec/conformance/scene: every invalid vector is
// refused with the ID of its folder, every valid one reads as its expected.json says (binary32
// values bit for bit, world spheres of the fields that exist within binary32 rounding, the spheres
// read by the JavaScript decoder). Run: node --test test/
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFileSync, readdirSync, existsSync } from 'node:fs';
import { join, dirname } from 'node:path';
import { fileURLToPath } from 'node:url';
import { initVff, openVff } from '../src/vff.js';
import { readSceneDescription, resolveSceneUri, parseStrictJson, SceneError } from '../src/scene_description.js';

const root = join(dirname(fileURLToPath(import.meta.url)), '..', '..', 'spec', 'conformance', 'scene');
await initVff();

const invalid = readdirSync(join(root, 'invalid')).sort().flatMap((id) =>
  readdirSync(join(root, 'invalid', id)).filter((n) => n.endsWith('.json')).sort().map((n) => ({ id: Number(id), n })));
const valid = readdirSync(join(root, 'valid')).filter((n) => n.endsWith('.json') && !n.endsWith('.expected.json')).sort();

test('there are enough vectors, for every rule', () => {
  assert.ok(invalid.length >= 30 && valid.length >= 8);
  assert.deepEqual([...new Set(invalid.map((v) => v.id))], [11001, 11002, 11003, 11004, 11005]);
});

for (const { id, n } of invalid) {
  test(`invalid/${id}/${n}`, () => {
    const name = `invalid/${id}/${n}`;
    assert.throws(() => readSceneDescription(readFileSync(join(root, name)), name), (e) => {
      assert.ok(e instanceof SceneError, String(e));
      assert.equal(e.id, id, e.message);
      assert.ok(e.detail.startsWith(`${name}:`), e.message);
      return true;
    });
  });
}

// A rotation about `q` of v, then scaled and moved: world(p) of spec/scene.md section 4, in binary64.
function world(inst, c) {
  const [x, y, z, w] = inst.rotation, s = inst.scale, p = c.map((v) => s * v);
  const m = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
    [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
    [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]];
  return m.map((row, r) => inst.translation[r] + row[0] * p[0] + row[1] * p[1] + row[2] * p[2]);
}

const near = (a, b) => Math.abs(a - b) <= 1e-5 * (1 + Math.abs(b));

for (const n of valid) {
  test(`valid/${n}`, () => {
    const path = join(root, 'valid', n);
    const want = JSON.parse(readFileSync(path.replace(/\.json$/, '.expected.json'), 'utf8'));
    const got = readSceneDescription(readFileSync(path), n);
    assert.equal(got.generator, want.generator);
    assert.equal(got.fields.length, want.fields.length);
    const spheres = got.fields.map((f, i) => {
      const w = want.fields[i];
      assert.equal(f.uri, w.uri);
      assert.equal(f.name, w.name);
      const file = resolveSceneUri(path, f.uri);
      assert.equal(file, w.path.startsWith("/") ? w.path : `${dirname(path)}/${w.path}`);
      assert.equal(existsSync(file), w.exists, file);
      return w.exists ? openVff(readFileSync(file)).field.sphere : null;
    });
    assert.equal(got.instances.length, want.instances.length);
    got.instances.forEach((inst, i) => {
      const w = want.instances[i];
      assert.equal(inst.field, w.field);
      assert.equal(inst.name, w.name);
      for (const key of ['translation', 'rotation']) {
        inst[key].forEach((v, k) => assert.ok(Object.is(v, Math.fround(w[key][k])), `${key}[${k}]: ${v} != ${w[key][k]}`));
      }
      assert.ok(Object.is(inst.scale, Math.fround(w.scale)), `scale ${inst.scale}`);
      assert.equal('worldSphere' in w, spheres[inst.field] !== null);
      if (!spheres[inst.field]) return;
      const c = world(inst, spheres[inst.field].center);
      c.forEach((v, k) => assert.ok(near(v, w.worldSphere.center[k]), `center ${c} != ${w.worldSphere.center}`));
      assert.ok(near(inst.scale * spheres[inst.field].radius, w.worldSphere.radius));
    });
  });
}

// The JSON text rules of spec/scene.md section 1, placed as libvff places them.
test('JSON text problems carry line, column and path', () => {
  const problem = (s) => {
    try {
      parseStrictJson(typeof s === 'string' ? new TextEncoder().encode(s) : s);
      return 'accepted';
    } catch (p) {
      return `${p.line}:${p.column}: ${p.path}: ${p.message}`;
    }
  };
  assert.equal(problem('{"a": {"b": 1,\n "b": 2}}'), '2:2: a.b: the member name "b" is repeated in one object');
  assert.equal(problem('{"extras": {"k": [0,\n  1e400]}}'), '2:3: extras.k[1]: the number 1e400 is not representable as a finite binary64');
  assert.equal(problem('{"a":1}\0'), '1:8: : a NUL byte after the JSON value (only whitespace may follow it)');
  assert.equal(problem(`${'['.repeat(64)}${']'.repeat(64)}`), 'accepted');
  assert.match(problem(`${'['.repeat(65)}${']'.repeat(65)}`), /^1:65: .*nest deeper than 64/);
  assert.equal(problem(Uint8Array.from([0xef, 0xbb, 0xbf, 0x7b, 0x7d])), 'accepted');
});

// An integer is written without a fraction or an exponent and held in 64 bits (spec/scene.md
// section 1); the messages quote it as written, as libvff does.
test('integers are integers as written, within 64 bits', () => {
  const read = (field, asset = '"version": 1') => {
    const text = `{"asset": {"format": "vff-scene", ${asset}}, "fields": [{"uri": "a.vff"}, {"uri": "b.vff"}], "instances": [{"field": ${field}}]}`;
    try {
      return readSceneDescription(new TextEncoder().encode(text), 's.json').instances[0].field;
    } catch (e) {
      assert.ok(e instanceof SceneError, String(e));
      return `${e.id} ${e.detail}`;
    }
  };
  assert.ok(Object.is(read('-0'), 0));
  assert.equal(read('1'), 1);
  assert.equal(read('1.0'), '11003 s.json: instances[0].field: expected an integer, got 1.0');
  assert.equal(read('0e5'), '11003 s.json: instances[0].field: expected an integer, got 0.0');
  assert.match(read('18446744073709551616'), /^11003 s\.json: instances\[0\]\.field: expected an integer/);
  assert.match(read('-9223372036854775809'), /^11003 s\.json: instances\[0\]\.field: expected an integer/);
  assert.equal(read('18446744073709551615'), '11005 s.json: instances[0].field: index 18446744073709551615 is not one of the 2 fields');
  assert.equal(read('-9223372036854775808'), '11005 s.json: instances[0].field: index -9223372036854775808 is not one of the 2 fields');
  assert.equal(read('0', '"version": 1.0'), '11002 s.json: asset.version: is 1.0; this reader implements version 1');
  assert.equal(read('0', '"version": 1, "minorVersion": 2e1'), '11003 s.json: asset.minorVersion: expected a non-negative integer, got 20.0');
  assert.equal(read('0', '"version": 1, "minorVersion": 18446744073709551615'), 0);
});
