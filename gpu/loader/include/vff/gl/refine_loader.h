// vff/gl/refine_loader.h - a refined field's exact step (vff/refine.h) on OpenGL 4.3, for the
// refined path, gpu/glsl/vff_refine.glsl after gpu/glsl/vff_query.glsl (Reconstruction::kRefined: vffIntersectRefined,
// vffOccludedRefined).
//
//   vff::Result<vff::File> file = vff::File::open("bunny.vff");        // written with a refinement
//   auto field  = vff::gl::loadField(*file);                          // a GL 4.3 context is current
//   auto refine = vff::gl::loadRefinement(*file);                     // the file's REFN section
//   if (!field || !refine) ...                                        // vff::Error values
//   field->bind();                                                    // bindings 0 to 3
//   refine->bind();                                                   // bindings 10 to 14
//   // shader: #version 430, shaderDefines(field, layout), refine->shaderDefines(), then the text
//   // of vff_query.glsl; vffIntersectRefined(o, d, 0.0, tmax, -1.0), vffOccludedRefined(...)
//
// What loadRefinement uploads (all owned by the GpuRefinement, deleted by its destructor):
// * a uniform buffer holding a RefineBlock (std140, the shader's VffRefineBlock): the margin in
//   object units, the counts and the BVH's depth;
// * four shader storage buffers: the unsure bits as 32-bit words (bit x % 32 of word x / 32, x the
//   texel's index (k M + j) M + i); the vertex positions (three floats per vertex); the BVH of
//   vff::buildRefinementBvh (8 words per node, as the CPU query builds it); its triangles' vertex
//   indices (three words per triangle, leaf order).
// An empty refinement uploads a block with triangleCount 0 (and one-word buffers): the shader
// then answers every ray as kNearest, as the CPU query does without a refinement.
//
// Preconditions, as loadField's (vff/gl/loader.h): a GL 4.3 context current on the calling thread
// for loadRefinement, bind and the destructor; the state loadRefinement changes is restored.
// The refinement must be the one of the field uploaded with loadField (same map count and M).
//
// Errors (values): those of vff::encodeRefinement for a refinement that does not match the field
// (kInvalidArgument...); kUnsupported when the texels' index (mapCount M^2) or a count does not
// fit the shader's 32-bit words, or the BVH is deeper than kRefineStack; kBadState,
// kOutOfMemory as loadField's.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "vff/error.h"
#include "vff/format.h"
#include "vff/gl/gl_name.h"
#include "vff/reader.h"
#include "vff/refine.h"

namespace vff::gl {

// The shader's uniform block VffRefineBlock, std140 (four 4-byte scalars).
struct RefineBlock {
  float margin = 0;            // RefinementView::margin * R, the CPU query's float product
  uint32_t triangleCount = 0;  // 0: no refinement (every ray is answered as kNearest)
  uint32_t nodeCount = 0;      // BVH nodes
  uint32_t stackDepth = 0;     // the BVH's depth (root 0): the cast's stack holds at most this many
};
static_assert(sizeof(RefineBlock) == 16, "RefineBlock must match the std140 block");

// VFF_REFINE_STACK's default in the shader: the depth the CPU's builder never exceeds
// (vff::kRefinementBvhMaxDepth). loadRefinement refuses a deeper BVH.
inline constexpr uint32_t kRefineStack = kRefinementBvhMaxDepth;

// What loadRefinement uploads, computed without GL (tests check it against libvff).
struct RefinementBuffers {
  RefineBlock block;
  std::vector<uint32_t> unsure;     // ceil(mapCount M^2 / 32) words
  std::vector<float> vertices;      // RefinementView::positions
  std::vector<uint32_t> nodes;      // vff::buildRefinementBvh(...).nodes
  std::vector<uint32_t> triangles;  // vff::buildRefinementBvh(...).triangles
};
Result<RefinementBuffers> makeRefinementBuffers(const FieldDesc& field, const RefinementView& refinement);

// The #define lines of the refined path, to put after shaderDefines(field, layout):
// "#define VFF_REFINED\n#define VFF_REFINE_STACK <max(1, stackDepth)>\n".
std::string refinementShaderDefines(const RefineBlock& block);

// Where bind() attaches the refinement; the defaults are those of vff_query.glsl.
struct RefinementBindings {
  uint32_t unsure = 10;     // shader storage buffer (VFF_UNSURE_BINDING)
  uint32_t vertices = 11;   // shader storage buffer (VFF_VERTICES_BINDING)
  uint32_t bvh = 12;        // shader storage buffer (VFF_BVH_BINDING)
  uint32_t triangles = 13;  // shader storage buffer (VFF_TRIANGLES_BINDING)
  uint32_t block = 14;      // uniform buffer (VFF_REFINE_BINDING)
};

// A refinement on the GPU. Move-only (a moved-from GpuRefinement is empty); the destructor deletes
// the GL objects (the context must be current).
class GpuRefinement {
 public:
  GpuRefinement() = default;
  GpuRefinement(GpuRefinement&& o) noexcept : s_(std::exchange(o.s_, {})) {}
  GpuRefinement& operator=(GpuRefinement&& o) noexcept {
    s_ = std::exchange(o.s_, {});  // (the objects held before are deleted)
    return *this;
  }

  void bind(const RefinementBindings& bindings = {}) const noexcept;
  // Deletes the GL objects now (the context must be current); the object becomes empty.
  void release() noexcept { s_ = {}; }

  const RefineBlock& block() const noexcept { return s_.block; }
  // refinementShaderDefines(block()).
  std::string shaderDefines() const { return refinementShaderDefines(s_.block); }
  uint64_t bytes() const noexcept { return s_.bytes; }  // bytes of the five buffers

 private:
  friend Result<GpuRefinement> loadRefinement(const FieldDesc& field, const RefinementView& refinement);
  struct State {
    RefineBlock block;
    GlName blockBuffer{GlName::Kind::kBuffer}, unsure{GlName::Kind::kBuffer}, vertices{GlName::Kind::kBuffer};
    GlName bvh{GlName::Kind::kBuffer}, triangles{GlName::Kind::kBuffer};
    uint64_t bytes = 0;
  } s_;
};

// Uploads a refinement of `field` (see the top of this file). The FieldQuery of the same maps has
// the field as FieldQuery::field().
Result<GpuRefinement> loadRefinement(const FieldDesc& field, const RefinementView& refinement);
// The file's own refinement (File::refinement(); empty without a REFN section).
Result<GpuRefinement> loadRefinement(const File& file);

}  // namespace vff::gl
