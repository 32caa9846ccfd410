// vff/vk/query.h - rays through gpu/glsl/vff_query.glsl in a Vulkan compute pipeline.
//
//   auto ctx  = vff::vk::Context::create();
//   auto gpu  = vff::vk::loadField(*ctx, file);                               // vff/vk/field.h
//   auto pipe = vff::vk::QueryPipeline::create(*ctx, gpu->kind());  // {.language = kHlsl}: the HLSL kernel
//   std::vector<vff::vk::QueryRay> rays = ...;          // object space, as vffIntersect takes them
//   auto answers = pipe->run(*ctx, *gpu, rays);               // one QueryAnswer a ray, both reconstructions
//
// The shader is gpu/vulkan/shaders/vff_vk_query.comp, which includes vff_query.glsl; it is compiled
// to SPIR-V at build time (glslangValidator -V) in three variants, one per MapsKind, and embedded in
// the library, so nothing is read from disk at run time.
//
// The same kernel is also built from HLSL (PipelineOptions::language = ShaderLanguage::kHlsl): the
// GLSL's SPIR-V is turned into HLSL for shader model 6.0 by spirv-cross and that HLSL is compiled to
// SPIR-V by glslang's HLSL front end (glslangValidator -D), again per variant, at build time
// (gpu/vulkan/make_hlsl.cmake; gpu/README.md, "HLSL"). Both kernels take the same descriptor set,
// push constant and structs, so a caller changes nothing else. The HLSL kernels exist only where
// spirv-cross was found at configure time: QueryPipeline::available(ShaderLanguage::kHlsl) says so.
//
// Descriptor set 0 of the pipeline: bindings 0 to 3 are the field's (vff/vk/field.h's table), then
//   4  STORAGE_BUFFER  VffVkRays     QueryRay[n]
//   5  STORAGE_BUFFER  VffVkAnswers  QueryAnswer[n]
// and a 12-byte push constant (which reconstructions to run, RunOptions; the first ray of the
// dispatch; the batch's ray count). Workgroups of 64 rays; a batch beyond the device's
// maxComputeWorkGroupCount[0] groups is split into several dispatches.
//
// Errors (values): a failing Vulkan call's (vkError); kUnsupported from create() for a language
// whose kernels this build lacks; kInvalidArgument when the field needs another variant than the
// pipeline's; kUnsupported when the answers of a batch exceed the device's maxStorageBufferRange
// (run it in parts).
//
// Move-only; a moved-from or default-constructed QueryPipeline may only be destroyed or assigned to.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "vff/error.h"
#include "vff/vk/context.h"
#include "vff/vk/field.h"

namespace vff::vk {

// A ray (std430 VffVkRay): origin and direction in xyz (w unused), range = tmin, tmax, intraBias
// (vffIntersect's: >= 0 that bias, VFF_OFF_OBJECT = -2 off the object, other negatives the
// field's default), unused.
struct QueryRay {
  float origin[4];
  float direction[4];
  float range[4];
};
static_assert(sizeof(QueryRay) == 48);

// An answer (std430 VffVkAnswer).
struct QueryAnswer {
  enum : uint32_t { kHit = 1, kInside = 2, kLooked = 4, kHasNormal = 8, kInterpHit = 16, kInterpHasNormal = 32 };
  uint32_t flags;
  float t;                  // kNearest, in multiples of the direction; +inf without a hit
  uint32_t sampleIndex;     // kNearest's lookup (valid with kLooked): sample k, texel (i, j),
  uint32_t texelI, texelJ;  // stored code, decoded distance
  uint32_t code;
  float distance;
  float visibility;       // kInterpolated FieldQuery::visibility
  float normal[4];        // kNearest's object-space normal (kHasNormal)
  float interpNormal[4];  // kInterpolated's (kInterpHasNormal)
  float interpT[4];       // x: kInterpolated t
};
static_assert(sizeof(QueryAnswer) == 80);

struct RunOptions {
  bool nearest = true;       // vffIntersect (Reconstruction::kNearest)
  bool interpolated = true;  // vffQuery(..., true, visibility) (kInterpolated)
  uint32_t repeat = 1;       // dispatches over the same rays in one submission (benchmarks)
};

// The language the pipeline's kernel was compiled from. Both are the one query source
// (gpu/glsl/vff_query.glsl); kHlsl is the HLSL that spirv-cross generates from it, which is what an
// HLSL engine would compile, so running it here tests that text.
enum class ShaderLanguage : uint32_t {
  kGlsl = 0,  // glslangValidator -V of shaders/vff_vk_query.comp
  kHlsl = 1,  // spirv-cross --hlsl --shader-model 60 of that, then glslangValidator -D -V (HLSL front end)
};

struct PipelineOptions {
  ShaderLanguage language = ShaderLanguage::kGlsl;
};

class QueryPipeline {
 public:
  QueryPipeline();
  QueryPipeline(QueryPipeline&&) noexcept;
  QueryPipeline& operator=(QueryPipeline&&) noexcept;
  ~QueryPipeline();

  // The pipeline for fields of `kind` (GpuField::kind()), its kernel compiled from
  // options.language. The Context outlives it. kUnsupported when that language's kernels were not
  // built (available() is false).
  static Result<QueryPipeline> create(const Context& ctx, MapsKind kind, const PipelineOptions& options = {});

  // Whether this build embeds the kernels of `language`: kGlsl always; kHlsl where spirv-cross was
  // found when vff_vk was configured.
  static bool available(ShaderLanguage language) noexcept;

  // Runs every ray once (RunOptions::repeat times) and returns the answers, in order. Waits for the
  // device. `ctx`: the one the pipeline and the field were made with. `seconds`, when given,
  // receives the time of the command buffer's recording, submission and completion, without the
  // buffers' creation and copies.
  Result<std::vector<QueryAnswer>> run(const Context& ctx, const GpuField& field, std::span<const QueryRay> rays,
                                       const RunOptions& options = {}, double* seconds = nullptr) const;

  MapsKind kind() const noexcept;
  ShaderLanguage language() const noexcept;

  struct State;  // (the implementation's)

 private:
  std::unique_ptr<State> s_;
};

}  // namespace vff::vk
