// vff_sdf.glsl - the distance-field peer on the GPU: sphere tracing of a NanoVDB float or Fp8 grid
// (samples/experiments/sdf_field.h, built by vffx::SdfField) through PNanoVDB's GLSL path, the same
// algorithm as the CPU tracer (samples/experiments/sdf_field.cpp), step for step:
//
//   the ray, in the grid's object space, taken to index space by the grid's float map
//   (pnanovdb_grid_world_to_indexf / _dirf, as nanovdb's worldToIndexF / worldToIndexDirF);
//   clipped to the root's index box widened by one voxel (the trace starts at the box, skipping
//   startVoxels first); then at each step the trilinear sample of the eight voxels around floor(p)
//   (voxel centres at integer coordinates, lerps in the CPU's order), divided by the voxel size: a
//   hit below hitVoxels; else t advances by max(d, minStepVoxels) (in voxels, over |dir| in index
//   space), or to the exit of the empty tree block around the voxel nearest p when that is further
//   (skipEmpty); a miss after maxSteps steps or past tmax.
//
// The cone estimate (vffSdfVisibility, when the block's coneTan or coneRadiusAtEnd is positive):
// the minimum over the steps of 0.5 + 0.5 d / (t tan(half-angle)), t in voxels no less than
// VFF_SDF_CONE_MIN_DISTANCE, clamped to [0, 1]; the trace goes on inside (steps of |d|) until it
// reaches 0 or a sample deeper than VFF_SDF_CONE_DEPTH of the band (covered: 0). sdf_field.h
// says why.
//
// No #include in GL: the line `#include "nanovdb/PNanoVDB.h"` below is replaced by the header's
// text (Debian's libnanovdb-dev) by vffx::gl::sdfShaderSource (gpu/sdf/sdf_gl.h), after this file's
// buffer declaration, which PNanoVDB's GLSL path reads as `pnanovdb_buf_data`. The constants and
// the trace options come from the C++ side (sdfShaderDefines: VFF_SDF_GRID_TYPE and sdf_field.h's
// kSdfSkipNudge, kSdfConeDepth, kSdfConeMinDistance; the VffSdfBlock uniform block,
// vffx::gl::SdfBlock, filled from vffx::SdfTraceOptions), never retyped here.
//
// Resources (defaults; define to move): the grid's bytes as an SSBO at VFF_SDF_GRID_BINDING (8),
// the uniform block at VFF_SDF_BLOCK_BINDING (9).
#ifndef VFF_SDF_GRID_BINDING
#define VFF_SDF_GRID_BINDING 8
#endif
#ifndef VFF_SDF_BLOCK_BINDING
#define VFF_SDF_BLOCK_BINDING 9
#endif
#ifndef VFF_SDF_GRID_TYPE
#error "VFF_SDF_GRID_TYPE: the grid's PNANOVDB_GRID_TYPE (vffx::gl::sdfShaderDefines)"
#endif
#if !defined(VFF_SDF_SKIP_NUDGE) || !defined(VFF_SDF_CONE_DEPTH) || !defined(VFF_SDF_CONE_MIN_DISTANCE)
#error "VFF_SDF_SKIP_NUDGE, VFF_SDF_CONE_DEPTH, VFF_SDF_CONE_MIN_DISTANCE: vffx::gl::sdfShaderDefines"
#endif

layout(std430, binding = VFF_SDF_GRID_BINDING) readonly buffer VffSdfGrid { uint pnanovdb_buf_data[]; };

#define PNANOVDB_GLSL
#include "nanovdb/PNanoVDB.h"

// vffx::gl::SdfBlock (std140).
layout(std140, binding = VFF_SDF_BLOCK_BINDING) uniform VffSdfBlock {
  vec4 vffSdfScale;   // x: voxel size (object units); y: the band's half-width (voxels)
  vec4 vffSdfTrace;   // hitVoxels, minStepVoxels, startVoxels, skipEmpty (0 or 1)
  ivec4 vffSdfSteps;  // x: maxSteps
  vec4 vffSdfCone;    // x: coneTan; y: coneRadiusAtEnd (object units at tmax)
};

struct VffSdfHit {
  bool hit;
  float t;    // in multiples of the given direction
  int steps;  // samples taken
};

pnanovdb_buf_t vffSdfBuf() {
  pnanovdb_buf_t b;
  b.unused = 0u;
  return b;
}

// The value at voxel ijk (grid units: the distance in object units).
float vffSdfValue(inout pnanovdb_readaccessor_t acc, ivec3 ijk) {
  pnanovdb_buf_t buf = vffSdfBuf();
#if VFF_SDF_GRID_TYPE == PNANOVDB_GRID_TYPE_FP8
  uint level;
  pnanovdb_address_t a = pnanovdb_readaccessor_get_value_address_and_level(PNANOVDB_GRID_TYPE_FP8, buf, acc, ijk, level);
  return pnanovdb_root_fp8_read_float(buf, a, ijk, level);
#else
  return pnanovdb_read_float(buf, pnanovdb_readaccessor_get_value_address(PNANOVDB_GRID_TYPE_FLOAT, buf, acc, ijk));
#endif
}

float vffSdfLerp(float a, float b, float t) { return a + t * (b - a); }

// The distance in voxels at index-space point p (sdf_field.cpp Tracer::sample).
float vffSdfSample(inout pnanovdb_readaccessor_t acc, vec3 p) {
  vec3 f = floor(p);
  vec3 w = p - f;
  ivec3 b = ivec3(f);
  float c000 = vffSdfValue(acc, b), c100 = vffSdfValue(acc, b + ivec3(1, 0, 0));
  float c010 = vffSdfValue(acc, b + ivec3(0, 1, 0)), c110 = vffSdfValue(acc, b + ivec3(1, 1, 0));
  float c001 = vffSdfValue(acc, b + ivec3(0, 0, 1)), c101 = vffSdfValue(acc, b + ivec3(1, 0, 1));
  float c011 = vffSdfValue(acc, b + ivec3(0, 1, 1)), c111 = vffSdfValue(acc, b + ivec3(1, 1, 1));
  float x00 = vffSdfLerp(c000, c100, w.x), x10 = vffSdfLerp(c010, c110, w.x);
  float x01 = vffSdfLerp(c001, c101, w.x), x11 = vffSdfLerp(c011, c111, w.x);
  return vffSdfLerp(vffSdfLerp(x00, x10, w.y), vffSdfLerp(x01, x11, w.y), w.z) / vffSdfScale.x;
}

// std::lround: halves away from zero.
ivec3 vffSdfRound(vec3 p) { return ivec3(sign(p) * floor(abs(p) + 0.5)); }

// When the voxel nearest p lies in a block of the tree with no leaf, the t where the ray leaves the
// points whose nearest voxel is in that block, else 0 (sdf_field.cpp Tracer::emptyExit).
float vffSdfEmptyExit(inout pnanovdb_readaccessor_t acc, vec3 p, vec3 org, vec3 dir) {
  ivec3 ijk = vffSdfRound(p);
  int dim = int(pnanovdb_readaccessor_get_dim(VFF_SDF_GRID_TYPE, vffSdfBuf(), acc, ijk));
  if (dim <= 1) return 0.0;
  bool found = false;
  float exitT = 0.0;
  for (int a = 0; a < 3; ++a) {
    if (dir[a] == 0.0) continue;
    float base = float(ijk[a] & ~(dim - 1));
    float bound = dir[a] > 0.0 ? base + float(dim) - 0.5 : base - 0.5;
    float e = (bound - org[a]) / dir[a];
    exitT = found ? min(exitT, e) : e;
    found = true;
  }
  return found ? exitT * (1.0 + VFF_SDF_SKIP_NUDGE) + VFF_SDF_SKIP_NUDGE : 0.0;
}

// The march along o + t d, t in [tmin, tmax] (object space, t in multiples of d); cone: tan of the
// cone estimate's half-angle, 0 for none; vis gets the estimate (1 without a cone) (Tracer::trace).
VffSdfHit vffSdfMarch(vec3 o, vec3 d, float tmin, float tmax, float cone, out float vis) {
  vis = 1.0;
  VffSdfHit h;
  h.hit = false;
  h.t = 0.0;
  h.steps = 0;
  pnanovdb_buf_t buf = vffSdfBuf();
  pnanovdb_grid_handle_t grid;
  grid.address.byte_offset = 0u;
  pnanovdb_root_handle_t root = pnanovdb_tree_get_root(buf, pnanovdb_grid_get_tree(buf, grid));
  pnanovdb_readaccessor_t acc;
  pnanovdb_readaccessor_init(acc, root);
  vec3 org = pnanovdb_grid_world_to_indexf(buf, grid, o);
  vec3 dir = pnanovdb_grid_world_to_index_dirf(buf, grid, d);
  float len = length(dir);  // voxels per unit of t
  if (!(len > 0.0)) return h;
  // The slab test against the root's index box, one voxel wider (sample neighbours).
  vec3 lo = vec3(pnanovdb_root_get_bbox_min(buf, root)) - 1.0;
  vec3 hi = vec3(pnanovdb_root_get_bbox_max(buf, root)) + 1.0;
  float t0 = tmin + vffSdfTrace.z / len, t1 = tmax;
  for (int a = 0; a < 3; ++a) {
    if (dir[a] == 0.0) {
      if (org[a] < lo[a] || org[a] > hi[a]) return h;
      continue;
    }
    float inv = 1.0 / dir[a];
    float ta = (lo[a] - org[a]) * inv, tb = (hi[a] - org[a]) * inv;
    t0 = max(t0, min(ta, tb));
    t1 = min(t1, max(ta, tb));
  }
  if (!(t0 <= t1)) return h;
  float minStep = vffSdfTrace.y / len;
  float t = t0;
  for (int step = 0; step < vffSdfSteps.x; ++step) {
    vec3 p = org + dir * t;
    float dv = vffSdfSample(acc, p);
    h.steps = step + 1;
    float skip = vffSdfTrace.w != 0.0 ? vffSdfEmptyExit(acc, p, org, dir) : 0.0;
    if (cone > 0.0) {
      vis = min(vis, 0.5 + 0.5 * dv / (max(t * len, VFF_SDF_CONE_MIN_DISTANCE) * cone));
      if (vis <= 0.0 || dv <= -VFF_SDF_CONE_DEPTH * vffSdfScale.y) {
        h.hit = true;
        h.t = t;
        vis = 0.0;
        return h;
      }
      t = max(t + max(abs(dv) / len, minStep), skip);
      if (t > t1) break;
      continue;
    }
    if (dv < vffSdfTrace.x) {
      h.hit = true;
      h.t = t;
      vis = 0.0;
      return h;
    }
    t = max(t + max(dv / len, minStep), skip);
    if (t > t1) break;
  }
  vis = clamp(vis, 0.0, 1.0);
  return h;
}

// The first hit (SdfField::intersect, without the normal).
VffSdfHit vffSdfIntersect(vec3 o, vec3 d, float tmin, float tmax) {
  float vis;
  return vffSdfMarch(o, d, tmin, tmax, 0.0, vis);
}

bool vffSdfOccluded(vec3 o, vec3 d, float tmin, float tmax) { return vffSdfIntersect(o, d, tmin, tmax).hit; }

// tan of the cone estimate's half-angle for this ray, 0 for none (sdf_field.cpp coneTan).
float vffSdfConeTan(vec3 d, float tmax) {
  if (vffSdfCone.y > 0.0) return vffSdfCone.y / (tmax * length(d));
  return max(vffSdfCone.x, 0.0);
}

// SdfField::visibility: the cone estimate when the block asks for one, else 0 (hit) or 1.
float vffSdfVisibility(vec3 o, vec3 d, float tmin, float tmax) {
  float cone = vffSdfConeTan(d, tmax);
  float vis;
  bool hit = vffSdfMarch(o, d, tmin, tmax, cone, vis).hit;
  return cone > 0.0 ? vis : (hit ? 0.0 : 1.0);
}
