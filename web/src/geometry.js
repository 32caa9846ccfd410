// geometry.js - the duff2017 frame, the direction schemes and texel addressing
// (spec/geometry.md sections 3 to 5), in binary32 where the spec says binary32.
const f = Math.fround;
const QUARTER_PI = f(Math.PI / 4);

export const DIRECTION_CONCENTRIC = 1;
export const DIRECTION_HEMI_OCTAHEDRAL = 2;

/** Texel (i, j) of an M x M map containing square point (u, v). */
export function squareToTexel(u, v, M) {
  const c = (x) => Math.min(Math.max(Math.floor(f(f(f(x + 1) * 0.5) * M)), 0), M - 1);
  return [c(u), c(v)];
}

/** The square point of the centre of texel (i, j): ((2i + 1)/M - 1, (2j + 1)/M - 1), binary32. */
export function texelCenter(i, j, M) {
  return [f(f((2 * i + 1) / M) - 1), f(f((2 * j + 1) / M) - 1)];
}

/** squareToHemisphere: the local unit direction of square point (u, v). */
export function squareToHemisphere(scheme, u, v) {
  const a = Math.min(Math.max(u, -1), 1), b = Math.min(Math.max(v, -1), 1);
  if (scheme === DIRECTION_HEMI_OCTAHEDRAL) {
    const x = f(f(a + b) * 0.5), y = f(f(a - b) * 0.5);
    const z = f(f(1 - Math.abs(x)) - Math.abs(y));
    const len = f(Math.sqrt(f(f(f(x * x) + f(y * y)) + f(z * z))));
    return [f(x / len), f(y / len), f(z / len)];
  }
  let r, phi;
  if (a === 0 && b === 0) { r = 0; phi = 0; }
  else if (Math.abs(a) > Math.abs(b)) { r = a; phi = f(QUARTER_PI * f(b / a)); }
  else { r = b; phi = f(f(2 * QUARTER_PI) - f(QUARTER_PI * f(a / b))); }
  const r2 = f(r * r);
  const s = f(r * f(Math.sqrt(Math.max(0, f(2 - r2)))));
  return [f(s * f(Math.cos(phi))), f(s * f(Math.sin(phi))), f(1 - r2)];
}

/** hemisphereToSquare: the square point (u, v) of a local direction (z < 0 taken as the horizon). */
export function hemisphereToSquare(scheme, d) {
  const z = Math.max(0, d[2]);
  const cl = (x) => Math.min(Math.max(x, -1), 1);
  if (scheme === DIRECTION_HEMI_OCTAHEDRAL) {
    const q = f(1 / f(f(Math.abs(d[0]) + Math.abs(d[1])) + z));
    const x = f(d[0] * q), y = f(d[1] * q);
    return [cl(f(x + y)), cl(f(x - y))];
  }
  const r = f(Math.sqrt(Math.max(0, f(1 - z))));
  if (r === 0) return [0, 0];
  let phi = f(Math.atan2(d[1], d[0]));
  if (phi < -QUARTER_PI) phi = f(phi + f(2 * Math.PI));
  let a, b;
  if (phi < QUARTER_PI) { a = r; b = f(f(phi * a) / QUARTER_PI); }
  else if (phi < 3 * QUARTER_PI) { b = r; a = f(f(-f(phi - f(Math.PI / 2)) * b) / QUARTER_PI); }
  else if (phi < 5 * QUARTER_PI) { a = -r; b = f(f(f(phi - f(Math.PI)) * a) / QUARTER_PI); }
  else { b = -r; a = f(f(-f(phi - f(3 * Math.PI / 2)) * b) / QUARTER_PI); }
  return [cl(a), cl(b)];
}

/** The local direction through the centre of texel (i, j) (`texelDirection`). */
export function texelDirection(scheme, i, j, M) {
  const [u, v] = texelCenter(i, j, M);
  return squareToHemisphere(scheme, u, v);
}

/** duff2017 frame around unit normal n: [t, b, n] (spec/geometry.md section 3). */
export function frameFromNormal(n) {
  const s = n[2] >= 0 ? 1 : -1;
  const a = -1 / (s + n[2]);
  const k = n[0] * n[1] * a;
  const t = [1 + s * n[0] * n[0] * a, s * k, -s * n[0]];
  const b = [k, s + n[1] * n[1] * a, -n[1]];
  return [t, b, n];
}

export const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];

/** The local coordinates (w.t, w.b, w.n) of w in frame F. */
export function toLocal(F, w) { return [dot(w, F[0]), dot(w, F[1]), dot(w, F[2])]; }
