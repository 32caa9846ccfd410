// vff/vk/refine.h - the refined query (Reconstruction::kRefined, vff/refine.h: gpu/glsl/vff_refine.glsl
// after vff_query.glsl) in a Vulkan compute pipeline: a refined field's exact step uploaded beside
// the field, and a kernel that answers rays with it.
//
//   auto ctx    = vff::vk::Context::create();
//   auto file   = vff::File::open("bunny.vff");                   // baked with --refine
//   auto gpu    = vff::vk::loadField(*ctx, *file);                // vff/vk/field.h: bindings 0 to 3
//   auto refine = vff::vk::loadRefinement(*ctx, *file);           // the file's REFN: bindings 10 to 14
//   auto pipe   = vff::vk::RefinedPipeline::create(*ctx, gpu->kind());  // {.language = kHlsl}: HLSL
//   auto answers = pipe->run(*ctx, *gpu, *refine, rays);          // one RefinedAnswer a ray
//
// What loadRefinement uploads is what vff::gl::loadRefinement uploads (vff/gl/refine_loader.h,
// computed once by vff::gl::makeRefinementBuffers), in host-visible buffers owned by the
// GpuRefinement:
//
//   binding  type             shader name (vff_refine.glsl)   contents
//   10       STORAGE_BUFFER   VffUnsureBlock                  the unsure bits, 32 texels a word
//   11       STORAGE_BUFFER   VffVerticesBlock                vertex positions, three floats each
//   12       STORAGE_BUFFER   VffBvhBlock                     the BVH, 8 words a node
//   13       STORAGE_BUFFER   VffTrianglesBlock               three vertex indices a triangle
//   14       UNIFORM_BUFFER   VffRefineBlock                  vff::gl::RefineBlock (std140, 16 bytes)
//
// A file without a REFN section uploads an empty refinement (triangleCount 0): the kernel then
// answers every ray as kNearest, as the CPU query does.
//
// The kernel is gpu/vulkan/shaders/vff_vk_refine.comp, compiled at build time per MapsKind with the
// shader's default stack (VFF_REFINE_STACK = vff::gl::kRefineStack, the deepest BVH the loader
// takes) and embedded, as the query's kernels are (vff/vk/query.h); its HLSL is spirv-cross's
// (<build>/hlsl/vff_refine_<variant>.hlsl, installed beside the query's). Set 0 of the pipeline:
// the field's bindings 0 to 3, the rays (QueryRay[n], vff/vk/query.h) at 4, the answers
// (RefinedAnswer[n]) at 5, the refinement's at 10 to 14; the push constant is the query's.
//
// Errors (values): makeRefinementBuffers' (a refinement that does not match the field, a BVH
// deeper than the stack: kInvalidArgument, kUnsupported); a failing Vulkan call's (vkError);
// kUnsupported from create() for a language whose kernels this build lacks; kInvalidArgument from
// run() when the field needs another variant than the pipeline's, or the refinement is not the
// field's (another map count or resolution); kUnsupported when a batch's answers exceed the device's
// maxStorageBufferRange.
//
// Preconditions: the Context outlives what is made with it. Move-only; a moved-from or
// default-constructed GpuRefinement or RefinedPipeline may only be destroyed or assigned to.
#pragma once

#include <vulkan/vulkan.h>

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "vff/error.h"
#include "vff/gl/refine_loader.h"
#include "vff/reader.h"
#include "vff/refine.h"
#include "vff/vk/context.h"
#include "vff/vk/field.h"
#include "vff/vk/query.h"

namespace vff::vk {

// Set 0's bindings of the refinement: vff_refine.glsl's defaults (vff::gl::RefinementBindings).
inline constexpr uint32_t kUnsureBinding = 10;
inline constexpr uint32_t kVerticesBinding = 11;
inline constexpr uint32_t kBvhBinding = 12;
inline constexpr uint32_t kTrianglesBinding = 13;
inline constexpr uint32_t kRefineBlockBinding = 14;

// A refined answer (std430 VffVkRefinedAnswer of vff_vk_refine.comp). The flags are floats 0 or 1,
// as the kernel writes them.
struct RefinedAnswer {
  float hit;        // vffIntersectRefined (Reconstruction::kRefined): a hit within the range
  float t;          // its distance in multiples of the direction; +inf without a hit
  float occluded;   // vffOccludedRefined over the same range
  float hasNormal;  // the answer carries an object-space normal
  float normal[3];
  float sameAsQuery;  // 1 when vffQueryRefined answered as vffIntersectRefined (the kernel's own check)
  float nearestHit;   // vffIntersect (kNearest) over the same range, for comparison
  float nearestT;
  float unused[2];
  uint32_t exact;        // 1 when the exact step answered (an unsure texel, or a hit near the range's ends)
  uint32_t sampleIndex;  // kNearest's lookup: the sample, 0xffffffff without a lookup (the ray missed the sphere)
  uint32_t texelI, texelJ;
};
static_assert(sizeof(RefinedAnswer) == 64);

class GpuRefinement {
 public:
  GpuRefinement();
  GpuRefinement(GpuRefinement&&) noexcept;
  GpuRefinement& operator=(GpuRefinement&&) noexcept;
  ~GpuRefinement();

  // Writes bindings 10 to 14 of `set` (a set of a layout with them as in the table).
  void write(VkDescriptorSet set) const noexcept;

  const gl::RefineBlock& block() const noexcept;
  uint32_t mapCount() const noexcept;  // the field's, which the unsure bits cover
  uint64_t bytes() const noexcept;     // bytes of the five buffers

  struct State;  // (the implementation's)

 private:
  friend Result<GpuRefinement> loadRefinement(const Context& ctx, const FieldDesc& field,
                                              const RefinementView& refinement);
  friend class RefinedPipeline;
  std::unique_ptr<State> s_;
};

// Uploads a refinement of `field` (see the top of this file).
Result<GpuRefinement> loadRefinement(const Context& ctx, const FieldDesc& field, const RefinementView& refinement);
// The file's own refinement (File::refinement(); empty without a REFN section).
Result<GpuRefinement> loadRefinement(const Context& ctx, const File& file);

class RefinedPipeline {
 public:
  RefinedPipeline();
  RefinedPipeline(RefinedPipeline&&) noexcept;
  RefinedPipeline& operator=(RefinedPipeline&&) noexcept;
  ~RefinedPipeline();

  // The pipeline for fields of `kind`, its kernel compiled from options.language (kUnsupported
  // where that language's kernels were not built: QueryPipeline::available).
  static Result<RefinedPipeline> create(const Context& ctx, MapsKind kind, const PipelineOptions& options = {});

  // Answers every ray (RunOptions::repeat times; its nearest and interpolated flags are ignored:
  // the kernel always gives both answers) and returns the answers, in order. Waits for the
  // device. `seconds`: as QueryPipeline::run's.
  Result<std::vector<RefinedAnswer>> run(const Context& ctx, const GpuField& field, const GpuRefinement& refinement,
                                         std::span<const QueryRay> rays, const RunOptions& options = {},
                                         double* seconds = nullptr) const;

  MapsKind kind() const noexcept;
  ShaderLanguage language() const noexcept;

  struct State;  // (the implementation's)

 private:
  std::unique_ptr<State> s_;
};

}  // namespace vff::vk
