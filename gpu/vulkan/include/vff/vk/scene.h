// vff/vk/scene.h - a vff::Scene on Vulkan for gpu/glsl/vff_scene.glsl: several fields resident at
// once, the instances and top-level hierarchy updated per frame, and a compute pipeline that runs
// world rays through the scene walk. The Vulkan counterpart of vff/gl/scene_loader.h, with the
// same data (vff::gl::planScene, makeSceneInstances, makeSceneNodes; no second copy of the
// planning). The loader uploads an empty scene until the first update (every ray misses).
//
//   std::vector<vff::gl::SceneField> fields = {{&bunnyFile, &bunnyQuery}, {&teapotFile, &teapotQuery}};
//   vff::Result<vff::vk::GpuScene> gpu = vff::vk::loadScene(ctx, fields);
//   if (!gpu) { fprintf(stderr, "%s\n", gpu.error().toString().c_str()); return 1; }
//   auto pipe = vff::vk::ScenePipeline::create(ctx);         // {.language = kHlsl}: the HLSL kernel
//   for (each frame) {
//     ... scene.setTransform(id, x) ...; scene.commit();     // the CPU vff::Scene (vff/scene.h)
//     if (vff::Status s = gpu->update(ctx, scene); !s) return s;
//     auto answers = pipe->run(ctx, *gpu, rays);              // one SceneAnswer a ray
//   }
//
// Descriptor set 0 (vff_scene.glsl's `binding =` defaults, the numbers the GL loader binds):
//
//   binding  type                      shader name (vff_scene.glsl)   contents
//   1        COMBINED_IMAGE_SAMPLER    vffMaps                        every field's distance slices, one 2D array
//   2        STORAGE_BUFFER            VffPositionsBlock              every field's positions buffer, back to back
//   3        COMBINED_IMAGE_SAMPLER    vffNormals                     the normal slices of the fields with normals
//   4        STORAGE_BUFFER            VffSceneFieldsBlock            vff::gl::SceneFieldBlock[] (std430, 128 B)
//   5        STORAGE_BUFFER            VffSceneInstancesBlock         vff::gl::SceneInstanceBlock[], leaf order
//   6        STORAGE_BUFFER            VffSceneNodesBlock             vff::gl::SceneNodesHeader, vff::SceneNode[]
// Binding 0 (the single field's uniform block) is not declared: the field table replaces it.
// ScenePipeline adds
//   7        STORAGE_BUFFER            VffVkSceneRays                 SceneRay[n]
//   8        STORAGE_BUFFER            VffVkSceneAnswers              SceneAnswer[n]
// and a 12-byte push constant (the queries to run, the first ray of a dispatch, the ray count).
//
// What loadScene creates once (owned by the GpuScene; the layout of vff::gl::planScene):
// * every field's distance slices in ONE 2D-array image, R8_UINT (unorm8-diameter, unorm8-chord,
//   bit1, which mix) or R16_UINT (every field unorm16-diameter), field f's from layer
//   SceneFieldBlock::mapsLayer at the corner (0, 0) of layers as large as the largest field's
//   slices; copied as the single-field loader copies them (vff/vk/field.h);
// * the normal slices of the fields with a normal plane in one R16G16_SINT 2D array (a 1 x 1 x 1
//   placeholder when no field has one: Vulkan wants every declared binding valid);
// * the positions buffer and the field table in storage buffers; one nearest, clamped sampler.
// What update(ctx, scene) writes per frame: the instance table and the nodes buffer (host-visible,
// grown when the scene does). A descriptor set written before an update may hold a buffer that the
// update replaced: write() after update(), as ScenePipeline::run does on every call.
//
// The kernel: gpu/vulkan/shaders/vff_vk_scene.comp, which includes vff_scene.glsl (and through it
// vff_query.glsl) unchanged, compiled by glslangValidator -V at build time; with
// ShaderLanguage::kHlsl, the HLSL that spirv-cross generates from that SPIR-V
// (<build>/hlsl/vff_scene_array2d.hlsl) compiled by glslang's HLSL front end (gpu/README.md, "HLSL").
//
// Errors (values): those of vff::gl::planScene and makeSceneInstances (kInvalidArgument: no
// fields, a null file or query, the same query twice, an instance whose field was not loaded;
// kUnsupported: a 3D layout, bc4-diameter, texel formats that differ between fields; kBadState: the
// scene is not committed); kUnsupported when the slices exceed maxImageDimension2D or all fields'
// slices together maxImageArrayLayers, or the hierarchy is deeper than the shader's stack
// (vff::gl::kSceneStack); File's; a failing Vulkan call's (vkError). ScenePipeline::create:
// kUnsupported for a language whose kernels this build lacks; run: kUnsupported when a batch's
// answers exceed maxStorageBufferRange.
//
// Preconditions: the Context outlives what is made from it; one thread at a time. The Files must
// stay open during loadScene only; the FieldQuery pointers identify the fields. Move-only; a
// moved-from or default-constructed object may only be destroyed or assigned to.
#pragma once

#include <vulkan/vulkan.h>

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "vff/error.h"
#include "vff/gl/scene_loader.h"
#include "vff/scene.h"
#include "vff/vk/context.h"
#include "vff/vk/query.h"

namespace vff::vk {

// Set 0's bindings of the scene (vff_scene.glsl's defaults, vff::gl::SceneBindings).
inline constexpr uint32_t kSceneMapsBinding = 1;
inline constexpr uint32_t kScenePositionsBinding = 2;
inline constexpr uint32_t kSceneNormalsBinding = 3;
inline constexpr uint32_t kSceneFieldsBinding = 4;
inline constexpr uint32_t kSceneInstancesBinding = 5;
inline constexpr uint32_t kSceneNodesBinding = 6;

class GpuScene {
 public:
  GpuScene();
  GpuScene(GpuScene&&) noexcept;
  GpuScene& operator=(GpuScene&&) noexcept;
  ~GpuScene();

  // Writes the committed scene's instances (leaf order) and hierarchy (see the top of this file).
  // Waits for nothing: no dispatch reading the buffers may be in flight (ScenePipeline::run waits).
  Status update(const Context& ctx, const Scene& scene);
  // Writes bindings 1 to 6 of `set` (a set of a layout with them as in the table).
  void write(VkDescriptorSet set) const noexcept;

  const gl::ScenePlan& plan() const noexcept;
  uint32_t instanceCount() const noexcept;
  uint64_t textureBytes() const noexcept;  // bytes copied into the images

  struct State;  // (the implementation's)

 private:
  friend Result<GpuScene> loadScene(const Context& ctx, std::span<const gl::SceneField> fields);
  std::unique_ptr<State> s_;
};

// Uploads the fields (see the top of this file); update() then writes a scene's instances.
Result<GpuScene> loadScene(const Context& ctx, std::span<const gl::SceneField> fields);

// A world-space ray (std430 VffVkSceneRay): t in multiples of the direction, as vff::Ray.
// `source`: the instance the ray starts on (vff::Scene's *From calls: that instance answers with
// intraBias, section 7.3, every other off the object, 7.4), kNoInstance for none, or
// kSceneNoSources for the calls without a source (every instance with intraBias).
inline constexpr uint32_t kSceneNoSources = 0xFFFFFFFEu;
struct SceneRay {
  float origin[3];
  uint32_t source = kSceneNoSources;
  float direction[3];
  float tmin = 0;
  float tmax = 0;
  float intraBias = -1;  // vffQuery's: >= 0 that bias, -2 off the object, other negatives the field's
  uint32_t reserved[2] = {0, 0};
};
static_assert(sizeof(SceneRay) == 48);

// An answer (std430 VffVkSceneAnswer); the members of the queries not run are zero.
struct SceneAnswer {
  uint32_t nearestHit;       // vffSceneIntersect, kNearest
  float nearestT;            // +inf without a hit
  uint32_t nearestInstance;  // the instance's id; kNoInstance without a hit
  uint32_t occluded;         // vffSceneOccluded, kNearest
  uint32_t interpHit;        // vffSceneIntersect, kInterpolated
  float interpT;
  uint32_t interpInstance;
  float visibility;  // vffSceneVisibility, kInterpolated
  float normal[4];   // the kNearest hit's world normal; w = 1 when it has one
};
static_assert(sizeof(SceneAnswer) == 48);

struct SceneRunOptions {
  bool nearest = true;       // intersect with Reconstruction::kNearest
  bool interpolated = true;  // intersect with kInterpolated
  bool occluded = true;      // occluded, kNearest
  bool visibility = true;    // visibility, kInterpolated
  uint32_t repeat = 1;       // dispatches over the same rays in one submission (benchmarks)
};

class ScenePipeline {
 public:
  ScenePipeline();
  ScenePipeline(ScenePipeline&&) noexcept;
  ScenePipeline& operator=(ScenePipeline&&) noexcept;
  ~ScenePipeline();

  // The pipeline, its kernel compiled from options.language (QueryPipeline::available says
  // whether this build has it).
  static Result<ScenePipeline> create(const Context& ctx, const PipelineOptions& options = {});

  // Runs every ray through the scene as last updated and returns the answers, in order. Waits for
  // the device. `seconds`: as QueryPipeline::run's.
  Result<std::vector<SceneAnswer>> run(const Context& ctx, const GpuScene& scene, std::span<const SceneRay> rays,
                                       const SceneRunOptions& options = {}, double* seconds = nullptr) const;

  ShaderLanguage language() const noexcept;

  struct State;  // (the implementation's)

 private:
  std::unique_ptr<State> s_;
};

}  // namespace vff::vk
