// Compile check of gpu/glsl/vff_scene.glsl (which includes vff_query.glsl) with glslangValidator
// (tests/gpu/CMakeLists.txt): OpenGL SPIR-V (-G) and Vulkan SPIR-V (-V), with the default bindings
// (1 to 6, all in set 0) and this shader's buffers at 8 and 9.
#version 430
#extension GL_GOOGLE_include_directive : require
#include "vff_scene.glsl"

layout(local_size_x = 64) in;

struct VffCheckRay {
  vec4 origin;     // xyz
  vec4 direction;  // xyz
  vec4 range;      // tmin, tmax, intraBias
};
layout(std430, binding = 8) readonly buffer VffCheckRays { VffCheckRay rays[]; };
layout(std430, binding = 9) writeonly buffer VffCheckOut { vec4 results[]; };

void main() {
  uint id = gl_GlobalInvocationID.x;
  if (id >= uint(rays.length())) return;
  VffCheckRay r = rays[id];
  VffSceneHit h = vffSceneIntersect(r.origin.xyz, r.direction.xyz, r.range.x, r.range.y, r.range.z, false);
  bool o = vffSceneOccluded(r.origin.xyz, r.direction.xyz, r.range.x, r.range.y, r.range.z, false);
  float v = vffSceneVisibility(r.origin.xyz, r.direction.xyz, r.range.x, r.range.y, r.range.z, true);
  results[id] = vec4(h.hit ? 1.0 : 0.0, h.t, o ? 1.0 : 0.0, v);
}
