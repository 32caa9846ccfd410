// sdf_gl.h - the distance-field peer (samples/experiments/sdf_field.h) on OpenGL 4.3, for
// gpu/glsl/vff_sdf.glsl: sphere tracing of the SdfField's NanoVDB grid through PNanoVDB's GLSL path.
//
//   vffx::SdfField sdf = ...;                            // vffx::SdfField::build(mesh, options)
//   auto gpu = vffx::gl::uploadSdf(sdf);                 // a GL 4.3 context is current
//   if (!gpu) { fprintf(stderr, "%s\n", gpu.error().toString().c_str()); return 1; }
//   gpu->bind();                                         // SSBO 8 (the grid), UBO 9 (VffSdfBlock)
//   // shader: "#version 430\n" + sdfShaderDefines(sdf) + sdfShaderSource(text of vff_sdf.glsl)
//   //         + main calling vffSdfIntersect(o, d, tmin, tmax) / vffSdfOccluded (object space)
//
// Why here and not in vff_gl (vff/gl/loader.h): the grid is the distance-field peer's (sdf/, vffx,
// built with OpenVDB and NanoVDB), not part of the .vff format that libvff and vff_gl serve; the
// public GL library stays free of those dependencies, and this library (vff_sdf_gl) serves
// vff-gpu-bench and tests/gpu.
//
// What uploadSdf creates (owned by the GpuSdf, deleted by its destructor): a shader storage buffer
// holding the grid's bytes as SdfField::gridBuffer() gives them (the NanoVDB buffer, read in place
// by PNanoVDB: no conversion), and a uniform buffer holding an SdfBlock made by makeSdfBlock.
// Memory on the GPU: the NanoVDB buffer (SdfField::nanovdbBytes()) plus the 64-byte block.
//
// Errors (values): kUnsupported for a grid over GL_MAX_SHADER_STORAGE_BLOCK_SIZE or 4 GiB
// (PNanoVDB's GLSL path addresses bytes with 32 bits) or a context below 4.3; kBadState when GL
// reports an error or no context is current; kOutOfMemory for GL_OUT_OF_MEMORY.
#pragma once

#include <cstdint>
#include <string>
#include <utility>

#include "vff/sdf/sdf_field.h"
#include "vff/error.h"
#include "vff/gl/gl_name.h"

namespace vffx::gl {

// The shader's uniform block VffSdfBlock, std140 (four 16-byte rows).
struct SdfBlock {
  float voxel = 0;       // object units (SdfField::voxelSize())
  float bandVoxels = 0;  // SdfField::bandVoxels()
  float pad0[2] = {0, 0};
  float hitVoxels = 0;  // SdfTraceOptions, as given
  float minStepVoxels = 0;
  float startVoxels = 0;
  float skipEmpty = 0;  // 0 or 1
  int32_t maxSteps = 0;
  int32_t pad1[3] = {0, 0, 0};
  float coneTan = 0;          // SdfTraceOptions: the cone estimate (vffSdfVisibility) when either
  float coneRadiusAtEnd = 0;  // is positive
  float pad2[2] = {0, 0};
};
static_assert(sizeof(SdfBlock) == 64);

// The block for a field and the trace options (the CPU tracer's, field by field).
SdfBlock makeSdfBlock(const SdfField& sdf, const SdfTraceOptions& options);
// `block` with its trace options replaced (the grid's voxel and band kept).
SdfBlock withTraceOptions(SdfBlock block, const SdfTraceOptions& options);

// The #define lines vff_sdf.glsl needs, to put after `#version 430`: the grid's PNanoVDB type
// (VFF_SDF_GRID_TYPE: PNANOVDB_GRID_TYPE_FLOAT 1 or _FP8 14), VFF_SDF_SKIP_NUDGE (kSdfSkipNudge),
// VFF_SDF_CONE_DEPTH (kSdfConeDepth) and VFF_SDF_CONE_MIN_DISTANCE (kSdfConeMinDistance).
std::string sdfShaderDefines(const SdfField& sdf);

// vff_sdf.glsl's text with its `#include "nanovdb/PNanoVDB.h"` line replaced by the header's text
// (Debian's libnanovdb-dev, embedded at build time: pnanovdbHeader()).
std::string sdfShaderSource(const std::string& sdfGlsl);

// The text of nanovdb/PNanoVDB.h that this library was built against.
const std::string& pnanovdbHeader();

struct SdfBindings {
  uint32_t grid = 8;   // storage buffer (VFF_SDF_GRID_BINDING)
  uint32_t block = 9;  // uniform buffer (VFF_SDF_BLOCK_BINDING)
};

// Move-only (a moved-from GpuSdf is empty); the destructor deletes the GL objects (the context
// must be current).
class GpuSdf {
 public:
  GpuSdf() = default;
  GpuSdf(GpuSdf&& o) noexcept : s_(std::exchange(o.s_, {})) {}
  GpuSdf& operator=(GpuSdf&& o) noexcept {
    s_ = std::exchange(o.s_, {});  // (the objects held before are deleted)
    return *this;
  }

  void bind(const SdfBindings& bindings = {}) const noexcept;
  void release() noexcept { s_ = {}; }  // deletes the GL objects now (the context must be current)
  // Replaces the block's trace options (glBufferSubData); kBadState when GL reports an error.
  vff::Status setTraceOptions(const SdfTraceOptions& options);

  const SdfBlock& block() const noexcept { return s_.block; }
  uint32_t gridBuffer() const noexcept { return s_.grid.get(); }
  uint32_t blockBuffer() const noexcept { return s_.blockBuffer.get(); }
  uint64_t gridBytes() const noexcept { return s_.gridBytes; }  // bytes in the storage buffer

 private:
  friend vff::Result<GpuSdf> uploadSdf(const SdfField& sdf, const SdfTraceOptions& options);
  struct State {
    SdfBlock block;
    vff::gl::GlName grid{vff::gl::GlName::Kind::kBuffer}, blockBuffer{vff::gl::GlName::Kind::kBuffer};
    uint64_t gridBytes = 0;
  } s_;
};

// Uploads the field's grid and block (see the top of this file).
vff::Result<GpuSdf> uploadSdf(const SdfField& sdf, const SdfTraceOptions& options = {});

}  // namespace vffx::gl
