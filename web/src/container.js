// container.js - opening a .vff: the header, the section table, FDSC, LAYT, the plane indexes, META
// and REFN (1.3), checked in the order of spec/validation.md sections 4 to 8 (a first-error reader),
// plus the validator-only checks of section 9 (padding, block decoding, normals of misses) on request.
import { ByteReader, alignUp, hex64 } from './bytes.js';
import { xxh3Hex } from './checksum.js';
import { VffError, require } from './errors.js';
import { sampleCount } from './positions.js';
import { decodeFrame } from './zstd.js';
import { checkJsonText } from './meta.js';
import { VffFile } from './file.js';

export const MAGIC = [0x89, 0x56, 0x46, 0x46, 0x0d, 0x0a, 0x1a, 0x0a];
/** Tag -> its defined flags (format.md section 3). */
const KNOWN = { FDSC: 1, LAYT: 1, META: 2, DIST: 1, NORM: 0, REFN: 0 };
const PLANES = new Set(['DIST', 'NORM']);

/** The reader limits of spec/validation.md section 10, and the checksum policy. */
export const DEFAULT_READ_OPTIONS = Object.freeze({
  maxSections: 64,
  maxMaps: 2 ** 24,
  maxMapResolution: 4096,
  maxPayloadBytes: 2 ** 36,
  maxSectionBytes: 64 * 2 ** 20,
  maxBlockBytes: 64 * 2 ** 20,
  checksums: 'verify-all',          // 'verify-all' | 'lazy' | 'none'
});

export const ENCODING_NAMES = { 1: 'unorm8-diameter', 2: 'unorm8-chord', 3: 'unorm16-diameter', 4: 'bit1', 5: 'bc4-diameter' };
export const POSITION_NAMES = { 1: 'octa-hemi2', 2: 'ea-octa-grid', 3: 'fibonacci' };
export const DIRECTION_NAMES = { 1: 'concentric-equal-area', 2: 'hemi-octahedral' };
export const MISS_CODES = { 1: 255, 2: 255, 3: 65535, 4: 0, 5: 255 };

/** Raw bytes per distance map of encoding e, resolution M (format.md 7.1). */
export function distanceMapBytes(e, M) {
  const t = M * M;
  return e === 3 ? 2 * t : e === 4 ? t / 8 : e === 5 ? t / 2 : t;
}

function num(v) { return Number(v); }

function readHeader(r, opt, warnings) {
  const n = r.length;
  require(n >= 64, 2001, `the file has ${n} bytes, fewer than the 64 of a header`, { offset: 0 });
  require(MAGIC.every((b, i) => r.u8(i) === b), 2002, 'not a .vff file (bad magic)', { offset: 0 });
  const versionMajor = r.u16(8);
  require(versionMajor === 1, 2003, `versionMajor ${versionMajor}, this reader knows 1`, { offset: 8 });
  require(r.u32(12) === 64, 3001, `headerSize ${r.u32(12)}, expected 64`, { offset: 12 });
  const incompat = r.u64(24);
  if (incompat & ~7n) {
    let bit = 3;
    while (!((incompat >> BigInt(bit)) & 1n)) ++bit;
    throw new VffError(2004, `unknown incompatible feature bit ${bit}`, { offset: 24 });
  }
  const roCompat = r.u64(32);
  if (roCompat !== 0n) warnings.push(new VffError(3008, 'unknown read-only-compatible feature bits', { offset: 32 }));
  const fileSize = r.u64(16);
  require(fileSize === BigInt(n), 3002, `fileSize ${fileSize}, the file has ${n} bytes`, { offset: 16 });
  require(r.u8(54) === 1, 3004, `checksumAlgorithm ${r.u8(54)}, expected 1 (XXH3-64)`, { offset: 54 });
  require(r.u8(55) === 0, 3003, 'reserved header byte 55 is not zero', { offset: 55 });
  require(r.u16(52) === 64, 3006, `sectionEntrySize ${r.u16(52)}, expected 64`, { offset: 52 });
  const count = r.u32(48);
  require(count >= 1 && count <= opt.maxSections, 3007, `sectionCount ${count} not in 1..${opt.maxSections}`, { offset: 48 });
  const tableOffset = r.u64(40);
  require(tableOffset >= 64n && BigInt(count) * 64n <= BigInt(n) - tableOffset && tableOffset <= BigInt(n), 3006,
    `the section table (offset ${tableOffset}, ${count} entries) does not lie inside the file`, { offset: 40 });
  const to = num(tableOffset);
  const sum = xxh3Hex(r.bytes.subarray(0, 56), r.bytes.subarray(to, to + 64 * count));
  require(sum === hex64(r.u64(56)), 3005, `headerChecksum ${hex64(r.u64(56))}, computed ${sum}`, { offset: 56 });
  return {
    versionMajor, versionMinor: r.u16(10), fileSize: n, incompatFeatures: num(incompat), headerChecksum: hex64(r.u64(56)),
    roCompatFeatures: num(roCompat), sectionTableOffset: to, sectionCount: count, checksumAlgorithm: 1,
  };
}

function readSectionTable(r, header, opt) {
  const n = BigInt(r.length);
  const sections = [];
  const byTag = {};
  let prevEnd = BigInt(header.sectionTableOffset + 64 * header.sectionCount);
  for (let i = 0; i < header.sectionCount; ++i) {
    const e = header.sectionTableOffset + 64 * i;
    const tag = r.fourcc(e);
    const flags = r.u32(e + 4), offset = r.u64(e + 8), storedSize = r.u64(e + 16), rawSize = r.u64(e + 24);
    const codec = r.u16(e + 32), version = r.u16(e + 34);
    const known = tag in KNOWN;
    const where = (d) => ({ section: tag, offset: e + d });
    require(!(flags & ~3) && (!known || flags === KNOWN[tag]), 4009, `flags ${flags} of ${tag}`, where(4));
    require(r.zero(e + 36, 4) && r.zero(e + 48, 16), 4009, 'reserved bytes of the entry are not zero', where(36));
    require(known || !(flags & 1), 4004, `unknown section ${JSON.stringify(tag)} is REQUIRED`, where(0));
    require(!known || version === 1, 4013, `sectionVersion ${version}, expected 1`, where(34));
    require(storedSize <= n && offset <= n - storedSize, 4001, `the section [${offset}, +${storedSize}) is not inside the file`, where(8));
    require(offset % 4096n === 0n, 4002, `offset ${offset} is not a multiple of 4096`, where(8));
    require(offset >= prevEnd, 4003, `offset ${offset} is before the end of the previous structure (${prevEnd})`, where(8));
    require(codec <= 1 && !(PLANES.has(tag) && codec !== 0), 4007, `codec ${codec}`, where(32));
    require(codec !== 0 || rawSize === storedSize, 4010, `rawSize ${rawSize} differs from storedSize ${storedSize}`, where(24));
    require(!known || PLANES.has(tag) || rawSize <= BigInt(opt.maxSectionBytes), 4014,
      `rawSize ${rawSize} above the reader's limit ${opt.maxSectionBytes}`, where(24));
    require(!(tag in byTag), 4005, `a second ${tag} section`, where(0));
    const s = { tag, flags, offset: num(offset), storedSize: num(storedSize), rawSize: num(rawSize), codec, sectionVersion: version, known, entry: e, checksum: hex64(r.u64(e + 40)) };
    const verify = opt.checksums === 'verify-all' || (opt.checksums === 'lazy' && !PLANES.has(tag));
    if (verify) {
      const sum = xxh3Hex(r.bytes.subarray(s.offset, s.offset + s.storedSize));
      require(sum === s.checksum, 4008, `checksum ${s.checksum}, computed ${sum}`, where(40));
    }
    prevEnd = offset + storedSize;
    sections.push(s);
    byTag[tag] = s;
  }
  if (sections.some((s) => s.codec === 1))
    require(header.incompatFeatures & 1, 6012, 'a section uses zstd but incompatFeatures bit 0 is clear', { offset: 24 });
  for (const t of ['FDSC', 'LAYT', 'DIST']) require(t in byTag, 4006, `no ${t} section`);
  return { sections, byTag };
}

/** The raw bytes of a non-plane section (decoding zstd), or throws 4011. */
function sectionBytes(r, s) {
  const stored = r.bytes.subarray(s.offset, s.offset + s.storedSize);
  if (s.codec === 0) return stored;
  const d = decodeFrame(stored, s.rawSize);
  if (d.error) throw new VffError(4011, d.error, { section: s.tag, offset: s.offset });
  return d.bytes;
}

function readField(r, s, header, opt) {
  const b = sectionBytes(r, s);
  require(b.length === 64, 4010, `FDSC holds ${b.length} bytes, expected 64`, { section: 'FDSC', offset: s.entry + 24 });
  const f = new ByteReader(b);
  const at = (o) => ({ section: 'FDSC', offset: s.codec === 0 ? s.offset + o : -1 });
  require(f.zero(52, 12), 5010, 'reserved FDSC bytes 52-63 are not zero', at(52));
  const center = [f.f32(0), f.f32(4), f.f32(8)], radius = f.f32(12);
  require(center.every(Number.isFinite) && Number.isFinite(radius) && radius > 0, 5001, `sphere (${center}; ${radius})`, at(0));
  const scheme = f.u32(16), n = f.u32(20), mapCount = f.u32(24), dirs = f.u32(28), M = f.u32(32);
  const frame = f.u32(36), enc = f.u32(40), missCode = f.u32(44), normalEncoding = f.u32(48);
  const nMax = { 1: 1024, 2: 2048, 3: 2 ** 24 }[scheme];
  require(nMax !== undefined && n >= 1 && n <= nMax, 5002, `positionScheme ${scheme} with n = ${n}`, at(16));
  require(mapCount === sampleCount(scheme, n), 5003, `mapCount ${mapCount}, the scheme has ${sampleCount(scheme, n)}`, at(24));
  require(dirs === 1 || dirs === 2, 5004, `directionScheme ${dirs}`, at(28));
  require(frame === 1, 5006, `frame ${frame}`, at(36));
  require(enc >= 1 && enc <= 5, 5007, `distanceEncoding ${enc}`, at(40));
  require(M >= 1 && M <= 16384 && !(enc === 4 && M % 8) && !(enc === 5 && M % 4), 5005, `mapResolution ${M}`, at(32));
  require(normalEncoding <= 1, 5009, `normalEncoding ${normalEncoding}`, at(48));
  require(missCode === MISS_CODES[enc], 5008, `missCode ${missCode}, ${ENCODING_NAMES[enc]} uses ${MISS_CODES[enc]}`, at(44));
  if (enc === 5) require(header.incompatFeatures & 4, 6012, 'bc4-diameter without incompatFeatures bit 2', { offset: 24 });
  require(mapCount <= opt.maxMaps, 5003, `mapCount ${mapCount} above the reader's limit`, at(24));
  require(M <= opt.maxMapResolution, 5005, `mapResolution ${M} above the reader's limit`, at(32));
  const payload = mapCount * (distanceMapBytes(enc, M) + (normalEncoding ? 4 * M * M : 0));
  require(payload <= opt.maxPayloadBytes, 5011, `${payload} bytes of maps above the reader's limit`, at(24));
  return {
    sphere: { center, radius }, positionScheme: scheme, positionParam: n, mapCount, directionScheme: dirs,
    mapResolution: M, frame, distanceEncoding: enc, missCode, normalEncoding,
  };
}

function readLayout(r, s, field) {
  const b = sectionBytes(r, s);
  require(b.length === 64, 4010, `LAYT holds ${b.length} bytes, expected 64`, { section: 'LAYT', offset: s.entry + 24 });
  const l = new ByteReader(b);
  const at = (o) => ({ section: 'LAYT', offset: s.codec === 0 ? s.offset + o : -1 });
  require(l.zero(40, 24), 7004, 'reserved LAYT bytes 40-63 are not zero', at(40));
  const L = {
    target: l.u32(0), gutter: l.u32(4), tileSize: l.u32(8), tilesPerRow: l.u32(12), tilesPerColumn: l.u32(16),
    sliceWidth: l.u32(20), sliceHeight: l.u32(24), sliceCount: l.u32(28), maxTextureSize: l.u32(32), maxLayers: l.u32(36),
  };
  const enc = field.distanceEncoding;
  require((L.target === 1 || L.target === 2) && !(enc === 5 && L.target !== 1), 7001, `target ${L.target}`, at(0));
  require(!((enc === 4 || enc === 5) && L.gutter !== 0), 7002, `gutter ${L.gutter} for ${ENCODING_NAMES[enc]}`, at(4));
  require(L.tileSize === field.mapResolution + 2 * L.gutter, 7002, `tileSize ${L.tileSize}`, at(4));
  require(L.gutter <= 64, 7002, `gutter ${L.gutter} above 64`, at(4));
  require(L.tilesPerRow >= 1 && L.tilesPerColumn >= 1, 7003, 'no tiles per row or column', at(12));
  require(L.sliceWidth === L.tilesPerRow * L.tileSize && L.sliceHeight === L.tilesPerColumn * L.tileSize, 7003, 'slice size is not tiles x tileSize', at(12));
  require(L.sliceCount === Math.ceil(field.mapCount / (L.tilesPerRow * L.tilesPerColumn)), 7003, `sliceCount ${L.sliceCount}`, at(12));
  require(L.maxTextureSize === 0 || (L.sliceWidth <= L.maxTextureSize && L.sliceHeight <= L.maxTextureSize), 7003, 'slices above maxTextureSize', at(12));
  require(L.maxLayers === 0 || L.sliceCount <= L.maxLayers, 7003, 'sliceCount above maxLayers', at(12));
  return L;
}

function readPlane(r, s, field, header, opt, isDist) {
  const tag = s.tag, so = s.offset;
  const at = (o) => ({ section: tag, offset: so + o });
  require(s.storedSize >= 32, 6001, 'the section is shorter than a plane header', at(0));
  require(r.zero(so + 16, 16), 6001, 'reserved plane-header bytes are not zero', at(16));
  const mapCount = r.u32(so), mapBytes = r.u32(so + 4), G = r.u32(so + 8), blockCount = r.u32(so + 12);
  const M = field.mapResolution;
  const expectBytes = isDist ? distanceMapBytes(field.distanceEncoding, M) : 4 * M * M;
  require(mapCount === field.mapCount && mapBytes === expectBytes && G >= 1 && G <= mapCount &&
    blockCount === Math.ceil(mapCount / G) && G * mapBytes <= 2 ** 32 - 1, 6001,
    `plane header (${mapCount} maps of ${mapBytes} bytes, ${G} per block, ${blockCount} blocks)`, at(0));
  require(32 + 32 * blockCount <= s.storedSize, 6003, 'the block index does not fit in the section', at(12));
  const blocks = [];
  let pos = alignUp(32 + 32 * blockCount, 64);
  let limitReported = false;
  for (let b = 0; b < blockCount; ++b) {
    const w = so + 32 + 32 * b;
    const wat = (d) => ({ section: tag, offset: w + d });
    const offset = r.u64(w), storedSize = r.u64(w + 8), rawSize = r.u32(w + 16);
    const codec = r.u8(w + 20), filter = r.u8(w + 21);
    require(r.u16(w + 22) === 0, 6011, 'reserved block-entry bytes are not zero', wat(22));
    const size = BigInt(s.storedSize);
    require(storedSize <= size && offset <= size - storedSize, 6003, `block ${b} is not inside the section`, wat(0));
    require(offset % 64n === 0n, 6004, `block ${b} offset ${offset} is not a multiple of 64`, wat(0));
    require(Number(offset) === pos, 6005, `block ${b} at ${offset}, expected ${pos}`, wat(0));
    const maps = Math.min(G, mapCount - b * G);
    require(rawSize === maps * mapBytes, 6006, `block ${b} rawSize ${rawSize}, expected ${maps * mapBytes}`, wat(16));
    if (rawSize > opt.maxBlockBytes && !limitReported) {
      limitReported = true;
      throw new VffError(5011, `block ${b} rawSize above the reader's limit`, wat(16));
    }
    require(codec <= 1, 6007, `block ${b} codec ${codec}`, wat(20));
    require(codec !== 0 || Number(storedSize) === rawSize, 6007, `stored block ${b} storedSize ${storedSize} != rawSize ${rawSize}`, wat(8));
    if (codec === 1) require(header.incompatFeatures & 1, 6012, 'a zstd block without incompatFeatures bit 0', wat(20));
    require(filter <= 1, 6008, `block ${b} filter ${filter}`, wat(21));
    if (filter === 1) {
      require(isDist && (field.distanceEncoding === 1 || field.distanceEncoding === 2), 6008, 'hits-med on a plane that is not unorm8 distances', wat(21));
      require(codec === 1, 6008, 'hits-med on a block that is not zstd', wat(21));
      require(header.incompatFeatures & 2, 6012, 'a filtered block without incompatFeatures bit 1', wat(21));
    }
    const blk = { offset: so + Number(offset), storedSize: Number(storedSize), rawSize, codec, filter, checksum: hex64(r.u64(w + 24)), entry: w, verified: false };
    if (opt.checksums === 'verify-all') verifyBlock(r, blk, tag, b);
    blocks.push(blk);
    pos = alignUp(Number(offset) + blk.storedSize, 64);
  }
  const last = blocks[blocks.length - 1];
  require(last.offset - so + last.storedSize === s.storedSize, 6005, 'the last block does not end at the section end', at(last.offset - so + last.storedSize));
  return { tag, offset: so, mapCount, mapBytes, mapsPerBlock: G, blockCount, blocks };
}

export function verifyBlock(r, blk, tag, b) {
  if (blk.verified) return;
  const sum = xxh3Hex(r.bytes.subarray(blk.offset, blk.offset + blk.storedSize));
  require(sum === blk.checksum, 6009, `block ${b} checksum ${blk.checksum}, computed ${sum}`, { section: tag, offset: blk.entry + 24 });
  blk.verified = true;
}

function readMeta(r, s) {
  const b = sectionBytes(r, s);
  const bad = checkJsonText(b);
  if (bad) throw new VffError(8001, `${bad.message} at byte ${bad.offset} of the text`, { section: 'META', offset: s.offset });
  const text = new TextDecoder('utf-8').decode(b);
  const value = JSON.parse(text);
  require(value !== null && typeof value === 'object' && !Array.isArray(value), 8002, 'the metadata is not a JSON object', { section: 'META', offset: s.offset });
  return { text, value };
}

/**
 * REFN (format.md section 14, rules 8501-8503 in the order of validation.md): the margin, the count
 * and bytes of unsure bits (texel (k * M + j) * M + i at bit x % 8 of byte x / 8), the vertex
 * positions and the triangles' indices. Problems are at the byte for a stored section, else at it.
 */
function readRefinement(r, s, field) {
  const b = sectionBytes(r, s);
  const at = (o) => ({ section: 'REFN', offset: s.codec === 0 ? s.offset + o : s.offset });
  require(field.distanceEncoding !== 4, 8501, 'a bit1 field has no distances to refine: it cannot have REFN', at(0));
  require(b.length >= 64, 8501, `REFN holds ${b.length} bytes, less than its 64-byte header`, at(0));
  const h = new ByteReader(b);
  require(h.u32(0) === 64, 8501, `headerSize ${h.u32(0)}, expected 64`, at(0));
  const V = h.u32(4), T = h.u32(8), margin = h.f32(12), unsureTexels = h.u32(16);
  require(V >= 3 && T >= 1, 8501, `vertexCount ${V} and triangleCount ${T}: at least 3 and 1`, at(4));
  require(Number.isFinite(margin) && margin >= 0, 8501, `margin ${margin} is not a finite number >= 0`, at(12));
  for (let o = 20; o < 64; ++o) require(b[o] === 0, 8501, 'reserved REFN header bytes are not zero', at(o));
  const texels = field.mapCount * field.mapResolution * field.mapResolution;
  const U = Math.ceil(texels / 8), posAt = 64 + alignUp(U, 4), idxAt = posAt + 12 * V, size = idxAt + 12 * T;
  require(b.length === size, 8501, `REFN holds ${b.length} bytes; its header and the field give ${size}`, at(4));
  let set = 0;
  for (let i = 0; i < U; ++i) {
    const v = b[64 + i];
    require(!(i === U - 1 && texels % 8 && v >> (texels % 8)), 8502, 'bits past the last texel are not zero', at(64 + i));
    for (let x = v; x; x &= x - 1) ++set;
  }
  for (let o = 64 + U; o < posAt; ++o) require(b[o] === 0, 8502, 'padding after the unsure bits is not zero', at(o));
  require(set === unsureTexels, 8502, `unsureTexels ${unsureTexels}, ${set} bits are set`, at(16));
  const positions = new Float32Array(3 * V), indices = new Uint32Array(3 * T);
  for (let i = 0; i < 3 * V; ++i) positions[i] = h.f32(posAt + 4 * i);
  const c = field.sphere.center, lim = field.sphere.radius * (1 + 1e-4) + 1e-6;
  for (let v = 0; v < V; ++v) {
    const x = positions[3 * v] - c[0], y = positions[3 * v + 1] - c[1], z = positions[3 * v + 2] - c[2];
    require(Number.isFinite(x) && Number.isFinite(y) && Number.isFinite(z) && x * x + y * y + z * z <= lim * lim, 8503,
      `vertex ${v} is not finite or lies outside the field's bounding sphere`, at(posAt + 12 * v));
  }
  for (let i = 0; i < 3 * T; ++i) {
    indices[i] = h.u32(idxAt + 4 * i);
    require(indices[i] < V, 8503, `triangle ${Math.floor(i / 3)} names vertex ${indices[i]} of ${V}`, at(idxAt + 4 * i));
  }
  return { margin, unsureTexels, unsure: b.slice(64, 64 + U), positions, indices };
}

/**
 * Opens a .vff held in memory: runs every reader check of spec/validation.md sections 4 to 8 and
 * throws the first problem as a VffError. Blocks are decoded when first read (rule 6010 then).
 * Requires `await initChecksums()` first.
 * @param {Uint8Array|ArrayBuffer} data
 * @param {Partial<typeof DEFAULT_READ_OPTIONS>} [options]
 * @returns {VffFile}
 */
export function openVff(data, options = {}) {
  const opt = { ...DEFAULT_READ_OPTIONS, ...options };
  const bytes = data instanceof Uint8Array ? data : new Uint8Array(data);
  const r = new ByteReader(bytes);
  const warnings = [];
  const header = readHeader(r, opt, warnings);
  const { sections, byTag } = readSectionTable(r, header, opt);
  const field = readField(r, byTag.FDSC, header, opt);
  const layout = readLayout(r, byTag.LAYT, field);
  const planes = { distance: readPlane(r, byTag.DIST, field, header, opt, true) };
  require((field.normalEncoding !== 0) === ('NORM' in byTag), 6002,
    field.normalEncoding ? 'normalEncoding is set but there is no NORM section' : 'a NORM section without normalEncoding');
  if (byTag.NORM) planes.normal = readPlane(r, byTag.NORM, field, header, opt, false);
  const metadata = byTag.META ? readMeta(r, byTag.META) : null;
  const refinement = byTag.REFN ? readRefinement(r, byTag.REFN, field) : null;
  return new VffFile({ reader: r, options: opt, header, sections, field, layout, planes, metadata, refinement, warnings });
}
