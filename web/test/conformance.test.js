// The JavaScript decoder against spec/conformance: every valid vector decodes to the values of its
// expected.json (hashes exact, values within 2e-6 x max(1, |value|)), every invalid vector is
// rejected with the validation ID of its folder. Run: node --test test/
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFileSync, readdirSync, existsSync } from 'node:fs';
import { join, dirname } from 'node:path';
import { fileURLToPath } from 'node:url';
import { initVff, openVff, xxh3Hex, ENCODING_NAMES, POSITION_NAMES, DIRECTION_NAMES } from '../src/vff.js';

const root = join(dirname(fileURLToPath(import.meta.url)), '..', '..', 'spec', 'conformance');
await initVff();

const near = (a, b) => Math.abs(a - b) <= 2e-6 * Math.max(1, Math.abs(b));

/** Compares a decoded file with an expected.json; returns nothing, asserts. */
export function checkValid(file, bytes, exp) {
  assert.equal(bytes.length, exp.fileSize);
  assert.equal(xxh3Hex(bytes), exp.fileXxh3);
  const h = file.header;
  assert.equal(h.versionMajor, exp.versionMajor);
  assert.equal(h.versionMinor, exp.versionMinor);
  assert.equal(h.incompatFeatures, exp.incompatFeatures);
  assert.equal(h.roCompatFeatures, exp.roCompatFeatures);
  assert.deepEqual(file.warnings.map((w) => w.id), exp.warnings);
  assert.deepEqual(file.sections.map((s) => ({ tag: s.tag, flags: s.flags, codec: s.codec ? 'zstd' : 'stored', known: s.known })), exp.sections);
  const f = file.field, ef = exp.field;
  assert.ok(f.sphere.center.every((c, i) => near(c, ef.sphere.center[i])) && near(f.sphere.radius, ef.sphere.radius));
  assert.equal(POSITION_NAMES[f.positionScheme], ef.positionScheme);
  assert.equal(DIRECTION_NAMES[f.directionScheme], ef.directionScheme);
  assert.equal(ENCODING_NAMES[f.distanceEncoding], ef.distanceEncoding);
  assert.equal(f.normalEncoding ? 'oct-snorm16' : 'none', ef.normalEncoding);
  for (const k of ['positionParam', 'mapCount', 'mapResolution', 'missCode']) assert.equal(f[k], ef[k], k);
  const { target, ...rest } = exp.layout;
  assert.equal(file.layout.target, target === '2d-array' ? 1 : 2);
  for (const [k, v] of Object.entries(rest)) assert.equal(file.layout[k], v, k);
  if (exp.metadata === null) assert.equal(file.metadata, null);
  else if (typeof exp.metadata === 'string') assert.equal(file.metadata.text, exp.metadata);
  else assert.deepEqual(file.metadata.value, exp.metadata);
  for (const [name, p] of Object.entries(exp.planes)) {
    const mine = file.planes[name];
    assert.equal(mine.mapBytes, p.mapBytes);
    assert.equal(mine.mapsPerBlock, p.mapsPerBlock);
    assert.deepEqual(mine.blocks.map((b) => (b.codec ? 'zstd' : 'stored')), p.blockCodecs);
    if (p.blockFilters) assert.deepEqual(mine.blocks.map((b) => (b.filter ? 'hits-med' : 'none')), p.blockFilters);
  }
  if (exp.refinement === undefined) assert.equal(file.refinement, null);
  else checkRefinement(file.refinement, exp.refinement, f);
  const M = f.mapResolution;
  for (const m of exp.maps) {
    assert.equal(xxh3Hex(file.mapBytes('distance', m.map)), m.distanceXxh3, `map ${m.map} distance bytes`);
    const d = file.distances(m.map);
    m.distance.forEach((v, t) => {
      if (v === null) assert.ok(Number.isNaN(d[t]), `map ${m.map} texel ${t} should miss`);
      else if (f.distanceEncoding === 4) assert.equal(Number.isNaN(d[t]) ? 0 : 1, v);
      else assert.ok(near(d[t], v), `map ${m.map} texel ${t}: ${d[t]} vs ${v}`);
    });
    if (m.normalXxh3) {
      assert.equal(xxh3Hex(file.mapBytes('normal', m.map)), m.normalXxh3);
      m.normals.forEach((v, t) => {
        if (v === null) return;
        const n = file.normal(m.map, t % M, Math.floor(t / M));
        assert.ok(n.every((c, i) => Math.abs(c - v[i]) <= 1.5e-6), `map ${m.map} texel ${t} normal ${n} vs ${v}`);
      });
    }
  }
  for (const [name, hashes] of Object.entries(exp.slices))
    hashes.forEach((hx, s) => assert.equal(xxh3Hex(file.slice(name, s)), hx, `${name} slice ${s}`));
}

/** REFN (format 1.3) against the expected.json's "refinement". */
function checkRefinement(r, er, f) {
  assert.ok(r, 'no refinement');
  assert.equal(r.margin, Math.fround(er.margin));
  assert.equal(r.unsureTexels, er.unsureTexels);
  assert.equal(r.unsure.length, er.unsureBytes);
  assert.equal(xxh3Hex(r.unsure), er.unsureXxh3);
  const MM = f.mapResolution * f.mapResolution;
  er.unsure.forEach((want, k) => {
    const got = [];
    for (let t = 0; t < MM; ++t) if ((r.unsure[(k * MM + t) >> 3] >> ((k * MM + t) & 7)) & 1) got.push(t);
    assert.deepEqual(got, want, `the unsure texels of map ${k}`);
  });
  assert.equal(er.unsure.length, f.mapCount);
  assert.equal(r.positions.length, 3 * er.vertexCount);
  assert.equal(r.indices.length, 3 * er.triangleCount);
  assert.equal(xxh3Hex(new Uint8Array(r.positions.buffer, r.positions.byteOffset, r.positions.byteLength)), er.positionsXxh3);
  assert.equal(xxh3Hex(new Uint8Array(r.indices.buffer, r.indices.byteOffset, r.indices.byteLength)), er.indicesXxh3);
  er.positions.forEach((p, v) => p.forEach((c, a) => assert.equal(r.positions[3 * v + a], Math.fround(c), `vertex ${v}`)));
  er.indices.forEach((t, i) => t.forEach((c, a) => assert.equal(r.indices[3 * i + a], c, `triangle ${i}`)));
}

/** The first validation ID a reader raises for the bytes (open, then read everything), or 0. */
export function firstProblem(bytes) {
  try {
    const file = openVff(bytes);
    file.validateDeep();
    for (let k = 0; k < file.field.mapCount; ++k) file.codes(k);
    for (const p of Object.keys(file.planes)) for (let s = 0; s < file.layout.sliceCount; ++s) file.slice(p, s);
    return 0;
  } catch (e) {
    if (e.id === undefined) throw e;
    return e.id;
  }
}

const validDir = join(root, 'valid');
for (const name of readdirSync(validDir).filter((n) => n.endsWith('.vff')).sort()) {
  test(`valid ${name}`, () => {
    const bytes = new Uint8Array(readFileSync(join(validDir, name)));
    const exp = JSON.parse(readFileSync(join(validDir, name.replace(/\.vff$/, '.expected.json')), 'utf8'));
    const file = openVff(bytes);
    file.validateDeep();
    checkValid(file, bytes, exp);
  });
}

const invalidDir = join(root, 'invalid');
for (const id of readdirSync(invalidDir).sort()) {
  for (const name of readdirSync(join(invalidDir, id)).filter((n) => n.endsWith('.vff')).sort()) {
    test(`invalid ${id}/${name}`, () => {
      const bytes = new Uint8Array(readFileSync(join(invalidDir, id, name)));
      assert.equal(firstProblem(bytes), Number(id));
    });
  }
}

test('the conformance folder is there', () => assert.ok(existsSync(validDir)));
