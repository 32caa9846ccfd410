// vff/gl/scene_loader.h - a vff::Scene on OpenGL 4.3 for gpu/glsl/vff_scene.glsl: several fields
// resident at once, and the instances and top-level hierarchy, updated per frame.
//
//   std::vector<vff::gl::SceneField> fields = {{&bunnyFile, &bunnyQuery}, {&teapotFile, &teapotQuery}};
//   vff::Result<vff::gl::GpuScene> gpu = vff::gl::loadScene(fields);   // a GL 4.3 context is current
//   if (!gpu) { fprintf(stderr, "%s\n", gpu.error().toString().c_str()); return 1; }
//   for (each frame) {
//     ... scene.setTransform(id, x) ...; scene.commit();     // the CPU vff::Scene (vff/scene.h)
//     if (vff::Status s = gpu->update(scene); !s) return s;  // instances + hierarchy
//     gpu->bind();                                           // bindings 1..6 (SceneBindings)
//     // shader: #version 430, then sceneShaderSource(vff_scene.glsl, vff_query.glsl), then e.g.
//     // vffSceneIntersect(o, d, 0.0, tmax, -1.0, false)
//   }
//
// What loadScene uploads once (owned by the GpuScene):
// * every field's distance slices in ONE GL_TEXTURE_2D_ARRAY (GL_R8UI for unorm8-diameter,
//   unorm8-chord and bit1, which mix freely; GL_R16UI when every field is unorm16-diameter), field
//   f's slices from layer SceneFieldBlock::mapsLayer, each at the corner (0, 0) of layers as wide
//   and high as the largest field's slices (fields may differ in slice size, tile size, gutter,
//   map resolution, position and direction scheme);
// * the normal slices of the fields that have a normal plane in one GL_RG16I array (normalsLayer);
// * every field's positions buffer (makePositionsBuffer), back to back (positionsBase, in vec4);
// * the field table: one SceneFieldBlock per field.
// What update(scene) uploads per frame: one SceneInstanceBlock per instance, in the hierarchy's
// leaf order, and the nodes buffer (SceneNodesHeader then vff::SceneNode per node,
// vff::Scene::hierarchy). The buffers grow when the scene does; their contents are replaced.
//
// Preconditions: as loadField's (vff/gl/loader.h): a GL 4.3 context current on the calling
// thread for loadScene, update, bind and the destructor. The Files must stay open during
// loadScene only; the FieldQuery pointers identify the fields: every instance of the scenes given
// to update() must use one of them (the query whose maps were uploaded from that file).
//
// Errors (values): kInvalidArgument (no fields, a null file or query, the same query twice, an
// instance whose field is not among them); kUnsupported (a 3D layout, bc4-diameter, texel formats
// that differ between fields, more layers than GL_MAX_ARRAY_TEXTURE_LAYERS, slices beyond
// GL_MAX_TEXTURE_SIZE, a hierarchy deeper than the shader's stack, VFF_SCENE_STACK); kBadState
// (the scene is not committed, or GL reports an error); those of File::readSlice.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "vff/gl/loader.h"
#include "vff/scene.h"

namespace vff::gl {

// A field of the scene: its file (for the upload) and the FieldQuery the Scene's instances use.
struct SceneField {
  const File* file = nullptr;
  const FieldQuery* query = nullptr;
};

// GLSL VffSceneField (std430, 128 bytes): the field's FieldBlock, then where its data lie.
struct SceneFieldBlock {
  FieldBlock field;
  uint32_t mapsLayer = 0;      // first slice in the maps texture
  uint32_t normalsLayer = 0;   // first slice in the normals texture (fields with normals)
  uint32_t positionsBase = 0;  // vec4 index of its positions buffer in the shared buffer
  uint32_t reserved2 = 0;
};
static_assert(sizeof(SceneFieldBlock) == 128, "SceneFieldBlock must match the std430 VffSceneField");

// GLSL VffSceneInstance (std430, 96 bytes).
struct SceneInstanceBlock {
  float rotation[3][4] = {};    // rows of RigidTransform::rotation, w = 0
  float translation[3] = {};
  float invScale = 1;           // 1.0f / scale (the CPU's float division)
  float sphere[4] = {};         // Instance::worldSphere(): centre, radius
  uint32_t id = 0;              // the instance's id in the Scene
  uint32_t field = 0;           // index into the field table
  float scale = 1;
  uint32_t reserved = 0;
};
static_assert(sizeof(SceneInstanceBlock) == 96, "SceneInstanceBlock must match the std430 VffSceneInstance");

// The head of GLSL VffSceneNodesBlock (the nodes follow, 16-byte aligned).
struct SceneNodesHeader {
  uint32_t nodeCount = 0;
  float maxRadius = 0;          // SceneHierarchy::maxRadius
  uint32_t instanceCount = 0;
  uint32_t reserved = 0;
};
static_assert(sizeof(SceneNodesHeader) == 16, "SceneNodesHeader is a vec4 of the std430 block");

// The shader's stack (VFF_SCENE_STACK's default): update() refuses a deeper hierarchy.
inline constexpr uint32_t kSceneStack = 64;

// Where the fields of a scene go (no GL calls): field f's block with mapsLayer, normalsLayer and
// positionsBase filled in; *positions receives every field's positions buffer back to back.
// Errors: those of makeFieldBlock and makePositionsBuffer; kUnsupported for a 3D layout,
// bc4-diameter, or texel formats that differ between fields.
struct ScenePlan {
  std::vector<SceneFieldBlock> fields;
  std::vector<float> positions;
  uint32_t mapsWidth = 0, mapsHeight = 0, mapsLayers = 0;  // the maps texture (width in texels)
  uint32_t normalsWidth = 0, normalsHeight = 0, normalsLayers = 0;  // 0 layers: no normals
  bool wideTexels = false;  // GL_R16UI (unorm16-diameter) rather than GL_R8UI
};
Result<ScenePlan> planScene(std::span<const FieldDesc> fields, std::span<const LayoutDesc> layouts);

// The instance table of a committed scene in the hierarchy's leaf order (no GL calls): `fields`
// maps each instance's FieldQuery to its index. Errors: kBadState (not committed),
// kInvalidArgument (an instance's field is not in `fields`).
Result<std::vector<SceneInstanceBlock>> makeSceneInstances(const Scene& scene, const SceneHierarchy& hierarchy,
                                                           std::span<const FieldQuery* const> fields);

// The nodes buffer of a hierarchy (no GL calls): SceneNodesHeader (instanceCount instances), then
// the nodes. Errors: kUnsupported when the hierarchy could need more than the shader's stack
// (kSceneStack).
Result<std::vector<uint8_t>> makeSceneNodes(const SceneHierarchy& hierarchy, uint32_t instanceCount);

// The compute/fragment shader text for a scene: vff_scene.glsl's text with its
// `#include "vff_query.glsl"` line replaced by vff_query.glsl's text (GL has no #include).
std::string sceneShaderSource(const std::string& sceneGlsl, const std::string& queryGlsl);

// Where bind() attaches the scene; the defaults are those of vff_scene.glsl.
struct SceneBindings {
  uint32_t maps = 1;       // texture unit (VFF_MAPS_BINDING)
  uint32_t positions = 2;  // storage buffer (VFF_POSITIONS_BINDING)
  uint32_t normals = 3;    // texture unit (VFF_NORMALS_BINDING)
  uint32_t fields = 4;     // storage buffer (VFF_SCENE_FIELDS_BINDING)
  uint32_t instances = 5;  // storage buffer (VFF_SCENE_INSTANCES_BINDING)
  uint32_t nodes = 6;      // storage buffer (VFF_SCENE_NODES_BINDING)
};

// A scene on the GPU. Move-only (a moved-from GpuScene is empty); the destructor deletes the GL
// objects (the context must be current).
class GpuScene {
 public:
  GpuScene() = default;
  GpuScene(GpuScene&& o) noexcept : s_(std::exchange(o.s_, {})) {}
  GpuScene& operator=(GpuScene&& o) noexcept {
    s_ = std::exchange(o.s_, {});  // (the objects held before are deleted)
    return *this;
  }

  // Uploads the committed scene's instances and hierarchy (see the top of this file).
  Status update(const Scene& scene);
  // Binds the resources (the normals texture only when a field has normals). Leaves the active
  // texture unit at `maps`.
  void bind(const SceneBindings& bindings = {}) const noexcept;
  // Deletes the GL objects now; the object becomes empty.
  void release() noexcept { s_ = {}; }

  const ScenePlan& plan() const noexcept { return s_.plan; }
  uint32_t instanceCount() const noexcept { return s_.instanceCount; }
  uint64_t textureBytes() const noexcept { return s_.textureBytes; }

 private:
  friend Result<GpuScene> loadScene(std::span<const SceneField> fields, const LoadOptions& options);
  struct State {
    ScenePlan plan;
    std::vector<const FieldQuery*> queries;
    GlName maps{GlName::Kind::kTexture}, normals{GlName::Kind::kTexture};
    GlName positions{GlName::Kind::kBuffer}, fields{GlName::Kind::kBuffer};
    GlName instances{GlName::Kind::kBuffer}, nodes{GlName::Kind::kBuffer};
    uint64_t instancesSize = 0, nodesSize = 0;  // bytes allocated
    uint32_t instanceCount = 0;
    uint64_t textureBytes = 0;
  } s_;
};

// Uploads the fields (see the top of this file); update() then uploads a scene's instances.
Result<GpuScene> loadScene(std::span<const SceneField> fields, const LoadOptions& options = {});

}  // namespace vff::gl
