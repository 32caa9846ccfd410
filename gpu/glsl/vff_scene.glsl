// vff_scene.glsl - a scene of field instances in GLSL 4.30 core: the GPU side of vff::Scene
// (libvff/include/vff/scene.h), answering world-space rays as the CPU Scene does.
//
// Include it after `#version 430` (or later) INSTEAD of vff_query.glsl: it defines the macros
// through which vff_query.glsl reads its field (VFF_FIELD, VFF_POSITIONS_BASE, VFF_MAPS_LAYER,
// VFF_NORMALS_LAYER), declares the scene's buffers and then includes vff_query.glsl (GL has no
// #include: paste that file's text in place of the #include line below, as
// vff::gl::sceneShaderSource does). Every lookup step is vff_query.glsl's; this file only selects
// the field, takes the ray to the instance's object space and walks the top-level hierarchy.
//
// Resources (filled by vff::gl::GpuScene, gpu/loader/include/vff/gl/scene_loader.h):
//   binding VFF_MAPS_BINDING       (default 1): every field's packed distance slices in one
//                                               usampler2DArray, field f's from layer mapsLayer
//   binding VFF_POSITIONS_BINDING  (default 2): every field's positions buffer (vff_query.glsl),
//                                               back to back, field f's from vec4 positionsBase
//   binding VFF_NORMALS_BINDING    (default 3): the normal slices of the fields that have them, one
//                                               isampler2DArray, field f's from layer normalsLayer
//   binding VFF_SCENE_FIELDS_BINDING    (default 4): VffSceneFieldsBlock, one VffSceneField per
//                                               field (vff::gl::SceneFieldBlock, std430, 128 bytes)
//   binding VFF_SCENE_INSTANCES_BINDING (default 5): VffSceneInstancesBlock, one VffSceneInstance
//                                               per instance (vff::gl::SceneInstanceBlock, 96
//                                               bytes), in the hierarchy's leaf order
//   binding VFF_SCENE_NODES_BINDING     (default 6): VffSceneNodesBlock: a header (node count,
//                                               largest box half-size), then the nodes
//                                               (vff::SceneNode, 144 bytes, four children each)
// The fields share one texel format: all R8UI (unorm8-diameter, unorm8-chord, bit1) or all R16UI
// (unorm16-diameter); 2D-array layouts only (no 3D, no bc4-diameter).
//
// Entry points (world-space rays; t in multiples of the direction, as vff::Ray):
//   VffSceneHit vffSceneIntersect(vec3 origin, vec3 direction, float tmin, float tmax,
//                                 float intraBias, bool interpolated)
//     vff::Scene::intersect: the nearest of the instances' hits, the lowest id on equal t.
//   bool vffSceneOccluded(...)   vff::Scene::occluded: whether any instance reports a hit.
//   float vffSceneVisibility(...) vff::Scene::visibility: the product of the instances'
//     visibility (multiplied in the walk's order, not in id order: equal to the CPU's within
//     float rounding for kInterpolated; exact for kNearest, whose factors are 0 or 1).
// intraBias as vff_query.glsl's (VFF_OFF_OBJECT: every instance answers by section 7.4);
// interpolated selects Reconstruction::kInterpolated. The *From variants take the ray's source,
// the id of the instance it starts on or VFF_NO_INSTANCE, as vff::Scene's *From calls: that
// instance answers with intraBias (section 7.3), every other as VFF_OFF_OBJECT (section 7.4).
// Like the CPU, the walk skips only instances whose enlarged world box the segment [0, tmax]
// never reaches, so culling changes no answer. The stack holds VFF_SCENE_STACK entries (default
// 64); vff::gl::GpuScene::update refuses a hierarchy that could need more.
#ifndef VFF_SCENE_GLSL
#define VFF_SCENE_GLSL

#ifndef VFF_SCENE_FIELDS_BINDING
#define VFF_SCENE_FIELDS_BINDING 4
#endif
#ifndef VFF_SCENE_INSTANCES_BINDING
#define VFF_SCENE_INSTANCES_BINDING 5
#endif
#ifndef VFF_SCENE_NODES_BINDING
#define VFF_SCENE_NODES_BINDING 6
#endif
#ifndef VFF_SCENE_STACK
#define VFF_SCENE_STACK 64
#endif

// A field of the scene: vff_query.glsl's VffFieldBlock members (same names, order and offsets:
// std430 of these members equals std140), then where its data lie. Must match
// vff::gl::SceneFieldBlock (checked by tests/gpu/test_glsl_layout.cpp).
struct VffSceneField {
  vec3 sphereCenter;
  float sphereRadius;
  uint positionScheme;
  uint positionParam;
  uint mapCount;
  uint directionScheme;
  uint mapResolution;
  uint distanceEncoding;
  uint missCode;
  uint normalEncoding;
  uint target;
  uint gutter;
  uint tileSize;
  uint tilesPerRow;
  uint tilesPerColumn;
  uint sliceWidth;
  uint sliceHeight;
  uint sliceCount;
  float intraBias;
  float distanceScale;
  float invRadius;
  float twoRadius;
  uint neighbourOffset;
  float kernelRadius2;
  uint reserved0;
  uint reserved1;
  uint mapsLayer;           // the field's first slice in vffMaps
  uint normalsLayer;        // the field's first slice in vffNormals (fields with normals)
  uint positionsBase;       // the vec4 index of its positions buffer in vffPositions
  uint reserved2;
};

// An instance: its RigidTransform (world = translation + scale * rotation * object), its world
// sphere and its field. Must match vff::gl::SceneInstanceBlock.
struct VffSceneInstance {
  vec4 rotation0;           // row 0 of RigidTransform::rotation (w: 0)
  vec4 rotation1;           // row 1
  vec4 rotation2;           // row 2
  vec3 translation;
  float invScale;           // 1 / scale, as the CPU computes it (float)
  vec4 sphere;              // the world sphere (Instance::worldSphere): centre, radius
  uint id;                  // the instance's id in the vff::Scene
  uint field;               // index into vffSceneFields
  float scale;
  uint reserved;
};

// A node of the hierarchy: four children, child c in lane c. Child c is an inner node when
// count[c] == 0 (child[c] indexes the nodes), a leaf when count[c] > 0 (the instances
// vffSceneInstances[child[c]] .. [child[c] + count[c] - 1]), absent when bit c of valid.x is
// clear. Must match vff::SceneNode.
struct VffSceneNode {
  vec4 loX;                 // the children's boxes, lane c = child c
  vec4 loY;
  vec4 loZ;
  vec4 hiX;
  vec4 hiY;
  vec4 hiZ;
  uvec4 child;
  uvec4 count;
  uvec4 valid;              // x: bit c set when child c exists
};

layout(std430, binding = VFF_SCENE_FIELDS_BINDING) readonly buffer VffSceneFieldsBlock {
  VffSceneField vffSceneFields[];
};
layout(std430, binding = VFF_SCENE_INSTANCES_BINDING) readonly buffer VffSceneInstancesBlock {
  VffSceneInstance vffSceneInstances[];
};
layout(std430, binding = VFF_SCENE_NODES_BINDING) readonly buffer VffSceneNodesBlock {
  uint vffSceneNodeCount;   // 0: an empty scene (every ray misses)
  float vffSceneMaxRadius;  // the largest half-size of an instance's box (vff::SceneHierarchy)
  uint vffSceneInstanceCount;
  uint vffSceneReserved;
  VffSceneNode vffSceneNodes[];
};

// The field the lookup steps read: set by vffSceneQuery before each instance's lookup.
uint vffSceneCurrent;

#define VFF_FIELD vffSceneFields[vffSceneCurrent]
#define VFF_POSITIONS_BASE vffSceneFields[vffSceneCurrent].positionsBase
#define VFF_MAPS_LAYER vffSceneFields[vffSceneCurrent].mapsLayer
#define VFF_NORMALS_LAYER vffSceneFields[vffSceneCurrent].normalsLayer

#include "vff_query.glsl"

// RigidTransform::toObjectVector as the CPU's ToObject: the transposed rotation, each dot product
// in the CPU's order, then times 1 / scale.
vec3 vffSceneToObjectVector(VffSceneInstance x, vec3 v) {
  precise vec3 r = vec3(vffDot(vec3(x.rotation0.x, x.rotation1.x, x.rotation2.x), v),
                        vffDot(vec3(x.rotation0.y, x.rotation1.y, x.rotation2.y), v),
                        vffDot(vec3(x.rotation0.z, x.rotation1.z, x.rotation2.z), v));
  precise vec3 s = r * x.invScale;
  return s;
}

// RigidTransform::toWorldVector: rotation * v, times scale.
vec3 vffSceneToWorldVector(VffSceneInstance x, vec3 v) {
  precise vec3 r = vec3(vffDot(x.rotation0.xyz, v), vffDot(x.rotation1.xyz, v), vffDot(x.rotation2.xyz, v));
  precise vec3 s = r * x.scale;
  return s;
}

// One instance's answer to a world-space ray (vff::Instance): the ray in object space, the
// instance's field selected, vff_query.glsl's vffQuery.
VffHit vffSceneQuery(VffSceneInstance x, vec3 origin, vec3 direction, float tmin, float tmax, float intraBias,
                     bool interpolated, out float visibility) {
  vffSceneCurrent = x.field;
  precise vec3 p = origin - x.translation;
  precise vec3 o = vffSceneToObjectVector(x, p);
  precise vec3 d = vffSceneToObjectVector(x, direction);
  return vffQuery(o, d, tmin, tmax, intraBias, interpolated, visibility);
}

struct VffSceneHit {
  bool hit;
  float t;            // along the world ray, in multiples of its direction; +inf without a hit
  uint instance;      // the id of the instance hit (vff::kNoInstance, 0xFFFFFFFF, without a hit)
  bool hasNormal;
  vec3 normal;        // world-space unit normal, when hasNormal
};

const uint VFF_NO_INSTANCE = 0xFFFFFFFFu;    // vff::kNoInstance: a ray that starts on no instance
const uint VFF_SCENE_NO_SOURCE = 0xFFFFFFFEu;  // (the walk's: no sources, intraBias for every instance)
const uint VFF_SCENE_INTERSECT = 0u;
const uint VFF_SCENE_OCCLUDED = 1u;
const uint VFF_SCENE_VISIBILITY = 2u;

// The walk shared by the three entry points (mode: VFF_SCENE_INTERSECT, _OCCLUDED, _VISIBILITY).
// Nearest child first, as the CPU's; intersect narrows the segment to the best hit plus the
// largest instance diameter (a kInterpolated hit can lie that far before its sphere's entry).
VffSceneHit vffSceneWalk(vec3 origin, vec3 direction, float tmin, float tmax, float intraBias, bool interpolated,
                         uint source, uint mode, out float visibility) {
  VffSceneHit best;
  best.hit = false;
  best.t = uintBitsToFloat(0x7f800000u);
  best.instance = 0xFFFFFFFFu;
  best.hasNormal = false;
  best.normal = vec3(0.0);
  visibility = 1.0;
  if (vffSceneNodeCount == 0u) return best;
  float len = sqrt(dot(direction, direction));
  float margin = len > 0.0 ? 2.1 * vffSceneMaxRadius / len : uintBitsToFloat(0x7f800000u);
  // A zero component becomes a tiny one: the slab test then never forms 0 * inf (as the CPU).
  vec3 dd = vec3(direction.x == 0.0 ? 1e-30 : direction.x, direction.y == 0.0 ? 1e-30 : direction.y,
                 direction.z == 0.0 ? 1e-30 : direction.z);
  vec3 inv = 1.0 / dd;
  // Stack items: an inner node, or (leaf bit | node << 2 | child) for a leaf child of a node.
  uint stackRef[VFF_SCENE_STACK];
  float stackEntry[VFF_SCENE_STACK];
  int top = 0;
  stackRef[0] = 0u;
  stackEntry[0] = 0.0;
  top = 1;
  float limit = tmax;
  while (top > 0) {
    --top;
    uint ref = stackRef[top];
    if (stackEntry[top] > limit) continue;
    if ((ref & 0x80000000u) != 0u) {
      uint node = (ref & 0x7FFFFFFFu) >> 2u;
      uint c = ref & 3u;
      uint first = vffSceneNodes[node].child[c];
      uint count = vffSceneNodes[node].count[c];
      for (uint i = 0u; i < count; ++i) {
        VffSceneInstance x = vffSceneInstances[first + i];
        float v;
        float bias = source == VFF_SCENE_NO_SOURCE || x.id == source ? intraBias : VFF_OFF_OBJECT;
        VffHit h = vffSceneQuery(x, origin, direction, tmin, tmax, bias, interpolated, v);
        if (mode == VFF_SCENE_VISIBILITY) {
          visibility *= v;
        } else if (mode == VFF_SCENE_OCCLUDED) {
          if (h.hit) {
            best.hit = true;
            return best;
          }
        } else if (h.hit && (h.t < best.t || (h.t == best.t && x.id < best.instance))) {
          best.hit = true;
          best.t = h.t;
          best.instance = x.id;
          best.hasNormal = h.hasNormal;
          best.normal = h.hasNormal ? normalize(vffSceneToWorldVector(x, h.normal)) : vec3(0.0);
        }
      }
      if (mode == VFF_SCENE_INTERSECT && best.hit) limit = min(tmax, best.t + margin);
      continue;
    }
    VffSceneNode n = vffSceneNodes[ref];
    vec4 tLoX = (n.loX - origin.x) * inv.x, tHiX = (n.hiX - origin.x) * inv.x;
    vec4 tLoY = (n.loY - origin.y) * inv.y, tHiY = (n.hiY - origin.y) * inv.y;
    vec4 tLoZ = (n.loZ - origin.z) * inv.z, tHiZ = (n.hiZ - origin.z) * inv.z;
    vec4 tn = max(max(vec4(0.0), min(tLoX, tHiX)), max(min(tLoY, tHiY), min(tLoZ, tHiZ)));
    vec4 tf = min(min(vec4(limit), max(tLoX, tHiX)), min(max(tLoY, tHiY), max(tLoZ, tHiZ)));
    // The children the segment reaches, sorted by entry (insertion sort of at most four).
    uint order[4];
    int k = 0;
    for (uint c = 0u; c < 4u; ++c) {
      if ((n.valid.x & (1u << c)) == 0u || !(tn[c] <= tf[c])) continue;
      int b = k++;
      while (b > 0 && tn[c] < tn[order[b - 1]]) {
        order[b] = order[b - 1];
        --b;
      }
      order[b] = c;
    }
    for (int a = k - 1; a >= 0; --a) {  // the nearest child ends on top
      uint c = order[a];
      if (top >= VFF_SCENE_STACK) break;  // cannot happen for a hierarchy GpuScene accepted
      stackRef[top] = n.count[c] == 0u ? n.child[c] : (0x80000000u | (ref << 2u) | c);
      stackEntry[top] = tn[c];
      ++top;
    }
  }
  return best;
}

// vff::Scene::intersect, occluded and visibility; with a source, intersectFrom, occludedFrom and
// visibilityFrom.
VffSceneHit vffSceneIntersectFrom(vec3 origin, vec3 direction, float tmin, float tmax, float intraBias,
                                  bool interpolated, uint source) {
  float v;
  return vffSceneWalk(origin, direction, tmin, tmax, intraBias, interpolated, source, VFF_SCENE_INTERSECT, v);
}
bool vffSceneOccludedFrom(vec3 origin, vec3 direction, float tmin, float tmax, float intraBias, bool interpolated,
                          uint source) {
  float v;
  return vffSceneWalk(origin, direction, tmin, tmax, intraBias, interpolated, source, VFF_SCENE_OCCLUDED, v).hit;
}
float vffSceneVisibilityFrom(vec3 origin, vec3 direction, float tmin, float tmax, float intraBias, bool interpolated,
                             uint source) {
  float v;
  vffSceneWalk(origin, direction, tmin, tmax, intraBias, interpolated, source, VFF_SCENE_VISIBILITY, v);
  return v;
}
VffSceneHit vffSceneIntersect(vec3 origin, vec3 direction, float tmin, float tmax, float intraBias,
                              bool interpolated) {
  return vffSceneIntersectFrom(origin, direction, tmin, tmax, intraBias, interpolated, VFF_SCENE_NO_SOURCE);
}
bool vffSceneOccluded(vec3 origin, vec3 direction, float tmin, float tmax, float intraBias, bool interpolated) {
  return vffSceneOccludedFrom(origin, direction, tmin, tmax, intraBias, interpolated, VFF_SCENE_NO_SOURCE);
}
float vffSceneVisibility(vec3 origin, vec3 direction, float tmin, float tmax, float intraBias, bool interpolated) {
  return vffSceneVisibilityFrom(origin, direction, tmin, tmax, intraBias, interpolated, VFF_SCENE_NO_SOURCE);
}

#endif  // VFF_SCENE_GLSL
