// summary.js - the text `vff-inspect FILE` prints (tools/vff-inspect/text.cpp), from a decoded
// file: format, sections, field, payload, layout, hit ratio, distance histogram, refinement and metadata. A
// partial result (spec/partial.md) says so, and its statistics count only its range's maps.
import { ENCODING_NAMES, POSITION_NAMES, DIRECTION_NAMES } from './container.js';
import { partialRange } from './meta.js';

const HISTOGRAM_BINS = 16;     // vff-inspect's default --histogram-bins

/** printf's %.*f: like toFixed, but an exact tie rounds to even, as C's printf does. */
function fixed(v, d) {
  const x = v * 10 ** d;
  if (Math.abs(x - Math.trunc(x)) === 0.5 && Number.isFinite(x)) {
    const t = Math.trunc(x), r = t % 2 === 0 ? t : t + Math.sign(x);
    return (r / 10 ** d).toFixed(d);
  }
  return v.toFixed(d);
}
const bytes = (b) => `${b} bytes (${fixed(b / 1048576, 3)} MiB)`;
const hex = (v) => `0x${v.toString(16)}`;
const lpad = (s, n) => String(s).padStart(n);
const rpad = (s, n) => String(s).padEnd(n);
/** printf's %.9g. */
function g9(v) {
  if (v === 0) return '0';
  const e = Math.floor(Math.log10(Math.abs(v)));
  if (e < -5 || e >= 9) return v.toExponential(8).replace(/\.?0+e/, 'e').replace(/e([+-])(\d)$/, 'e$10$2');
  return String(Number(v.toPrecision(9)));
}
/** JSON text with sorted keys and 2-space indent, as nlohmann::json's dump(2). */
function dump(v, ind = '') {
  if (Array.isArray(v)) return v.length ? `[\n${v.map((x) => `${ind}  ${dump(x, `${ind}  `)}`).join(',\n')}\n${ind}]` : '[]';
  if (v && typeof v === 'object') {
    const keys = Object.keys(v).sort((a, b) => (a < b ? -1 : a > b ? 1 : 0));
    return keys.length ? `{\n${keys.map((k) => `${ind}  ${JSON.stringify(k)}: ${dump(v[k], `${ind}  `)}`).join(',\n')}\n${ind}}` : '{}';
  }
  return JSON.stringify(v);
}

function featureNames(v, known) {
  const out = [];
  for (let b = 0; b < 64 && 2 ** b <= v; ++b) if (Math.floor(v / 2 ** b) % 2) out.push(known[b] ?? `bit ${b}`);
  return out.join(', ') || 'none';
}

function planeLines(file, name, p) {
  if (!p) return [`  ${rpad(name, 8)} absent`];
  const raw = p.mapCount * p.mapBytes, stored = p.blocks.reduce((a, b) => a + b.storedSize, 0);
  const count = (f) => {
    const m = new Map();
    for (const b of p.blocks) m.set(f(b), (m.get(f(b)) ?? 0) + 1);
    return [...m].sort((a, b) => (a[0] < b[0] ? -1 : 1)).map(([k, n]) => `${k} ${n}`).join(', ');
  };
  const last = p.mapCount - (p.blockCount - 1) * p.mapsPerBlock;
  const out = [
    `  ${rpad(name, 8)} ${bytes(raw)} raw, ${p.mapBytes} bytes per map`,
    `           stored ${bytes(stored)}, compression ratio ${fixed((raw / stored), 3)} (raw/stored)`,
    `           ${p.blockCount} block${p.blockCount === 1 ? '' : 's'}, ${p.mapsPerBlock} maps per block (last block ${last}), codecs: ${count((b) => (b.codec ? 'zstd' : 'stored'))}; filters: ${count((b) => (b.filter ? 'hits-med' : 'none'))}`,
  ];
  const sizes = p.blocks.map((b) => b.storedSize);
  if (sizes.length <= 32) out.push(`           block stored bytes: ${sizes.map((s, i) => (i === 0 ? '' : i % 8 === 0 ? ',\n                                ' : ', ') + s).join('')}`);
  else {
    sizes.sort((a, b) => a - b);
    out.push(`           block stored bytes: min ${sizes[0]}, median ${sizes[sizes.length >> 1]}, max ${sizes[sizes.length - 1]} (--format json lists every block)`);
  }
  const L = file.layout, e = file.field.distanceEncoding;
  const texels = L.sliceWidth * L.sliceHeight;
  const slice = name === 'normal' ? 4 * texels : e === 3 ? 2 * texels : e === 4 ? texels / 8 : e === 5 ? texels / 2 : texels;
  out.push(`           slice ${bytes(slice)}`);
  return out;
}

function histogramLines(file, partial) {
  const f = file.field, e = f.distanceEncoding;
  let hits = 0, texels = 0;
  const bins = new Array(HISTOGRAM_BINS).fill(0);
  const diameter = 2 * f.sphere.radius;
  const ranged = partial && partial.mapBegin !== null;
  for (let k = ranged ? partial.mapBegin : 0; k < (ranged ? partial.mapEnd : f.mapCount); ++k) {
    const d = file.distances(k);
    texels += d.length;
    for (const v of d) {
      if (Number.isNaN(v)) continue;
      ++hits;
      if (e === 4) continue;
      const x = (v / diameter) * HISTOGRAM_BINS;
      ++bins[!(x > 0) ? 0 : x >= HISTOGRAM_BINS ? HISTOGRAM_BINS - 1 : Math.floor(x)];
    }
  }
  const ratio = hits / texels;
  const out = ['', `hits:        ${hits} of ${texels} texels, hit ratio ${fixed(ratio, 6)} (${fixed((100 * ratio), 3)} %)`];
  if (ranged) out.push(`             (maps ${partial.mapBegin}:${partial.mapEnd} only: the others are fillers, not the field's)`);
  out.push('');
  if (e === 4) {
    out.push(`histogram:   hits only (bit1 stores no distance): ${hits} hits, ${texels - hits} misses`);
    return out;
  }
  out.push(`distance histogram (${HISTOGRAM_BINS} bins over [0, 2R] = [0, ${g9(diameter)}]):`);
  out.push(`  ${rpad('distance', 22)}  ${rpad('of 2R', 15)}  ${lpad('hits', 12)}  ${lpad('share', 8)}`);
  for (let i = 0; i < HISTOGRAM_BINS; ++i) {
    const lo = i / HISTOGRAM_BINS, hi = (i + 1) / HISTOGRAM_BINS;
    const share = hits ? bins[i] / hits : 0;
    const bar = '#'.repeat(Math.floor(share * 40 + 0.5));
    out.push(`  ${rpad(`[${fixed((lo * diameter), 4)}, ${fixed((hi * diameter), 4)})`, 22)}  ${rpad(`${fixed(lo, 3)}-${fixed(hi, 3)}`, 15)}  ${lpad(bins[i], 12)}  ${lpad(fixed((100 * share), 2), 7)}%${bar ? `  ${bar}` : ''}`);
  }
  return out;
}

/** The summary of an opened file, named `name`, line for line as vff-inspect prints it. */
export function summary(file, name) {
  const h = file.header, f = file.field, L = file.layout;
  const partial = partialRange(file.metadata?.value ?? null, f.mapCount, file.metadata?.text);
  const out = [
    `file:        ${name}`,
    `format:      vff ${h.versionMajor}.${h.versionMinor}, ${bytes(h.fileSize)}`,
    `features:    incompat ${hex(h.incompatFeatures)} (${featureNames(h.incompatFeatures, ['zstd', 'filters', 'bc4'])}), roCompat ${hex(h.roCompatFeatures)} (${featureNames(h.roCompatFeatures, [])})`,
    `header:      checksum xxh3-64 0x${h.headerChecksum}, verified OK`,
    '',
    `sections (${file.sections.length}):`,
    `  ${rpad('tag', 4)}  ${rpad('flags', 19)}  ${lpad('offset', 10)}  ${lpad('stored', 12)}  ${lpad('raw', 12)}  ${rpad('codec', 6)}  ${lpad('ver', 3)}  ${rpad('checksum', 18)}  status`,
  ];
  for (const s of file.sections) {
    const names = [s.flags & 1 ? 'required' : '', s.flags & 2 ? 'copy-safe' : ''].filter(Boolean).join(', ');
    const flags = hex(s.flags) + (names ? ` ${names}` : '');
    out.push(`  ${rpad(s.tag, 4)}  ${rpad(flags, 19)}  ${lpad(s.offset, 10)}  ${lpad(s.storedSize, 12)}  ${lpad(s.rawSize, 12)}  ${rpad(s.codec ? 'zstd' : 'stored', 6)}  ${lpad(s.sectionVersion, 3)}  ${rpad(`0x${s.checksum}`, 18)}  verified OK${s.known ? '' : ' (unknown tag)'}`);
  }
  out.push('', 'field:',
    `  sphere:     centre (${f.sphere.center.map(g9).join(', ')}), radius ${g9(f.sphere.radius)}`,
    `  positions:  ${POSITION_NAMES[f.positionScheme]}, param ${f.positionParam}, ${f.mapCount} maps`,
    `  directions: ${DIRECTION_NAMES[f.directionScheme]}, map resolution ${f.mapResolution} (${f.mapResolution}x${f.mapResolution} texels)`,
    '  frame:      duff2017',
    `  distance:   ${ENCODING_NAMES[f.distanceEncoding]}, miss code ${f.missCode}`,
    `  normals:    ${f.normalEncoding ? 'oct-snorm16' : 'none'}`,
    ...(!partial ? [] : partial.mapBegin === null
      ? ['  partial:    a partial result whose "vff.partial" gives no usable map range']
      : [`  partial:    maps ${partial.mapBegin}:${partial.mapEnd} of ${partial.mapCount} only (vff-bake --map-range); the others hold misses until vff-bake --merge`]),
    '', 'payload:', ...planeLines(file, 'distance', file.planes.distance), ...planeLines(file, 'normal', file.planes.normal),
    '', 'layout:',
    `  target:    ${L.target === 1 ? '2d-array' : '3d'}`,
    `  tiles:     ${L.tileSize} texels (gutter ${L.gutter}), ${L.tilesPerRow} per row x ${L.tilesPerColumn} per column = ${L.tilesPerRow * L.tilesPerColumn} per slice`,
    `  slices:    ${L.sliceWidth} x ${L.sliceHeight} texels, ${L.sliceCount} slice${L.sliceCount === 1 ? '' : 's'}`,
    `  limits:    max texture size ${L.maxTextureSize}, max layers ${L.maxLayers}`,
    ...histogramLines(file, partial), '');
  const R = file.refinement;
  if (R) {  // REFN (format 1.3)
    const texels = f.mapCount * f.mapResolution * f.mapResolution;
    out.push(`refinement:  ${R.unsureTexels} unsure texels (${fixed(texels > 0 ? 100 * R.unsureTexels / texels : 0, 2)}%), ` +
      `margin ${fixed(R.margin, 4)} R; exact step: ${R.positions.length / 3} vertices, ${R.indices.length / 3} triangles`, '');
  }
  out.push(file.metadata ? `metadata:\n${dump(file.metadata.value)}` : 'metadata: none');
  return out.join('\n');
}
