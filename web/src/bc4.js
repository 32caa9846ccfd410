// bc4.js - BC4 blocks of `bc4-diameter` maps decoded to unorm8 codes (spec/format.md section 7.4).

/** Decodes the 16 codes of one 8-byte block at src[o..o+7] into out (block texel u = 4y + x). */
export function decodeBc4Block(src, o, out) {
  const r0 = src[o], r1 = src[o + 1];
  const pal = [r0, r1, 0, 0, 0, 0, 0, 0];
  if (r0 > r1) {
    for (let k = 2; k < 8; ++k) pal[k] = Math.floor(((8 - k) * r0 + (k - 1) * r1 + 3) / 7);
  } else {
    for (let k = 2; k < 6; ++k) pal[k] = Math.floor(((6 - k) * r0 + (k - 1) * r1 + 2) / 5);
    pal[6] = 0;
    pal[7] = 255;
  }
  // W is a 48-bit little-endian integer: read it as two 24-bit halves to stay in exact integers.
  const lo = src[o + 2] | (src[o + 3] << 8) | (src[o + 4] << 16);
  const hi = src[o + 5] | (src[o + 6] << 8) | (src[o + 7] << 16);
  for (let u = 0; u < 8; ++u) out[u] = pal[(lo >> (3 * u)) & 7];
  for (let u = 0; u < 8; ++u) out[8 + u] = pal[(hi >> (3 * u)) & 7];
}

/** Decodes one map of M x M texels (M/4 x M/4 blocks) to M*M row-major codes. */
export function decodeBc4Map(src, M) {
  const out = new Uint8Array(M * M);
  const blk = new Uint8Array(16);
  const bw = M / 4;
  for (let by = 0; by < bw; ++by)
    for (let bx = 0; bx < bw; ++bx) {
      decodeBc4Block(src, 8 * (by * bw + bx), blk);
      for (let y = 0; y < 4; ++y)
        for (let x = 0; x < 4; ++x) out[(4 * by + y) * M + 4 * bx + x] = blk[4 * y + x];
    }
  return out;
}
