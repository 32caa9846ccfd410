// A compute shader of the refined query (gpu/glsl/vff_refine.glsl after vff_query.glsl): one ray per
// invocation, the refined answer, the refined occlusion, whether the exact step answered, and
// kNearest's answer beside them, for checking and for a port to start from. vff_vk compiles it at
// build time per MapsKind, as GLSL and through spirv-cross as HLSL, with the stack at its default
// depth (VFF_REFINE_STACK, the deepest BVH the loader takes), and runs it as
// vff::vk::RefinedPipeline (vff/vk/refine.h); web/tools/gen-wgsl.mjs makes its WGSL
// (gpu/wgsl/kernels/vff_vk_refine.wgsl) for the WebGPU suite.
//
// Set 0: the field's bindings 0 to 3 (vff/vk/field.h), the rays at 4 (QueryRay, vff/vk/query.h),
// the answers at 5 (RefinedAnswer, vff/vk/refine.h), the refinement's storage buffers at 10 to 13
// and its uniform block at 14 (vff/vk/refine.h: vff::vk::loadRefinement).
#version 430
#extension GL_GOOGLE_include_directive : require
#include "vff_query.glsl"
#include "vff_refine.glsl"

layout(local_size_x = 64) in;

struct VffVkRay {
  vec4 origin;     // xyz
  vec4 direction;  // xyz, any length
  vec4 range;      // tmin, tmax, intraBias (vffIntersect's), unused
};
struct VffVkRefinedAnswer {
  vec4 refined;  // hit (0 or 1), t, occluded (0 or 1), hasNormal (0 or 1)
  vec4 normal;   // xyz; w: 1 when vffQueryRefined gave vffIntersectRefined's answer
  vec4 nearest;  // vffIntersect's hit (0 or 1) and t
  uvec4 lookup;  // the exact step answered (0 or 1), the sample (0xffffffff: no lookup), texel i, j
};
layout(std430, binding = 4) readonly buffer VffVkRays { VffVkRay vffVkRays[]; };
layout(std430, binding = 5) writeonly buffer VffVkRefinedAnswers { VffVkRefinedAnswer vffVkRefinedAnswers[]; };
layout(push_constant) uniform VffVkPush { uint which; uint firstRay; uint rayCount; } vffVkPush;

void main() {
  uint id = gl_GlobalInvocationID.x + vffVkPush.firstRay;
  if (id >= vffVkPush.rayCount) return;
  VffVkRay r = vffVkRays[id];
  VffHit h = vffIntersectRefined(r.origin.xyz, r.direction.xyz, r.range.x, r.range.y, r.range.z);
  bool occluded = vffOccludedRefined(r.origin.xyz, r.direction.xyz, r.range.x, r.range.y, r.range.z);
  bool exact;
  VffHit x = vffQueryRefined(r.origin.xyz, r.direction.xyz, r.range.x, r.range.y, r.range.z, false, exact);
  VffHit n = vffIntersect(r.origin.xyz, r.direction.xyz, r.range.x, r.range.y, r.range.z);
  VffVkRefinedAnswer o;
  o.refined = vec4(h.hit ? 1.0 : 0.0, h.t, occluded ? 1.0 : 0.0, h.hasNormal ? 1.0 : 0.0);
  o.normal = vec4(h.normal, x.hit == h.hit && (!h.hit || x.t == h.t) ? 1.0 : 0.0);
  o.nearest = vec4(n.hit ? 1.0 : 0.0, n.t, 0.0, 0.0);
  o.lookup = uvec4(exact ? 1u : 0u, x.looked ? x.sampleIndex : 0xffffffffu, x.texel);
  vffVkRefinedAnswers[id] = o;
}
