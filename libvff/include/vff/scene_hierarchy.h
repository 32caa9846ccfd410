// vff/scene_hierarchy.h - a committed vff::Scene's top-level hierarchy in a flat layout, for a
// walker outside libvff (the GLSL scene query, gpu/glsl/vff_scene.glsl; any other renderer).
//
//   vff::Result<vff::SceneHierarchy> h = scene.hierarchy();    // after scene.commit()
//   // h->nodes[0] is the root; a leaf child lists the instance ids h->order[first .. first + count)
//
// The hierarchy is the one the CPU queries walk (vff/scene.h): axis-aligned boxes around the
// instances' world spheres, each slightly enlarged (radius + 1e-3 radius + 1e-5 of the largest
// coordinate's magnitude), so that a float slab test never misses a ray that the instance's own
// sphere test lets through. A walker that visits every instance whose box the segment [0, tmax]
// of a ray reaches, and answers each as vff::Instance does, answers as the Scene does.
//
// Experimental (VFF_EXPERIMENTAL, vff/export.h): the layout follows the GLSL walker and may change
// with it.
#pragma once

#include <cstdint>
#include <vector>

namespace vff {

// A node of four children; child c is lane c of every array. Child c is
// * an inner node when count[c] == 0: child[c] indexes SceneHierarchy::nodes;
// * a leaf when count[c] > 0: the instance ids order[child[c]] .. order[child[c] + count[c] - 1];
// * absent when bit c of valid is clear (its box is empty: lo = +inf, hi = -inf).
// 144 bytes, the std430 layout of GLSL's VffSceneNode (vec4 loX, loY, loZ, hiX, hiY, hiZ; uvec4
// child, count, valid).
struct SceneNode {
  float lo[3][4];  // lo[axis][child]
  float hi[3][4];
  uint32_t child[4];
  uint32_t count[4];
  uint32_t valid;  // bit c: child c exists
  uint32_t reserved[3];
};
static_assert(sizeof(SceneNode) == 144, "SceneNode is the std430 VffSceneNode");

struct SceneHierarchy {
  std::vector<SceneNode> nodes;  // the root is nodes[0]; empty for a scene without instances
  std::vector<uint32_t> order;   // the leaves' instance ids (every id once)
  // The largest half-size of an instance's box: a hit of another instance can lie up to twice
  // this (in world distance) before the nearest hit found so far (Scene::intersect's margin).
  float maxRadius = 0;
  // Levels of nodes from the root to the deepest (1 for a single node; 0 when empty). A
  // depth-first walk that keeps the other children of each level needs 3 * depth + 1 entries.
  uint32_t depth = 0;
};

}  // namespace vff
