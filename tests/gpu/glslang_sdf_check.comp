#version 430
// vff_sdf.glsl compiled for SPIR-V (tests/gpu/CMakeLists.txt: -G and -V, VFF_SDF_GRID_TYPE given
// as -D per case), with PNanoVDB.h found on the include path as glslang resolves #include.
// VFF_SDF_SKIP_NUDGE and the cone's: any float literal here; this is a compile check (the C++ passes the value).
#extension GL_GOOGLE_include_directive : require
#define VFF_SDF_SKIP_NUDGE 0.0
#define VFF_SDF_CONE_DEPTH 0.0
#define VFF_SDF_CONE_MIN_DISTANCE 1.0
#include "vff_sdf.glsl"
layout(local_size_x = 64) in;
layout(std430, binding = 3) buffer Outs { vec4 outs[]; };
void main() {
  VffSdfHit h = vffSdfIntersect(outs[0].xyz, outs[1].xyz, 0.0, outs[2].x);
  outs[gl_GlobalInvocationID.x] = vec4(vffSdfOccluded(outs[3].xyz, outs[4].xyz, 0.0, 1.0) ? 1.0 : 0.0, h.t + vffSdfVisibility(outs[5].xyz, outs[6].xyz, 0.0, 1.0), float(h.steps), 0.0);
}
