// query_tables.js - the values the GPU lookup reads besides the maps, derived from the field as
// libvff's FieldQuery derives them (gpu/glsl/vff_query.glsl, "Resources"): the field block, and the
// positions table (unit vectors, unorm8-chord decode scales, kInterpolated neighbour lists).
import { PositionSet } from './positions.js';
import { frameFromNormal } from './geometry.js';

const f32 = Math.fround;
export const NEIGHBOURS = 8;            // VFF_NEIGHBOURS, vff::kQueryNeighbours
const KERNEL_SPACINGS = 1.3;            // vff::kQueryKernelSpacings

function stepAt1(e) { return e === 4 ? 0 : e === 3 ? f32(2 / 65534) : f32(2 / 254); }

/** Up to NEIGHBOURS samples around each sample: nearest to probes on rings at 1 and 1.6 spacings. */
export function queryNeighbours(ps) {
  const n = ps.count;
  const out = new Int32Array(n * NEIGHBOURS).fill(-1);
  const spacing = Math.sqrt((4 * Math.PI) / n);
  for (let k = 0; k < n; ++k) {
    const u = ps.position(k);
    const [t, b] = frameFromNormal([-u[0], -u[1], -u[2]]);
    const found = [];
    for (const ring of [1.0, 1.6]) {
      const a = ring * spacing;
      for (let p = 0; p < 12 && found.length < NEIGHBOURS; ++p) {
        const phi = (2 * Math.PI * (p + (ring > 1.2 ? 0.5 : 0))) / 12;
        const d = [0, 1, 2].map((i) => u[i] * Math.cos(a) + (t[i] * Math.cos(phi) + b[i] * Math.sin(phi)) * Math.sin(a));
        const q = ps.nearest(d);
        if (q !== k && !found.includes(q)) found.push(q);
      }
    }
    out.set(found, k * NEIGHBOURS);
  }
  return out;
}

/**
 * The std140 VffFieldBlock (112 bytes) and the positions table (vec4s) for a file and a layout.
 * @returns {{block: ArrayBuffer, table: Float32Array, positions: PositionSet}}
 */
export function buildQueryTables(file, layout) {
  const fd = file.field, e = fd.distanceEncoding, M = fd.mapResolution, n = fd.mapCount;
  const ps = new PositionSet(fd.positionScheme, fd.positionParam);
  const chord = e === 2 ? file.chordScales() : null;
  const chordVec4 = chord ? Math.ceil((M * M) / 4) : 0;
  const neighbourOffset = n + chordVec4;
  const table = new Float32Array(4 * (neighbourOffset + (n * NEIGHBOURS) / 4));
  for (let k = 0; k < n; ++k) table.set(ps.position(k), 4 * k);
  if (chord) for (let t = 0; t < M * M; ++t) table[4 * n + t] = f32(chord[t] / 254);
  const nb = queryNeighbours(ps);
  for (let i = 0; i < nb.length; ++i) table[4 * neighbourOffset + i] = nb[i];
  const R = fd.sphere.radius, spacing = f32(Math.sqrt(f32((4 * Math.PI) / n)));
  const block = new ArrayBuffer(112);
  const F = new Float32Array(block), U = new Uint32Array(block);
  F.set(fd.sphere.center, 0);
  F[3] = R;
  U.set([fd.positionScheme, fd.positionParam, n, fd.directionScheme, M, e, fd.missCode, fd.normalEncoding,
    layout.target, layout.gutter, layout.tileSize, layout.tilesPerRow, layout.tilesPerColumn,
    layout.sliceWidth, layout.sliceHeight, layout.sliceCount], 4);
  F[20] = f32(f32(2 * stepAt1(e)) + spacing);
  F[21] = e === 3 ? f32(f32(2 * R) / 65534) : f32(f32(2 * R) / 254);
  F[22] = f32(1 / R);
  F[23] = f32(2 * R);
  U[24] = neighbourOffset;
  F[25] = f32(f32(KERNEL_SPACINGS * spacing) ** 2);
  return { block, table, positions: ps };
}
