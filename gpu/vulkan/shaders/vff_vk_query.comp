// The compute shader of vff_vk's QueryPipeline (vff/vk/query.h): one ray per invocation through
// gpu/glsl/vff_query.glsl, both reconstructions. Compiled to Vulkan SPIR-V at build time by
// glslangValidator -V with -I gpu/glsl, once per maps variant (none, -DVFF_MAPS_3D,
// -DVFF_MAPS_BC4), and embedded in the library (gpu/vulkan/CMakeLists.txt).
//
// Set 0: the include's bindings 0 to 3 (vff/vk/field.h), the rays at 4 and the answers at 5.
// QueryRay and QueryAnswer in vff/vk/query.h are these structs (std430).
#version 430
#extension GL_GOOGLE_include_directive : require
#include "vff_query.glsl"

layout(local_size_x = 64) in;

struct VffVkRay {
  vec4 origin;     // xyz
  vec4 direction;  // xyz, any length
  vec4 range;      // tmin, tmax, intraBias (vffIntersect's), unused
};
struct VffVkAnswer {
  uint flags;          // bits: 1 hit, 2 inside, 4 looked, 8 hasNormal (kNearest); 16 hit, 32 hasNormal (kInterpolated)
  float t;             // kNearest
  uint k;              // kNearest's lookup: sample, texel (i, j), code, decoded distance
  uint i;
  uint j;
  uint code;
  float distance;
  float visibility;    // kInterpolated
  vec4 normal;         // kNearest, xyz
  vec4 interpNormal;   // kInterpolated, xyz
  vec4 interpT;        // x: kInterpolated t
};
layout(std430, binding = 4) readonly buffer VffVkRays { VffVkRay vffVkRays[]; };
layout(std430, binding = 5) writeonly buffer VffVkAnswers { VffVkAnswer vffVkAnswers[]; };
// which: bit 0 kNearest, bit 1 kInterpolated (the other's members are left zero); firstRay: the
// ray of invocation 0 (a batch beyond the device's work-group count limit runs in several dispatches);
// rayCount: the rays in the batch. The count is passed rather than taken from vffVkRays.length():
// in the HLSL generated from this shader that is ByteAddressBuffer.GetDimensions, which glslang's
// HLSL front end answers in 4-byte words where HLSL defines bytes, so the HLSL kernel would stop at a
// quarter of the rays.
layout(push_constant) uniform VffVkPush { uint which; uint firstRay; uint rayCount; } vffVkPush;

void main() {
  uint id = gl_GlobalInvocationID.x + vffVkPush.firstRay;
  if (id >= vffVkPush.rayCount) return;
  VffVkRay r = vffVkRays[id];
  VffVkAnswer o;
  o.flags = 0u;
  o.t = 0.0;
  o.k = 0u;
  o.i = 0u;
  o.j = 0u;
  o.code = 0u;
  o.distance = 0.0;
  o.visibility = 0.0;
  o.normal = vec4(0.0);
  o.interpNormal = vec4(0.0);
  o.interpT = vec4(0.0);
  if ((vffVkPush.which & 1u) != 0u) {
    VffHit h = vffIntersect(r.origin.xyz, r.direction.xyz, r.range.x, r.range.y, r.range.z);
    o.flags |= (h.hit ? 1u : 0u) | (h.inside ? 2u : 0u) | (h.looked ? 4u : 0u) | (h.hasNormal ? 8u : 0u);
    o.t = h.t;
    o.k = h.sampleIndex;
    o.i = h.texel.x;
    o.j = h.texel.y;
    o.code = h.code;
    o.distance = h.distance;
    o.normal = vec4(h.normal, 0.0);
  }
  if ((vffVkPush.which & 2u) != 0u) {
    float vis;
    VffHit b = vffQuery(r.origin.xyz, r.direction.xyz, r.range.x, r.range.y, r.range.z, true, vis);
    o.flags |= (b.hit ? 16u : 0u) | (b.hasNormal ? 32u : 0u);
    o.visibility = vis;
    o.interpNormal = vec4(b.normal, 0.0);
    o.interpT = vec4(b.t, 0.0, 0.0, 0.0);
  }
  vffVkAnswers[id] = o;
}
