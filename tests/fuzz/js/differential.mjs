// Differential test of the JavaScript decoder (web/src) against libvff: for every input file, under
// each checksum policy (verify-all, lazy, none), both must give the same first error ID, or decode
// the same values (distances, normals and composed slices). libvff's side is the helper vff_fuzz_first_error (tests/fuzz/first_error.cpp),
// which prints one line per file; this script computes the same line with web/src and compares.
//
//   node differential.mjs --helper PATH [--policies P,...] [--mutants N] [--seed S] [--show K] [--save DIR]
//                         FILE|FOLDER...
//
// --policies: the checksum policies compared (default all three). Without verified block checksums
// (`none`) a damaged zstd frame reaches the two zstd decoders, libzstd and fzstd, which do not
// refuse the same damaged frames (neither frame has a content checksum): tests/fuzz/README.md.
//
// --mutants N adds N damaged copies of every .vff file given (cut short, bytes flipped or
// overwritten, little-endian fields set to edge values), made by a seeded generator so that a run
// is repeatable; they live in a temporary folder removed at the end. --save DIR copies every file
// the two disagree on there. Exit status: 0 when every file
// agrees, 1 when one disagrees (each printed with both answers), 2 on a usage or helper problem.
import { execFileSync } from 'node:child_process';
import { copyFileSync, mkdirSync, mkdtempSync, readFileSync, rmSync, statSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { basename, join } from 'node:path';
import { initVff, openVff, xxh3Hex } from '../../../web/src/vff.js';

const MAX_PAYLOAD_BYTES = 256 * 2 ** 20; // first_error.cpp's kMaxPayloadBytes
const MISS_BITS = 0x7fc00000;
const MAX_SLICE_TEXELS = 2 ** 24; // first_error.cpp's kMaxSliceTexels
const POLICIES = ['verify-all', 'lazy', 'none']; // first_error.cpp's order

function usage(message) {
  console.error(`differential.mjs: ${message}`);
  console.error('usage: node differential.mjs --helper PATH [--policies P,...] [--mutants N] [--seed S] [--show K] [--save DIR] FILE|FOLDER...');
  process.exit(2);
}

function parseArgs(argv) {
  const o = { helper: null, policies: POLICIES, mutants: 0, seed: 1, show: 20, save: null, inputs: [] };
  for (let a = 0; a < argv.length; ++a) {
    const v = argv[a];
    const next = () => {
      if (a + 1 >= argv.length) usage(`${v} needs a value`);
      return argv[++a];
    };
    if (v === '--helper') o.helper = next();
    else if (v === '--mutants') o.mutants = Number(next());
    else if (v === '--seed') o.seed = Number(next());
    else if (v === '--show') o.show = Number(next());
    else if (v === '--save') o.save = next();
    else if (v === '--policies') o.policies = next().split(',');
    else if (v.startsWith('--')) usage(`unknown option ${v}`);
    else o.inputs.push(v);
  }
  if (!o.helper) usage('--helper is required');
  if (!o.inputs.length) usage('no input files or folders');
  for (const p of o.policies) if (!POLICIES.includes(p)) usage(`unknown checksum policy ${p} (${POLICIES.join(', ')})`);
  for (const k of ['mutants', 'seed', 'show'])
    if (!Number.isInteger(o[k]) || o[k] < 0) usage(`--${k} must be a non-negative integer`);
  return o;
}

/** A small seeded generator (xorshift32): the same seed gives the same mutants everywhere. */
function rng(seed) {
  let s = (seed >>> 0) || 0x9e3779b9;
  return (n) => {
    s ^= s << 13; s >>>= 0;
    s ^= s >>> 17;
    s ^= s << 5; s >>>= 0;
    return n === undefined ? s : s % n;
  };
}

/**
 * Makes the header of a damaged file consistent again where it can: fileSize (offset 16) the file's
 * length, headerChecksum (56) the XXH3-64 of bytes 0..55 and the section table (format.md section
 * 3), so that the damage reaches the checks past the header.
 */
function fixHeader(b) {
  if (b.length < 64) return b;
  const v = new DataView(b.buffer, b.byteOffset, b.byteLength);
  v.setBigUint64(16, BigInt(b.length), true);
  const table = v.getBigUint64(40, true), count = BigInt(v.getUint32(48, true));
  if (table < 64n || table + 64n * count > BigInt(b.length)) return b;
  const t = Number(table);
  const sum = xxh3Hex(b.subarray(0, 56), b.subarray(t, t + 64 * Number(count)));
  v.setBigUint64(56, BigInt(`0x${sum}`), true);
  return b;
}

/** One damaged copy of `good`: its kind and place chosen by `r`; every other one with its header fixed. */
function mutant(good, r) {
  const b = damaged(good, r);
  return r(2) ? fixHeader(b) : b;
}

function damaged(good, r) {
  const n = good.length;
  // Most fields that steer the decoder sit in the header, the section table and the section and
  // plane headers, all near the start of a section: favour offsets there.
  const at = () => (r(2) ? r(Math.min(n, 512)) : r(n));
  switch (r(6)) {
    case 0: return good.slice(0, r(n));
    case 1: { const b = good.slice(); b[at()] ^= 1 << r(8); return b; }
    case 2: { const b = good.slice(); b[at()] = r(256); return b; }
    case 3: { // a 32-bit little-endian field set to an edge value
      const b = good.slice(), o = at() & ~3;
      const edges = [0, 1, 0xffffffff, 0x80000000, 0x7fffffff, 4096, 64, r()];
      if (o + 4 <= n) new DataView(b.buffer).setUint32(o, edges[r(edges.length)], true);
      return b;
    }
    case 4: { const b = good.slice(); for (let k = 0, o = at(); k < 8 && o + k < n; ++k) b[o + k] = r(256); return b; }
    default: { // a page's bytes swapped with another's
      const b = good.slice(), a = at(), c = r(n), len = Math.min(16, n - Math.max(a, c));
      for (let k = 0; k < len; ++k) [b[a + k], b[c + k]] = [b[c + k], b[a + k]];
      return b;
    }
  }
}

/** What web/src makes of the bytes: "error ID" or "ok HASH", as first_error.cpp defines them. */
export function outcome(bytes, checksums) {
  try {
    const file = openVff(bytes, { maxPayloadBytes: MAX_PAYLOAD_BYTES, checksums });
    const { mapCount, mapResolution: M } = file.field;
    const parts = [];
    for (let k = 0; k < mapCount; ++k) {
      const d = file.distances(k);
      const bits = new Uint32Array(M * M);
      const f = new Float32Array(bits.buffer);
      for (let t = 0; t < M * M; ++t) {
        if (Number.isNaN(d[t])) bits[t] = MISS_BITS;
        else f[t] = d[t];
      }
      parts.push(new Uint8Array(bits.buffer));
    }
    if (file.planes.normal) for (let k = 0; k < mapCount; ++k) parts.push(file.mapBytes('normal', k).slice());
    const l = file.layout;
    if (l.sliceWidth * l.sliceHeight * l.sliceCount <= MAX_SLICE_TEXELS)
      for (const name of ['distance', 'normal'])
        if (file.planes[name]) for (let s = 0; s < l.sliceCount; ++s) parts.push(file.slice(name, s));
    return `ok ${xxh3Hex(...parts)}`;
  } catch (e) {
    if (e.id === undefined) return `exception ${String(e.stack ?? e).split('\n').slice(0, 3).join(' | ')}`;
    return `error ${e.id}`;
  }
}

function helperLines(helper, inputs) {
  let out;
  try {
    out = execFileSync(helper, inputs, { encoding: 'utf8', maxBuffer: 1 << 30, stdio: ['ignore', 'pipe', 'inherit'] });
  } catch (e) {
    console.error(`differential.mjs: ${helper} failed: ${e.message}`);
    process.exit(2);
  }
  const lines = out.split('\n').filter((l) => l);
  return lines.map((l) => {
    const cols = l.split('\t');
    return { path: cols.slice(0, -POLICIES.length).join('\t'), cpp: cols.slice(-POLICIES.length) };
  });
}

function main() {
  const o = parseArgs(process.argv.slice(2));
  let work = null;
  const inputs = [...o.inputs];
  try {
    if (o.mutants > 0) {
      work = mkdtempSync(join(tmpdir(), 'vff-differential-'));
      const r = rng(o.seed);
      const vffs = helperLines(o.helper, o.inputs).map((x) => x.path).filter((p) => p.endsWith('.vff'));
      for (const p of vffs) {
        const good = new Uint8Array(readFileSync(p));
        for (let m = 0; m < o.mutants; ++m)
          writeFileSync(join(work, `${basename(p, '.vff')}.m${String(m).padStart(4, '0')}.vff`), mutant(good, r));
      }
      inputs.push(work);
    }
    const results = helperLines(o.helper, inputs);
    const count = {}, bad = [];
    for (const { path, cpp } of results) {
      if (!statSync(path).isFile()) continue;
      const bytes = new Uint8Array(readFileSync(path));
      POLICIES.forEach((policy, k) => {
        if (!o.policies.includes(policy)) return;
        const js = outcome(bytes, policy);
        const kind = `${policy} ${cpp[k].startsWith('ok ') ? 'decoded' : cpp[k]}`;
        count[kind] = (count[kind] ?? 0) + 1;
        if (js !== cpp[k]) bad.push({ path, policy, cpp: cpp[k], js });
      });
    }
    const summary = Object.entries(count).sort().map(([k, v]) => `${k}: ${v}`).join(', ');
    console.log(`compared ${results.length} files, checksums ${o.policies.join(', ')} (libvff: ${summary})`);
    for (const b of bad.slice(0, o.show))
      console.log(`DISAGREE ${b.path} (checksums ${b.policy})\n  libvff: ${b.cpp}\n  web:    ${b.js}`);
    if (bad.length > o.show) console.log(`... and ${bad.length - o.show} more`);
    if (o.save && bad.length) {
      mkdirSync(o.save, { recursive: true });
      for (const b of bad) copyFileSync(b.path, join(o.save, basename(b.path)));
      console.log(`the files they disagree on: ${o.save}`);
    }
    console.log(bad.length ? `${bad.length} disagreements` : 'no disagreements');
    return bad.length ? 1 : 0;
  } finally {
    if (work) rmSync(work, { recursive: true, force: true });
  }
}

await initVff();
process.exitCode = main();
