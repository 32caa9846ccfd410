// vff/bake/gltf.h - a glTF scene as separate rigid objects: one field per mesh or per node, and
// where each stands (the instances of a scene description, spec/scene.md).
//
// loadMesh (vff/bake/mesh.h) bakes a whole scene as one object. A scene of many objects, or one
// whose objects will move, wants a field per object instead: loadGltfObjects gives, for one scene,
//   GltfSplit::kMesh  one object per glTF mesh, placed once for every node that uses it (a mesh used
//                     by 50 nodes is baked once);
//   GltfSplit::kNode  one object per node that has a mesh, placed once.
// An object's geometry is in its own frame and each placement is a similarity transform (uniform
// scale, rotation, translation): what a vff::RigidTransform can express. A node whose world
// transform is not a similarity (a non-uniform scale, a shear, a mirror) cannot place a shared
// field, so its linear part is baked into an object of its own (named after the mesh and the node),
// placed by its translation alone.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "vff/bake/mesh.h"
#include "vff/direction.h"

namespace vff::bake {

enum class GltfSplit { kMesh, kNode };

struct GltfPlacement {
  int node = -1;                              // glTF node index
  std::string name;                           // the node's name ("" when unnamed)
  Vec3 translation;                           // world = translation + rotate(rotation, scale * p)
  std::array<float, 4> rotation{0, 0, 0, 1};  // unit quaternion x, y, z, w
  float scale = 1.0f;
};

struct GltfObject {
  std::string name;  // the mesh's name (kMesh) or the node's (kNode); "" when unnamed
  int mesh = -1;     // glTF mesh index
  int node = -1;     // the node whose transform is in the geometry (kNode, or a non-similarity
                     // node under kMesh); -1 for a mesh shared in its own frame
  Mesh geometry;     // checked (checkMesh), in the object's frame
  std::vector<GltfPlacement> placements;  // in node order
};

struct GltfObjectOptions {
  GltfSplit split = GltfSplit::kMesh;
  int scene = -1;  // -1: the file's default scene, else scene 0 (as MeshLoadOptions::gltfScene)
  // kMesh only: every mesh one object in its own frame (node -1), also a mesh whose nodes are not
  // similarities; their placements are left out (a field inside a glTF mesh, VFF_visibility_field,
  // is always in its mesh's frame). An object's placements may then be empty.
  bool ownFrame = false;
};

// The objects of one scene of a .gltf/.glb file, in order of first use by a depth-first walk of the
// scene's nodes. *info, when given, says which scenes the file has and which was read. Errors are
// loadMesh's (a mesh without triangles is kMeshEmpty, naming it), and kInvalidArgument for a scene
// that does not exist or a file that is not glTF.
Result<std::vector<GltfObject>> loadGltfObjects(const std::string& path, const GltfObjectOptions& options,
                                                MeshInfo* info = nullptr);

}  // namespace vff::bake
