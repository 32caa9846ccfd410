// Partial results (spec/partial.md) in the JavaScript decoder: every valid partial of the vectors
// (spec/conformance/partial/manifest.json) is reported with its range, whole fields are not, and the
// summary is vff-inspect's line for line (VFF_INSPECT: the tool; that case skipped without it).
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFileSync, readdirSync } from 'node:fs';
import { execFileSync } from 'node:child_process';
import { join, dirname } from 'node:path';
import { fileURLToPath } from 'node:url';
import { initVff, openVff } from '../src/vff.js';
import { summary } from '../src/summary.js';
import { partialRange } from '../src/meta.js';

const dir = join(dirname(fileURLToPath(import.meta.url)), '..', '..', 'spec', 'conformance', 'partial');
const manifest = JSON.parse(readFileSync(join(dir, 'manifest.json'), 'utf8'));
await initVff();
const inspect = process.env.VFF_INSPECT;
const open = (rel) => openVff(new Uint8Array(readFileSync(join(dir, rel))));
const partialOf = (file) => partialRange(file.metadata?.value ?? null, file.field.mapCount, file.metadata?.text);

test('the manifest lists every part of every valid set', () => {
  const onDisk = [];
  for (const set of readdirSync(join(dir, 'merge')).filter((n) => !/^[0-9]/.test(n))) {
    for (const f of readdirSync(join(dir, 'merge', set))) if (/^p[0-9]+\.vff$/.test(f)) onDisk.push(`merge/${set}/${f}`);
  }
  assert.deepEqual(Object.keys(manifest.partials).sort(), onDisk.sort());
  assert.ok(onDisk.length >= 6);
});

for (const [rel, r] of Object.entries(manifest.partials)) {
  test(`${rel} is a partial result of maps ${r.mapBegin}:${r.mapEnd}`, () => {
    const file = open(rel);
    assert.deepEqual(partialOf(file), { mapBegin: r.mapBegin, mapEnd: r.mapEnd, mapCount: r.mapCount, maps: r.mapEnd - r.mapBegin });
    const text = summary(file, rel).split('\n');
    assert.ok(text.includes(`  partial:    maps ${r.mapBegin}:${r.mapEnd} of ${r.mapCount} only (vff-bake --map-range); the others hold misses until vff-bake --merge`));
    // the statistics count the range's maps only
    const m = file.field.mapResolution;
    assert.match(text.find((l) => l.startsWith('hits:')), new RegExp(` of ${(r.mapEnd - r.mapBegin) * m * m} texels,`));
  });
  test(`summary of ${rel} is vff-inspect's`, { skip: inspect ? false : 'VFF_INSPECT is not set' }, () => {
    const path = join(dir, rel);
    const mine = summary(openVff(new Uint8Array(readFileSync(path))), path).split('\n');
    const theirs = execFileSync(inspect, [path], { encoding: 'utf8' }).replace(/\n$/, '').split('\n');
    assert.deepEqual(mine, theirs);
  });
}

test('whole fields are not partial; a vff.partial without a valid range still is', () => {
  for (const set of Object.keys(manifest.sets).filter((n) => manifest.sets[n].exit === 0)) {
    const file = open(`merge/${set}/expected.vff`);
    assert.equal(partialOf(file), null, set);
    assert.ok(!summary(file, set).includes('partial:'));
  }
  const none = { mapBegin: null, mapEnd: null, mapCount: 6, maps: null };
  assert.deepEqual(partialOf(open('merge/12009-partial-range/p2.vff')), none);
  assert.deepEqual(partialOf(open('merge/12003-partial-object/p2.vff')), none);
  assert.equal(partialOf(open('merge/12002-partial-missing/p2.vff')), null);
});

test('bounds count as vff-inspect reads them: integers as written, no number beyond binary64', () => {
  const range = (text) => partialRange(JSON.parse(text), 6, text);
  const part = (b, e, c, extra = '') => `{"a":[1,{"mapBegin":9.5}],${extra}"vff.partial":{"codec":"zstd","mapBegin":${b},"mapCount":${c},"mapEnd":${e},"x":"\\"mapBegin\\":7"}}`;
  const none = { mapBegin: null, mapEnd: null, mapCount: 6, maps: null };
  assert.deepEqual(range(part('2', '4', '6')), { mapBegin: 2, mapEnd: 4, mapCount: 6, maps: 2 });
  assert.deepEqual(range(part('2.0', '4', '6')), none);
  assert.deepEqual(range(part('2', '4e0', '6')), none);
  assert.deepEqual(range(part('-0', '4', '6')), none);
  assert.deepEqual(range(part('0', '4', '6')), { mapBegin: 0, mapEnd: 4, mapCount: 6, maps: 4 });
  // nlohmann-json refuses the whole text over one number beyond binary64: no partial result.
  assert.equal(range(part('2', '4', '6', '"big":1e400,')), null);
  assert.deepEqual(range(part('2', '4', '6', '"tiny":1e-400,')), { mapBegin: 2, mapEnd: 4, mapCount: 6, maps: 2 });
  // Without the text (a caller holding only the parsed value) the values decide.
  assert.deepEqual(partialRange(JSON.parse(part('2.0', '4', '6')), 6), { mapBegin: 2, mapEnd: 4, mapCount: 6, maps: 2 });
});
