// The GLSL ES shader is generated from gpu/'s desktop include: the committed file must be exactly
// what the generator makes from the current include (so the two lookups cannot drift apart).
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFileSync } from 'node:fs';
import { generate, TARGET } from '../tools/gen-glsl-es.mjs';
import { VFF_QUERY_GLSL_ES } from '../src/vff_query_es.js';

test('src/vff_query_es.js is generated from gpu/glsl/vff_query.glsl', () => {
  assert.equal(readFileSync(TARGET, 'utf8'), generate(), 'run: node tools/gen-glsl-es.mjs');
});

test('the ES text keeps every lookup function of the desktop include', () => {
  for (const fn of ['vffNearestSample', 'vffHemisphereToSquare', 'vffFetchCode', 'vffDecode', 'vffQuery', 'vffVisibility', 'vffOccluded'])
    assert.match(VFF_QUERY_GLSL_ES, new RegExp(`\\b${fn}\\(`));
  const code = VFF_QUERY_GLSL_ES.replace(/\/\/.*$/gm, '');
  assert.doesNotMatch(code, /\bprecise\b|\bbuffer\b|binding =|\bfma\(|\bumulExtended\(/);
});
