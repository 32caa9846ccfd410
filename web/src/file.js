// file.js - an opened .vff: its maps decoded on demand (codecs, filters, encodings), distances and
// normals of texels, composed slices, and the validator-only checks (spec/validation.md section 9).
import { VffError } from './errors.js';
import { decodeFrame } from './zstd.js';
import { hitsMedBound, unfilterHitsMed } from './filters.js';
import { decodeBc4Map } from './bc4.js';
import { texelDirection } from './geometry.js';
import { composeSlice } from './layout.js';
import { verifyBlock } from './container.js';

const f32 = Math.fround;

/** oct-snorm16 texel (X, Y) to the unit normal (format.md 7.3). */
export function decodeNormal(X, Y) {
  const px = Math.max(X / 32767, -1), py = Math.max(Y / 32767, -1);
  let v = [px, py, 1 - Math.abs(px) - Math.abs(py)];
  if (v[2] < 0) v = [(1 - Math.abs(v[1])) * (v[0] >= 0 ? 1 : -1), (1 - Math.abs(v[0])) * (v[1] >= 0 ? 1 : -1), v[2]];
  const l = Math.hypot(v[0], v[1], v[2]);
  return [v[0] / l, v[1] / l, v[2] / l];
}

export class VffFile {
  constructor(parts) {
    Object.assign(this, parts);
    this.blockCache = new Map();
    this.codeCache = new Map();
    this.chordScale = null;
  }

  get bytes() { return this.reader.bytes; }

  /** The decoded bytes of block b of a plane ('distance' or 'normal'); throws 6009/6010. */
  block(planeName, b) {
    const key = `${planeName}:${b}`;
    const hit = this.blockCache.get(key);
    if (hit) return hit;
    const plane = this.planes[planeName];
    const blk = plane.blocks[b];
    if (this.options.checksums === 'lazy') verifyBlock(this.reader, blk, plane.tag, b);
    const stored = this.bytes.subarray(blk.offset, blk.offset + blk.storedSize);
    let raw = stored;
    if (blk.codec === 1) {
      const at = { section: plane.tag, offset: blk.offset };
      const d = decodeFrame(stored, blk.rawSize, blk.filter === 1 ? hitsMedBound(blk.rawSize) : -1);
      if (d.error) throw new VffError(6010, `block ${b}: ${d.error}`, at);
      raw = d.bytes;
      if (blk.filter === 1) {
        const u = unfilterHitsMed(raw, blk.rawSize, this.field.mapResolution);
        if (u.error) throw new VffError(6010, `block ${b}: hits-med: ${u.error}`, at);
        raw = u.bytes;
      }
    }
    // Keep few decoded blocks: a viewer walks maps in order, and a whole field may not fit twice.
    if (this.blockCache.size > 64) this.blockCache.clear();
    this.blockCache.set(key, raw);
    return raw;
  }

  /** The raw stored bytes of map k of a plane (mapBytes long). */
  mapBytes(planeName, k) {
    const plane = this.planes[planeName];
    if (!plane || !(k >= 0 && k < plane.mapCount)) throw new VffError(9002, `no map ${k} in the ${planeName} plane`);
    const G = plane.mapsPerBlock, b = Math.floor(k / G);
    const o = (k - b * G) * plane.mapBytes;
    return this.block(planeName, b).subarray(o, o + plane.mapBytes);
  }

  /** The M*M distance codes of map k (bit1: 0/1; bc4: decoded to unorm8 codes), row-major. */
  codes(k) {
    const M = this.field.mapResolution, e = this.field.distanceEncoding;
    const raw = this.mapBytes('distance', k);
    if (e === 1 || e === 2) return raw;
    if (e === 3) {
      const out = new Uint16Array(M * M);
      for (let t = 0; t < M * M; ++t) out[t] = raw[2 * t] | (raw[2 * t + 1] << 8);
      return out;
    }
    if (e === 4) {
      const out = new Uint8Array(M * M);
      for (let t = 0; t < M * M; ++t) out[t] = (raw[t >> 3] >> (t & 7)) & 1;
      return out;
    }
    return decodeBc4Map(raw, M);
  }

  /** 2R max(cos alpha, 0) / 254 of every texel of a map (unorm8-chord decode scales). */
  chordScales() {
    if (this.chordScale) return this.chordScale;
    const M = this.field.mapResolution, R2 = f32(2 * this.field.sphere.radius);
    const s = new Float32Array(M * M);
    for (let j = 0; j < M; ++j)
      for (let i = 0; i < M; ++i) {
        const c = Math.max(texelDirection(this.field.directionScheme, i, j, M)[2], 0);
        s[j * M + i] = f32(R2 * c);
      }
    return (this.chordScale = s);
  }

  /** Decodes code c of texel t: the distance, null for a miss (bit1: 1 or null). */
  decodeCode(c, t) {
    const e = this.field.distanceEncoding;
    if (e === 4) return c ? 1 : null;
    if (c === this.field.missCode) return null;
    const R2 = f32(2 * this.field.sphere.radius);
    if (e === 3) return f32(f32(c * R2) / 65534);
    const s = e === 2 ? this.chordScales()[t] : R2;
    return f32(f32(c * s) / 254);
  }

  /** The distance of texel (i, j) of map k (object units from the sample point), null for a miss. */
  distance(k, i, j) {
    const M = this.field.mapResolution;
    return this.decodeCode(this.codes(k)[j * M + i], j * M + i);
  }

  /** Every texel's distance of map k (Float32Array, NaN for a miss; bit1: 1 or NaN). */
  distances(k) {
    const c = this.codes(k);
    const out = new Float32Array(c.length);
    for (let t = 0; t < c.length; ++t) out[t] = this.decodeCode(c[t], t) ?? NaN;
    return out;
  }

  /** The unit normal of texel (i, j) of map k (the field must have normals). */
  normal(k, i, j) {
    const M = this.field.mapResolution;
    const raw = this.mapBytes('normal', k);
    const dv = new DataView(raw.buffer, raw.byteOffset + 4 * (j * M + i), 4);
    return decodeNormal(dv.getInt16(0, true), dv.getInt16(2, true));
  }

  /** Slice s of a plane composed as format.md 10.3 says (the bytes a texture upload takes). */
  slice(planeName, s) {
    const e = this.field.distanceEncoding, isDist = planeName === 'distance';
    const plane = isDist
      ? { kind: e === 4 ? 'bit1' : e === 5 ? 'bc4' : 'bytes', texelBytes: e === 3 ? 2 : 1, fill: e === 4 ? 0 : 0xff }
      : { kind: 'bytes', texelBytes: 4, fill: 0 };
    return composeSlice(this.layout, { ...plane, M: this.field.mapResolution, mapCount: this.field.mapCount }, s,
      (k) => this.mapBytes(planeName, k));
  }

  /**
   * The validator-only checks (validation.md section 9): padding (4012), decoding every block
   * (6010) and the normals of misses (6013). Throws the first problem.
   */
  validateDeep() {
    this.checkPadding();
    for (const name of Object.keys(this.planes))
      for (let b = 0; b < this.planes[name].blockCount; ++b) this.block(name, b);
    if (this.planes.normal) {
      for (let k = 0; k < this.field.mapCount; ++k) {
        const c = this.codes(k), nb = this.mapBytes('normal', k);
        const miss = this.field.distanceEncoding === 4 ? 0 : this.field.missCode;
        for (let t = 0; t < c.length; ++t)
          if (c[t] === miss && (nb[4 * t] | nb[4 * t + 1] | nb[4 * t + 2] | nb[4 * t + 3]))
            throw new VffError(6013, `map ${k} texel ${t}: a miss with a non-zero normal`, { section: 'NORM' });
      }
    }
  }

  checkPadding() {
    const covered = [[0, 64], [this.header.sectionTableOffset, this.header.sectionTableOffset + 64 * this.header.sectionCount]];
    for (const s of this.sections) {
      if (s.tag === 'DIST' || s.tag === 'NORM') {
        const p = this.planes[s.tag === 'DIST' ? 'distance' : 'normal'];
        covered.push([s.offset, s.offset + 32 + 32 * p.blockCount]);
        for (const b of p.blocks) covered.push([b.offset, b.offset + b.storedSize]);
      } else covered.push([s.offset, s.offset + s.storedSize]);
    }
    covered.sort((a, b) => a[0] - b[0]);
    const bytes = this.bytes;
    let pos = 0;
    const gap = (from, to) => {
      for (let i = from; i < to; ++i) if (bytes[i] !== 0) throw new VffError(4012, 'a non-zero padding byte', { offset: i });
    };
    for (const [a, b] of covered) {
      if (a > pos) gap(pos, a);
      pos = Math.max(pos, b);
    }
    gap(pos, bytes.length);
  }
}
