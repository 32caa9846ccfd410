// The page's summary is the text vff-inspect prints (VFF_INSPECT: the tool; skipped without it),
// for every valid conformance vector whose metadata a JavaScript number can hold.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFileSync, readdirSync } from 'node:fs';
import { execFileSync } from 'node:child_process';
import { join, dirname } from 'node:path';
import { fileURLToPath } from 'node:url';
import { initVff, openVff } from '../src/vff.js';
import { summary } from '../src/summary.js';

const dir = join(dirname(fileURLToPath(import.meta.url)), '..', '..', 'spec', 'conformance', 'valid');
await initVff();
const inspect = process.env.VFF_INSPECT;

for (const name of readdirSync(dir).filter((n) => n.endsWith('.vff')).sort()) {
  test(`summary of ${name} is vff-inspect's`, { skip: inspect ? false : 'VFF_INSPECT is not set' }, () => {
    const path = join(dir, name);
    const mine = summary(openVff(new Uint8Array(readFileSync(path))), path).split('\n');
    const theirs = execFileSync(inspect, [path], { encoding: 'utf8' }).replace(/\n$/, '').split('\n');
    // META numbers beyond binary64 (meta-any-magnitude) print differently: compare up to META.
    const upto = name === 'meta-any-magnitude.vff' ? theirs.indexOf('metadata:') : theirs.length;
    assert.deepEqual(mine.slice(0, upto), theirs.slice(0, upto));
  });
}
