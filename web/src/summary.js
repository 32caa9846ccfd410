// summary.js - the text `vff-inspect FILE` prints (its main parts), from a decoded file.
import { ENCODING_NAMES, POSITION_NAMES, DIRECTION_NAMES } from './container.js';

const mib = (b) => (b / 1048576).toFixed(3);
const pad = (s, n) => String(s).padEnd(n);
const lpad = (s, n) => String(s).padStart(n);

/** The summary of an opened file, named `name`. */
export function summary(file, name) {
  const h = file.header, f = file.field, L = file.layout;
  const bits = (v, names) => names.filter((_, i) => v & (1 << i)).join(', ') || 'none';
  const out = [];
  out.push(`file:        ${name}`);
  out.push(`format:      vff ${h.versionMajor}.${h.versionMinor}, ${h.fileSize} bytes (${mib(h.fileSize)} MiB)`);
  out.push(`features:    incompat 0x${h.incompatFeatures.toString(16)} (${bits(h.incompatFeatures, ['zstd', 'filters', 'bc4'])}), roCompat 0x${h.roCompatFeatures.toString(16)} (none)`);
  out.push(`header:      checksum xxh3-64, verified OK`, '');
  out.push(`sections (${file.sections.length}):`);
  out.push('  tag   flags                    offset        stored           raw  codec   ver  checksum            status');
  const fl = (v) => `0x${v.toString(16)} ${['', 'required', 'copy-safe', 'required copy-safe'][v & 3]}`;
  for (const s of file.sections)
    out.push(`  ${pad(s.tag, 6)}${pad(fl(s.flags), 19)}${lpad(s.offset, 12)}${lpad(s.storedSize, 14)}${lpad(s.rawSize, 14)}  ${pad(s.codec ? 'zstd' : 'stored', 6)}${lpad(s.sectionVersion, 4)}  0x${s.checksum}  ${s.known ? 'verified OK' : 'unknown, skipped'}`);
  out.push('', 'field:');
  out.push(`  sphere:     centre (${f.sphere.center.map((v) => +v.toPrecision(9)).join(', ')}), radius ${+f.sphere.radius.toPrecision(9)}`);
  out.push(`  positions:  ${POSITION_NAMES[f.positionScheme]}, param ${f.positionParam}, ${f.mapCount} maps`);
  out.push(`  directions: ${DIRECTION_NAMES[f.directionScheme]}, map resolution ${f.mapResolution} (${f.mapResolution}x${f.mapResolution} texels)`);
  out.push('  frame:      duff2017');
  out.push(`  distance:   ${ENCODING_NAMES[f.distanceEncoding]}, miss code ${f.missCode}`);
  out.push(`  normals:    ${f.normalEncoding ? 'oct-snorm16' : 'none'}`, '', 'payload:');
  for (const [name, p] of Object.entries(file.planes)) {
    const raw = p.mapCount * p.mapBytes, stored = p.blocks.reduce((a, b) => a + b.storedSize, 0);
    const codecs = p.blocks.filter((b) => b.codec).length, filt = p.blocks.filter((b) => b.filter).length;
    out.push(`  ${pad(name, 9)}${raw} bytes (${mib(raw)} MiB) raw, ${p.mapBytes} bytes per map`);
    out.push(`           stored ${stored} bytes (${mib(stored)} MiB), compression ratio ${(raw / stored).toFixed(3)} (raw/stored)`);
    out.push(`           ${p.blockCount} blocks, ${p.mapsPerBlock} maps per block, codecs: ${codecs ? `zstd ${codecs}` : ''}${codecs && codecs < p.blockCount ? ', ' : ''}${codecs < p.blockCount ? `stored ${p.blockCount - codecs}` : ''}; filters: ${filt ? `hits-med ${filt}, ` : ''}none ${p.blockCount - filt}`);
  }
  out.push('', 'layout:');
  out.push(`  target:    ${L.target === 1 ? '2d-array' : '3d'}`);
  out.push(`  tiles:     ${L.tileSize} texels (gutter ${L.gutter}), ${L.tilesPerRow} per row x ${L.tilesPerColumn} per column = ${L.tilesPerRow * L.tilesPerColumn} per slice`);
  out.push(`  slices:    ${L.sliceWidth} x ${L.sliceHeight} texels, ${L.sliceCount} slice${L.sliceCount > 1 ? 's' : ''}`);
  out.push(`  limits:    max texture size ${L.maxTextureSize}, max layers ${L.maxLayers}`, '');
  let hits = 0, total = 0;
  const miss = f.distanceEncoding === 4 ? 0 : f.missCode;
  for (let k = 0; k < f.mapCount; ++k) {
    const c = file.codes(k);
    for (let t = 0; t < c.length; ++t) hits += c[t] !== miss;
    total += c.length;
  }
  out.push(`hits:        ${hits} of ${total} texels, hit ratio ${(hits / total).toPrecision(6)} (${((100 * hits) / total).toFixed(3)} %)`);
  if (file.warnings.length) out.push('', 'warnings:', ...file.warnings.map((w) => `  ${w.message}`));
  out.push('', 'metadata:', file.metadata ? JSON.stringify(file.metadata.value, null, 2) : '(none)');
  return out.join('\n');
}
