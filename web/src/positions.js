// positions.js - the positional-sample schemes: the unit vector of every sample and the nearest
// sample to a direction (spec/positions.md sections 2 to 5), in binary64 as the spec writes them.

export const POSITION_OCTA_HEMI2 = 1;
export const POSITION_EA_OCTA_GRID = 2;
export const POSITION_FIBONACCI = 3;

const HALF_PI = 1.5707963267948966;
const TWO_PI = 6.283185307179586;
const PI_SQRT5 = 7.024814731040727;
const INV_LN_PHI2 = 1.0390434606175138;
const K = 0x9E3779B97F4A7C15n;
const MASK64 = (1n << 64n) - 1n;
const FIB = [0, 1, 1, 2, 3, 5, 8, 13, 21, 34, 55, 89, 144, 233, 377, 610, 987, 1597, 2584, 4181, 6765, 10946];

/** The number of samples of scheme with parameter n (rule 5003). */
export function sampleCount(scheme, n) {
  if (scheme === POSITION_OCTA_HEMI2) return 2 * (2 * n * n + 2 * n + 1);
  if (scheme === POSITION_EA_OCTA_GRID) return n * n;
  return n;
}

function octaStart(n, q) {
  const t = n + q;
  return q <= 0 ? t * t : t * t - 2 * q * (q - 1);
}
function octaIndex(n, h, p, q) {
  return h * (2 * n * n + 2 * n + 1) + octaStart(n, q) + p + n - Math.abs(q);
}

function octaHemi2(n, k) {
  const T = 2 * n * n + 2 * n + 1;
  const h = Math.floor(k / T);
  let r = k - h * T, flip = false;
  if (r >= n * n + 2 * n + 1) { r = T - 1 - r; flip = true; }
  let p, q;
  if (r < n * n) { q = Math.floor(Math.sqrt(r)) - n; p = r - octaStart(n, q) - (n - Math.abs(q)); }
  else { q = 0; p = r - n * n - n; }
  if (flip) { p = -p; q = -q; }
  const m = (h === 0 ? 1 : -1) * (n - Math.abs(p) - Math.abs(q));
  const len = Math.sqrt(p * p + q * q + m * m);
  return [p / len, q / len, m === 0 ? 0 : m / len];
}

function eaOctaGrid(n, k) {
  const i = k % n, j = Math.floor(k / n);
  const P = 2 * i + 1 - n, Q = 2 * j + 1 - n;
  let a, b, s;
  if (Math.abs(P) + Math.abs(Q) <= n) { a = Math.abs(P); b = Math.abs(Q); s = 1; }
  else { a = n - Math.abs(Q); b = n - Math.abs(P); s = -1; }
  const r = a + b;
  if (r === 0) return [0, 0, s];
  const z = (s * (n * n - r * r)) / (n * n);
  const rho = (r * Math.sqrt(2 * n * n - r * r)) / (n * n);
  let x = rho * Math.sin((a / r) * HALF_PI), y = rho * Math.sin((b / r) * HALF_PI);
  if (P < 0) x = -x;
  if (Q < 0) y = -y;
  return [x, y, z];
}

function fibonacci(n, k) {
  const fr = ((BigInt(k) * K) & MASK64) >> 11n;
  const phi = Number(fr) * 2 ** -53 * TWO_PI;
  const z = (n - 2 * k - 1) / n;
  const rho = Math.sqrt((2 * k + 1) * (2 * n - 2 * k - 1)) / n;
  return [rho * Math.cos(phi), rho * Math.sin(phi), z];
}

/** The nearest-sample lookup and the positions of one scheme. */
export class PositionSet {
  constructor(scheme, n) {
    this.scheme = scheme;
    this.n = n;
    this.count = sampleCount(scheme, n);
    const gen = scheme === POSITION_OCTA_HEMI2 ? octaHemi2 : scheme === POSITION_EA_OCTA_GRID ? eaOctaGrid : fibonacci;
    /** binary64 positions (what the lookup compares) and binary32 ones (what a shader reads). */
    this.exact = new Float64Array(3 * this.count);
    this.unit = new Float32Array(3 * this.count);
    for (let k = 0; k < this.count; ++k) {
      const u = gen(n, k);
      this.exact.set(u, 3 * k);
      this.unit.set(u, 3 * k);
    }
    if (scheme === POSITION_FIBONACCI) {
      this.fibStep = FIB.map((m) => {
        const s = BigInt.asIntN(64, (BigInt(m) * K) & MASK64) >> 11n;
        return TWO_PI * (Number(s) * 2 ** -53);
      });
    }
  }

  /** The binary32 unit vector of sample k. */
  position(k) { return [this.unit[3 * k], this.unit[3 * k + 1], this.unit[3 * k + 2]]; }

  /** The index of the sample nearest to direction d (any length); 0 for a zero or non-finite d. */
  nearest(d) {
    const l = Math.hypot(d[0], d[1], d[2]);
    if (!(l > 0) || !Number.isFinite(l)) return 0;
    const u = [d[0] / l, d[1] / l, d[2] / l];
    let best = -Infinity, bestK = 0;
    const consider = (k) => {
      const e = this.exact;
      const v = u[0] * e[3 * k] + u[1] * e[3 * k + 1] + u[2] * e[3 * k + 2];
      if (v > best || (v === best && k < bestK)) { best = v; bestK = k; }
    };
    const n = this.n;
    if (this.scheme === POSITION_OCTA_HEMI2) {
      const h = u[2] >= 0 ? 0 : 1;
      const L = Math.abs(u[0]) + Math.abs(u[1]) + Math.abs(u[2]);
      const a0 = Math.min(Math.floor((Math.abs(u[0]) / L) * n), n - 1);
      const b0 = Math.min(Math.floor((Math.abs(u[1]) / L) * n), n - 1);
      const sx = u[0] < 0 ? -1 : 1, sy = u[1] < 0 ? -1 : 1;
      for (const [da, db] of [[0, 0], [1, 0], [0, 1], [1, 1], [-1, 1], [1, -1], [2, 0], [0, 2]]) {
        const a = a0 + da, b = b0 + db;
        if (Math.abs(a) + Math.abs(b) > n) continue;
        consider(octaIndex(n, Math.abs(a) + Math.abs(b) === n ? 0 : h, sx * a, sy * b));
      }
    } else if (this.scheme === POSITION_EA_OCTA_GRID) {
      const x = Math.abs(u[0]), y = Math.abs(u[1]), z = Math.abs(u[2]);
      const r = Math.sqrt((x * x + y * y) / (1 + z));
      const b = r * (Math.atan2(y, x) / HALF_PI);
      const a = r - b;
      let [uu, vv] = u[2] >= 0 ? [a, b] : [1 - b, 1 - a];
      if (u[0] < 0) uu = -uu;
      if (u[1] < 0) vv = -vv;
      const cell = (t) => Math.min(Math.max(Math.floor((t + 1) * 0.5 * n), 0), n - 1);
      const i0 = cell(uu), j0 = cell(vv);
      for (let dj = -1; dj <= 1; ++dj)
        for (let di = -1; di <= 1; ++di) {
          let i = i0 + di, j = j0 + dj;
          if (i < 0 || i >= n) { i = i < 0 ? 0 : n - 1; j = n - 1 - j; }
          if (j < 0 || j >= n) { j = j < 0 ? 0 : n - 1; i = n - 1 - i; }
          consider(j * n + i);
        }
    } else {
      const rho2 = u[0] * u[0] + u[1] * u[1];
      const v = n * PI_SQRT5 * rho2;
      const k = v <= 1 ? 2 : Math.min(Math.max(Math.floor(Math.log(v) * INV_LN_PHI2), 2), 20);
      const f0 = FIB[k], f1 = FIB[k + 1];
      const p0 = this.fibStep[k], p1 = this.fibStep[k + 1];
      const z0 = (-2 * f0) / n, z1 = (-2 * f1) / n;
      const phi = u[0] === 0 && u[1] === 0 ? 0 : Math.atan2(u[1], u[0]);
      const dz = u[2] - (1 - 1 / n);
      const det = p0 * z1 - p1 * z0;
      const c0 = Math.floor((phi * z1 - p1 * dz) / det), c1 = Math.floor((p0 * dz - z0 * phi) / det);
      for (let s = 0; s < 4; ++s) {
        const i = (c0 + (s & 1)) * f0 + (c1 + (s >> 1)) * f1;
        if (i >= 0 && i < n) consider(i);
      }
    }
    return bestK;
  }
}
