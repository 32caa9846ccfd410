// The compute shader of vff_vk's ScenePipeline (vff/vk/scene.h): one world ray per invocation
// through gpu/glsl/vff_scene.glsl's walk (which includes vff_query.glsl: glslang resolves the
// #include that the GL path replaces with vff::gl::sceneShaderSource). Compiled to Vulkan SPIR-V at
// build time by glslangValidator -V with -I gpu/glsl (the scene takes 2D-array layouts only: one
// variant) and embedded in the library (gpu/vulkan/CMakeLists.txt).
//
// Set 0: vff_scene.glsl's bindings 1 to 6, the rays at 7 and the answers at 8. SceneRay and
// SceneAnswer in vff/vk/scene.h are these structs (std430).
#version 430
#extension GL_GOOGLE_include_directive : require
#include "vff_scene.glsl"

layout(local_size_x = 64) in;

struct VffVkSceneRay {
  vec3 origin;
  uint source;        // an instance id, VFF_NO_INSTANCE, or VFF_SCENE_NO_SOURCE (no sources)
  vec3 direction;
  float tmin;
  float tmax;
  float intraBias;
  uint reserved0;
  uint reserved1;
};
struct VffVkSceneAnswer {
  uint nearestHit;
  float nearestT;
  uint nearestInstance;
  uint occluded;
  uint interpHit;
  float interpT;
  uint interpInstance;
  float visibility;
  vec4 normal;        // the kNearest hit's world normal, w = hasNormal
};
layout(std430, binding = 7) readonly buffer VffVkSceneRays { VffVkSceneRay vffVkSceneRays[]; };
layout(std430, binding = 8) writeonly buffer VffVkSceneAnswers { VffVkSceneAnswer vffVkSceneAnswers[]; };
// which: bit 0 intersect kNearest, 1 intersect kInterpolated, 2 occluded (kNearest), 3 visibility
// (kInterpolated); firstRay and rayCount as vff_vk_query.comp's (the count is not the buffer's
// length(), for the HLSL kernel's sake).
layout(push_constant) uniform VffVkPush { uint which; uint firstRay; uint rayCount; } vffVkPush;

void main() {
  uint id = gl_GlobalInvocationID.x + vffVkPush.firstRay;
  if (id >= vffVkPush.rayCount) return;
  VffVkSceneRay r = vffVkSceneRays[id];
  VffVkSceneAnswer o;
  o.nearestHit = 0u;
  o.nearestT = 0.0;
  o.nearestInstance = 0u;
  o.occluded = 0u;
  o.interpHit = 0u;
  o.interpT = 0.0;
  o.interpInstance = 0u;
  o.visibility = 0.0;
  o.normal = vec4(0.0);
  // One call of the walk inside a loop, so that the compiler has one copy of it, not four.
  for (uint q = 0u; q < 4u; ++q) {
    if ((vffVkPush.which & (1u << q)) == 0u) continue;
    uint mode = q < 2u ? VFF_SCENE_INTERSECT : (q == 2u ? VFF_SCENE_OCCLUDED : VFF_SCENE_VISIBILITY);
    float v;
    VffSceneHit h = vffSceneWalk(r.origin, r.direction, r.tmin, r.tmax, r.intraBias, q == 1u || q == 3u, r.source,
                                 mode, v);
    if (q == 0u) {
      o.nearestHit = h.hit ? 1u : 0u;
      o.nearestT = h.t;
      o.nearestInstance = h.instance;
      o.normal = vec4(h.normal, h.hasNormal ? 1.0 : 0.0);
    } else if (q == 1u) {
      o.interpHit = h.hit ? 1u : 0u;
      o.interpT = h.t;
      o.interpInstance = h.instance;
    } else if (q == 2u) {
      o.occluded = h.hit ? 1u : 0u;
    } else {
      o.visibility = v;
    }
  }
  vffVkSceneAnswers[id] = o;
}
