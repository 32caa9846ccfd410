// bytes.js - little-endian field access on an ArrayBuffer view (spec/README.md, conventions).

/** Little-endian reads at absolute offsets of a Uint8Array. u64 values are BigInt. */
export class ByteReader {
  /** @param {Uint8Array} bytes */
  constructor(bytes) {
    this.bytes = bytes;
    this.view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  }
  get length() { return this.bytes.length; }
  u8(o) { return this.view.getUint8(o); }
  u16(o) { return this.view.getUint16(o, true); }
  u32(o) { return this.view.getUint32(o, true); }
  u64(o) { return this.view.getBigUint64(o, true); }
  f32(o) { return this.view.getFloat32(o, true); }
  fourcc(o) { return String.fromCharCode(...this.bytes.subarray(o, o + 4)); }
  /** True when bytes [o, o + n) are all zero. */
  zero(o, n) {
    for (let i = o; i < o + n; ++i) if (this.bytes[i] !== 0) return false;
    return true;
  }
}

/** A u64 as a 16-digit lowercase hex string (the form checksums are printed in). */
export function hex64(v) { return v.toString(16).padStart(16, '0'); }

/** The smallest multiple of a (a power of two) that is >= v, for BigInt or Number alike. */
export function alignUp(v, a) {
  if (typeof v === 'bigint') return (v + BigInt(a) - 1n) & ~(BigInt(a) - 1n);
  return Math.ceil(v / a) * a;
}
