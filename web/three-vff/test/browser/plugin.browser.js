// In headless Chromium: GLTFLoader with VffGLTFPlugin loads the .glb vff-bake writes for
// vff-procedural-mesh's sample scene: both fields are found and decoded, the node with a
// non-similarity transform is reported (14104) and gets no field, the objects the fields answer for
// carry userData.vffField, and VffOcclusion.collect draws them as instances. VFF_WORK: scratch.
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import { join } from 'node:path';
import { BAKE, MESHGEN, SKIP, scratch, openTestPage } from '../tools.js';

let session, page, errors = [];

before(async () => {
  if (SKIP) return;
  const dir = scratch('plugin');
  const scene = join(dir, 's.gltf'), glb = join(dir, 's.glb');
  execFileSync(MESHGEN, ['--gltf-scene', scene], { stdio: 'ignore' });
  execFileSync(BAKE, [scene, '-o', glb, '-n', '2', '-m', '8'], { stdio: 'ignore' });
  session = await openTestPage({ '/s.glb': glb });
  ({ page, errors } = session);
});
after(async () => { await session?.close(); });

test('VffGLTFPlugin: fields found, problems reported, userData.vffField set', { skip: SKIP || false }, async () => {
  const r = await page.evaluate(() => window.loadGlb('/s.glb'));
  console.log(JSON.stringify(r));
  assert.deepEqual(r.fields.map((f) => [f.mesh, f.name, f.match, f.hasField]), [[0, 'box', 'exact', true], [1, 'knot', 'exact', true]]);
  assert.deepEqual(r.problems, [14104]);
  assert.deepEqual(r.fields.map((f) => f.problems), [[], [14104]]);
  // boxA and boxB use mesh 0; knotStretched (mesh 1, scaled unevenly) is answered by no field.
  assert.deepEqual(r.carriers.map((c) => [c.name, c.type, c.field]).sort(), [['boxA', 'Mesh', 'box'], ['boxB', 'Mesh', 'box']]);
  assert.equal(r.instances, 2);
  assert.equal(r.frame, 2);
  assert.deepEqual(r.ids.filter((i) => i !== 0), [1, 2, 4095], 'instance ids 1 and 2, other receivers 4095');
  assert.deepEqual(errors, []);
});
