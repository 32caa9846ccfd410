// inspect_json.js - the summary as `vff-inspect FILE --format json` gives it (tools/vff-inspect/
// summary.cpp): the format, field, layout, sections and metadata the decoder reads. The payload
// statistics (planes, histogram, hits) are vff-inspect's alone and are left out.
import { ENCODING_NAMES, POSITION_NAMES, DIRECTION_NAMES } from '../container.js';

const FEATURES = ['zstd', 'filters', 'bc4'];
const names = (v, known) => {
  const out = [];
  for (let b = 0; b < 53 && 2 ** b <= v; ++b) if (Math.floor(v / 2 ** b) % 2) out.push(known[b] ?? `bit ${b}`);
  return out;
};

/** The JSON object (sorted keys when serialised by the caller) for an opened file named `name`. */
export function inspectJson(file, name) {
  const h = file.header, f = file.field, L = file.layout;
  const num = (v) => Number(v);
  return {
    file: name,
    format: {
      checksumAlgorithm: 'xxh3-64',
      fileSize: num(h.fileSize),
      headerChecksum: `0x${h.headerChecksum}`,
      headerChecksumStatus: 'verified',
      incompatFeatures: { names: names(num(h.incompatFeatures), FEATURES), value: num(h.incompatFeatures) },
      roCompatFeatures: { names: names(num(h.roCompatFeatures), []), value: num(h.roCompatFeatures) },
      version: `${h.versionMajor}.${h.versionMinor}`,
      versionMajor: h.versionMajor,
      versionMinor: h.versionMinor,
    },
    field: {
      directionScheme: DIRECTION_NAMES[f.directionScheme],
      distanceEncoding: ENCODING_NAMES[f.distanceEncoding],
      frame: 'duff2017',
      mapCount: f.mapCount,
      mapResolution: f.mapResolution,
      missCode: f.missCode,
      normalEncoding: f.normalEncoding ? 'oct-snorm16' : 'none',
      positionParam: f.positionParam,
      positionScheme: POSITION_NAMES[f.positionScheme],
      sphere: { center: [...f.sphere.center], radius: f.sphere.radius },
    },
    layout: {
      gutter: L.gutter, maxLayers: L.maxLayers, maxTextureSize: L.maxTextureSize, sliceCount: L.sliceCount,
      sliceHeight: L.sliceHeight, sliceWidth: L.sliceWidth, target: L.target === 1 ? '2d-array' : '3d',
      tileSize: L.tileSize, tilesPerColumn: L.tilesPerColumn, tilesPerRow: L.tilesPerRow, tilesPerSlice: L.tilesPerRow * L.tilesPerColumn,
    },
    metadata: file.metadata ? file.metadata.value : null,
    sections: file.sections.map((s) => ({
      checksum: `0x${s.checksum}`, checksumStatus: 'verified', codec: s.codec ? 'zstd' : 'stored',
      flagNames: [s.flags & 1 ? 'required' : '', s.flags & 2 ? 'copy-safe' : ''].filter(Boolean), flags: s.flags,
      known: s.known, offset: s.offset, rawSize: s.rawSize, sectionVersion: s.sectionVersion, storedSize: s.storedSize, tag: s.tag,
    })),
  };
}

/** JSON text with sorted keys, 2-space indent (as vff-inspect's nlohmann::json dump(2)). */
export function jsonText(v) {
  const sort = (x) => Array.isArray(x) ? x.map(sort) : x && typeof x === 'object'
    ? Object.fromEntries(Object.keys(x).sort().map((k) => [k, sort(x[k])])) : x;
  return `${JSON.stringify(sort(v), null, 2)}\n`;
}
