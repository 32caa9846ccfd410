// zstd.js - one Zstandard frame as format.md section 4 ("Codecs") admits it, decoded with fzstd.
//
// The frame header and block headers are walked here (RFC 8878 sections 3.1.1 and 3.1.1.2) so that
// the declared content size is checked against the caller's bound before anything is allocated,
// and so that a dictionary, a missing content size, a skippable frame or bytes after the frame are
// refused, which a general-purpose decompressor would accept.
import { decompress } from 'fzstd';

const MAGIC = 0xfd2fb528;

/**
 * Parses the frame header and walks the blocks of one zstd frame.
 * @param {Uint8Array} src the stored bytes
 * @returns {{contentSize: number} | {error: string}}
 */
export function inspectFrame(src) {
  const n = src.length;
  if (n < 6) return { error: 'shorter than a frame header' };
  const dv = new DataView(src.buffer, src.byteOffset, n);
  if (dv.getUint32(0, true) !== MAGIC) return { error: 'not a zstd frame (bad magic)' };
  const fhd = src[4];
  const fcsFlag = fhd >> 6, single = (fhd >> 5) & 1, checksum = (fhd >> 2) & 1, dictFlag = fhd & 3;
  if (fhd & 0x08) return { error: 'reserved bit of the frame header set' };
  let p = 5 + (single ? 0 : 1);
  const dictSize = [0, 1, 2, 4][dictFlag];
  const fcsSize = [single ? 1 : 0, 2, 4, 8][fcsFlag];
  if (p + dictSize + fcsSize > n) return { error: 'truncated frame header' };
  let dictId = 0;
  for (let i = 0; i < dictSize; ++i) dictId += src[p + i] * 2 ** (8 * i);
  if (dictId !== 0) return { error: 'the frame needs a dictionary' };
  p += dictSize;
  if (fcsSize === 0) return { error: 'the frame does not declare its content size' };
  let size = 0;
  for (let i = 0; i < fcsSize; ++i) size += src[p + i] * 2 ** (8 * i);
  if (fcsSize === 2) size += 256;
  p += fcsSize;
  for (;;) {
    if (p + 3 > n) return { error: 'truncated block header' };
    const h = src[p] | (src[p + 1] << 8) | (src[p + 2] << 16);
    const last = h & 1, type = (h >> 1) & 3, bsize = h >>> 3;
    if (type === 3) return { error: 'reserved block type' };
    p += 3 + (type === 1 ? 1 : bsize);
    if (p > n) return { error: 'truncated block' };
    if (last) break;
  }
  if (checksum) p += 4;
  if (p > n) return { error: 'truncated content checksum' };
  if (p !== n) return { error: `${n - p} byte(s) after the frame` };
  return { contentSize: size };
}

/**
 * Decodes one frame that must declare exactly `expected` bytes (or, when `bound` is given, at most
 * `bound` bytes). Returns the bytes, or {error}.
 */
export function decodeFrame(src, expected, bound = -1) {
  const f = inspectFrame(src);
  if (f.error) return f;
  if (bound < 0 && f.contentSize !== expected)
    return { error: `the frame declares ${f.contentSize} bytes, expected ${expected}` };
  if (bound >= 0 && f.contentSize > bound)
    return { error: `the frame declares ${f.contentSize} bytes, above the bound ${bound}` };
  let out;
  try {
    out = decompress(src, new Uint8Array(f.contentSize));
  } catch (e) {
    return { error: `zstd: ${e.message}` };
  }
  if (out.length !== f.contentSize) return { error: 'the frame decodes to fewer bytes than it declares' };
  return { bytes: out };
}
