// Compile check of gpu/glsl/vff_refine.glsl (after vff_query.glsl) with glslangValidator
// (tests/gpu/CMakeLists.txt): OpenGL SPIR-V (-G) and Vulkan SPIR-V (-V), with the include's default
// bindings (0 to 3, and 10 to 14 for the refinement, all in set 0) and this shader's buffers at 5
// and 6.
#version 430
#extension GL_GOOGLE_include_directive : require
#define VFF_REFINED
#include "vff_query.glsl"
#include "vff_refine.glsl"

layout(local_size_x = 64) in;

struct VffCheckRay {
  vec4 origin;     // xyz
  vec4 direction;  // xyz
  vec4 range;      // tmin, tmax, intraBias
};
layout(std430, binding = 5) readonly buffer VffCheckRays { VffCheckRay rays[]; };
layout(std430, binding = 6) writeonly buffer VffCheckOut { vec4 results[]; };

void main() {
  uint id = gl_GlobalInvocationID.x;
  if (id >= uint(rays.length())) return;
  VffCheckRay r = rays[id];
  VffHit h = vffIntersectRefined(r.origin.xyz, r.direction.xyz, r.range.x, r.range.y, r.range.z);
  bool occluded = vffOccludedRefined(r.origin.xyz, r.direction.xyz, r.range.x, r.range.y, r.range.z);
  results[id] = vec4(h.hit ? 1.0 : 0.0, h.t, occluded ? 1.0 : 0.0, h.normal.x);
}
