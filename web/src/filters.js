// filters.js - block filter 1 `hits-med` reversed (spec/format.md section 4, "Filters").

/** The largest filtered stream hits-med makes from rawSize bytes: rawSize + ceil(rawSize / 8). */
export function hitsMedBound(rawSize) { return rawSize + Math.ceil(rawSize / 8); }

/**
 * Rebuilds the raw codes of a block of maps of M x M unorm8 texels from a hits-med stream.
 * @returns {{bytes: Uint8Array} | {error: string}}
 */
export function unfilterHitsMed(stream, rawSize, M) {
  const T = rawSize;
  const maskBytes = Math.ceil(T / 8);
  if (stream.length < maskBytes) return { error: 'stream shorter than its hit mask' };
  const isHit = (t) => (stream[t >> 3] >> (t & 7)) & 1;
  let hits = 0;
  for (let t = 0; t < T; ++t) hits += isHit(t);
  if (T % 8 !== 0 && stream[maskBytes - 1] >> (T % 8)) return { error: 'mask bits set after the last texel' };
  if (stream.length !== maskBytes + hits)
    return { error: `the stream holds ${stream.length - maskBytes} residuals for ${hits} hits` };
  const out = new Uint8Array(T);
  const mapTexels = M * M;
  let r = maskBytes;
  for (let base = 0; base < T; base += mapTexels) {
    let prev = 0;
    for (let y = 0; y < M; ++y) {
      for (let x = 0; x < M; ++x) {
        const t = base + y * M + x;
        if (!isHit(t)) { out[t] = 255; continue; }
        const aOk = x > 0 && isHit(t - 1), bOk = y > 0 && isHit(t - M), cOk = x > 0 && y > 0 && isHit(t - M - 1);
        const a = out[t - 1], b = out[t - M], c = out[t - M - 1];
        let P;
        if (aOk && bOk && cOk) {
          const mn = Math.min(a, b), mx = Math.max(a, b);
          P = c >= mx ? mn : c <= mn ? mx : a + b - c;
        } else if (aOk && bOk) P = (a + b) >> 1;
        else if (aOk) P = a;
        else if (bOk) P = b;
        else P = cOk ? c : prev;
        const v = (P + stream[r++]) & 255;
        if (v === 255) return { error: `hit texel ${t} decodes to the miss code` };
        out[t] = v;
        prev = v;
      }
    }
  }
  return { bytes: out };
}
